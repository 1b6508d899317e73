"""Ctrl-C during a long command: one line on stderr, exit status 130, and the run resumes."""

import csv
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")


def _rows(path):
    if not path.exists():
        return []
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _start(argv):
    """The command in its own process group, as a terminal runs it (Ctrl-C reaches all)."""
    env = dict(os.environ, PYTHONPATH=str(REPO))
    return subprocess.Popen([sys.executable, "-m", "design.cli", *argv], cwd=REPO, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)


def _cpu_seconds(pid) -> float:
    """User + system CPU time [s] of a process so far (Linux /proc)."""
    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _interrupt_after_first_row(argv, log):
    proc = _start(argv)
    deadline = time.monotonic() + 120
    while not _rows(log) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
    assert proc.poll() is None, "the command ended before it could be interrupted"
    os.killpg(proc.pid, signal.SIGINT)                 # what Ctrl-C in a terminal does
    try:
        out, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:                  # something still holds the pipes:
        os.killpg(proc.pid, signal.SIGKILL)            # leave no process behind, and say so
        out, err = proc.communicate()
        pytest.fail(f"processes of the command still ran 60 s after Ctrl-C; stderr: {err}")
    return proc.returncode, out, err


@pytest.mark.parametrize("parallel", [[], ["--parallel", "2"]], ids=["serial", "processes"])
def test_ctrl_c_during_optimize_saves_and_resumes(tmp_path, parallel):
    out = tmp_path / "cd"
    log = out / "evaluations.csv"
    argv = ["optimize", "gripper", "--method", "cd", "--out", str(out), "-q"]
    code, stdout, stderr = _interrupt_after_first_row(argv + parallel, log)
    assert code == 130
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1, stderr                     # no traceback, from any process
    saved = len(_rows(log))
    assert saved >= 1
    noun = "evaluation" if saved == 1 else "evaluations"
    assert lines[0].startswith(f"interrupted: {saved} {noun} saved in {log}")
    assert "resume" in lines[0] and "Traceback" not in stderr
    if parallel:
        return
    rerun = subprocess.run([sys.executable, "-m", "design.cli", *argv, "--max-evaluations",
                            str(saved + 1)], cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)),
                           capture_output=True, text=True, timeout=120)
    assert f"1 computed, {saved} reused" in rerun.stdout, rerun.stdout + rerun.stderr
    evals = [int(r["eval"]) for r in _rows(log)]
    assert evals == list(range(1, saved + 2))          # the log continues, it does not restart


@pytest.mark.slow
def test_ctrl_c_during_dask_sweep_is_one_line(tmp_path):
    pytest.importorskip("distributed")
    out = tmp_path / "sweep"
    values = ",".join(str(v) for v in range(-30, 1, 2))
    argv = ["sweep", "residual-fold", f"--values={values}", "--out", str(out), "--dask", "local",
            "-q"]
    code, _, stderr = _interrupt_after_first_row(argv, out / "evaluations.csv")
    assert code == 130
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("interrupted: "), stderr
    assert re.search(r"\b[1-9]\d* points? saved in ", lines[0]) and "resume" in lines[0]


def test_ctrl_c_during_run_saves_a_partial_result(tmp_path):
    """Issue 21: Ctrl-C on ``run`` keeps the accepted increments (status "interrupted")."""
    import json

    out = tmp_path / "run"
    proc = _start(["run", "single-fold", "--set", "thermal_steps=100000", "--out", str(out),
                   "-q"])
    # start-up, self-fold and gravity take about 2-3 s of CPU: interrupt after 6 s of the
    # process's own CPU time (not wall time, which depends on the machine's load)
    deadline = time.monotonic() + 300
    while _cpu_seconds(proc.pid) < 6.0 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
    assert proc.poll() is None, "the run ended before it could be interrupted"
    os.killpg(proc.pid, signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail("the run did not end after Ctrl-C")
    assert proc.returncode == 130
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    n = int(re.match(r"interrupted: (\d+) accepted increments? saved in ", lines[0]).group(1))
    assert 'status "interrupted"' in lines[0] and "step 'heat' at increment" in lines[0]
    meta = json.loads((out / "meta.json").read_text())
    assert meta["status"] == "interrupted" and meta["interrupted"] is True
    assert [s["status"] for s in meta["steps"]][-1] == "interrupted"
    assert {s["status"] for s in meta["steps"][:-1]} <= {"converged"}
    rows = _rows(out / "creases.csv")
    assert len(rows) == n + 1                                # one crease: a row per record
    assert sum(r["stage"] == "heat" for r in rows) >= 1      # heating increments were kept
