"""Nested-dissection solves of large tangents by SuperLU (simulator.linalg.linsolve): agreement with
spsolve, one ordering per sparsity pattern, and the fallbacks to SuperLU's own orderings.
PARDISO is switched off here; its path is tested in test_pardiso.py."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from simulator.steps import initial_state
from simulator.linalg import linsolve, pardiso, thresholds
from simulator.linalg import factorize, solve as _solve_linear
from simulator.cases import miura_sheet_model
from simulator.thermal import thermal_model
from simulator.geometry.example_patterns import miura_sheet_pattern
from simulator.model.model import Supports, make_model
from simulator.solvers.newton import NewtonOptions, newton
from simulator.model.properties import BarHingeParameters
from simulator.mechanics import equilibrium_system



@pytest.fixture(autouse=True)
def superlu_only(monkeypatch):
    """The SuperLU paths, as on a machine without PARDISO."""
    monkeypatch.setattr(pardiso, "_library", ())


def _sheet(cells):
    """A flat Miura sheet clamped on panel 0 in a slightly perturbed state (the benchmark's)."""
    model = make_model(miura_sheet_pattern(m=cells, n=cells), None, BarHingeParameters())
    panel0 = model.mesh.panel_nodes(0)
    model = make_model(model.mesh, Supports.nodes(panel0))
    u = np.random.default_rng(0).normal(size=(model.mesh.n_nodes, 3)) * 1e-9
    u[panel0] = 0
    return model, u, initial_state(model).spring_rest


@pytest.fixture(scope="module")
def sheet():
    model, u, rest = _sheet(20)                     # 12 825 free DOFs
    system = equilibrium_system(model)
    ev = system.evaluate(u, rest)
    return model, system, u, rest, ev.K, -ev.f_int[system.free]


def _minimum_degree(K, r):
    return spla.splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                     options={"SymmetricMode": True}).solve(r)


def test_mid_size_sheet_solve_agrees_with_spsolve(sheet):
    *_, K, r = sheet
    assert K.shape[0] >= thresholds.ND_LIMIT
    du = _solve_linear(K, r)
    ref = spla.spsolve(K.tocsc(), r)
    assert np.linalg.norm(du - ref) <= 1e-8 * np.linalg.norm(ref)
    assert np.linalg.norm(K @ du - r) <= 1e-13 * np.linalg.norm(r)
    nd = linsolve.ordering_for(K)
    assert np.array_equal(np.sort(nd.perm), np.arange(K.shape[0]))
    # the reordered matrix is K[perm][:, perm]
    A = sp.csc_matrix((K.data[nd.data_map], nd.indices, nd.indptr), shape=K.shape)
    assert abs(A - K[nd.perm][:, nd.perm]).max() == 0


def test_nested_dissection_has_less_fill_than_minimum_degree(sheet):
    *_, K, _ = sheet
    nd = linsolve.ordering_for(K).factorize(K).lu
    mmd = spla.splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                    options={"SymmetricMode": True})
    assert nd.L.nnz + nd.U.nnz < mmd.L.nnz + mmd.U.nnz


def test_dofs_of_a_node_form_one_supervariable(sheet):
    model, system, *_, K, _ = sheet
    group = linsolve.supervariables(K.indptr, K.indices)
    node = system.free // 3
    assert group[-1] + 1 == len(np.unique(node))
    assert np.array_equal(np.flatnonzero(np.diff(group)), np.flatnonzero(np.diff(node)))


def test_ordering_is_computed_once_per_pattern(monkeypatch):
    model, u, rest = _sheet(18)
    system = equilibrium_system(model)
    assert system.n_free >= thresholds.ND_LIMIT
    calls = []
    original = linsolve.NestedDissection.of.__func__

    def counting(cls, indptr, indices):
        calls.append(len(indptr))
        return original(cls, indptr, indices)

    monkeypatch.setattr(linsolve.NestedDissection, "of", classmethod(counting))
    monkeypatch.setattr(linsolve, "_cache", [])
    f_ext = np.zeros(model.mesh.n_dof)
    res = newton(system, u, f_ext, rest, NewtonOptions(max_iter=3))
    assert len(res.correction_norms) >= 2             # several solves ...
    assert len(calls) == 1                            # ... one ordering
    # a matrix with equal (not identical) index arrays finds it too
    K = system.evaluate(u, rest).K
    copy = sp.csr_matrix((K.data, K.indices.copy(), K.indptr.copy()), shape=K.shape)
    assert linsolve.ordering_for(copy) is linsolve.ordering_for(K)
    assert len(calls) == 1


