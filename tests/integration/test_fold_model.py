"""FOLD model files (model + steps), folded 3-D start shapes and multi-frame histories."""

import copy
import json
import math

import numpy as np
import pytest

from simulator import FoldFormatError, Heat, get_case, simulate
from simulator.fold import fold_to_model, read_model, write_fold_frames, write_model
from simulator.steps import initial_state
from simulator.mechanics import equilibrium_system


def assert_same_run(r1, r2):
    assert r1.success and r2.success
    for key in ("u", "temperature", "power"):
        np.testing.assert_allclose(r2.history[key], r1.history[key], rtol=1e-9, atol=0)
    np.testing.assert_allclose(r2.fold_angle, r1.fold_angle, rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("name, overrides", [
    ("single_fold", dict(thermal_steps=4)),
    ("double_fold", dict(thermal_steps=4)),
    ("miura_lifter", dict(thermal_steps=4, substrate=True)),
    ("crane", dict(thermal_steps=4)),
])
def test_exported_case_reruns_to_the_same_results(name, overrides, tmp_path):
    case = get_case(name, **overrides)
    path = write_model(case.model, case.steps, tmp_path / f"{name}.fold", title=name)
    model, steps = read_model(path)
    assert [s.describe() for s in steps] == [s.describe() for s in case.steps]
    assert model.to_dict() == case.model.to_dict()
    assert_same_run(case.run(), simulate(model, steps))


def test_gripper_model_keeps_edited_mesh_nodes_and_load_arrays(tmp_path):
    from design.devices.gripper import GripperDesign, make_gripper_model

    model, pre = make_gripper_model(GripperDesign(residual_fold=0.05), gravity_increments=2)
    data = json.loads(write_model(model, pre, tmp_path / "g.fold").read_text())
    assert "etorigami:mesh_nodes" in data
    model2, pre2 = read_model(tmp_path / "g.fold")
    assert np.array_equal(model2.mesh.nodes, model.mesh.nodes)
    assert np.array_equal(model2.mesh.bar_length, model.mesh.bar_length)
    assert [type(s).__name__ for s in pre2] == ["SelfFold", "Load"]
    assert_same_run(simulate(model, pre), simulate(model2, pre2))


# ---------------------------------------------------------------------- hand-written files
def miura_3x3_mm() -> dict:
    """A flat 3 x 3 Miura-ori sheet written by hand in mm: parallelogram panels 1 mm wide,
    rows 1 mm high, zig-zag offset 0.5 mm; each zig-zag line one type, the straight lines
    alternating (Maekawa 3:1 at every vertex); panel 0 clamped, all creases heated."""
    n = 3
    verts = [[i + 0.5 * (j % 2), float(j)] for j in range(n + 1) for i in range(n + 1)]
    vid = lambda i, j: j * (n + 1) + i  # noqa: E731
    faces = [[vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)]
             for j in range(n) for i in range(n)]
    edges, letters = [], []
    for j in range(n + 1):                                   # straight lines along x
        for i in range(n):
            edges.append([vid(i, j), vid(i + 1, j)])
            letters.append("B" if j in (0, n) else ("V" if (i + j) % 2 else "M"))
    for i in range(n + 1):                                   # zig-zag lines across them
        for j in range(n):
            edges.append([vid(i, j), vid(i, j + 1)])
            letters.append("B" if i in (0, n) else ("M" if i % 2 else "V"))
    crease = [c != "B" for c in letters]
    return {
        "file_spec": 1.2, "file_creator": "by hand", "frame_unit": "mm",
        "vertices_coords": verts, "faces_vertices": faces, "edges_vertices": edges,
        "edges_assignment": letters,
        "edges_etorigami:width": [100e-6 if c else None for c in crease],
        "edges_etorigami:thickness": [1e-6 if c else None for c in crease],
        "edges_etorigami:heater": ["all" if c else None for c in crease],
        "edges_etorigami:delta_alpha": [(50e-6 if a == "V" else -50e-6) if c else None
                                        for a, c in zip(letters, crease)],
        "faces_etorigami:thickness": [10e-6] * len(faces),
        "faces_etorigami:support": ["xyz"] + [None] * (len(faces) - 1),
        "etorigami:bimorph": {"E1": 50e9, "t1": 0.2e-6, "E2": 2e9, "t2": 0.8e-6},
        "etorigami:thermal": {"loss": {"model": "chain", "thickness": 1e-3}},
        "etorigami:steps": [{"type": "Heat", "power": {"all": 2e-3}, "increments": 4}],
    }


