"""Quick runs never overwrite full results (issue 21, item 3).

``--quick`` without ``--out`` writes to ``./results-quick/<name>`` (git-ignored), its figures
carry a stamp, its ``meta.json`` says ``"quick": true``; a folder holding results of another
study or other settings is refused unless ``--overwrite``. The output location is checked for
every study module (with a stub ``run``/``plot``, so no study runs), and one cheap study runs end
to end from the repository root as a user would.
"""

import importlib
import json
import os
import pathlib
import pkgutil
import shutil
import subprocess
import sys

import pandas as pd
import pytest
from matplotlib.figure import Figure

import studies
from studies import _common, plotting
from studies.plotting import NO_HEAT, QUICK_STAMP, note_assumptions, save_figure, stamp_quick

ROOT = pathlib.Path(__file__).resolve().parents[2]
#: Every study module: the modules of ``studies`` with a ``main``.
STUDIES = sorted(info.name for info in pkgutil.iter_modules(studies.__path__)
                 if hasattr(importlib.import_module(f"studies.{info.name}"), "main"))


def _stamps(fig) -> list:
    return [t for t in fig.texts if t.get_text() == QUICK_STAMP]


class Stub:
    """A stand-in ``run``/``plot`` pair: records its calls, makes one row and one figure."""

    def __init__(self):
        self.quick, self.figures = [], []

    def run(self, quick, progress):
        self.quick.append(quick)
        return pd.DataFrame({"x [um]": [1.0, 2.0]})

    def plot(self, df):
        fig = Figure(figsize=(4, 3), layout="constrained")
        fig.add_subplot().plot(df["x [um]"])
        note_assumptions(fig, "environment: none", NO_HEAT)   # save_figure requires a footer
        self.figures.append(fig)
        return fig


def _main(name, argv, stub):
    return _common.study_main(name, "A stub study.\n", stub.run, stub.plot, argv)


def test_every_study_module_is_discovered():
    assert len(STUDIES) >= 15 and {"single_fold", "gripper_yield", "crane"} <= set(STUDIES)
    assert not {"_common", "plotting"} & set(STUDIES)


@pytest.mark.parametrize("name", STUDIES)
def test_quick_main_writes_to_the_quick_folder_of_the_working_directory(name, tmp_path,
                                                                         monkeypatch):
    module = importlib.import_module(f"studies.{name}")
    stub, gifs = Stub(), []
    real = _common.study_main
    monkeypatch.setattr(module, "study_main",
                        lambda study, doc, run, plot, argv=None: real(study, doc, stub.run,
                                                                      stub.plot, argv))
    if hasattr(module, "animation"):           # single_fold's GIF after the study's files
        monkeypatch.setattr(module, "animation",
                            lambda df, path, quick=False: gifs.append((path, quick)))
    monkeypatch.chdir(tmp_path)
    out = module.main(["--quick", "--no-progress"])
    assert out == tmp_path / "results-quick" / module.NAME
    assert stub.quick == [True]
    assert (out / f"{module.NAME}.csv").is_file() and (out / f"{module.NAME}.png").is_file()
    assert json.loads((out / "meta.json").read_text())["settings"]["quick"] is True
    assert len(_stamps(stub.figures[0])) == 1
    assert not (tmp_path / "results").exists()
    assert all(path.parent == out and quick for path, quick in gifs)


