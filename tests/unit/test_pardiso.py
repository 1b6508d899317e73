"""PARDISO solves of large symmetric tangents (simulator.linalg.pardiso via simulator.linalg.linsolve):
agreement with SuperLU, inertia, one analysis per pattern, fallbacks, thread safety."""

import gc
import importlib.util
import platform
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from simulator.linalg import factorize, linsolve, pardiso, thresholds
from simulator.linalg import solve as _solve_linear
from simulator.solvers.newton import NewtonOptions, newton
from simulator.mechanics import equilibrium_system
from test_linsolve import _grounded_stiff_chain, _sheet

_spec = importlib.util.spec_from_file_location(
    "bench_fold", Path(__file__).resolve().parents[2] / "benchmarks" / "bench_fold.py")
bench_fold = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench_fold)

pytestmark = pytest.mark.skipif(
    platform.machine() not in ("x86_64", "AMD64") or sys.platform == "darwin",
    reason="MKL (PARDISO) has wheels for Linux and Windows on x86-64 only (pyproject marker)")


@pytest.fixture(autouse=True)
def fresh_cache(monkeypatch):
    monkeypatch.setattr(linsolve, "_cache", [])


@pytest.fixture(scope="module")
def sheet():
    model, u, rest = _sheet(20)                     # 12 825 free DOFs, an indefinite tangent
    system = equilibrium_system(model)
    ev = system.evaluate(u, rest)
    return model, system, u, rest, ev.K, -ev.f_int[system.free]


def test_pardiso_is_installed_with_the_test_extra():
    assert pardiso.available()


def test_large_solve_uses_pardiso_and_agrees_with_superlu(sheet, monkeypatch):
    *_, K, r = sheet
    assert K.shape[0] >= thresholds.ND_LIMIT
    orderings = []
    monkeypatch.setattr(linsolve.NestedDissection, "of",
                        classmethod(lambda cls, ip, ind: orderings.append(1)))
    du = _solve_linear(K, r)
    assert not orderings                                    # no METIS ordering of our own
    handle = linsolve._cache[0].pardiso
    assert isinstance(handle, pardiso.PardisoLDLT) and handle.negative_eigenvalues > 0
    ref = spla.spsolve(K.tocsc(), r)
    assert np.linalg.norm(du - ref) <= 1e-8 * np.linalg.norm(ref)
    assert np.linalg.norm(K @ du - r) <= 1e-12 * np.linalg.norm(r)
    R = np.stack([r, np.roll(r, 3)], axis=1)                # several right-hand sides
    X = linsolve.pardiso_solve(K, R)
    assert np.allclose(X[:, 0], du, rtol=0, atol=1e-12 * np.abs(du).max())
    ref1 = spla.spsolve(K.tocsc(), R[:, 1])
    assert np.linalg.norm(X[:, 1] - ref1) <= 1e-8 * np.linalg.norm(ref1)


def test_inertia_matches_the_eigenvalues():
    model, u, rest = _sheet(4)
    system = equilibrium_system(model)
    ev = system.evaluate(u, rest)
    K = sp.csr_matrix(ev.K)
    handle = pardiso.PardisoLDLT(K.indptr, K.indices)
    handle.factor_solve(K, np.ones(K.shape[0]))
    assert handle.negative_eigenvalues == int(np.sum(np.linalg.eigvalsh(K.toarray()) < 0))


def test_one_analysis_per_pattern_over_newton_iterations(monkeypatch):
    model, u, rest = _sheet(20)
    system = equilibrium_system(model)
    made = []
    original = pardiso.PardisoLDLT.__init__

    def counting(self, indptr, indices):
        made.append(len(indptr))
        original(self, indptr, indices)

    monkeypatch.setattr(pardiso.PardisoLDLT, "__init__", counting)
    res = newton(system, u, np.zeros(model.mesh.n_dof), rest, NewtonOptions(max_iter=3))
    assert len(res.correction_norms) >= 2 and len(made) == 1


