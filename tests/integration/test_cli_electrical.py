"""``etorigami run FILE --heat WHICH --voltage V | --current MA`` (issue 30 item 4): each heated
crease driven through a gold-film heater, the circuits printed in V, mA and mW."""

import pathlib

import pandas as pd
import pytest

from design.cli import main

FOLD = str(pathlib.Path(__file__).resolve().parents[1] / "data" / "fold" /
           "single_crease_60.fold")


def _circuit_row(out: str) -> list:
    lines = out.splitlines()
    head = next(i for i, line in enumerate(lines) if line.split()[:2] == ["circuit",
                                                                          "voltage"])
    assert lines[head].split() == ["circuit", "voltage", "[V]", "current", "[mA]", "power",
                                   "[mW]", "lead_loss", "[mW]"]
    return lines[head + 1].split()


def test_voltage_drive_prints_volts_milliamps_and_milliwatts(tmp_path, capsys):
    out_dir = tmp_path / "v"
    assert main(["run", FOLD, "--heat", "all", "--voltage", "0.05", "--set", "thermal_steps=20",
                 "--out", str(out_dir), "-q"]) == 0
    row = _circuit_row(capsys.readouterr().out)
    table = pd.read_csv(out_dir / "creases.csv")
    last = table.iloc[-1]
    assert row[0] == "2" and float(row[1]) == pytest.approx(0.05)
    assert last["circuit_2_voltage [V]"] == pytest.approx(0.05)
    assert float(row[2]) == pytest.approx(1e3 * last["circuit_2_current [A]"], rel=1e-5)
    assert float(row[3]) == pytest.approx(last["power [mW]"], rel=1e-5)
    assert float(row[3]) == pytest.approx(0.05 * float(row[2]), rel=1e-5)   # mW = V mA
    assert last["heater_resistance [Ohm]"] == pytest.approx(
        last["circuit_2_voltage [V]"] / last["circuit_2_current [A]"], rel=1e-12)
    heated = table.dropna(subset=["heater_resistance [Ohm]"])
    base = heated["heater_resistance [Ohm]"] / (1 + 0.0034 * (heated["temperature [degC]"] - 21))
    assert heated["temperature [degC]"].max() > heated["temperature [degC]"].min() + 10
    assert base.max() == pytest.approx(base.min(), rel=1e-9)     # R0 (1 + tcr dT), gold film
    assert abs(last["fold_angle [deg]"]) > 1


def test_current_drive_in_milliamps(tmp_path, capsys):
    assert main(["run", FOLD, "--heat", "2", "--current", "40", "--set", "thermal_steps=10",
                 "--out", str(tmp_path / "c"), "-q"]) == 0
    row = _circuit_row(capsys.readouterr().out)
    assert float(row[2]) == pytest.approx(40.0)
    table = pd.read_csv(tmp_path / "c" / "creases.csv")
    R = table.iloc[-1]["heater_resistance [Ohm]"]
    assert float(row[3]) == pytest.approx(1e3 * 0.04**2 * R, rel=1e-5)


@pytest.mark.parametrize("argv, words", [
    (["--heat", "all", "--voltage", "0.05", "--power", "2"],
     "give one of --power MW, --voltage V or --current MA per heated crease (got --power, "
     "--voltage)"),
    (["--heat", "all", "--voltage", "-1"], "--voltage = -1 V is outside the plausible range"),
    (["--heat", "all", "--current", "1e6"], "--current = 1e+06 mA is outside the plausible"),
])
def test_bad_drive_flags_are_one_line(tmp_path, capsys, argv, words):
    assert main(["run", FOLD, *argv, "--out", str(tmp_path / "x"), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and words in err
    assert not (tmp_path / "x" / "creases.csv").exists()


def test_voltage_without_heat_on_a_built_in_case_is_refused(tmp_path, capsys):
    assert main(["run", "single-fold", "--voltage", "1", "--out", str(tmp_path / "x"),
                 "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--voltage drive the creases of --heat WHICH" in err
