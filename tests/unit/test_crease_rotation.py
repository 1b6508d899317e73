"""Crease rotation (sum of a crease's fold-line rotations) against an independent dihedral."""

import inspect

import numpy as np
import pandas as pd
import pytest

from simulator import get_case
from simulator.cases import CASES
from simulator.mechanics.kinematics import crease_rotations, fold_angles


def _rotation(p, q, w1, w2):
    """Signed rotation from flat [rad] of the fold line p-q with wing points w1 and w2 (n, 3).

    Wing normals n1 = e x (w1 - p), n2 = (w2 - p) x e with the axis e oriented so that n1
    points to +z in the flat reference; positive when the wings fold towards +z.
    """
    e = (q - p) / np.linalg.norm(q - p, axis=1, keepdims=True)
    n1, n2 = np.cross(e, w1 - p), np.cross(w2 - p, e)
    return np.arctan2(np.einsum("ij,ij->i", e, np.cross(n2, n1)), np.einsum("ij,ij->i", n1, n2))


def _crease_rotation_by_hand(mesh, x):
    """Edge line 1 + centre line (mean of its halves A-Ctr, B-Ctr) + edge line 2, from nodes."""
    n11, n12, n21, n22, a, b, ctr = mesh.crease_nodes.T
    c1, c2 = mesh.panel_center[mesh.crease_panels].T
    total = 0.0
    for p, q, w1, w2, weight in [(n11, n12, c1, ctr, 1.0), (a, ctr, n11, n21, 0.5),
                                 (b, ctr, n12, n22, 0.5), (n21, n22, ctr, c2, 1.0)]:
        X = mesh.nodes
        swap = np.cross(X[q] - X[p], X[w1] - X[p])[:, 2] < 0       # orient e: n1_z > 0 at rest
        p, q = np.where(swap, q, p), np.where(swap, p, q)
        total = total + weight * _rotation(x[p], x[q], x[w1], x[w2])
    return total


@pytest.fixture(scope="module")
def crane():
    case = get_case("crane", thermal_steps=20)
    return case, case.run()


def test_hand_dihedral_reproduces_the_fold_angle_of_a_flat_panel_fold():
    case = get_case("single_fold", thermal_steps=10)
    res = case.run()
    mesh = case.model.mesh
    x = mesh.nodes + res.history["u"][-1]
    assert np.degrees(fold_angles(mesh, x))[0] > 5                 # it did fold, towards +z
    np.testing.assert_allclose(_crease_rotation_by_hand(mesh, x), fold_angles(mesh, x), atol=1e-9)


def test_crane_crease_rotation_is_the_sum_of_its_fold_line_rotations(crane):
    case, res = crane
    assert res.success, res.message
    mesh = case.model.mesh
    for k in (1, 10, len(res.history["u"]) - 1):
        x = mesh.nodes + res.history["u"][k]
        np.testing.assert_allclose(res.crease_rotation[k], _crease_rotation_by_hand(mesh, x),
                                   rtol=0, atol=1e-10)
    np.testing.assert_array_equal(res.crease_rotation[-1],
                                  crease_rotations(mesh, mesh.nodes + res.history["u"][-1]))


def test_crane_panels_bend_so_the_two_measures_differ(crane):
    _, res = crane
    frame = res.to_frame()
    last = frame[frame.step == frame.step.max()]
    diff = (last["crease_rotation [deg]"] - last["fold_angle [deg]"]).abs()
    assert 5 < diff.max() < 12                                     # measured 8.46 deg
    assert np.all(np.sign(last["crease_rotation [deg]"]) == np.sign(last["fold_angle [deg]"]))
    assert res.crease_rotation.shape == res.fold_angle.shape == (21, 17)


@pytest.mark.parametrize("name", list(CASES))
def test_every_case_reports_crease_rotation(name, tmp_path):
    fn = CASES[name]
    kw = {"thermal_steps": 4} if "thermal_steps" in inspect.signature(fn).parameters else {}
    res = get_case(name, **kw).run()
    assert res.success, res.message
    frame = res.to_frame()
    cols = list(frame.columns)
    assert cols.index("crease_rotation [deg]") == cols.index("fold_angle [deg]") + 1
    assert np.isfinite(frame["crease_rotation [deg]"]).all()
    rest = frame.loc[frame.step == 0]                   # Miura: 2e-11 m off-plane, 3e-6 deg
    np.testing.assert_allclose(rest["crease_rotation [deg]"], rest["fold_angle [deg]"], atol=1e-5)
    saved = res.save(tmp_path)
    assert "crease_rotation [deg]" in pd.read_csv(saved / "creases.csv").columns


def _meshes():
    from simulator.model import build_sharp_mesh
    from simulator.geometry.example_patterns import miura_sheet_pattern

    cases = [("single_fold", {}), ("double_fold", {}), ("miura_lifter", {}), ("crane", {})]
    meshes = [(name, get_case(name, **kw).model.mesh) for name, kw in cases]
    return meshes + [("sharp miura", build_sharp_mesh(miura_sheet_pattern()))]


@pytest.mark.parametrize("name, mesh", _meshes(), ids=lambda v: v if isinstance(v, str) else "")
@pytest.mark.parametrize("measure", [fold_angles, crease_rotations])
def test_measures_of_many_records_at_once_are_bit_identical_to_one_call_per_record(
        name, mesh, measure):
    rng = np.random.default_rng(7)
    size = np.ptp(mesh.nodes, axis=0).max()
    x = mesh.nodes + 0.05 * size * rng.standard_normal((6, *mesh.nodes.shape))
    one_by_one = np.array([measure(mesh, xk) for xk in x])
    np.testing.assert_array_equal(measure(mesh, x), one_by_one)
    np.testing.assert_array_equal(measure(mesh, x.reshape(2, 3, *mesh.nodes.shape)),
                                  one_by_one.reshape(2, 3, -1))


def test_result_measures_are_the_per_record_measures(crane, monkeypatch):
    import simulator.results as results

    case, res = crane
    monkeypatch.setattr(results, "_RECORD_BLOCK", 7)          # several blocks, a short last one
    fresh = results.SimulationResult(res.steps, res.state, res.model, res.initial_state)
    mesh = case.model.mesh
    x = mesh.nodes + res.history["u"]
    np.testing.assert_array_equal(fresh.fold_angle, [fold_angles(mesh, xk) for xk in x])
    np.testing.assert_array_equal(fresh.crease_rotation, [crease_rotations(mesh, xk) for xk in x])