def test_matrices_of_one_assembly_pattern_are_matched_without_comparing(monkeypatch):
    """scipy's CSR keeps a new view ``indices[:nnz]`` of the assembler's array at every
    construction: whole views of one array match the cached pattern by identity (no
    element-wise comparison); a partial or reversed view is compared."""
    model, u, rest = _sheet(5)
    system = equilibrium_system(model)
    monkeypatch.setattr(linsolve, "_cache", [])
    K1, K2 = system.evaluate(u, rest).K, system.evaluate(u, rest).K
    assert K1.indices is not K2.indices and K1.indices.base is K2.indices.base
    entry = linsolve._pattern_of(K1)
    compared = []
    real = np.array_equal
    monkeypatch.setattr(linsolve.np, "array_equal",
                        lambda a, b: compared.append(1) or real(a, b))
    assert linsolve._pattern_of(K2) is entry and compared == []
    ind = K1.indices.base
    assert linsolve._same_array(ind[:len(ind)], ind) and linsolve._same_array(ind[:], ind[:])
    assert not linsolve._same_array(ind[:-1], ind[:-1].copy())
    assert not linsolve._same_array(ind[::-1], ind)
    assert not linsolve._same_array(ind[1:], ind[1:][:])


def test_small_systems_keep_the_minimum_degree_path(monkeypatch):
    def fail(K):
        raise AssertionError("no nested dissection below ND_LIMIT")

    monkeypatch.setattr(linsolve, "ordering_for", fail)
    model, u, rest = _sheet(5)
    system = equilibrium_system(model)
    ev = system.evaluate(u, rest)
    r = -ev.f_int[system.free]
    assert thresholds.DENSE_LIMIT < system.n_free < thresholds.ND_LIMIT
    assert np.array_equal(_solve_linear(ev.K, r), _minimum_degree(ev.K, r))   # bitwise


def test_without_an_ordering_the_minimum_degree_path_is_taken(sheet, monkeypatch):
    *_, K, r = sheet
    monkeypatch.setattr(linsolve, "_cache", [])
    monkeypatch.setattr(linsolve, "nested_dissection_ordering", lambda indptr, indices: None)
    assert linsolve.ordering_for(K) is None
    assert np.array_equal(_solve_linear(K, r), _minimum_degree(K, r))


def test_a_failing_ordering_falls_back_to_minimum_degree(sheet, monkeypatch):
    *_, K, r = sheet

    calls = []

    def broken(cls, indptr, indices):
        calls.append(1)
        raise RuntimeError("METIS error")

    monkeypatch.setattr(linsolve, "_cache", [])
    monkeypatch.setattr(linsolve.NestedDissection, "of", classmethod(broken))
    assert np.array_equal(_solve_linear(K, r), _minimum_degree(K, r))
    assert linsolve.ordering_for(K) is None and len(calls) == 1     # not tried again


def test_a_zero_pivot_falls_back_to_minimum_degree(sheet, monkeypatch):
    *_, K, r = sheet

    def zero_pivot(self, K):
        raise RuntimeError("Factor is exactly singular")

    monkeypatch.setattr(linsolve.NestedDissection, "factorize", zero_pivot)
    assert np.array_equal(_solve_linear(K, r), _minimum_degree(K, r))


def test_an_inaccurate_symmetric_solve_falls_back_to_partial_pivoting(monkeypatch):
    # 2x2 blocks [[e, 1], [1, e]] chained weakly: diagonal pivots of 1e-14 ruin the symmetric
    # modes' solutions, partial pivoting is exact
    n = 2 * 6000
    e = 1e-14
    main = np.full(n, e)
    off = np.zeros(n - 1)
    off[::2] = 1.0
    off[1::2] = 1e-3
    K = sp.diags([off, main, off], [-1, 0, 1], format="csr")
    r = np.random.default_rng(1).normal(size=n)
    monkeypatch.setattr(thresholds, "ND_LIMIT", 100)
    monkeypatch.setattr(linsolve, "_cache", [])
    nd = linsolve.ordering_for(K)
    assert nd is not None
    with np.errstate(all="ignore"):
        bad = nd.factorize(K).solve(r)
    assert not np.linalg.norm(K @ bad - r) <= 1e-6 * np.linalg.norm(r)
    du = _solve_linear(K, r)
    assert np.linalg.norm(K @ du - r) <= 1e-10 * np.linalg.norm(r)


