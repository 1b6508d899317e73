"""Every study's ``meta.json`` says what produced it: the version, the commit (when known), the
date and the machine (issue 31), beside the study, its settings, rows and wall time.

Checked through ``study_main`` with a stub ``run``/``plot`` (no study runs); the committed
``results/*/meta.json`` gain the fields when their study next runs in full.
"""

import datetime
import json
import re
import shutil
import subprocess

import pandas as pd
from matplotlib.figure import Figure

import simulator
from simulator import _result
from studies import _common
from studies.plotting import NO_HEAT, note_assumptions

_HEX40 = re.compile(r"[0-9a-f]{40}")


def _run(out, argv=()):
    def run(quick, progress):
        return pd.DataFrame({"x [um]": [1.0, 2.0]})

    def plot(df):
        fig = Figure(figsize=(3, 2))
        fig.add_subplot().plot(df["x [um]"])
        note_assumptions(fig, "environment: none", NO_HEAT)
        return fig

    _common.study_main("demo", "A stub study.\n", run, plot, ["--out", str(out), "--no-progress",
                                                             *argv])
    return json.loads((out / "meta.json").read_text())


def test_meta_records_version_commit_date_and_machine(tmp_path):
    before = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0)
    meta = _run(tmp_path, ["--quick"])
    after = datetime.datetime.now(datetime.timezone.utc)
    assert meta["study"] == "demo" and meta["settings"] == {"quick": True} and meta["rows"] == 2
    assert meta["etorigami_version"] == simulator.__version__
    date = datetime.datetime.fromisoformat(meta["date"])
    assert date.tzinfo is not None and before <= date <= after
    machine = meta["machine"]
    assert set(machine) == {"system", "architecture", "cpu", "cpus", "python"}
    assert machine["cpus"] >= 1 and machine["python"].count(".") == 2 and machine["system"]
    git = shutil.which("git")
    head = None if git is None else subprocess.run(
        [git, "rev-parse", "HEAD"], cwd=_common.RESULTS.parent, capture_output=True,
        text=True).stdout.strip() or None
    assert meta["git"] == head                        # this checkout's commit, or None
    assert head is None or _HEX40.fullmatch(head)


def test_meta_commit_is_none_when_git_is_unknown(tmp_path, monkeypatch):
    # an installed copy: no .git beside the package (the commit is read from its files)
    monkeypatch.setattr(_result, "__file__", str(tmp_path / "site" / "simulator" / "_result.py"))
    meta = _run(tmp_path)
    assert meta["git"] is None and meta["settings"] == {"quick": False}
    assert meta["etorigami_version"] == simulator.__version__ and meta["machine"]["cpus"] >= 1


def test_new_fields_do_not_change_what_a_rerun_is_compared_by(tmp_path):
    """A folder is refused by its study and settings only: a rerun with the same settings on
    another day or machine is accepted, and committed meta.json files without the new fields
    still compare."""
    _run(tmp_path)
    assert _common.refusal(tmp_path, "demo", {"quick": False}) is None
    old = {"study": "demo", "etorigami_version": "0.1.0", "settings": {"quick": False},
           "rows": 2, "wall_time [s]": 1.0}
    (tmp_path / "meta.json").write_text(json.dumps(old))
    assert _common.refusal(tmp_path, "demo", {"quick": False}) is None
    assert "other settings" in _common.refusal(tmp_path, "demo", {"quick": True})
