"""The one factorisation ladder (simulator.linalg.ladder): one place for every threshold and
factorisation, backends as options, inertia, and arc length on a large sheet solved by the
same backend as Newton."""

import pathlib
import re

import numpy as np
import pytest
import scipy.sparse as sp

from simulator import NewtonOptions
from simulator.errors import ParameterError
from simulator.linalg import ladder, pardiso, thresholds
from simulator.linalg import factorize, solve
from simulator.solvers import load_path, newton as newton_module
from simulator.solvers import mgdcm
from simulator.solvers.dynamics_options import DynamicsOptions
from simulator.mechanics import equilibrium_system
from test_linsolve import _sheet

ROOT = pathlib.Path(__file__).resolve().parents[2]
SOURCES = sorted((ROOT / "simulator").rglob("*.py"))


def _outside_linalg(path):
    return "linalg" not in path.relative_to(ROOT / "simulator").parts


def test_every_dense_sparse_threshold_is_defined_in_thresholds_only():
    definition = re.compile(r"^\s*([A-Z_]*(DENSE|PARDISO|ND_LIMIT|SPARSE)[A-Z_]*)\s*=\s*[\d(]",
                            re.MULTILINE)
    found = {f"{p.relative_to(ROOT)}: {m.group(1)}" for p in SOURCES
             for m in definition.finditer(p.read_text())}
    assert found == {f"simulator/linalg/thresholds.py: {name}" for name in thresholds.__all__}
    assert not any("DENSE_NODES" in p.read_text() for p in SOURCES)


def test_factorisations_happen_in_linalg_only():
    call = re.compile(r"(?<![\w.])(?<!def )(?!self\.)(?:\w+\.)*_?(splu|spsolve|spilu|factorized|"
                      r"cho_factor|lu_factor|lu_solve|cho_solve|d?potrf|d?getrf|d?sytrf|ldl)\s*\(|"
                      r"(?<![\w.])(?:scipy\.|np\.|numpy\.)?linalg\.solve\s*\(")
    offenders = [f"{p.relative_to(ROOT)}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)}"
                 for p in SOURCES if _outside_linalg(p)
                 for text in [p.read_text()] for m in call.finditer(text)]
    assert offenders == []
    # shift-invert eigen-solves bring their own factor from the ladder
    for p in SOURCES:
        for line in p.read_text().splitlines():
            if "eigsh(" in line and "sigma=" in line:
                assert "OPinv=" in line, f"{p.name}: {line.strip()}"


def test_one_ladder_the_choice_of_a_rung_lives_in_ladder_py():
    # the thresholds of the choice are read in the ladder (and where a caller builds a dense
    # matrix itself), never compared against in another solver module
    users = {p.relative_to(ROOT).as_posix() for p in SOURCES
             if re.search(r"\b(PARDISO_LIMIT|ND_LIMIT)\b", p.read_text())}
    assert users <= {"simulator/linalg/ladder.py", "simulator/linalg/thresholds.py",
                     "simulator/linalg/linsolve.py", "simulator/solvers/modes.py",
                     "simulator/thermal/steady.py"}


def _spd(n, seed=0):
    A = sp.random(n, n, density=min(1.0, 8 / n), random_state=seed)
    return (A @ A.T + sp.identity(n)).tocsr()


def _indefinite(n, seed=0):
    A = _spd(n, seed)
    return (A - 2.0 * sp.identity(n)).tocsr()


@pytest.mark.parametrize("backend", ["dense", "superlu"] + (["pardiso"] if pardiso.available()
                                                            else []))
@pytest.mark.parametrize("kind", ["symmetric", "spd"])
def test_every_backend_solves_and_says_which_it_is(backend, kind):
    A = _spd(300)
    b = np.random.default_rng(2).normal(size=(300, 2))
    f = factorize(A, kind=kind, backend=backend)
    assert f.backend.startswith(backend) and f.n == 300
    assert np.linalg.norm(A @ f.solve(b) - b) <= 1e-10 * np.linalg.norm(b)
    x = solve(A, b[:, 0], kind=kind, backend=backend)
    assert ladder.last_backend().startswith(backend)
    assert np.linalg.norm(A @ x - b[:, 0]) <= 1e-10 * np.linalg.norm(b[:, 0])


def test_auto_is_dense_below_the_limit_and_sparse_above(monkeypatch):
    small, large = _spd(thresholds.DENSE_LIMIT), _spd(thresholds.DENSE_LIMIT + 1)
    assert factorize(small).backend == "dense"
    assert factorize(large).backend == ("pardiso" if pardiso.available() else "superlu-mmd")
    assert factorize(large, dense_limit=1000).backend == "dense"
    monkeypatch.setattr(pardiso, "_library", ())                    # no MKL
    assert factorize(large).backend == "superlu-mmd"
    assert factorize(large, kind="spd").backend == "superlu"        # COLAMD, as before
    monkeypatch.setattr(thresholds, "ND_LIMIT", 100)                # read at call time
    assert factorize(large).backend == "superlu-nd"


@pytest.mark.parametrize("backend", ["dense"] + (["pardiso"] if pardiso.available() else []))
def test_inertia_counts_the_negative_eigenvalues(backend):
    A = _indefinite(200, seed=4)
    w = np.linalg.eigvalsh(A.toarray())
    inertia = factorize(A, backend=backend).inertia
    assert inertia == (int(np.sum(w > 0)), int(np.sum(w < 0)), 0)
    assert factorize(_spd(20)).inertia == (20, 0, 0)
    # SuperLU with diagonal pivots gives it too (Sylvester's law on U's diagonal)
    assert factorize(_spd(300), backend="superlu").inertia == (300, 0, 0)