def test_full_main_still_writes_to_results(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    stub = Stub()
    assert _main("demo", ["--no-progress"], stub) == tmp_path / "results" / "demo"
    assert stub.quick == [False] and not _stamps(stub.figures[0])
    assert _common.default_out("demo", quick=True) == tmp_path / "results-quick" / "demo"
    assert json.loads((tmp_path / "results" / "demo" / "meta.json").read_text())[
        "settings"] == {"quick": False}


def test_a_folder_with_other_settings_is_refused_before_any_work(tmp_path, capsys):
    full = Stub()
    _main("demo", ["--out", str(tmp_path), "--no-progress"], full)
    csv = (tmp_path / "demo.csv").read_bytes()
    quick = Stub()
    with pytest.raises(SystemExit) as exc:
        _main("demo", ["--quick", "--out", str(tmp_path), "--no-progress"], quick)
    assert exc.value.code == 2 and quick.quick == []          # refused before running
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "other settings" in err and "--overwrite" in err
    assert (tmp_path / "demo.csv").read_bytes() == csv
    assert json.loads((tmp_path / "meta.json").read_text())["settings"] == {"quick": False}
    # the same settings again are a rerun, not a mix
    _main("demo", ["--out", str(tmp_path), "--no-progress"], full)
    assert full.quick == [False, False]
    # another study's folder is refused too
    with pytest.raises(SystemExit) as exc:
        _main("other", ["--out", str(tmp_path), "--no-progress"], Stub())
    assert exc.value.code == 2 and "'demo', not 'other'" in capsys.readouterr().err


def test_overwrite_flag_writes_into_a_folder_with_other_settings(tmp_path):
    _main("demo", ["--out", str(tmp_path), "--no-progress"], Stub())
    stub = Stub()
    _main("demo", ["--quick", "--overwrite", "--out", str(tmp_path), "--no-progress"], stub)
    assert stub.quick == [True]
    assert json.loads((tmp_path / "meta.json").read_text())["settings"] == {"quick": True}


def test_an_unreadable_meta_json_is_refused(tmp_path):
    (tmp_path / "meta.json").write_text("{not json")
    assert "cannot be read" in _common.refusal(tmp_path, "demo", {"quick": True})
    assert _common.refusal(tmp_path / "new", "demo", {"quick": True}) is None


def test_help_names_the_quick_folder_and_the_override(capsys):
    with pytest.raises(SystemExit) as exc:
        _main("demo", ["--help"], Stub())
    assert exc.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "--overwrite" in text and "./results-quick/demo" in text and "refused" in text


def test_save_figure_stamps_quick_figures_once_below_the_axes(tmp_path):
    fig = Figure(figsize=(4, 3), layout="constrained")
    ax = fig.add_subplot()
    ax.plot([0, 1], [0, 1])
    note_assumptions(fig, "environment: none", NO_HEAT)
    save_figure(fig, tmp_path / "full.png")
    assert not _stamps(fig)
    save_figure(fig, tmp_path / "quick.png", quick=True)
    save_figure(fig, tmp_path / "quick.png", quick=True)
    (stamp,) = _stamps(fig)
    stamp_quick(fig)
    assert len(_stamps(fig)) == 1
    fig.canvas.draw()                 # the constrained layout keeps the stamp's strip free
    top = stamp.get_window_extent().transformed(fig.transFigure.inverted()).y1
    assert ax.get_tightbbox().transformed(fig.transFigure.inverted()).y0 > top


def test_figures_only_stamps_what_meta_json_calls_quick(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(plotting, "save_figure",
                        lambda fig, path, quick=False: calls.append(quick))
    stub = Stub()
    pd.DataFrame({"x [um]": [1.0]}).to_csv(tmp_path / "demo.csv", index=False)
    _common.replot("demo", stub.plot, tmp_path)
    (tmp_path / "meta.json").write_text(json.dumps({"study": "demo", "settings": {"quick": True}}))
    _common.replot("demo", stub.plot, tmp_path)
    assert calls == [False, True]
    assert _common.run_was_quick(tmp_path) and not _common.run_was_quick(tmp_path / "none")


def test_a_real_quick_run_records_quick_in_meta(quick_study):
    _, out, _ = quick_study("heater_allocation")          # shared with test_studies_heaters
    assert json.loads((out / "meta.json").read_text())["settings"] == {"quick": True}


def test_quick_study_from_the_repository_root_leaves_results_untouched():
    """The acceptance line: ``python -m studies.<name> --quick`` from the repository root
    leaves ``git status`` of results/ as it was (one cheap study, as a subprocess)."""
    git = shutil.which("git")
    if git is None or subprocess.run([git, "-C", str(ROOT), "rev-parse"],
                                     capture_output=True).returncode != 0:
        pytest.skip("needs git and a git checkout")

    def status():
        return subprocess.run([git, "status", "--porcelain", "--untracked-files=all", "results/"],
                              cwd=ROOT, capture_output=True, text=True, check=True).stdout

    before = status()
    quick_root = ROOT / "results-quick"
    out = quick_root / "heat_within_structure"
    existed = out.exists()
    try:
        run = subprocess.run([sys.executable, "-m", "studies.heat_within_structure", "--quick",
                              "--no-progress"], cwd=ROOT, capture_output=True, text=True,
                             env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=600)
        assert run.returncode == 0, run.stderr
        assert str(out) in run.stdout and "quick run" in run.stdout
        assert json.loads((out / "meta.json").read_text())["settings"] == {"quick": True}
        assert subprocess.run([git, "check-ignore", "-q", str(out / "meta.json")],
                              cwd=ROOT).returncode == 0            # never committed
        assert status() == before
    finally:
        if not existed:
            shutil.rmtree(out, ignore_errors=True)
            if quick_root.is_dir() and not any(quick_root.iterdir()):
                quick_root.rmdir()
