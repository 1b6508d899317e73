"""``etorigami sweep uncertainty`` and a worker killed under a running CLI sweep."""

import os
import pathlib
import signal
import subprocess
import sys
import time

import pandas as pd
import pytest

from design.cli import main
from design.cli.sweep import SCENARIO_NAMES
from design.analysis.uncertainty import SCENARIOS

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_scenario_names_match_the_library():
    assert SCENARIO_NAMES == tuple(SCENARIOS)


def test_sweep_uncertainty_writes_tables_and_resumes(tmp_path, capsys):
    out = tmp_path / "unc"
    argv = ["sweep", "uncertainty", "--samples", "3", "--seed", "4", "--scenario", "off",
            "--out", str(out), "-q"]
    assert main(argv) == 0
    assert "3 points written" in capsys.readouterr().out
    table = pd.read_csv(out / "uncertainty.csv")
    summary = pd.read_csv(out / "summary.csv")
    assert list(table["sample"]) == [0, 1, 2] and (table["residual_fold [deg]"] == 0).all()
    assert summary["yield [-]"].iloc[0] in (0.0, 1.0)          # uncertainty off: 0 or 1
    logged = (out / "evaluations.csv").read_text()
    assert logged.count("\n") == 2                               # 3 identical points, 1 run
    assert main(argv) == 0                                       # resumed: nothing computed
    assert (out / "evaluations.csv").read_text() == logged
    again = pd.read_csv(out / "uncertainty.csv").drop(columns=["wall_time [s]"])
    assert again.equals(table.drop(columns=["wall_time [s]"]))
    assert (out / "sensitivity.csv").exists() and (out / "scenario.json").exists()
    with pytest.raises(SystemExit):
        main(["sweep", "uncertainty", "--scenario", "bad", "--out", str(out)])
    assert main(argv[:3] + ["0"] + argv[4:]) == 2                # --samples 0


def _stat(pid):
    """(ppid, pgrp) of a process from /proc."""
    with open(f"/proc/{pid}/stat") as fh:
        fields = fh.read().rsplit(")", 1)[1].split()
    return int(fields[1]), int(fields[2])


def _pool_workers(leader):
    """Worker processes of the command's pool: in its process group, started by the
    forkserver (a child of the command), i.e. grandchildren of the command."""
    group = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            try:
                ppid, pgrp = _stat(int(name))
            except (OSError, IndexError, ValueError):
                continue
            if pgrp == leader:
                group[int(name)] = ppid
    children = {p for p, pp in group.items() if pp == leader}
    return sorted(p for p, pp in group.items() if pp in children)


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_killing_a_worker_of_a_cli_sweep_costs_nothing(tmp_path):
    """The issue's scenario: SIGKILL one worker of `sweep residual-fold --parallel 2` after
    the first point is logged; the sweep ends normally with every point, as an undisturbed
    serial run."""
    out = tmp_path / "hurt"
    argv = ["sweep", "residual-fold", "--values=-10,-5,0,5", "--parallel", "2", "-q"]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.Popen([sys.executable, "-m", "design.cli", *argv, "--out", str(out)],
                            cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    log = out / "evaluations.csv"
    deadline = time.monotonic() + 300
    while (not log.exists() or log.read_text().count("\n") < 2) and proc.poll() is None \
            and time.monotonic() < deadline:
        time.sleep(0.1)
    workers = _pool_workers(proc.pid)
    assert proc.poll() is None and workers, "nothing to kill"
    os.kill(workers[0], signal.SIGKILL)
    stdout, stderr = proc.communicate(timeout=600)
    assert proc.returncode == 0, stderr
    assert "4 points written" in stdout
    hurt = pd.read_csv(out / "sweep.csv").drop(columns=["wall_time [s]"])
    assert main([*argv[:3], "--out", str(tmp_path / "calm")]) == 0
    calm = pd.read_csv(tmp_path / "calm" / "sweep.csv").drop(columns=["wall_time [s]"])
    assert hurt.to_csv(index=False) == calm.to_csv(index=False)
    assert hurt["success"].all()


@pytest.mark.slow
def test_ctrl_c_during_uncertainty_sweep_resumes(tmp_path):
    """Ctrl-C after the first logged point: one line, exit 130; the same command finishes
    the sweep, reusing what was saved."""
    out = tmp_path / "unc"
    argv = [sys.executable, "-m", "design.cli", "sweep", "uncertainty", "--samples", "4",
            "--seed", "2", "--scenario", "residual-fold", "--parallel", "2", "--out", str(out),
            "-q"]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.Popen(argv, cwd=REPO, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    log = out / "evaluations.csv"
    deadline = time.monotonic() + 300
    while (not log.exists() or log.read_text().count("\n") < 2) and proc.poll() is None \
            and time.monotonic() < deadline:
        time.sleep(0.1)
    assert proc.poll() is None, "the sweep ended before it could be interrupted"
    os.killpg(proc.pid, signal.SIGINT)
    _, stderr = proc.communicate(timeout=60)
    lines = [line for line in stderr.splitlines() if line.strip()]
    assert proc.returncode == 130 and len(lines) == 1, stderr
    assert " saved in " in lines[0] and "resume" in lines[0]
    saved = log.read_text().count("\n") - 1
    assert 1 <= saved < 4
    done = subprocess.run(argv, cwd=REPO, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert log.read_text().count("\n") - 1 == 4                 # saved points not recomputed
    assert len(pd.read_csv(out / "uncertainty.csv")) == 4
