"""The etorigami command."""

import subprocess
import sys

import pytest

from design.cli import main
from simulator import __version__


def test_version(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert __version__ in capsys.readouterr().out


def test_help_lists_commands(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    assert "demo" in out and "usage" in out


def test_demo_runs_and_reports(capsys):
    assert main(["demo"]) == 0
    out = capsys.readouterr().out
    assert "self_fold" in out and "gravity" in out and "converged" in out


def test_console_script_installed():
    out = subprocess.run([sys.executable, "-m", "design.cli", "--version"], capture_output=True,
                         text=True)
    assert out.returncode == 0 and __version__ in out.stdout


def test_bad_option_exits_nonzero():
    with pytest.raises(SystemExit) as info:
        main(["demo", "--residual-fold", "abc"])
    assert info.value.code == 2


def test_cases_lists_parameters(capsys):
    assert main(["cases"]) == 0
    out = capsys.readouterr().out
    assert "single-fold" in out and "residual_fold_deg = 0.0 [deg]" in out and "miura-lifter" in out


def test_run_writes_results(tmp_path, capsys):
    out = tmp_path / "sf"
    code = main(["run", "single-fold", "--set", "thermal_steps=4", "--set", "power_mW=8",
                 "--set", "gravity=true", "--set", "residual_fold_deg=-10", "--out", str(out),
                 "--quiet"])
    assert code == 0
    assert (out / "creases.csv").exists() and (out / "nodes.npz").exists()
    import json
    meta = json.loads((out / "meta.json").read_text())
    assert meta["case"] == "single_fold" and meta["parameters"]["gravity"] is True
    import pandas as pd
    frame = pd.read_csv(out / "creases.csv")
    assert frame["power [mW]"].max() == pytest.approx(8.0)
    assert "gravity" in set(frame["stage"])


@pytest.mark.parametrize("argv, message", [
    (["run", "paper-plane", "--out", "x"], "Unknown case"),
    (["run", "single-fold", "--set", "power=3", "--out", "x"], "no parameter 'power'"),
    (["run", "single-fold", "--set", "thermal_steps=abc", "--out", "x"], "expects an integer"),
    (["run", "single-fold", "--set", "gravity=maybe", "--out", "x"], "expects true or false"),
    (["run", "single-fold", "--set", "power_mW", "--out", "x"], "name=value"),
    (["run", "single-fold", "--set", "crease_width=-1", "--out", "x"], "crease_width"),
])
def test_run_errors_are_one_line(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and "Traceback" not in err
