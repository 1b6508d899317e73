"""When the integral loss operator is kept and when rebuilt (simulator.thermal.integral): a rigid
motion keeps it and equals a fresh build, a change beyond IntegralLoss.shape_tol rebuilds it, the
substrate plane's height counts, and the compiled factorisation agrees with LAPACK."""

import dataclasses

import numpy as np
import pytest
import scipy.linalg

from simulator import IntegralLoss, simulate
from simulator.cases import get_case, verification_strip
from simulator.linalg import dense_jit
from simulator.thermal import thermal_model
from simulator.thermal import _single_layer_jit
from simulator.thermal.integral import IntegralOperator


def _sheet(plane=None, shape_tol=0.05):
    mesh = verification_strip().model.mesh
    loss = IntegralOperator(mesh.triangles, mesh.n_nodes, 0.026, 2, plane, shape_tol)
    return loss, mesh.nodes.copy()


def _rotation(angle, axis):
    return scipy.linalg.expm(angle * np.cross(np.eye(3), np.asarray(axis, float)))


def _size(loss, x):
    sub = loss.sub_triangles(x)
    return np.linalg.norm(sub - np.roll(sub, 1, axis=1), axis=2).max(axis=1).mean()


def test_a_rigid_motion_keeps_the_operator_and_equals_a_fresh_build():
    loss, x = _sheet()
    L0 = loss.loss_matrix(x).copy()
    moved = x @ _rotation(0.7, [1, 2, 3]).T + [2e-3, -1e-3, 5e-3]
    assert np.array_equal(loss.loss_matrix(moved), L0)
    assert loss.builds == 1
    fresh = _sheet()[0].loss_matrix(moved)
    assert np.allclose(fresh, L0, rtol=0, atol=1e-10 * np.abs(L0).max())


def test_a_change_beyond_the_tolerance_rebuilds():
    loss, x = _sheet()
    loss.loss_matrix(x)
    h = _size(loss, x)
    node = loss.nodes[0]
    small, large = x.copy(), x.copy()
    small[node, 0] += 0.5 * 0.05 * h               # in plane: half the allowed change
    large[node, 0] += 10 * 0.05 * h
    loss.loss_matrix(small)
    assert loss.builds == 1
    loss.loss_matrix(large)
    assert loss.builds == 2


def test_zero_tolerance_rebuilds_on_every_change_of_position():
    loss, x = _sheet(shape_tol=0.0)
    loss.loss_matrix(x)
    loss.loss_matrix(x.copy())
    assert loss.builds == 1
    loss.loss_matrix(x + [1e-9, 0, 0])
    assert loss.builds == 2


def test_with_a_plane_the_height_counts_but_not_a_motion_along_it():
    plane = (np.array([0, 0, -0.2]), np.array([0, 0, 1.0]))        # the strip is 2.4 x 1
    loss, x = _sheet(plane)
    L0 = loss.loss_matrix(x).copy()
    along = x @ _rotation(0.4, [0, 0, 1]).T + [3e-3, 1e-3, 0]
    assert np.array_equal(loss.loss_matrix(along), L0) and loss.builds == 1
    assert np.allclose(_sheet(plane)[0].loss_matrix(along), L0, rtol=0,
                       atol=1e-10 * np.abs(L0).max())
    closer = x - [0, 0, 0.02]                       # 0.2 -> 0.18 above the plane
    assert not np.allclose(loss.loss_matrix(closer), L0)
    assert loss.builds == 2


def test_the_kept_loss_matrix_is_read_only_and_symmetric():
    loss, x = _sheet()
    L = loss.loss_matrix(x)
    assert np.array_equal(L, L.T)
    with pytest.raises(ValueError):
        L[0, 0] = 1.0


def test_compiled_and_numpy_paths_give_the_same_operator_and_heats(monkeypatch):
    if not _single_layer_jit.use_compiled():
        pytest.skip("numba backend not selected")
    loss, x = _sheet()
    rise = np.linspace(1.0, 3.0, len(x))
    L1, p1 = loss.loss_matrix(x), loss.sub_triangle_heat(x, rise)
    monkeypatch.setattr(_single_layer_jit, "use_compiled", lambda: False)
    ref = _sheet()[0]
    L0, p0 = ref.loss_matrix(x), ref.sub_triangle_heat(x, rise)
    assert np.allclose(L1, L0, rtol=0, atol=1e-11 * np.abs(L0).max())
    assert np.allclose(p1, p0, rtol=0, atol=1e-11 * np.abs(p0).max())


