"""Sharp creases (concentrated hinges) from FOLD files and the CLI (issue 20, items 3 and 5).

A drawn Miura 3 x 3 file read with ``crease_model="sharp"`` folds along the rigid-origami
kinematics of the Miura cell; a folded file, its rigid rotations and mirror images give the
same sharp fold angles and the same self-fold response; the stiffness data a sharp read lacks
and mixed crease widths are refused in one line; ``etorigami check`` / ``run`` take
``--crease-model sharp`` with a ``--fold`` drive and refuse heating.
"""

import copy
import json
import math
import pathlib

import numpy as np
import pandas as pd
import pytest

from design.cli import main
from simulator import SelfFold, Supports, simulate
from simulator.model import SharpHingeMesh, sharp_model
from simulator.errors import ParameterError
from simulator.io.fold.model_file import fold_to_model
from simulator.io.fold.reader import load_fold_json, parse_fold
from simulator.mechanics.kinematics import fold_angles

from test_fold_real import PHYS, random_rotation, transformed

DATA = pathlib.Path(__file__).resolve().parents[1] / "data" / "fold"
MIURA = str(DATA / "miura_3x3_plain.fold")
GAMMA = math.radians(60.0)                   # the file's sector angle
STIFF = dict(panel_thickness=10e-6, panel_bending_width=1e-6)


def load(name):
    return load_fold_json(DATA / name)


def clamped(model, panel):
    """The same sharp model with ``panel`` clamped."""
    nodes = model.mesh.panel_nodes(panel)
    return sharp_model(model.mesh.pattern, Supports.nodes(nodes), model.params)


def collinear_creases(pattern):
    d = np.diff(pattern.vertices[pattern.edges[pattern.creases]], axis=1)[:, 0]
    return np.abs(d[:, 0]) < 1e-12 * np.linalg.norm(d, axis=1)


# ------------------------------------------------------------------ reading
def test_sharp_read_builds_the_concentrated_hinge_model_with_the_default_rule():
    data = load("miura_3x3_plain.fold")
    model, steps = fold_to_model(data, crease_model="sharp", **PHYS)
    assert isinstance(model.mesh, SharpHingeMesh) and steps == ()
    pat = model.mesh.pattern
    k = pat.crease_material.youngs_modulus * PHYS["crease_thickness"] ** 3 / \
        (12 * PHYS["crease_width"])
    C = model.mesh.n_creases
    length = model.mesh.bar_length[model.mesh.spring_bar[:C]]
    np.testing.assert_allclose(model.properties.spring_stiffness[:C], k * length, rtol=1e-12)
    # width 0 in the file asks for the same model; the flags' width feeds the default rule
    zero = copy.deepcopy(data) | {"edges_etorigami:width": [0.0] * len(data["edges_vertices"])}
    again, _ = fold_to_model(zero, **PHYS)
    np.testing.assert_array_equal(again.properties.spring_stiffness,
                                  model.properties.spring_stiffness)


def test_a_sharp_read_without_crease_data_names_what_is_missing():
    data = load("miura_3x3_plain.fold")
    with pytest.raises(ParameterError) as info:
        fold_to_model(data, crease_model="sharp", panel_thickness=10e-6)
    msg = str(info.value)
    assert "no crease width and crease thickness" in msg and "\n" not in msg
    assert "fold_stiffness=<N m/rad/m>" in msg and "panel_bending_width=<m>" in msg
    assert "crease_width=<m>" in msg and "--" not in msg         # the library speaks Python
    from design.cli._terms import cli_terms                       # the CLI its options

    cli = cli_terms(msg)
    assert "--fold-stiffness" in cli and "--panel-bending-width UM" in cli
    assert "--crease-width UM" in cli and "=<" not in cli
    model, _ = fold_to_model(data, crease_model="sharp", fold_stiffness=2e-6, **STIFF)
    assert model.params.fold_stiffness == {int(c): 2e-6 for c in model.mesh.pattern.creases}
    with pytest.raises(ParameterError, match="apply to sharp creases only"):
        fold_to_model(data, fold_stiffness=1e-6, **PHYS)


