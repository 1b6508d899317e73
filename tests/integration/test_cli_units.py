"""CLI units of case parameters (``--set`` in um, mW, deg, s), implausible magnitudes, and
``--out`` checked before any work (issue 21, items 1 and 2)."""

import os
import pathlib
import subprocess
import sys
import time

import pytest

import design.cli as cli
from design.cli import main
from design.cli._common import CLIError, check_output
from design.cli.case_params import (CLI_UNITS, case_overrides, case_parameters, cli_unit,
                                    to_cli)

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert err.startswith("etorigami: error: ") and "\n" not in err and "Traceback" not in err
    return err


# ---------------------------------------------------------------------------- the unit table
def test_set_crease_width_is_in_um_and_builds_a_200_um_crease():
    from simulator import get_case

    overrides = case_overrides(["crease_width=200", "env_thickness=600"], "single-fold")
    assert overrides == {"crease_width": 200e-6, "env_thickness": 600e-6}   # bit-identical
    case = get_case("single_fold", **overrides)
    assert case.parameters["crease_width"] == 200e-6
    assert case.model.mesh.pattern.crease_width[2] == 200e-6


def test_names_with_a_unit_suffix_keep_their_unit():
    assert case_overrides(["power_mW=8", "residual_fold_deg=-10"], "single-fold") == {
        "power_mW": 8.0, "residual_fold_deg": -10.0}
    assert case_overrides(["dt=0.002", "t_on=0.5"], "single-fold-step-response") == {
        "dt": 2e-3, "t_on": 0.5}


def test_a_number_whose_default_the_case_chooses_is_checked_in_cli_units():
    """The crane's power_mW defaults to None (chosen by its loss_model): a number typed for
    it is a power in mW, range-checked like any other."""
    assert case_parameters()["crane"]["power_mW"] == (None, "mW")
    assert case_overrides(["power_mW=0.5", "loss_model=integral"], "crane") == {
        "power_mW": 0.5, "loss_model": "integral"}
    with pytest.raises(CLIError, match="--set power_mW = -1 mW is outside"):
        case_overrides(["power_mW=-1"], "crane")
    with pytest.raises(CLIError, match="--set power_mW expects a number in mW"):
        case_overrides(["power_mW=high"], "crane")


def test_every_default_round_trips_through_cli_units_bit_identically():
    from simulator.cases import describe_cases

    for name, _, params in describe_cases():
        for pname, default, unit in params:
            assert unit in CLI_UNITS, f"{name}.{pname}: SI unit {unit!r} has no CLI unit"
            if isinstance(default, float) and not isinstance(default, bool):
                text = repr(to_cli(default, unit))
                assert case_overrides([f"{pname}={text}"], name)[pname] == default, (name, pname)


def test_cases_prints_defaults_in_cli_units(capsys):
    assert main(["cases"]) == 0
    out = capsys.readouterr().out
    assert "crease_width = 200.0 [um]" in out and "env_thickness = 750.0 [um]" in out
    assert "shape_tol = 5.0 [um]" in out and "power_mW = 100.0 [mW]" in out
    assert " [m]" not in out
    params = case_parameters()["miura_lifter"]
    assert params["a"] == (1000.0, "m") and cli_unit("m").name == "um"


