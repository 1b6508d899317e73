"""Plain crease patterns at the CLI (issue 20): check without physical parameters, run from
flags alone with a layer stack, heater names, one-line refusals."""

import json
import pathlib

import pandas as pd
import pytest

from design.cli import main

DATA = pathlib.Path(__file__).resolve().parents[1] / "data" / "fold"
MIURA = str(DATA / "miura_3x3_plain.fold")


def test_check_of_a_plain_pattern_says_all_that_a_run_needs_in_flags(capsys):
    assert main(["check", MIURA]) == 0
    out = capsys.readouterr().out
    assert "valid FOLD crease pattern" in out
    assert "creases 12 (6 M, 6 V, 0 U)" in out and "start shape: flat" in out
    assert "layer stack su8-au" in out and "0.2 um at 50 GPa" in out
    assert "a run needs: --heat all|M|V|IDS; --power MW" in out


def test_check_of_a_unit_less_pattern_asks_for_the_unit_scale_too(tmp_path, capsys):
    data = json.loads(pathlib.Path(MIURA).read_text())
    del data["frame_unit"]
    path = tmp_path / "p.fold"
    path.write_text(json.dumps(data))
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "--unit-scale METRES" in out and "--power MW" in out


def test_drawn_miura_runs_a_heating_simulation_from_flags_alone(tmp_path, capsys):
    out_dir = tmp_path / "run"
    assert main(["run", MIURA, "--heat", "all", "--power", "2", "--set", "thermal_steps=20",
                 "--out", str(out_dir), "-q"]) == 0
    out = capsys.readouterr().out
    assert "layer stack su8-au" in out and "converged" in out
    table = pd.read_csv(out_dir / "creases.csv")
    last = table[table["step"] == table["step"].max()]
    assert len(last.drop_duplicates("crease")) == 12
    assert last["fold_angle [deg]"].abs().max() > 5
    meta = json.loads((out_dir / "meta.json").read_text())
    assert meta["overrides"]["stack"] == "su8-au"


def test_heat_selects_valleys_and_ids(tmp_path, capsys):
    assert main(["run", MIURA, "--heat", "V", "--power", "1", "--set", "thermal_steps=5",
                 "--out", str(tmp_path / "v"), "-q"]) == 0
    meta = json.loads((tmp_path / "v" / "meta.json").read_text())
    assert len(meta["overrides"]["heated_creases"]) == 6
    assert main(["run", MIURA, "--heat", "99", "--power", "1", "--out",
                 str(tmp_path / "x"), "-q"]) == 2
    assert "99 is not a crease" in capsys.readouterr().err


def test_heater_names_from_the_file(tmp_path, capsys):
    data = json.loads(pathlib.Path(MIURA).read_text())
    letters = data["edges_assignment"]
    data["edges_etorigami:heater"] = ["valleys" if a == "V" else None for a in letters]
    path = tmp_path / "named.fold"
    path.write_text(json.dumps(data))
    assert main(["run", str(path), "--heat", "valleys", "--power", "1", "--set",
                 "power.valleys=3", "--set", "thermal_steps=5", "--out", str(tmp_path / "r"),
                 "-q"]) == 0
    table = pd.read_csv(tmp_path / "r" / "creases.csv")
    assert table["power [mW]"].max() == pytest.approx(3.0)
    assert main(["run", str(path), "--heat", "valleys", "--power", "1", "--set",
                 "power.nope=3", "--out", str(tmp_path / "s"), "-q"]) == 2
    assert "heaters: valleys" in capsys.readouterr().err