def test_mixed_crease_widths_are_refused_naming_the_creases():
    data = load("miura_3x3_plain.fold")
    widths = [None if a == "B" else 100e-6 for a in data["edges_assignment"]]
    first = widths.index(100e-6)
    widths[first] = 0.0
    data["edges_etorigami:width"] = widths
    with pytest.raises(ParameterError, match=rf"creases \(file edges\) \[{first}\] have width 0"
                       r".*not implemented"):
        parse_fold(data, **PHYS)


def test_fold_stiffness_per_crease_from_the_file():
    data = load("miura_3x3_plain.fold")
    data["edges_etorigami:fold_stiffness"] = [None if a == "B" else 3e-6
                                              for a in data["edges_assignment"]]
    model, _ = fold_to_model(data, crease_model="sharp", **STIFF)
    assert set(model.params.fold_stiffness.values()) == {3e-6}
    data["edges_etorigami:fold_stiffness"][0] = 1e-6               # a boundary edge
    with pytest.raises(ParameterError, match=r"fold_stiffness\[0\].*not a crease"):
        fold_to_model(data, crease_model="sharp", **STIFF)


# ------------------------------------------------------------------ mechanics
def test_drawn_miura_file_folds_along_the_rigid_origami_kinematics():
    """tan(rho_z / 2) = tan(rho_c / 2) / cos(gamma) at every increment, the collinear creases
    driven and the (soft) zig-zag creases following; stiffnesses from the file's field."""
    data = load("miura_3x3_plain.fold")
    geo = parse_fold(data, crease_model="sharp", panel_thickness=10e-6)
    pattern = geo.pattern
    collinear = collinear_creases(pattern)
    soft = {int(c) for c in pattern.creases[~collinear]}
    data["edges_etorigami:fold_stiffness"] = [
        None if e < 0 or not pattern.is_crease[e] else (1e-9 if e in soft else 1e-6)
        for e in geo.edge.tolist()]
    model, _ = fold_to_model(data, crease_model="sharp", **STIFF)
    model = clamped(model, 4)
    creases = model.mesh.crease_ids
    sign = np.where(pattern.edge_assignment[creases] == "M", -1.0, 1.0)
    folds = {int(c): s * 2.4 for c, s, keep in zip(creases, sign, collinear) if keep}
    res = simulate(model, [SelfFold(folds, increments=20)])
    assert res.success, res.message
    rho = np.abs(res.fold_angle)
    rho_c = rho[:, collinear].mean(axis=1)
    predicted = 2 * np.arctan(np.tan(rho_c / 2) / math.cos(GAMMA))
    assert rho_c[-1] > 2.39
    assert np.abs(rho[:, collinear] - rho_c[:, None]).max() < 1e-4
    assert np.abs(rho[:, ~collinear] - predicted[:, None]).max() < 1e-4
    assert np.all(np.sign(res.fold_angle[-1]) == sign)      # the file's assignments


def sharp_response(data):
    """(start fold angles, fold angles after a self-fold) [rad] of a file read as sharp."""
    model, _ = fold_to_model(data, crease_model="sharp", fold_stiffness=1e-6, **PHYS,
                             panel_bending_width=1e-6)
    mesh = model.mesh
    start = fold_angles(mesh, mesh.nodes)
    model = clamped(model, 0)
    targets = {int(c): a + 0.2 * np.sign(a) for c, a in zip(mesh.crease_ids, start)}
    res = simulate(model, [SelfFold(targets, increments=4)])
    assert res.success, res.message
    return start, res.fold_angle[-1]