def test_newton_iterates_match_the_superlu_path(monkeypatch):
    model, _, rest1 = bench_fold.folding_sheet(20)
    system = equilibrium_system(model)
    assert system.n_free >= thresholds.ND_LIMIT
    u0, f_ext = np.zeros((model.mesh.n_nodes, 3)), np.zeros(model.mesh.n_dof)
    fast = newton(system, u0, f_ext, rest1)
    assert isinstance(linsolve._cache[0].pardiso, pardiso.PardisoLDLT)
    monkeypatch.setattr(pardiso, "_library", ())
    slow = newton(system, u0, f_ext, rest1)
    assert fast.success and slow.success and fast.iterations == slow.iterations >= 3
    big = slow.residual_norms > 1e-5 * slow.residual_norms[0]   # above the solves' round-off
    assert big.sum() >= 3
    assert np.allclose(fast.residual_norms[big], slow.residual_norms[big], rtol=1e-5, atol=0)
    scale = np.abs(slow.u).max()
    assert scale > 1e-6                                     # the sheet folds (metres)
    assert np.allclose(fast.u, slow.u, rtol=0, atol=1e-9 * scale)


def test_a_pardiso_error_falls_back_to_superlu(sheet, monkeypatch):
    *_, K, r = sheet

    def broken(self, K, r, refine=None):
        raise pardiso.PardisoError("PARDISO phase 22 returned error -4")

    monkeypatch.setattr(pardiso.PardisoLDLT, "factor_solve", broken)
    du = _solve_linear(K, r)
    assert linsolve._cache[0].nd is not None               # the SuperLU path ordered it
    assert np.linalg.norm(K @ du - r) <= 1e-12 * np.linalg.norm(r)


def test_a_pattern_without_diagonal_is_left_to_superlu(monkeypatch):
    n = 400                                               # [[0, 1], [1, 0]] blocks
    off = np.zeros(n - 1)
    off[::2] = 1.0
    K = sp.diags([off, off], [-1, 1], format="csr")
    r = np.arange(1.0, n + 1)
    monkeypatch.setattr(thresholds, "ND_LIMIT", 100)
    du = _solve_linear(K, r)
    assert linsolve._cache[0].pardiso is False
    assert np.allclose(K @ du, r, rtol=1e-14)


def test_an_ill_conditioned_solve_is_accepted_by_its_backward_error(monkeypatch):
    K, r, exact = _grounded_stiff_chain()
    monkeypatch.setattr(thresholds, "ND_LIMIT", 100)
    du = linsolve.pardiso_solve(K, r)
    assert du is not None
    assert np.linalg.norm(K @ du - r) > 1e-6 * np.linalg.norm(r)      # the residual test fails
    assert linsolve.backward_error(K, du, r) <= linsolve.BACKWARD_ERROR_TOL
    pivoting = spla.spsolve(K.tocsc(), r)
    err = [float(np.linalg.norm(x - exact) / np.linalg.norm(exact)) for x in (du, pivoting)]
    assert err[0] <= max(2 * err[1], 1e-12)


