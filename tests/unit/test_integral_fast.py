"""The integral heat loss's fast path (simulator.thermal.integral_fast, theory 4.7): the operator
applied without being formed, and the coupled MINRES solve, against the dense operator."""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp
import pytest

from simulator.model import get_stack, stack_model
from simulator.errors import ParameterError
from simulator.geometry.example_patterns import miura_sheet_pattern
from simulator.model.mesh import make_mesh
from simulator.thermal import integral_fast
from simulator.thermal._single_layer import collocation_matrix, pair_values, _kernel_matrix
from simulator.model.heat_loss import MAX_SUB_TRIANGLES
from simulator.thermal.integral import IntegralOperator
from simulator.thermal import IntegralLoss, Substrate
from simulator.model.heat_loss import heat_loss_from_dict
from simulator.thermal import ThermalModel

PLANE = (np.array([0.0, 0.0, -1e-4]), np.array([0.0, 0.0, 1.0]))


def _sub_triangles(cells=2, m=2):
    mesh = make_mesh(miura_sheet_pattern(m=cells, n=cells))
    x = mesh.nodes.copy()
    x[:, 2] += 2e-4 * np.sin(x[:, 0] / 1e-3)                 # not flat: all rules in use
    return IntegralOperator(mesh.triangles, mesh.n_nodes, 0.026, m).sub_triangles(x)


def _miura_model(cells):
    pattern = miura_sheet_pattern(m=cells, n=cells)
    return stack_model(pattern, get_stack("su8-au"), list(pattern.creases))


@pytest.mark.parametrize("compiled", [False, True])
def test_pair_values_are_the_dense_entries(compiled):
    sub = _sub_triangles()
    c = sub.mean(axis=1)
    area = 0.5 * np.linalg.norm(np.cross(sub[:, 1] - sub[:, 0], sub[:, 2] - sub[:, 0]), axis=1)
    diam = np.linalg.norm(sub - np.roll(sub, 1, axis=1), axis=2).max(axis=1)
    full = _kernel_matrix(c, sub, c, area, diam, 1.5)
    rng = np.random.default_rng(0)
    rows, cols = rng.integers(0, len(sub), 400), rng.integers(0, len(sub), 400)
    rows[:50] = cols[:50]                                    # self terms too
    got = pair_values(c, sub, c, area, diam, rows, cols, compiled=compiled)
    assert np.allclose(got, full[rows, cols], rtol=1e-13, atol=0)


def test_direct_sum_compiled_matches_numpy():
    rng = np.random.default_rng(1)
    p, q = rng.random((300, 3)), rng.normal(size=300)
    a = integral_fast.direct_potential(p, q, compiled=False)
    b = integral_fast.direct_potential(p, q, compiled=True)
    d = np.linalg.norm(p[:, None] - p[None], axis=2)
    np.fill_diagonal(d, np.inf)
    assert np.allclose(a, (1 / d) @ q, rtol=1e-12) and np.allclose(b, a, rtol=1e-12)
    for compiled in (False, True):              # at the first points only (the images' case)
        part = integral_fast.direct_potential(p, q, compiled=compiled, n_targets=120)
        assert part.shape == (120,) and np.allclose(part, a[:120], rtol=1e-12)


@pytest.mark.parametrize("plane", [None, PLANE])
@pytest.mark.parametrize("direct", [True, False])
def test_fast_operator_is_the_dense_matrix(plane, direct, monkeypatch):
    """Direct far field: the dense matrix to rounding; FMM far field: to its tolerance."""
    if not direct:
        monkeypatch.setattr(integral_fast, "DIRECT_MAX", 10)
    sub = _sub_triangles()
    V, area, _ = collocation_matrix(sub, 0.026, plane)
    S = V / area[None, :]
    S = 0.5 * (S + S.T)
    fast = integral_fast.FastSingleLayer(sub, 0.026, plane).dense()
    assert np.abs(fast - S).max() <= (1e-12 if direct else 1e-6) * np.abs(S).max()


