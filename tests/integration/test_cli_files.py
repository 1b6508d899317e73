"""CLI commands on files: export, check, run FILE.fold, view, modes."""

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from design.cli import main

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]


@pytest.fixture
def exported(tmp_path, capsys):
    path = tmp_path / "crane.fold"
    assert main(["export", "crane", "--set", "thermal_steps=10", "--out", str(path)]) == 0
    assert "written to" in capsys.readouterr().out
    return path


def test_exported_case_runs_back_to_the_built_in_result(exported, tmp_path, capsys):
    assert main(["run", str(exported), "--out", str(tmp_path / "file"), "-q"]) == 0
    assert main(["run", "crane", "--set", "thermal_steps=10", "--out", str(tmp_path / "case"),
                 "-q"]) == 0
    capsys.readouterr()
    a = pd.read_csv(tmp_path / "file" / "creases.csv")
    b = pd.read_csv(tmp_path / "case" / "creases.csv")
    assert len(a) == len(b) > 0
    for col in ("fold_angle [deg]", "crease_rotation [deg]", "temperature [degC]", "power [mW]"):
        np.testing.assert_allclose(a[col], b[col], rtol=1e-9, atol=1e-12)
    meta = json.loads((tmp_path / "file" / "meta.json").read_text())
    assert meta["model_file"].endswith("crane.fold") and meta["status"] == "converged"