@pytest.mark.parametrize("pair, message", [
    ("crease_width=-5", "--set crease_width = -5 um must be > 0 um (lengths are in um, "
                        "plausible 0.01 to 100000 um)"),
    ("crease_width=0.0002", "--set crease_width = 0.0002 um is implausible: did you mean 200 um?"),
    ("env_thickness=750000", "--set env_thickness = 750000 um is implausible: did you mean "
                             "750 um?"),
    ("power_mW=1e9", "--set power_mW = 1e+09 mW is outside the plausible range 0 to 10000 mW "
                     "per crease"),
    ("power_mW=-1", "--set power_mW = -1 mW is outside the plausible range 0 to 10000 mW"),
    ("residual_fold_deg=200", "--set residual_fold_deg = 200 deg must be in (-180, 180] deg"),
    ("env_conductivity=-1", "--set env_conductivity = -1 W/(m K) must be >= 0 W/(m K)"),
    ("crease_width=wide", "--set crease_width expects a number in um"),
])
def test_set_errors_name_field_value_and_range_in_cli_units(pair, message, tmp_path, capsys):
    assert main(["run", "single-fold", "--set", pair, "--out", str(tmp_path / "x")]) == 2
    assert message in _one_line_error(capsys)
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("case, pair, message", [
    ("miura-lifter", "gamma_deg=95", "--set gamma_deg = 95 deg must be in (0, 90) deg"),
    ("miura-lifter", "a=1e-3", "--set a = 0.001 um is implausible: did you mean 1000 um?"),
    ("single-fold-step-response", "dt=0", "--set dt = 0 s must be > 0 s"),
])
def test_set_errors_of_other_cases(case, pair, message, tmp_path, capsys):
    assert main(["run", case, "--set", pair, "--out", str(tmp_path / "x")]) == 2
    assert message in _one_line_error(capsys)


# ---------------------------------------------------------------------------- um options
@pytest.mark.parametrize("argv, message", [
    (["gripper", "evaluate", "--W", "0.0002"],
     "--W = 0.0002 um is implausible (GripperDesign.W): did you mean 200 um? (lengths are in um"),
    (["gripper", "evaluate", "--La", "7e5"], "--La = 700000 um is implausible"),
    (["sweep", "residual-fold", "--design", "W=0.0003", "--out", "OUT"],
     "--design W = 0.0003 um is implausible: did you mean 300 um?"),
    (["sweep", "uncertainty", "--design", "W=300,La=2e6", "--out", "OUT"],
     "--design La = 2e+06 um is implausible"),
    (["check", "x.fold", "--crease-width", "0.0001"],
     "--crease-width = 0.0001 um is implausible: did you mean 100 um?"),
])
def test_implausible_lengths_get_a_hint(argv, message, tmp_path, capsys):
    argv = [str(tmp_path / "out") if a == "OUT" else a for a in argv]
    assert main(argv) == 2
    assert message in _one_line_error(capsys)


def test_fold_file_power_is_checked_in_mw(tmp_path, capsys):
    fold = tmp_path / "one.fold"
    assert main(["export", "single-fold", "--out", str(fold)]) == 0
    capsys.readouterr()
    assert main(["run", str(fold), "--set", "power.2=1e9", "--out", str(tmp_path / "x")]) == 2
    assert "--set power.2 = 1e+09 mW is outside the plausible range" in _one_line_error(capsys)


@pytest.mark.parametrize("args, unit", [
    (["run", "single-fold", "--set", "crease_width=-5"], "um"),
    (["gripper", "evaluate", "--W", "0.0002"], "um"),
    (["run", "single-fold", "--set", "power_mW=1e9"], "mW"),
])
def test_acceptance_errors_are_one_line_exit_2_within_2_s(args, unit, tmp_path):
    argv = args + (["--out", str(tmp_path / "x")] if args[0] == "run" else [])
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    # the command's own CPU time (user + system), not the wall time, which a loaded machine
    # stretches (the check is that no long work starts before the error)
    before = os.times()
    proc = subprocess.run([sys.executable, "-m", "design.cli", *argv], capture_output=True,
                          text=True, cwd=tmp_path, env=env, timeout=60)
    after = os.times()
    cpu = (after.children_user + after.children_system
           - before.children_user - before.children_system)
    err = proc.stderr.strip()
    assert proc.returncode == 2 and len(err.splitlines()) == 1 and f" {unit} " in err, err
    assert cpu < 2.0, f"{cpu:.2f} s CPU"