def test_run_of_a_plain_pattern_without_power_is_one_line(tmp_path, capsys):
    assert main(["run", MIURA, "--out", str(tmp_path / "r"), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "needs --heat all|M|V|IDS and --power MW" in err


@pytest.mark.parametrize("path", sorted(DATA.glob("*.fold")), ids=lambda p: p.name)
def test_check_of_every_file_is_a_summary_or_one_line(path, capsys):
    code = main(["check", str(path)])
    out, err = capsys.readouterr()
    assert code in (0, 2) and "Traceback" not in out + err
    if code == 2:
        assert len(err.strip().splitlines()) == 1 and path.name in (
            "fully_folded.fold", "crease_too_wide.fold", "sheets_touching_at_a_vertex.fold",
            "accordion_folded_flat.fold", "no_creases.fold")
    else:
        assert "valid FOLD" in out


def test_a_file_without_creases_is_checked_and_refused_in_one_line(tmp_path, capsys):
    """Issue 28: check crashed (zero-size minimum) and the sharp check printed a nan width on a
    valid file without creases; a run of it is refused in CLI terms."""
    path = str(DATA / "no_creases.fold")
    for flags in ([], ["--crease-model", "sharp"]):
        assert main(["check", path, *flags]) == 2            # check refuses what run refuses
        out, err = capsys.readouterr()
        assert "valid FOLD crease pattern" in out and "creases 0" in out and "nan" not in out
        assert err.count("\n") == 1 and "has no crease to heat or fold" in err, err
    for flags, what in ((["--heat", "all", "--power", "1"], "heat"), ([], "heat"),
                        (["--crease-model", "sharp", "--fold", "all=30"], "fold")):
        assert main(["run", path, *flags, "--out", str(tmp_path / "r"), "-q"]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and f"has no crease to {what}" in err, err
        assert "M, V or U edges" in err and "SharpHingeParameters" not in err


def test_a_sheet_folded_flat_is_refused_in_one_short_line_with_the_frame_option(tmp_path,
                                                                                capsys):
    """Issue 28: the +-180 deg refusal ran to 10,986 characters on an 8 x 8 maze and did not
    say --frame creasePattern; now the creases are capped and the option is named."""
    path = str(DATA / "accordion_folded_flat.fold")
    for command in (["check", path], ["run", path, "--heat", "all", "--power", "1", "--out",
                                      str(tmp_path / "r"), "-q"]):
        assert main(command) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and len(err) < 340, len(err)
        assert "crease(s) [2, 5, 8, 11, 14, and 34 more] are at +-180 deg" in err
        assert "--frame creasePattern" in err and "frame=" not in err


def test_the_crease_width_refusal_names_every_panel_and_the_option(tmp_path, capsys):
    """Issue 28: every panel too small for the crease width is named (capped), with the CLI
    option that fixes it."""
    assert main(["run", MIURA, "--crease-width", "5000", "--heat", "all", "--power", "1",
                 "--out", str(tmp_path / "r"), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "panel(s) [0, 1, 2, 3, 4, 5, 6, 7, 8] vanish" in err
    assert "at most about 857.4 um fit" in err and "(--crease-width UM" in err
    assert "crease_width" not in err


def test_values_the_file_gives_instead_of_the_stack_are_named(capsys):
    """Issue 28: the stack line printed 200 um while the file's own crease widths were used."""
    assert main(["check", str(DATA / "crease_too_wide.fold")]) == 2
    out = capsys.readouterr().out
    assert "note: used instead of the stack's values (from the file or the flags): crease " \
           "width 300 um" in out
    assert main(["check", MIURA, "--crease-width", "100", "--panel-thickness", "20"]) == 0
    out = capsys.readouterr().out
    assert "crease width 100 um, panel thickness 20 um" in out
    assert main(["check", MIURA]) == 0
    assert "used instead" not in capsys.readouterr().out


def test_a_flat_start_at_a_bifurcation_at_the_cli_in_cli_words(tmp_path, capsys):
    """Issue 28: the waterbomb base heated from flat. By default the run reaches a stable
    folded state; with --stability check it ends "unstable" (exit 1) with a "stability lost"
    event, and its status line names the CLI option, not NewtonOptions."""
    import sys

    sys.path.insert(0, str(pathlib.Path(__file__).parent))
    from test_heated_branches import _waterbomb

    path = tmp_path / "waterbomb.fold"
    path.write_text(json.dumps(_waterbomb()))
    common = ["run", str(path), "--heat", "all", "--power", "20", "--set", "thermal_steps=50",
              "--loss-model", "chain", "-q"]           # the heat loss the power was chosen for
    assert main(common + ["--out", str(tmp_path / "a")]) == 0
    out = capsys.readouterr().out
    assert "waterbomb: converged" in out and "stability lost" not in out
    assert main(common + ["--stability", "check", "--out", str(tmp_path / "b")]) == 1
    out = capsys.readouterr().out
    status = [line for line in out.splitlines() if line.startswith("waterbomb")][0]
    assert ": unstable (" in status and "--stability check" in status
    assert "event: stability lost in step heat" in out and "--stability switch leaves it" in out
    assert "NewtonOptions" not in out


def test_loss_model_integral_heats_a_plain_pattern_hotter_than_the_chains(tmp_path, capsys):
    """--loss-model integral: the boundary-integral heat loss (theory 4.7) on a drawn Miura;
    in still air it loses less than the paper's chains, so the same power heats it more."""
    runs = {}
    for loss in ("chain", "integral"):
        out_dir = tmp_path / loss
        assert main(["run", MIURA, "--heat", "all", "--power", "1", "--set", "thermal_steps=2",
                     "--loss-model", loss, "--out", str(out_dir), "-q"]) == 0
        meta = json.loads((out_dir / "meta.json").read_text())
        assert meta["overrides"]["loss_model"] == loss
        runs[loss] = pd.read_csv(out_dir / "creases.csv")
    assert "heat loss: integral model" in capsys.readouterr().out
    hottest = {k: v[v["step"] == v["step"].max()].filter(like="temperature").max().max()
               for k, v in runs.items()}
    assert hottest["integral"] > hottest["chain"]


def test_a_plain_pattern_heats_with_the_integral_loss_by_default(tmp_path, capsys):
    """Issue 29: new models use the calibration-free integral loss unless told otherwise; the
    run says which loss and medium it heats with."""
    out_dir = tmp_path / "default"
    assert main(["run", MIURA, "--heat", "all", "--power", "1", "--set", "thermal_steps=2",
                 "--out", str(out_dir)]) == 0
    out = capsys.readouterr().out
    assert "heat loss: integral model (calibration-free; m = 3, extrapolated), to air at " \
           "0.026 W/(m K)" in out
    assert json.loads((out_dir / "meta.json").read_text())["overrides"]["loss_model"] == \
        "integral"
    from simulator import ParameterError
    from simulator.fold import parse_fold
    from simulator.model import get_stack, stack_model

    stack = get_stack("su8-au")
    geo = parse_fold(json.loads(pathlib.Path(MIURA).read_text()),
                     crease_width=stack.crease_width, crease_thickness=stack.crease_thickness,
                     panel_thickness=stack.panel_thickness)
    creases = geo.pattern.creases.tolist()
    assert stack_model(geo.pattern, stack, creases).thermal.loss.model == "integral"
    paper = stack_model(geo.pattern, stack, creases, loss_model="chain").thermal.loss
    assert (paper.model, paper.thickness) == ("chain", stack.env_thickness)
    with pytest.raises(ParameterError, match="loss_model = 'fe'"):
        stack_model(geo.pattern, stack, creases, loss_model="fe")


def test_a_large_plain_pattern_heats_with_the_integral_loss_at_m_2(tmp_path, caplog, capsys):
    """Above the default integral model's dense limit (a 6 x 6-cell Miura: 504 triangles) a
    plain pattern heats with the integral loss at m = 2 without extrapolation (no fallback to
    the chains; 2016 sub-triangles, dense here), and the heat-loss line says so."""
    import logging

    from simulator.fold import write_fold
    from simulator.geometry.example_patterns import miura_sheet_pattern

    path = write_fold(miura_sheet_pattern(m=6, n=6), tmp_path / "miura6.fold")
    out_dir = tmp_path / "run"
    with caplog.at_level(logging.WARNING):
        assert main(["run", str(path), "--heat", "all", "--power", "0.1", "--set",
                     "thermal_steps=2", "--out", str(out_dir), "-q"]) == 0
    warned = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert not any("chains" in m for m in warned), warned
    out = capsys.readouterr().out
    assert "integral model (calibration-free; m = 2)" in out
    assert "m = 2 without extrapolation" in out
    assert json.loads((out_dir / "meta.json").read_text())["overrides"]["loss_model"] == \
        "integral"