def test_fmm_far_field_matches_the_direct_sum_on_a_larger_set(monkeypatch):
    sub = _sub_triangles(cells=4, m=2)                          # 896 sub-triangles
    fs = integral_fast.FastSingleLayer(sub, 0.026, PLANE)
    p = np.random.default_rng(2).normal(size=fs.n)
    direct = fs.far(p)
    monkeypatch.setattr(integral_fast, "DIRECT_MAX", 10)
    assert np.abs(fs.far(p) - direct).max() <= 1e-5 * np.abs(direct).max()


def _temperatures(model, x, operator, substrate=None, **kw):
    prm = dataclasses.replace(model.thermal, loss=IntegralLoss(operator=operator, **kw),
                              substrate=substrate, sheet_refinement=1)
    tm = ThermalModel(model.mesh, prm, warn_no_plane=False)
    q = tm.heat_vector(np.full(model.mesh.n_creases, 1e-3))
    T = tm.solve(x, q)
    return T - prm.room_temperature, tm.environment_loss(x, T), q, tm


@pytest.mark.parametrize("plane", [None, Substrate.plane((0.0, 0.0, -2e-4), (0.0, 0.0, 1.0))])
def test_fast_path_agrees_with_dense_on_a_folded_miura(plane):
    """Plain m = 2 (one level) on a 3 x 3-cell Miura bent out of plane: the same discrete
    model, to the solver's tolerance; the heat balance closes."""
    model = _miura_model(3)
    x = model.mesh.nodes.copy()
    x[:, 2] += 3e-4 * np.sin(x[:, 0] / 1.5e-3) ** 2
    dense, _, q, _ = _temperatures(model, x, "dense", refinement=2, substrate=plane)
    fast, loss, _, tm = _temperatures(model, x, "fast", refinement=2, substrate=plane)
    assert getattr(tm.integral, "fast", False)
    assert np.abs(fast - dense).max() <= 1e-6 * dense.max()
    assert loss.sum() == pytest.approx(q.sum(), rel=1e-6)


def test_fast_path_holds_the_nodes_touching_the_substrate():
    """A Miura sheet lying on the substrate plane along one edge: the touching nodes are held
    at room temperature and the sub-triangles in the plane left out, as in the dense model."""
    model = _miura_model(2)
    x = model.mesh.nodes.copy()
    x[:, 2] = 5e-4 * (x[:, 0] - x[:, 0].min()) / np.ptp(x[:, 0])     # tilted, one edge on z = 0
    x[x[:, 0] <= x[:, 0].min() + 1e-4, 2] = 0.0
    plane = Substrate.plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    dense, _, _, tm_d = _temperatures(model, x, "dense", refinement=2, substrate=plane)
    fast, _, _, tm_f = _temperatures(model, x, "fast", refinement=2, substrate=plane)
    held = tm_f.integral.touching(x)
    assert held.any() and np.array_equal(held, tm_d.integral.touching(x))
    assert np.all(fast[held] == 0)
    assert np.abs(fast - dense).max() <= 1e-6 * dense.max()


@pytest.mark.slow
@pytest.mark.parametrize("plane", [None, Substrate.plane((0.0, 0.0, -2e-4), (0.0, 0.0, 1.0))])
def test_fast_path_is_within_half_a_percent_of_dense_near_the_dense_limit(plane):
    """The default (m = 3 extrapolated from 2 and 3) on a 5 x 5-cell Miura bent out of plane:
    3060 + 1360 sub-triangles, near MAX_SUB_TRIANGLES. The fast path extrapolates the levels'
    solutions and corrects once towards the operators' extrapolation: measured 5.5e-4 free,
    1.5e-3 over the plane (1.9e-3 and 5.0e-3 without the correction)."""
    model = _miura_model(5)
    x = model.mesh.nodes.copy()
    x[:, 2] += 3e-4 * np.sin(x[:, 0] / 1.5e-3) ** 2
    dense, _, _, _ = _temperatures(model, x, "dense", substrate=plane)
    fast, loss, q, _ = _temperatures(model, x, "fast", substrate=plane)
    assert np.abs(fast - dense).max() <= 5e-3 * dense.max()
    assert loss.sum() == pytest.approx(q.sum(), rel=1e-4)


