"""Quiet success, loud events (issue 21, item 5): -q everywhere, no progress frames when stderr
is not a terminal, no WARNING from a run whose result is fine, and a summary of `run` that
names its events, its hottest crease and the 1.2 T_g check."""

import os
import pathlib
import subprocess
import sys

import pytest

from design.cli import main
from design.cli._summary import summary_lines

REPO = pathlib.Path(__file__).resolve().parents[2]
ENV = dict(os.environ, PYTHONPATH=str(REPO))


def _cli(argv, timeout=300):
    """The CLI in a fresh process with stderr a pipe (not a terminal), as in a log file."""
    return subprocess.run([sys.executable, "-m", "design.cli", *argv], cwd=REPO, env=ENV,
                          capture_output=True, text=True, timeout=timeout)


def _no_frames(stderr):
    return "\r" not in stderr and "it/s" not in stderr and "eval/s" not in stderr \
        and "inc/s" not in stderr and "%|" not in stderr


def test_optimize_cd_quiet_prints_no_warning_and_no_frames(tmp_path):
    out = _cli(["optimize", "gripper", "--method", "cd", "-q", "--max-evaluations", "6"])
    assert out.returncode in (0, 1), out.stderr
    assert "WARNING" not in out.stderr and "warning" not in out.stderr.lower(), out.stderr
    assert _no_frames(out.stderr), out.stderr
    assert out.stdout.startswith("cd: ")


def test_no_progress_frames_without_a_terminal_even_without_q(tmp_path):
    out = _cli(["run", "single-fold", "--set", "thermal_steps=10", "--out", str(tmp_path / "r")])
    assert out.returncode == 0, out.stderr
    assert _no_frames(out.stderr) and out.stderr.strip() == "", out.stderr


@pytest.mark.parametrize("argv", [["-q", "cases"], ["cases", "-q"], ["-q", "demo", "--help"],
                                  ["gripper", "evaluate", "-q", "--help"],
                                  ["sweep", "residual-fold", "--help"], ["check", "--help"]])
def test_one_quiet_flag_on_every_command(argv, capsys):
    try:
        code = main(argv)
    except SystemExit as exc:                        # --help
        code = exc.code
    assert code == 0
    if "--help" in argv:
        assert "-q, --quiet" in capsys.readouterr().out


def test_studies_take_q_and_the_older_no_progress():
    from studies._common import _parser

    parser = _parser("x", "doc")
    assert parser.parse_args(["-q"]).no_progress
    assert parser.parse_args(["--quiet"]).no_progress
    assert parser.parse_args(["--no-progress"]).no_progress
    assert not parser.parse_args([]).no_progress


def test_run_summary_names_hottest_crease_and_the_tg_limit(tmp_path, capsys):
    # prefolded to -90 deg: from flat the crease would fold past 180 deg at 300 mW, where the
    # heating stops (a panel crossing, issue 28), below the limit
    assert main(["run", "single-fold", "--set", "thermal_steps=20", "--set", "power_mW=400",
                 "--set", "residual_fold_deg=-90", "--out", str(tmp_path / "r"), "-q"]) == 0
    text = capsys.readouterr()
    lines = text.out.splitlines()
    verdict = [line for line in lines if line.startswith("temperature limit exceeded: crease 2: "
                                                         "centre-line mean ")]
    assert len(verdict) == 1 and "degC > 1.2 T_g = 252 degC" in verdict[0], text.out
    assert any(line.startswith("the centre-line mean first exceeds 1.2 T_g = 252 degC at "
                               "record ") for line in lines), text.out
    hottest = [line for line in lines if line.startswith("hottest node ")]
    assert len(hottest) == 1 and hottest[0].endswith(
        "information: the limit is judged on the crease centre-line mean)"), text.out


def test_summary_names_each_event_with_power_and_jump():
    import numpy as np

    from simulator import Event

    snap = Event(kind="snap", load_factor=0.5, displacement=1e-4, maximum=True,
                 power_per_crease=(0.0, 9.215e-3), jump=51e-6, temperature_max=458.0, node=7,
                 step="heat")

    class Result:                                         # the few fields summary_lines reads
        events = (snap,)
        history = {"temperature": np.zeros((0, 3))}

        class model:
            class mesh:
                crease_ids = np.array([1, 4])

    line, = summary_lines(Result())
    assert line == ("event: snap in step heat at 9.215 mW in all (crease 4: 9.215 mW), jump "
                    "51 um (node 7), hottest node 458 degC")