@pytest.mark.parametrize("backend", ["auto", "dense", "superlu"]
                         + (["pardiso"] if pardiso.available() else []))
def test_positive_definite_from_the_pivots_of_one_factorisation(backend, monkeypatch):
    for n in (20, 300):
        assert ladder.positive_definite(_spd(n), backend)
        assert ladder.positive_definite(_spd(n).toarray(), backend)
        assert not ladder.positive_definite(_indefinite(n, seed=4), backend)
    near = _spd(300).tolil()
    near[5, 5] = 0.0
    w = np.linalg.eigvalsh(near.toarray())
    assert ladder.positive_definite(near.tocsr(), backend) == bool(w[0] > 0)
    # no solve: the ladder's test of kept factors is not made
    monkeypatch.setattr(ladder.linsolve, "solves_ones", lambda *a, **k: 1 / 0)
    assert ladder.positive_definite(_spd(300), backend)
    assert ladder.positive_definite(sp.csr_matrix((0, 0)), backend)


def test_ill_conditioned_dense_systems_are_rejected_only_on_request():
    A = np.array([[1.0, 1.0], [1.0, 1.0]])
    b = np.array([1.0, 2.0])
    assert solve(A, b) is None and solve(A, b, reject_ill_conditioned=False) is None  # singular
    A = np.array([[1.0, 1.0], [1.0, 1.0 + 2e-16]])                  # nearly singular
    assert solve(A, b) is None                                      # Newton: rejected
    x = solve(A, b, reject_ill_conditioned=False)                   # arc length: accepted
    assert x is not None and np.allclose(A @ x, b, rtol=0, atol=1e-3)


@pytest.mark.parametrize("kind", ["symmetric", "spd", "general"])
def test_a_small_dense_array_takes_the_dense_rung_as_its_factors_do(kind):
    """The dense fast path of solve (Newton's loop on small models): the same solution as the
    kept dense factors, bit for bit, for one and several right-hand sides, Cholesky or LU."""
    rng = np.random.default_rng(5)
    for A in (_spd(40).toarray(), _indefinite(40, seed=6).toarray()):
        for b in (rng.normal(size=40), rng.normal(size=(40, 3))):
            x = solve(A, b, kind=kind)
            assert ladder.last_backend() == "dense"
            if kind == "spd" and np.linalg.eigvalsh(A).min() < 0:
                continue                        # kept "spd" factors refuse LU (sparse rungs)
            assert np.array_equal(x, factorize(A, kind=kind).solve(b))
    bad = _spd(40).toarray()
    bad[3, 3] = np.nan
    assert solve(bad, np.ones(40), kind=kind) is None and ladder.last_backend() is None


def test_bad_backends_are_errors_naming_the_option(monkeypatch):
    with pytest.raises(ParameterError, match="NewtonOptions.linear_solver = 'mumps'"):
        NewtonOptions(linear_solver="mumps")
    with pytest.raises(ParameterError, match="DynamicsOptions.linear_solver"):
        DynamicsOptions(linear_solver="lapack")
    monkeypatch.setattr(pardiso, "_library", ())
    with pytest.raises(ParameterError, match="PARDISO is not available"):
        factorize(_spd(300), backend="pardiso")


def test_newton_takes_the_backend_option():
    model, u, rest = _sheet(3)
    system = equilibrium_system(model)
    f = np.zeros(model.mesh.n_dof)
    runs = {b: newton_module.newton(system, u, f, rest, NewtonOptions(linear_solver=b))
            for b in ("auto", "dense", "superlu")}
    assert all(r.success for r in runs.values())
    for r in runs.values():
        assert np.allclose(r.u, runs["auto"].u, rtol=0, atol=1e-12)


def test_arc_length_on_a_large_sheet_uses_newtons_backend(monkeypatch):
    model, _, rest = _sheet(30)                           # ~1e4 nodes
    assert model.mesh.n_nodes >= 9000
    system = equilibrium_system(model)
    u0 = np.zeros((model.mesh.n_nodes, 3))
    f = np.zeros(model.mesh.n_dof)
    P = np.zeros(model.mesh.n_dof)
    P[2::3] = 1e-9                                        # a small out-of-plane load
    used = {"newton": [], "arc length": []}

    def spy(owner, inner):
        def wrapped(*args, **kwargs):
            out = inner(*args, **kwargs)
            used[owner].append(ladder.last_backend())
            return out
        return wrapped

    monkeypatch.setattr(newton_module, "linear_solve", spy("newton", newton_module.linear_solve))
    monkeypatch.setattr(load_path, "solve", spy("arc length", load_path.solve))
    res = newton_module.newton(system, u0, P, rest, NewtonOptions(max_iter=2))
    assert res.evaluation is not None or res.iterations >= 1
    path = load_path.LoadPath(system, f, P, rest)
    mgdcm(path, u0, arc_length=0.1, max_increments=1, stability=False,
          options=NewtonOptions(max_iter=2))
    expected = "pardiso" if pardiso.available() else "superlu-nd"
    assert set(used["newton"]) == {expected}
    assert set(used["arc length"]) == {expected}


def test_a_conduction_matrix_that_is_not_positive_definite_goes_to_the_sparse_rungs():
    A = _indefinite(50, seed=1).toarray()
    f = factorize(A, kind="spd", dense_limit=100)
    assert f.backend != "dense"
    b = np.ones(50)
    assert np.linalg.norm(A @ f.solve(b) - b) <= 1e-9 * np.linalg.norm(b)
    assert factorize(_spd(50).toarray(), kind="spd", dense_limit=100).backend == "dense"