def test_hand_written_miura_in_mm_imports_at_scale_and_simulates():
    data = miura_3x3_mm()
    model, steps = fold_to_model(data)
    pattern = model.mesh.pattern
    assert pattern.n_panels == 9 and len(pattern.creases) == 12
    assert np.ptp(pattern.vertices[:, 0]) == pytest.approx(3.5e-3)
    assert np.ptp(pattern.vertices[:, 1]) == pytest.approx(3e-3)
    # file edge order differs from the pattern's: data follow the edges
    for i, (a, b) in enumerate(data["edges_vertices"]):
        e = int(np.flatnonzero((pattern.edges == sorted((a, b))).all(axis=1))[0])
        assert pattern.edge_assignment[e] == data["edges_assignment"][i]
    assert sorted(dict(steps[0].power)) == [tuple(int(c) for c in pattern.creases)]
    assert model.fixed_mask.sum() == 3 * 5                    # panel 0: 4 corners + centre
    result = simulate(model, steps)
    assert result.success
    fold = np.degrees(result.fold_angle[-1])
    sign = np.where(pattern.edge_assignment[model.mesh.crease_ids] == "V", 1, -1)
    assert np.all(fold * sign > 2)                            # every crease folds its own way


def folded_pair(fold_deg: float) -> dict:
    """Two 1 mm squares, the second rotated up about the crease x = 0 by fold_deg."""
    c, s = math.cos(math.radians(fold_deg)), math.sin(math.radians(fold_deg))
    return {
        "file_spec": 1.2, "frame_unit": "mm", "frame_classes": ["foldedForm"],
        "vertices_coords": [[-1, 0, 0], [0, 0, 0], [0, 1, 0], [-1, 1, 0], [c, 0, s], [c, 1, s]],
        "faces_vertices": [[0, 1, 2, 3], [1, 4, 5, 2]],
        "edges_vertices": [[0, 1], [1, 2], [2, 3], [3, 0], [1, 4], [4, 5], [5, 2]],
        "edges_assignment": ["B", "V" if fold_deg >= 0 else "M", "B", "B", "B", "B", "B"],
        "edges_foldAngle": [0, fold_deg, 0, 0, 0, 0, 0],
        "edges_etorigami:width": [None, 100e-6] + [None] * 5,
        "edges_etorigami:thickness": [None, 1e-6] + [None] * 5,
        "edges_etorigami:delta_alpha": [None, 50e-6] + [None] * 5,
        "faces_etorigami:thickness": [10e-6, 10e-6],
        "faces_etorigami:support": ["xyz", None],
        "etorigami:bimorph": {"E1": 50e9, "t1": 0.2e-6, "E2": 2e9, "t2": 0.8e-6},
        "etorigami:thermal": {"loss": {"model": "chain", "thickness": 1e-3}},
        "etorigami:steps": [{"type": "Heat", "power": {"1": 0.0}, "increments": 2},
                            {"type": "Heat", "power": {"1": 5e-3}, "increments": 3}],
    }


@pytest.mark.parametrize("fold_deg", [30.0, -40.0, 110.0])
def test_folded_3d_file_is_in_equilibrium_at_its_start_shape(fold_deg):
    model, steps = fold_to_model(folded_pair(fold_deg))
    state = initial_state(model)
    assert np.degrees(state.rest_fold) == pytest.approx([fold_deg], abs=1e-9)
    ev = equilibrium_system(model).evaluate(state.u, state.spring_rest, hessian=False)
    free = ~model.fixed_mask.ravel()
    assert np.abs(ev.f_int.ravel()[free]).max() < 1e-15         # [N]: zero residual
    result = simulate(model, steps)
    assert result.success
    assert np.abs(result.steps[0].state.u).max() < 1e-15        # no load, no heat: no motion
    fold = np.degrees(result.fold_angle[:, 0])
    assert fold[0] == pytest.approx(fold_deg, abs=1e-9)
    assert fold[-1] > fold_deg + 5                               # heating folds it further


def test_vertex_supports_and_merged_faces_in_model_files():
    """A triangulated panel (F edge) is one panel; a vertex support fixes its corner nodes."""
    data = folded_pair(0.0)
    data["faces_vertices"] = [[0, 1, 2], [0, 2, 3], [1, 4, 5, 2]]
    data["edges_vertices"].append([0, 2])
    data["edges_assignment"].append("F")
    data["edges_foldAngle"].append(0)
    for key in ("edges_etorigami:width", "edges_etorigami:thickness",
                "edges_etorigami:delta_alpha"):
        data[key].append(None)
    data["faces_etorigami:thickness"] = [10e-6] * 3
    data["faces_etorigami:support"] = [None, None, None]
    data["vertices_etorigami:support"] = ["xyz", "z", None, "xyz", None, None]
    model, steps = fold_to_model(data)
    mesh = model.mesh
    assert mesh.pattern.n_panels == 2 and mesh.n_creases == 1
    fixed = {n: d for n, d in model.supports.fixed.items()}
    corner = {v: np.flatnonzero(mesh.node_vertex == v).tolist() for v in range(4)}
    assert all(fixed[n] == "xyz" for n in corner[0] + corner[3])
    assert all(fixed[n] == "z" for n in corner[1]) and len(corner[1]) == 2
    assert simulate(model, steps).success


