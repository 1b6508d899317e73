"""The etorigami command."""

import os
import pathlib
import subprocess
import sys
import time

import pytest

from design.cli import main
from simulator import __version__

ROOT = pathlib.Path(__file__).resolve().parents[2]


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
    assert "heat loss: chain model (the paper's" in out and "medium: air with k changed, k = 0.6" in out


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


# ---------------------------------------------------------------------------- demo, units
def test_demo_heats_until_lift_off_and_writes_results(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "heat converged" in text and "power [mW]" in text and "temperature [degC]" in text
    line = next(s for s in text.splitlines() if s.strip().startswith("threshold:"))
    threshold = float(line.split()[1])
    assert 45 < threshold < 60                 # the study single_fold finds 52.8 mW at -10 deg
    rows = [s for s in text.splitlines() if s.strip()[:1].isdigit()]
    assert 8 <= len(rows) <= 13
    assert (out / "creases.csv").exists() and (out / "demo.png").stat().st_size > 1000
    import pandas as pd
    frame = pd.read_csv(out / "creases.csv")
    assert frame["power [mW]"].max() == pytest.approx(100.0) and "heat" in set(frame["stage"])


def test_demo_threshold_is_lower_without_gravity(capsys):
    from design.cli.simulate import demo_run, heating_table, threshold_power

    _, result = demo_run(-10.0, gravity=False)
    power, what = threshold_power(heating_table(result))
    assert power is not None and power < 20 and "fold rises" in what


@pytest.mark.parametrize("argv, message", [
    (["demo", "--residual-fold", "400"], "--residual-fold = 400 deg must be a fold angle in "
                                         "(-180, 180] deg"),
    (["gripper", "evaluate", "--W", "-5"], "--W = -5 um must be > 0 um"),
    (["gripper", "evaluate", "--W", "800"], "--W = 800 um must be smaller than --L1, --L2 and "
                                            "--La (here 1000, 1000, 700 um)"),
    (["gripper", "evaluate", "--residual-fold=-181"], "(-180, 180] deg"),
    (["optimize", "gripper", "--robust=-10,120"], "--robust = 120 deg must be within -90 to 90"),
    (["sweep", "residual-fold", "--values=-10,100", "--out", "x"], "--values = 100 deg"),
    (["sweep", "residual-fold", "--design", "W=-3", "--out", "x"], "--design W = -3 um"),
])
def test_cli_errors_speak_cli_units(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and "Traceback" not in err
    assert " m " not in err and "rad" not in err


def test_python_entry_points_reject_fold_angles_outside_a_turn():
    from design.devices.gripper import GripperDesign
    from design import GripperProblem
    from simulator import ParameterError, get_case

    with pytest.raises(ParameterError, match=r"residual_fold_deg = 400 deg .*\(-180, 180\]"):
        get_case("single_fold", residual_fold_deg=400)
    with pytest.raises(ParameterError, match=r"residual_fold_deg = -180 deg"):
        get_case("double_fold", residual_fold_deg=-180)
    get_case("single_fold", residual_fold_deg=180)             # the closed end is allowed
    with pytest.raises(ParameterError, match=r"GripperDesign.residual_fold = 4 rad .*\(-pi, pi\]"):
        GripperDesign(residual_fold=4)
    with pytest.raises(ParameterError, match=r"GripperProblem.residual_fold = 7.0 rad"):
        GripperProblem(residual_fold=7.0)
    with pytest.raises(ParameterError, match=r"residual_fold_groups\['arm'\]"):
        GripperProblem(residual_fold_groups=(("arm", -4.0),))


def test_short_commands_run_on_one_tier(monkeypatch, tmp_path, capsys):
    """A short command chooses its kernels once, from the environment and the ahead-of-time
    module (never numpy because numba's cache is cold), and restores the default after."""
    from simulator import _jit

    monkeypatch.delenv("ETORIGAMI_JIT", raising=False)
    tiers = []
    monkeypatch.setattr(_jit, "warm_kernel_cache", lambda: tiers.append(_jit.tier()))
    argv = ["run", "single-fold", "--set", "thermal_steps=2", "--out", str(tmp_path), "-q"]
    assert main(argv) == 0
    assert _jit._backend is None and not _jit._aot
    if _jit.AVAILABLE and not _jit.command_tier(short=True) == "aot":
        assert tiers == ["numba"]                  # asked for the AOT module after the run


#: A short command of the paper's single fold (heated until it lifts off the substrate).
SAME_BITS_RUN = ["run", "single-fold", "--set", "residual_fold_deg=-10", "--set", "gravity=true",
                 "--set", "thermal_steps=40", "-q"]


def test_the_first_and_second_run_give_the_same_bits(tmp_path, monkeypatch):
    """Issue 31: the first run after install (an empty numba cache, no ahead-of-time module:
    numba's kernels compiled in the run) and the second (the ahead-of-time module the first
    asked for, built in the background before it) write the same files, byte for byte. (They
    differed when a cold cache meant the numpy kernels.)"""
    from simulator import _jit

    env = dict(os.environ, PYTHONPATH=str(ROOT), NUMBA_CACHE_DIR=str(tmp_path / "numba"),
               ETORIGAMI_AOT_DIR=str(tmp_path / "aot"))
    for name in ("ETORIGAMI_JIT", "ETORIGAMI_AOT"):
        env.pop(name, None)
    monkeypatch.setenv("NUMBA_CACHE_DIR", env["NUMBA_CACHE_DIR"])
    lock = _jit._compile_lock()              # of a background compilation into that cache

    def run(name):
        out = subprocess.run([sys.executable, "-m", "design.cli", *SAME_BITS_RUN, "--out",
                              str(tmp_path / name)], capture_output=True, text=True, env=env,
                             cwd=tmp_path, timeout=600)
        assert out.returncode == 0, out.stderr
        deadline = time.monotonic() + 600
        while lock.exists() and time.monotonic() < deadline:  # what the run asked for
            time.sleep(1.0)
        return {f: (tmp_path / name / f).read_bytes() for f in ("creases.csv", "nodes.npz")}

    first = run("first")
    if _jit.AVAILABLE:
        assert list((tmp_path / "aot").glob("_etorigami_kernels_*.json")), "no module built"
    assert run("second") == first