def test_concurrent_solves_of_one_pattern_are_serialised(sheet):
    *_, K, r = sheet
    Ks = [K, K + sp.diags(np.full(K.shape[0], 1e-3 * abs(K.diagonal()).max()), format="csr")]
    for A in Ks:
        A.sort_indices()
    refs = [spla.spsolve(A.tocsc(), r) for A in Ks]
    out = {}

    def work(i):
        for _ in range(3):
            out.setdefault(i, []).append(linsolve.pardiso_solve(Ks[i], r))

    threads = [threading.Thread(target=work, args=(i,)) for i in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(linsolve._cache) == 1                        # one pattern, one handle
    for i in (0, 1):
        for x in out[i]:
            assert np.linalg.norm(x - refs[i]) <= 1e-8 * np.linalg.norm(refs[i])


def test_an_evicted_pattern_frees_pardiso_memory(sheet):
    *_, K, r = sheet
    linsolve.pardiso_solve(K, r)
    handle = linsolve._cache[0].pardiso
    freed = []
    import weakref
    weakref.finalize(handle, freed.append, True)
    del handle
    linsolve._cache.clear()
    gc.collect()
    assert freed == [True]


def test_environment_variable_switches_pardiso_off(monkeypatch):
    monkeypatch.setattr(pardiso, "_library", None)
    monkeypatch.setenv("ETORIGAMI_PARDISO", "0")
    assert not pardiso.available()
    monkeypatch.setattr(pardiso, "_library", None)
    monkeypatch.setenv("ETORIGAMI_PARDISO", "1")
    assert pardiso.available()


def test_kept_factors_stay_correct_when_the_handle_factorises_another_matrix(sheet):
    *_, K, r = sheet
    K2 = (K + sp.diags(np.full(K.shape[0], 1e-3 * abs(K.diagonal()).max()))).tocsr()
    K2.sort_indices()
    f1 = factorize(K)
    f2 = factorize(K2)                                     # same pattern, same handle
    assert f1.backend == f2.backend == "pardiso" and f1.raw.handle is f2.raw.handle
    for f, A in ((f1, K), (f2, K2), (f1, K)):               # each solve with its own matrix
        x = f.solve(r)
        assert np.linalg.norm(A @ x - r) <= 1e-12 * np.linalg.norm(r)
    with pytest.raises(ValueError, match="not of this pattern"):
        f1.raw.handle.factorize(K[:-1, :-1].tocsr())


def test_thermal_modes_and_transient_heat_agree_with_superlu(monkeypatch):
    from simulator import natural_modes
    from simulator.cases import miura_sheet_model
    from simulator.thermal import thermal_model
    from simulator.thermal.transient import ThetaStepper

    model = miura_sheet_model(cells_x=8, cells_y=6)
    tm = thermal_model(model)
    assert len(tm.free_nodes) > thresholds.CONDUCTION_DENSE_LIMIT   # a sparse thermal solve
    q = tm.heat_vector(np.full(model.mesh.n_creases, 1e-3))
    K = sp.random(300, 300, density=0.02, random_state=1)
    K = (K @ K.T + sp.identity(300)).tocsr()                  # a conductance-like SPD matrix
    K.sort_indices()
    C = np.linspace(1e-6, 2e-6, 300)
    T0 = np.linspace(0.0, 5.0, 300)

    def run():
        linsolve._cache.clear()
        tm._factor_cache = None
        stepper = ThetaStepper(K, C, 1e-3)
        return (tm.solve(model.mesh.nodes, q), natural_modes(model, count=4).frequency,
                stepper.step(T0, np.ones(300), np.ones(300)), stepper._lu)

    fast = run()
    assert fast[3].backend == "pardiso"
    monkeypatch.setattr(pardiso, "_library", ())
    slow = run()
    assert slow[3].backend != "pardiso"
    for a, b in zip(fast[:3], slow[:3]):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=0)


def test_a_failed_analysis_is_released_and_left_to_superlu(sheet, monkeypatch):
    *_, K, r = sheet
    phases = []
    original = pardiso._invoke

    def failing_analysis(f, pt, iparm, phase, *args):
        phases.append((phase, id(pt)))
        return -2 if phase == 11 else original(f, pt, iparm, phase, *args)   # -2: no memory

    monkeypatch.setattr(pardiso, "_invoke", failing_analysis)
    du = _solve_linear(K, r)
    gc.collect()
    assert linsolve._cache[0].pardiso is False
    handle = [pt for phase, pt in phases if phase == 11]
    assert len(handle) == 1 and (-1, handle[0]) in phases               # analysis, release
    assert np.linalg.norm(K @ du - r) <= 1e-12 * np.linalg.norm(r)       # by SuperLU