@pytest.mark.parametrize("name", ["zigzag_folded.fold", "strip_folded.fold"])
def test_rigid_rotations_and_mirror_images_give_the_same_sharp_fold_angles(name):
    data = load(name)
    start, folded = sharp_response(data)
    design = np.radians([a for a, s in zip(data["edges_foldAngle"], data["edges_assignment"])
                         if s in "MV"])
    np.testing.assert_allclose(start, design, atol=1e-9)             # the file's own signs
    assert np.abs(folded - start).max() > 0.1
    rng = np.random.default_rng(21)
    mirror = np.diag([1.0, 1.0, -1.0])
    for _ in range(2):
        R = random_rotation(rng)
        for M in (R, R @ mirror):
            s, f = sharp_response(transformed(data, M))
            np.testing.assert_allclose(s, start, rtol=0, atol=1e-9)
            np.testing.assert_allclose(f, folded, rtol=0, atol=1e-9)


# ------------------------------------------------------------------ CLI
def test_check_with_the_sharp_crease_model(capsys):
    assert main(["check", MIURA, "--crease-model", "sharp"]) == 0
    out = capsys.readouterr().out
    assert "sharp creases (concentrated hinges): 25 nodes" in out
    assert "E t^3/(12 W)" in out and "a run needs: --fold all|M|V|IDS=DEG" in out
    assert main(["check", MIURA, "--crease-width", "0"]) == 0
    out = capsys.readouterr().out
    assert "--fold-stiffness N_M_PER_RAD_M" in out and "--panel-bending-width UM" in out


def test_run_of_a_sharp_pattern_from_flags(tmp_path, capsys):
    out_dir = tmp_path / "run"
    assert main(["run", MIURA, "--crease-model", "sharp", "--fold", "all=60", "--fold-steps",
                 "10", "--out", str(out_dir), "-q"]) == 0
    out = capsys.readouterr().out
    assert "converged" in out and "power [mW]" not in out
    assert "hottest crease" not in out and "T_g" not in out      # no thermal part: no claims
    table = pd.read_csv(out_dir / "creases.csv")
    last = table[table["step"] == table["step"].max()]
    fold = last.set_index("crease")["fold_angle [deg]"]
    assert len(fold) == 12 and fold.abs().min() > 10
    meta = json.loads((out_dir / "meta.json").read_text())
    assert meta["overrides"]["crease_model"] == "sharp"


def test_a_flat_miura_turned_in_space_folds_sharp_as_the_one_in_x_y(tmp_path, capsys):
    """Issue 28: a flat tessellation turned in space folded differently as a sharp model; laid
    flat by default (one note line), turned and mirrored copies fold alike to 1e-9 deg."""
    def folded(path, name):
        assert main(["run", str(path), "--crease-model", "sharp", "--fold", "all=90", "--out",
                     str(tmp_path / name), "-q"]) == 0
        table = pd.read_csv(tmp_path / name / "creases.csv")
        return capsys.readouterr().out, table.groupby("crease")["fold_angle [deg]"].last()

    _, reference = folded(MIURA, "flat")
    assert reference.abs().min() > 60
    rng = np.random.default_rng(30)
    R = random_rotation(rng)
    for k, M in enumerate((R, R @ np.diag([1.0, 1.0, -1.0]))):
        path = tmp_path / f"turned_{k}.fold"
        path.write_text(json.dumps(transformed(load("miura_3x3_plain.fold"), M)))
        out, fold = folded(path, f"turned_{k}")
        notes = [line for line in out.splitlines() if "laid in x-y" in line]
        assert len(notes) == 1 and notes[0].startswith("  note: flat sheet in the plane with "
                                                       "normal [")
        assert notes[0].endswith("top side up (its faces counter-clockwise seen from +z), the "
                                 "frame of the results; --no-lay-flat keeps it standing")
        np.testing.assert_allclose(fold.to_numpy(), reference.to_numpy(), rtol=0, atol=1e-9)