def test_compiled_loss_factor_matches_lapack():
    if not _single_layer_jit.use_compiled():
        pytest.skip("numba backend not selected")
    rng = np.random.default_rng(5)
    A = rng.random((40, 40))
    S, M = A @ A.T + 40 * np.eye(40), rng.random((40, 7))
    C, sign, W, G = dense_jit.loss_factor(S, M)
    assert np.all(sign == 1) and np.allclose(np.tril(C) @ np.tril(C).T, S)
    assert np.allclose(W, scipy.linalg.solve_triangular(np.linalg.cholesky(S), M, lower=True))
    assert np.allclose(G, M.T @ np.linalg.solve(S, M)) and np.array_equal(G, G.T)
    b = rng.random(7)
    assert np.allclose(dense_jit.back_substitute(C, W @ b), np.linalg.solve(S, M @ b))
    C, sign, W, G = dense_jit.loss_factor(-S, M)       # negative definite
    assert np.all(sign == -1) and np.allclose(G, -M.T @ np.linalg.solve(S, M))
    assert dense_jit.cholesky_solve(-S, M) is None


def test_compiled_signed_factor_solves_a_symmetric_indefinite_matrix():
    if not _single_layer_jit.use_compiled():
        pytest.skip("numba backend not selected")
    rng = np.random.default_rng(7)
    Q = np.linalg.qr(rng.random((30, 30)))[0]
    S = Q @ np.diag(np.linspace(-2.0, 3.0, 30) + 0.05) @ Q.T          # symmetric, indefinite
    M = rng.random((30, 5))
    C, sign, W, G = dense_jit.loss_factor(S, M)
    assert (sign < 0).any() and (sign > 0).any()
    C = np.tril(C)
    assert np.allclose(C @ np.diag(sign) @ C.T, S)
    assert np.allclose(G, M.T @ np.linalg.solve(S, M))
    b = rng.random(5)
    assert np.allclose(dense_jit.back_substitute(C, W @ b, sign),
                       np.linalg.solve(S, M @ b))


def test_a_kept_operator_changes_folding_temperatures_by_less_than_half_a_percent():
    """The double fold heated with the integral model: the operator kept within the default
    IntegralLoss.shape_tol against one rebuilt at every increment, at every increment."""
    case = get_case("double_fold", thermal_steps=40)
    default = IntegralLoss().shape_tol
    runs, builds = {}, {}
    for tol in (default, 0.0):
        thermal = dataclasses.replace(case.model.thermal, substrate=None, loss=IntegralLoss(
            refinement=2, correction_tol=0.0, shape_tol=tol))
        model = dataclasses.replace(case.model, thermal=thermal)
        result = simulate(model, case.steps)
        assert result.success, result.message
        runs[tol] = result.steps[-1].temperature_history - thermal.room_temperature
        builds[tol] = thermal_model(model).integral.builds
    kept, rebuilt = runs[default], runs[0.0]
    assert np.all(np.abs(kept - rebuilt).max(axis=1) <= 5e-3 * np.abs(rebuilt).max(axis=1))
    assert builds[default] < builds[0.0]


def test_compiled_lu_response_matches_numpy_for_an_indefinite_matrix():
    if not _single_layer_jit.use_compiled():
        pytest.skip("numba backend not selected")
    rng = np.random.default_rng(6)
    A = rng.random((30, 30))
    S, M = A + A.T - 15 * np.eye(30), rng.random((30, 5))       # symmetric, indefinite
    P, G = dense_jit.lu_response(S, M)
    assert np.allclose(P, np.linalg.solve(S, M))
    assert np.allclose(G, M.T @ np.linalg.solve(S, M)) and np.array_equal(G, G.T)
    assert dense_jit.lu_response(np.zeros((3, 3)), np.ones((3, 1))) is None


def test_a_vanishing_pivot_goes_to_lu_and_an_indefinite_operator_is_warned_once(monkeypatch,
                                                                                 caplog):
    if not _single_layer_jit.use_compiled():
        pytest.skip("numba backend not selected")
    loss, x = _sheet(shape_tol=0.0)
    rise = np.linspace(1.0, 3.0, len(x))
    L0, p0 = loss.loss_matrix(x).copy(), loss.sub_triangle_heat(x, rise)
    monkeypatch.setattr(dense_jit, "loss_factor", lambda S, M: None)
    with caplog.at_level("WARNING", logger="simulator.thermal.integral"):
        for shift in (1e-9, 2e-9):
            moved = x + [shift, 0, 0]
            L1, p1 = loss.loss_matrix(moved), loss.sub_triangle_heat(moved, rise)
    assert np.allclose(L1, L0, rtol=0, atol=1e-9 * np.abs(L0).max())
    assert np.allclose(p1, p0, rtol=0, atol=1e-9 * np.abs(p0).max())
    warnings = [r for r in caplog.records if "not positive definite" in r.message]
    assert len(warnings) == 1 and "pass through each other" in warnings[0].message