def test_auto_is_dense_up_to_the_dense_limit_and_identical_there():
    """"auto" takes the dense path where it can run: the temperatures are those of "dense"
    exactly (the same code)."""
    model = _miura_model(2)
    x = model.mesh.nodes
    auto, _, _, tm = _temperatures(model, x, "auto")
    dense, _, _, _ = _temperatures(model, x, "dense")
    assert not getattr(tm.integral, "fast", False)
    assert np.abs(auto - dense).max() <= 1e-6 * dense.max()
    loss = IntegralLoss()
    assert not loss.takes_fast_path(MAX_SUB_TRIANGLES // 9)
    assert loss.takes_fast_path(MAX_SUB_TRIANGLES // 9 + 1)
    assert IntegralLoss(operator="fast").takes_fast_path(1)
    assert not IntegralLoss(operator="dense").takes_fast_path(10 ** 6)


def test_fast_path_never_forms_the_loss_matrix():
    model = _miura_model(2)
    _, _, _, tm = _temperatures(model, model.mesh.nodes, "fast", refinement=1)
    with pytest.raises(ParameterError, match="never forms the loss conductance"):
        tm.integral_loss_matrix(model.mesh.nodes)


def test_the_operator_choice_round_trips_through_to_dict():
    for operator in ("auto", "dense", "fast"):
        loss = IntegralLoss(operator=operator)
        assert heat_loss_from_dict(loss.to_dict()) == loss
    assert "operator" not in IntegralLoss().to_dict()          # files of the default unchanged


def test_integral_operator_is_checked():
    with pytest.raises(ParameterError, match="IntegralLoss.operator"):
        IntegralLoss(operator="fmm")


def _minres_counts(caplog):
    return [r.args[1] for r in caplog.records if "MINRES iterations" in r.getMessage()]


def test_a_multiple_of_the_last_heat_input_is_not_solved_again_and_a_new_shape_starts_warm(
        caplog):
    """A heating run solves the same shape at a fraction of the power (a multiple of the last
    q: the scaled solution, no MINRES) and the next shape from the last solution (fewer
    iterations, the same answer to the solver's tolerance; shape_tol = 0: the operator rebuilt
    at the new shape, see the next test for the operator kept)."""
    import logging

    caplog.set_level(logging.DEBUG, logger="simulator.thermal.integral_fast")
    model = _miura_model(3)
    x = model.mesh.nodes.copy()
    prm = dataclasses.replace(model.thermal, loss=IntegralLoss(operator="fast", refinement=2,
                                                               shape_tol=0.0),
                              substrate=None)
    tm = ThermalModel(model.mesh, prm, warn_no_plane=False)
    q = tm.heat_vector(np.full(model.mesh.n_creases, 1e-3))
    full = tm.solve(x, q) - prm.room_temperature
    half = tm.solve(x, 0.5 * q) - prm.room_temperature
    assert len(_minres_counts(caplog)) == 1
    assert np.allclose(half, 0.5 * full, rtol=1e-12, atol=1e-12 * full.max())
    assert tm.environment_loss(x, half + prm.room_temperature).sum() == pytest.approx(
        0.5 * q.sum(), rel=1e-6)
    bent = x.copy()
    bent[:, 2] += 2e-5 * np.sin(bent[:, 0] / 1.5e-3) ** 2
    warm = tm.solve(bent, q) - prm.room_temperature
    cold_tm = ThermalModel(model.mesh, prm, warn_no_plane=False)
    cold = cold_tm.solve(bent, q) - prm.room_temperature
    counts = _minres_counts(caplog)
    assert len(counts) == 3 and counts[1] < counts[2], counts
    assert np.abs(warm - cold).max() <= 1e-6 * cold.max()


@pytest.mark.parametrize("plane", [None, Substrate.plane((0.0, 0.0, -2e-4), (0.0, 0.0, 1.0))])
def test_the_fast_operator_is_kept_within_shape_tol_as_the_dense_one(plane):
    """A bend of 20 um keeps the operator (near field, far field and preconditioners) at the
    default shape_tol (not 500 um over a plane, where it changes heights by 4 %), and the
    temperatures are those of the dense operator kept the same way; a bend of 1.5 mm
    rebuilds both, and the same holds."""
    model = _miura_model(3)
    x = model.mesh.nodes.copy()
    out = {}
    for op in ("dense", "fast"):
        prm = dataclasses.replace(model.thermal, substrate=plane, sheet_refinement=1,
                                  loss=IntegralLoss(operator=op, refinement=2,
                                                    correction_tol=0.0))  # dense: one plain
        tm = ThermalModel(model.mesh, prm, warn_no_plane=False)
        q = tm.heat_vector(np.full(model.mesh.n_creases, 1e-3))
        rises, builds = [], []
        for amp in (0.0, 2e-5, 1.5e-3):
            y = x.copy()
            y[:, 2] += amp * np.sin(y[:, 0] / 1.5e-3) ** 2 + 3e-4
            rises.append(tm.solve(y, q) - prm.room_temperature)
            builds.append(tm.integral.builds)
        out[op] = rises, builds
    assert out["fast"][1] == out["dense"][1]
    assert out["fast"][1] == ([1, 1, 2] if plane is None else [1, 2, 3])  # heights: 1/4 tol
    for fast, dense in zip(out["fast"][0], out["dense"][0]):
        assert np.abs(fast - dense).max() <= 1e-6 * dense.max()


def test_patches_split_the_points_into_groups_of_at_most_the_size():
    from simulator.thermal.integral_schwarz import patches

    points = np.random.default_rng(3).random((1000, 3))
    labels = patches(points, 37)
    counts = np.bincount(labels)
    assert counts.max() <= 37 and counts.min() >= 37 // 2 and counts.sum() == 1000


@pytest.mark.parametrize("plane", [None, PLANE])
def test_blocks_and_coarse_matrix_of_the_preconditioner(plane):
    """``S`` on a block is the dense matrix's; the coarse matrix ``R0 S R0^T`` is exact for
    near patch pairs and within 1 % (monopoles) for far ones."""
    from simulator.thermal.integral_schwarz import coarse_matrix, patches

    fs = integral_fast.FastSingleLayer(_sub_triangles(), 0.026, plane)
    S = fs.dense()
    idx = np.arange(0, fs.n, 3)
    assert np.abs(fs.block(idx) - S[np.ix_(idx, idx)]).max() <= 1e-12 * np.abs(S).max()
    labels = patches(fs.centroids, 16)
    groups = [np.flatnonzero(labels == i) for i in range(labels.max() + 1)]
    R0 = np.zeros((len(groups), fs.n))
    R0[labels, np.arange(fs.n)] = 1
    exact = R0 @ S @ R0.T
    assert np.abs(coarse_matrix(fs, groups) - exact).max() <= 1e-2 * np.abs(exact).max()


def test_the_two_level_preconditioner_bounds_the_condition_number_of_the_single_layer():
    """Zero-sum patch blocks and the patches' constants as the coarse space: the condition
    number of ``P_S^-1 S`` stays about 8 (measured 7.5-8.5 from 500 to 3000 sub-triangles);
    the Schur complement's preconditioner ``P_T`` is within a factor 4 of it too."""
    from simulator.thermal.integral_schwarz import TwoLevelPreconditioner

    model = _miura_model(4)
    mesh = model.mesh
    op = IntegralOperator(mesh.triangles, mesh.n_nodes, 0.026, 2)
    x = mesh.nodes.copy()
    x[:, 2] += 2e-4 * np.sin(x[:, 0] / 1e-3)
    fs = integral_fast.FastSingleLayer(op.sub_triangles(x), 0.026)
    tm = ThermalModel(mesh, dataclasses.replace(model.thermal, loss=IntegralLoss(), substrate=None))
    K = tm.sheet_conduction(x)[op.nodes][:, op.nodes].tocsr()
    M = sp.csr_matrix(op.M)
    pre = TwoLevelPreconditioner(fs, K, M, size=16)
    S = fs.dense()
    PS = np.column_stack([pre.heat(e) for e in np.eye(fs.n)])
    ev = np.sort(np.linalg.eigvals(PS @ S).real)
    assert ev[-1] / ev[0] < 12
    schur = K.toarray() + M.T @ np.linalg.solve(S, M.toarray())
    PT = np.column_stack([pre.rise(e) for e in np.eye(K.shape[0])])
    ev = np.sort(np.linalg.eigvals(PT @ schur).real)
    assert ev[0] > 0.2 and ev[-1] < 4