@pytest.mark.parametrize("flags, expected", [
    (["--crease-model", "sharp", "--heat", "all", "--power", "1"], "heating needs creases "
     "with a width"),
    (["--crease-model", "sharp"], "needs a mechanical drive: --fold WHICH=DEG"),
    (["--crease-model", "sharp", "--fold", "all=200"], "in (-180, 180)"),
    (["--fold", "all=60"], "add --crease-model sharp"),
    (["--fold-stiffness", "1e-6", "--heat", "all", "--power", "1"], "add --crease-model sharp"),
    (["--crease-width", "0", "--fold", "all=60"], "pass --fold-stiffness N_M_PER_RAD_M and "
     "--panel-bending-width UM"),
])
def test_cli_refusals_are_one_line(tmp_path, capsys, flags, expected):
    assert main(["run", MIURA, *flags, "--out", str(tmp_path / "r"), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert expected in err and "\n" not in err and "Traceback" not in err
    assert "=<" not in err and "stiffness=" not in err          # CLI spelling (issue 28)


def test_cli_refuses_mixed_widths_and_heating_width_zero_files(tmp_path, capsys):
    data = json.loads(pathlib.Path(MIURA).read_text())
    widths = [None if a == "B" else 100e-6 for a in data["edges_assignment"]]
    widths[widths.index(100e-6)] = 0.0
    mixed = tmp_path / "mixed.fold"
    mixed.write_text(json.dumps(data | {"edges_etorigami:width": widths}))
    for command in (["check", str(mixed)], ["run", str(mixed), "--heat", "all", "--power", "1",
                                            "--out", str(tmp_path / "m"), "-q"]):
        assert main(command) == 2
        err = capsys.readouterr().err.strip()
        assert "mixing sharp and compliant creases" in err and "\n" not in err
    zero = tmp_path / "zero.fold"
    zero.write_text(json.dumps(data | {"edges_etorigami:width": [
        None if a == "B" else 0.0 for a in data["edges_assignment"]]}))
    assert main(["run", str(zero), "--heat", "all", "--power", "1", "--out",
                 str(tmp_path / "z"), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "heating needs creases with a width" in err and "\n" not in err
    assert main(["run", str(zero), "--fold", "M=30", "--out", str(tmp_path / "f"), "-q"]) == 0


def test_a_heated_model_file_read_as_sharp_is_refused_in_one_line(tmp_path, capsys):
    path = tmp_path / "single.fold"
    assert main(["export", "single_fold", "--out", str(path)]) == 0
    capsys.readouterr()
    assert main(["run", str(path), "--crease-model", "sharp", "--out", str(tmp_path / "r"),
                 "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "sharp creases" in err and "\n" not in err


@pytest.mark.parametrize("stiffness", [None, 2e-6, "per crease"])
def test_a_sharp_model_file_runs_back_to_the_same_result(tmp_path, capsys, stiffness):
    from simulator.fold import read_model, write_model

    data = load("miura_3x3_plain.fold")
    if stiffness == "per crease":
        data["edges_etorigami:fold_stiffness"] = [None if a == "B" else 1e-6 + 1e-8 * i
                                                  for i, a in enumerate(data["edges_assignment"])]
        stiffness = None
    model, _ = fold_to_model(data, crease_model="sharp", fold_stiffness=stiffness, **PHYS)
    model = clamped(model, 4)
    c = int(model.mesh.crease_ids[0])
    steps = [SelfFold({c: 0.4}, increments=3)]
    path = write_model(model, steps, tmp_path / "sharp.fold")
    again, steps_again = read_model(path)
    assert isinstance(again.mesh, SharpHingeMesh) and again.params == model.params
    assert main(["check", str(path)]) == 0
    np.testing.assert_array_equal(again.properties.spring_stiffness,
                                  model.properties.spring_stiffness)
    assert "sharp creases: concentrated hinges" in capsys.readouterr().out
    np.testing.assert_array_equal(simulate(again, steps_again).fold_angle,
                                  simulate(model, steps).fold_angle)