def test_thermal_solve_in_nested_dissection_order_agrees_with_colamd(monkeypatch):
    model = miura_sheet_model(cells_x=8, cells_y=6)
    tm = thermal_model(model)
    assert len(tm.free_nodes) > thresholds.CONDUCTION_DENSE_LIMIT          # a sparse solve
    q = tm.heat_vector(np.full(model.mesh.n_creases, 1e-3))
    q2 = np.stack([q, np.roll(q, 7)], axis=1)
    ref = tm.solve(model.mesh.nodes, q2)                 # below ND_LIMIT: COLAMD
    used = []
    original = linsolve.ordering_for

    def spy(K):
        used.append(K.shape)
        return original(K)

    monkeypatch.setattr(thresholds, "ND_LIMIT", 100)
    monkeypatch.setattr(linsolve, "ordering_for", spy)
    tm._factor_cache = None                              # factorise again
    T = tm.solve(model.mesh.nodes, q2)
    assert used and used[0][0] >= 100
    assert np.allclose(T, ref, rtol=1e-12, atol=0)


def test_repeated_solves_with_nested_dissection_factors(sheet):
    *_, K, r = sheet
    lu = factorize(K.tocsc(), backend="superlu")             # any sparse format
    assert lu.backend == "superlu-nd"
    R = np.stack([r, np.roll(r, 5)], axis=1)
    X = lu.solve(R)
    assert np.linalg.norm(K @ X[:, 0] - r) <= 1e-13 * np.linalg.norm(r)
    for j in range(2):
        ref = spla.spsolve(K.tocsc(), R[:, j])
        assert np.linalg.norm(X[:, j] - ref) <= 1e-8 * np.linalg.norm(ref)
    with pytest.raises(ValueError, match="not of this pattern"):
        linsolve.ordering_for(K).factorize(K[:-1, :-1])


def _grounded_stiff_chain(n=2000):
    """Stiff springs (~1e10 N/m) in a chain held by one soft spring (0.375 N/m), with entries
    exact in floating point: |K| |x| ~ 1e9 |r|, so a backward-stable solution's residual is
    ~1e-4 |r| (the round-off of K x itself). Also the exact solution, from the spring forces
    in extended precision: spring i carries the load on nodes 0..i."""
    rng = np.random.default_rng(3)
    k = np.round(1e10 * (1 + rng.random(n - 1)))
    main = np.r_[k, 0] + np.r_[0, k]
    main[-1] += 0.375
    K = sp.diags([-k, main, -k], [-1, 0, 1], format="csr")
    r = rng.normal(size=n) * 1e-3
    load = np.cumsum(r.astype(np.longdouble))
    exact = np.empty(n, dtype=np.longdouble)
    exact[-1] = load[-1] / np.longdouble(0.375)
    for i in range(n - 2, -1, -1):
        exact[i] = exact[i + 1] + load[i] / np.longdouble(k[i])
    return K, r, exact


def test_backward_error_is_the_oettli_prager_measure():
    K = sp.csr_matrix(np.array([[2.0, 0.0], [0.0, 1.0]]))
    x, r = np.array([1.0, 1.0]), np.array([2.0, 1.001])
    assert linsolve.backward_error(K, x, r) == pytest.approx(1e-3 / 2.001, rel=1e-12)
    assert linsolve.backward_error(K, np.array([np.nan, 1.0]), r) == np.inf
    assert not linsolve.accurate(K, x, r) and linsolve.accurate(K, x, r, rtol=1e-3)
    X, R = np.column_stack([x, [1.0, 1.0]]), np.column_stack([r, [2.0, 1.0]])
    assert linsolve.backward_error(K, X, R) == pytest.approx(1e-3 / 2.001, rel=1e-12)


@pytest.mark.parametrize("nd_limit", [10**9, 100])
def test_an_ill_conditioned_backward_stable_solve_is_accepted(monkeypatch, nd_limit):
    # its residual misses 1e-6 |r| by round-off alone; a partial-pivoting factorisation
    # (15x slower at 1e5 nodes) would be no more exact
    K, r, exact = _grounded_stiff_chain()
    monkeypatch.setattr(thresholds, "ND_LIMIT", nd_limit)
    monkeypatch.setattr(linsolve, "_cache", [])
    factorisations = []
    original = spla.splu

    def spy(A, *args, **kwargs):
        factorisations.append(kwargs.get("permc_spec", "COLAMD"))
        return original(A, *args, **kwargs)

    monkeypatch.setattr(spla, "splu", spy)
    du = _solve_linear(K, r)
    assert len(factorisations) == 1 and factorisations[0] in ("MMD_AT_PLUS_A", "NATURAL")
    assert np.linalg.norm(K @ du - r) > 1e-6 * np.linalg.norm(r)       # the residual test fails
    assert linsolve.backward_error(K, du, r) <= 1e-15                    # but du is exact for K
    pivoting = spla.spsolve(K.tocsc(), r)                               # partial pivoting

    def error(x):
        return float(np.linalg.norm(x - exact) / np.linalg.norm(exact))
    assert error(du) <= max(2 * error(pivoting), 1e-12)