# ---------------------------------------------------------------------- model-file errors
MODEL_ERRORS = [
    (lambda d: d.__setitem__("etorigami:steps", [{"type": "Explode"}]),
     r"etorigami:steps\[0\]: type 'Explode' is not a step"),
    (lambda d: d["etorigami:steps"][0].__setitem__("increments", 0),
     r"etorigami:steps\[0\]: .*increments"),
    (lambda d: d["etorigami:steps"][0].__setitem__("power", {"nope": 1e-3}),
     r"etorigami:steps\[0\].power: 'nope' is neither an edge id nor a circuit"),
    (lambda d: d["etorigami:steps"][0].__setitem__("power", {"40": 1e-3}),
     r"etorigami:steps\[0\].power: edge 40 is not an edge"),
    (lambda d: d["edges_etorigami:delta_alpha"].__setitem__(0, 1e-5),
     r"edges_etorigami:delta_alpha\[0\]: 1e-05; give a number in 1/K on creases only"),
    (lambda d: d["edges_etorigami:heater"].__setitem__(5, 3),
     r"edges_etorigami:heater\[5\]: 3; give a circuit name \(string\) on creases only"),
    (lambda d: d["etorigami:thermal"]["loss"].__setitem__("thickness", -1),
     r"etorigami:thermal: .*ChainLoss.thickness = -1"),
    (lambda d: d["faces_etorigami:support"].__setitem__(0, "xq"),
     r"etorigami:supports: .*directions 'xq'"),
    (lambda d: d.__setitem__("etorigami:bimorph", {"E1": 1e9}),
     r"etorigami:bimorph: .*missing"),
    (lambda d: d.__setitem__("etorigami:actuation_scatter", {"scatter": 0.7}),
     r"etorigami:actuation_scatter: .*scatter = 0.7"),
    (lambda d: d.__setitem__("etorigami:actuation_scatter", {"spread": 0.1}),
     r"etorigami:actuation_scatter: .*spread"),
]


@pytest.mark.parametrize("edit, match", MODEL_ERRORS)
def test_malformed_model_fields(edit, match):
    data = copy.deepcopy(miura_3x3_mm())
    edit(data)
    with pytest.raises(FoldFormatError, match=match) as info:
        fold_to_model(data)
    assert "\n" not in str(info.value)


# ---------------------------------------------------------------------- frames
def test_history_as_multi_frame_fold(tmp_path):
    model, steps = fold_to_model(folded_pair(30.0))
    result = simulate(model, steps)
    path = write_fold_frames(result, tmp_path / "h.fold", every=2)
    data = json.loads(path.read_text())
    m = len(result.history["stage"])                             # 1 + 2 + 3 records
    frames = data["file_frames"]
    assert len(frames) == len(range(0, m, 2)) - 1 + (1 if (m - 1) % 2 else 0)
    assert all(f["frame_inherit"] and f["frame_parent"] == 0 for f in frames)
    n = model.mesh.n_nodes
    assert len(data["vertices_coords"]) == n and max(map(max, data["faces_vertices"])) == n - 1
    last = frames[-1]
    np.testing.assert_allclose(last["vertices_coords"], model.mesh.nodes + result.history["u"][-1])
    assert last["etorigami:fold_angle"] == pytest.approx(result.fold_angle[-1].tolist())
    assert last["etorigami:crease_power"] == pytest.approx([5e-3])
    assert last["etorigami:crease_rotation"][0] == pytest.approx(
        result.fold_angle[-1, 0] - math.radians(30))
    assert len(last["vertices_etorigami:temperature"]) == n
    assert set(data["edges_assignment"]) == {"B", "F"}


def test_written_model_is_independent_of_heat_key_form(tmp_path):
    """Circuit keys (tuples) become named heater circuits and come back as the same tuples."""
    case = get_case("double_fold", thermal_steps=2)
    data = json.loads(write_model(case.model, case.steps, tmp_path / "d.fold").read_text())
    assert data["edges_etorigami:heater"][2] == data["edges_etorigami:heater"][5] == "circuit1"
    _, steps = read_model(tmp_path / "d.fold")
    heat = [s for s in steps if isinstance(s, Heat)][0]
    assert dict(heat.power) == dict(case.steps[-1].power)


def test_actuation_scatter_round_trips_through_a_model_file(tmp_path):
    """etorigami:actuation_scatter: written only when set, read back into Actuators."""
    from dataclasses import replace

    case = get_case("double_fold", thermal_steps=2)
    plain = json.loads(write_model(case.model, case.steps, tmp_path / "a.fold").read_text())
    assert "etorigami:actuation_scatter" not in plain
    model = replace(case.model, actuators=replace(case.model.actuators, scatter=2e-3, seed=7))
    data = json.loads(write_model(model, case.steps, tmp_path / "b.fold").read_text())
    assert data["etorigami:actuation_scatter"] == {"scatter": 2e-3, "seed": 7}
    back, _ = read_model(tmp_path / "b.fold")
    assert back.actuators.scatter == 2e-3 and back.actuators.seed == 7
    np.testing.assert_array_equal(back.actuators.rotation_per_kelvin(back.mesh),
                                  model.actuators.rotation_per_kelvin(model.mesh))