def test_fold_run_overrides_power_and_increments(exported, tmp_path, capsys):
    assert main(["run", str(exported), "--set", "power.2=8", "--set", "thermal_steps=3",
                 "--out", str(tmp_path / "r"), "-q"]) == 0
    frame = pd.read_csv(tmp_path / "r" / "creases.csv")
    last = frame[frame["step"] == frame["step"].max()].set_index("crease")
    assert frame["step"].max() == 3
    assert last.loc[2, "power [mW]"] == pytest.approx(8.0)
    assert main(["run", str(exported), "--set", "power.2=-1", "--out", str(tmp_path / "x")]) == 2
    assert main(["run", str(exported), "--set", "colour=red", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "must be finite and >= 0" in err and "power.<crease id>=mW" in err


def test_check_summarises_and_rejects_bad_files_in_one_line(exported, tmp_path, capsys):
    assert main(["check", str(exported)]) == 0
    out = capsys.readouterr().out
    assert "valid FOLD model file" in out and "creases 17" in out and "steps: heat" in out
    bad = tmp_path / "bad.fold"
    bad.write_text('{"frame_unit": "mm", "vertices_coords": [[0, 0], [1, 0], [1, 1]],\n'
                   ' "faces_vertices": [[0, 1, 7]]}')
    proc = subprocess.run([sys.executable, "-m", "design.cli", "check", str(bad)],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "faces_vertices" in lines[0] and "Traceback" not in proc.stderr


def test_view_writes_a_self_contained_page(exported, tmp_path, capsys):
    assert main(["run", str(exported), "--out", str(tmp_path / "r"), "-q"]) == 0
    assert main(["view", str(tmp_path / "r"), "--out", str(tmp_path / "v.html")]) == 0
    capsys.readouterr()
    html = (tmp_path / "v.html").read_text()
    assert "<canvas" in html and "http://" not in html and "https://" not in html
    assert main(["view", str(tmp_path / "missing")]) == 2


def test_modes_writes_frequencies_and_plots(tmp_path, capsys):
    out = tmp_path / "m"
    assert main(["modes", "single-fold", "--set", "thermal_steps=5", "--count", "3",
                 "--out", str(out)]) == 0
    frame = pd.read_csv(out / "modes.csv")
    assert list(frame["mode"]) == [1, 2, 3]
    assert (np.diff(frame["frequency [Hz]"]) > 0).all() and frame["frequency [Hz]"][0] > 1
    assert (out / "modes.png").exists() and (out / "mode_1.png").exists()
    assert main(["modes", "single-fold", "--count", "0", "--out", str(out)]) == 2


def test_unit_files_need_a_scale(tmp_path, capsys):
    path = tmp_path / "square.fold"
    path.write_text(json.dumps({
        "vertices_coords": [[0, 0], [2, 0], [2, 1], [0, 1], [1, 0], [1, 1]],
        "faces_vertices": [[0, 4, 5, 3], [4, 1, 2, 5]]}))
    # a plain pattern is checked without physical parameters; what a run needs is listed at
    # once, in flags (issue 20), and the layer stack supplies the crease and panel values
    assert main(["check", str(path)]) == 0
    assert "a run needs: --unit-scale METRES" in capsys.readouterr().out
    assert main(["check", str(path), "--unit-scale", "1e-3"]) == 0
    out = capsys.readouterr().out
    assert "--unit-scale" not in out and "layer stack su8-au" in out
    assert main(["check", str(path), "--unit-scale", "1e-3", "--crease-width", "-5"]) == 2
    assert "--crease-width = -5 um must be > 0 um" in capsys.readouterr().err
    assert main(["check", str(path), "--unit-scale", "1e-3", "--crease-width", "100",
                 "--crease-thickness", "1", "--panel-thickness", "20"]) == 0
    assert "size 2000.0 x 1000.0" in capsys.readouterr().out


def test_every_malformed_file_is_one_line_and_exit_2_at_the_cli(tmp_path, capsys):
    import copy

    from test_fold import MALFORMED, two_panels

    assert len(MALFORMED) >= 15
    for name, edit, _ in MALFORMED:
        if name == "missing width":        # the layer stack gives it at the CLI (issue 20)
            continue
        data = copy.deepcopy(two_panels())
        edit(data)
        path = tmp_path / f"{name.replace(' ', '_')}.fold"
        path.write_text(json.dumps(data))
        assert main(["check", str(path)]) == 2, name
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("etorigami: error: FOLD"), (name, err)


def test_fold_refusals_and_notes_speak_cli_options_not_python_keywords(tmp_path, capsys):
    """Issue 28: run said unit_scale= (the Python keyword) where the option is --unit-scale;
    every library message of a FOLD file's check or run is spelled in options."""
    unit_less = tmp_path / "square.fold"
    unit_less.write_text(json.dumps({
        "vertices_coords": [[0, 0], [2, 0], [2, 1], [0, 1], [1, 0], [1, 1]],
        "faces_vertices": [[0, 4, 5, 3], [4, 1, 2, 5]]}))
    data = ROOT / "tests" / "data" / "fold"
    refusals = [
        (["run", str(unit_less), "--heat", "all", "--power", "1"], "pass --unit-scale METRES"),
        (["run", str(data / "t_junction.fold"), "--unit-scale", "1e-3", "--heat", "all",
          "--power", "1"], "so --unit-scale is not used"),
        (["run", str(data / "fully_folded.fold"), "--heat", "all", "--power", "1"],
         "(--frame creasePattern, or export it)")]
    for command, expected in refusals:
        assert main([*command, "--out", str(tmp_path / "r"), "-q"]) == 2
        err = capsys.readouterr().err.strip()
        assert expected in err and "\n" not in err, err
        assert not any(k in err for k in ("unit_scale", "frame=", "lay_flat", "crease_width"))
    assert main(["check", str(data / "origami_simulator_xz.fold")]) == 0
    out, err = capsys.readouterr()
    assert "note: flat sheet in the plane" in out and "--no-lay-flat keeps it standing" in out
    assert main(["check", str(data / "origami_simulator_xz.fold"), "--no-lay-flat"]) == 0
    more, more_err = capsys.readouterr()
    assert "note: flat sheet standing" in more and "--lay-flat lays it in x-y" in more
    assert "(--no-lay-flat)" in more
    assert "lay_flat" not in out + err + more + more_err


def test_the_map_from_keywords_to_options_is_applied_word_by_word():
    from design.cli._terms import cli_terms

    assert cli_terms("pass unit_scale=<metres per unit>; so unit_scale is unused") == (
        "pass --unit-scale METRES; so --unit-scale is unused")
    assert cli_terms("my_crease_width and edges_etorigami:width") == (
        "my_crease_width and edges_etorigami:width")


def test_a_model_file_given_heat_keeps_its_own_layer_stack(tmp_path, capsys):
    """Issue 28: --heat on a model file dropped its bimorph, air and supports for the default
    stack and printed the stack's 200 um / 10 um; now the file's own model is heated and its
    values are printed."""
    path = tmp_path / "single.fold"
    assert main(["export", "single_fold", "--out", str(path)]) == 0
    capsys.readouterr()
    flags = ["--set", "thermal_steps=10", "-q"]
    assert main(["run", str(path), "--heat", "all", "--power", "30", *flags, "--out",
                 str(tmp_path / "heat")]) == 0
    out = capsys.readouterr().out
    assert "model file's own parameters: heated creases 200 um wide, 0.5 um thick" in out
    assert "0.1 um at 39.5 GPa" in out and "heat loss: chains, t_env 750 um, to the medium at 0.6 W/(m K)" in out
    assert "layer stack" not in out and "19 fixed degrees of freedom" in out
    # the same run as the file's own heating step at that power
    assert main(["run", str(path), "--set", "power.2=30", *flags, "--out",
                 str(tmp_path / "own")]) == 0
    a = pd.read_csv(tmp_path / "heat" / "creases.csv")
    b = pd.read_csv(tmp_path / "own" / "creases.csv")
    pd.testing.assert_frame_equal(a, b)
    meta = json.loads((tmp_path / "heat" / "meta.json").read_text())
    assert meta["overrides"]["model_file_parameters"] is True
    for extra, expected in ((["--stack", "su8-au"], "--stack applies to plain crease patterns"),
                            (["--fix-panel", "0"], "drop --fix-panel")):
        assert main(["run", str(path), "--heat", "all", "--power", "1", *extra, "--out",
                     str(tmp_path / "x")]) == 2
        err = capsys.readouterr().err.strip()
        assert expected in err and "\n" not in err


def test_a_model_file_that_heats_without_thermal_parameters_is_refused_in_file_terms(
        tmp_path, capsys):
    path = tmp_path / "single.fold"
    assert main(["export", "single_fold", "--out", str(path)]) == 0
    data = json.loads(path.read_text())
    del data["etorigami:thermal"]
    path.write_text(json.dumps(data))
    capsys.readouterr()
    for extra in ([], ["--heat", "all", "--power", "1"]):
        assert main(["run", str(path), *extra, "--out", str(tmp_path / "r"), "-q"]) == 2
        err = capsys.readouterr().err.strip()
        assert "has no thermal parameters" in err and "add etorigami:thermal" in err
        assert "\n" not in err and "ThermalParameters" not in err
