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

    from simulator.steps import Event

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


def test_a_refusal_is_the_only_line_on_stderr_even_after_a_reader_warning(tmp_path):
    """Issue 28 (FOLD corpus: fold's box.fold and simple.fold): the reader's WARNING that
    creases are folded against their assignment came before the one-line refusal; a refused
    run has no result for a warning to qualify (the reader's note is on stdout), so stderr is
    the refusal alone. The reader is made to warn on a shipped file (in a fresh process, with
    the CLI's own logging set-up), then the run is refused."""
    path = REPO / "tests" / "data" / "fold" / "zigzag_folded.fold"
    argv = ["run", str(path), "--heat", "999", "--power", "1", "--out", str(tmp_path / "r"),
            "-q"]
    code = ("import logging, sys\n"
            "import simulator.io.fold.reader as reader\n"
            "def note(pattern, notes):\n"
            "    notes.append('creases [2] are folded against their assignment')\n"
            "    reader.logger.warning('FOLD: %s', notes[-1])\n"
            "reader._note_sign_mismatch = note\n"
            "from design.cli import main\n"
            f"sys.exit(main({argv!r}))\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, env=ENV, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 2
    assert "note: creases [2] are folded against their assignment" in out.stdout
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("etorigami: error: "), out.stderr
    assert "999 is not a crease" in lines[0]


def test_a_warning_of_a_run_with_a_result_is_still_printed(tmp_path, caplog):
    """The held warnings of a command that ends normally are printed (at its end)."""
    import logging

    from design import cli

    handler = logging.StreamHandler(sys.stderr)
    logging.getLogger().addHandler(handler)
    try:
        held = cli._HeldWarnings()
        assert handler in held.handlers
        logging.getLogger("simulator.test").warning("affects the result")
        assert held.records and held.records[0][1].getMessage() == "affects the result"
        held.close(release=True)
        assert not held.records and held not in handler.filters
        held = cli._HeldWarnings()
        logging.getLogger("simulator.test").warning("dropped")
        held.close(release=False)
        assert held not in handler.filters
    finally:
        logging.getLogger().removeHandler(handler)