# ---------------------------------------------------------------------------- --out
_WRITERS = [
    ["demo"],
    ["run", "single-fold"],
    ["modes", "single-fold"],
    ["optimize", "gripper"],
    ["sweep", "residual-fold"],
    ["sweep", "uncertainty"],
]


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if a command gets as far as starting its work."""
    def started(short):
        raise AssertionError("the command started its work")
    monkeypatch.setattr(cli, "kernel_backend", started)


@pytest.mark.parametrize("argv", _WRITERS, ids=" ".join)
@pytest.mark.parametrize("where", ["file", "proc"])
def test_out_is_refused_before_any_work(argv, where, tmp_path, no_work, capsys):
    if where == "file":
        out = tmp_path / "results.txt"
        out.write_text("not a folder")
    else:
        out = pathlib.Path("/proc/x")
    assert main([*argv, "--out", str(out)]) == 2
    err = _one_line_error(capsys)
    assert f"--out {out}" in err
    assert ("is an existing file" if where == "file" else "cannot be written") in err


@pytest.mark.parametrize("argv, out", [
    (["export", "crane"], "/proc/x.fold"),
    (["view", "RESULTS"], "/proc/viewer.html"),
    (["export", "crane"], "DIR"),
])
def test_file_outputs_are_refused_before_any_work(argv, out, tmp_path, no_work, capsys):
    argv = [str(tmp_path) if a == "RESULTS" else a for a in argv]
    out = str(tmp_path) if out == "DIR" else out
    assert main([*argv, "--out", out]) == 2
    err = _one_line_error(capsys)
    assert "cannot be written" in err or "is a folder" in err


def test_check_output_accepts_new_and_existing_folders(tmp_path):
    check_output("--out", tmp_path, "dir")
    check_output("--out", tmp_path / "a" / "b", "dir")
    check_output("--out", tmp_path / "a" / "x.fold", "file")
    (tmp_path / "f").write_text("")
    check_output("--out", tmp_path / "f", "file")            # a file is replaced
    check_output("--out", None)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f"]  # the probe leaves nothing
    with pytest.raises(CLIError, match="cannot be written"):
        check_output("--out", tmp_path / "f" / "sub", "dir")  # a file is in the way


# ---------------------------------------------------------------------------- heating pre-check
def test_crease_temperature_estimate_is_one_linear_solve():
    from simulator import get_case
    from design.cli.precheck import estimate_crease_temperature

    t = {p: estimate_crease_temperature(*_model_steps(get_case("single_fold", power_mW=p)))
         for p in (100.0, 200.0)}
    room = get_case("single_fold").model.thermal.room_temperature
    assert 60 < t[100.0][0] < 100     # centre-line mean 82 degC; the run ends at 89 degC
    assert t[200.0][0] - room == pytest.approx(2 * (t[100.0][0] - room), rel=1e-12)
    assert estimate_crease_temperature(*_model_steps(get_case("snap_through"))) is None


def _model_steps(case):
    return case.model, case.steps


def test_hot_requests_warn_and_absurd_ones_are_refused_before_work(tmp_path, capsys):
    from simulator import get_case
    from design.cli.precheck import check_heating

    hot = get_case("single_fold", power_mW=1000.0)
    line = check_heating(hot.model, hot.steps, "single_fold")
    assert line.startswith("warning: single_fold: crease 2 would reach a centre-line mean of "
                           "about 632 degC")
    assert line.endswith("above 1.2 T_g = 252 degC of the crease material; running anyway")
    cool = get_case("single_fold")
    assert check_heating(cool.model, cool.steps, "single_fold") is None
    t0 = time.process_time()              # CPU time: a loaded machine stretches the wall
    assert main(["run", "single-fold", "--set", "power_mW=9000", "--out",
                 str(tmp_path / "x")]) == 2
    err = _one_line_error(capsys)
    assert "centre-line mean of about 5517 degC" in err and "above 1000 degC" in err
    assert "lower the power" in err
    assert time.process_time() - t0 < 2.0 and not (tmp_path / "x").exists()
