"""The fused compiled evaluation of small models equals the numpy reference path; the sparse
Cholesky and the dense LAPACK solves keep the semantics of ``scipy.linalg.solve``."""

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp

from simulator import _jit
from simulator.kernels import spring_kernel_backend
from simulator.mechanics.assembly import assemble_vector, element_dofs
from simulator.cases import get_case
from simulator.mechanics.elements.bars import bar_kernel
from simulator.mechanics.elements.contact import contact_kernel
from simulator.mechanics.elements.springs import spring_kernel
from simulator.mechanics.equilibrium import ENERGY_KINDS, EquilibriumSystem, SystemValues
from simulator.geometry.example_patterns import miura_sheet_pattern
from simulator.linalg import solve as solve_linear
from simulator.linalg.small_solve import SparseCholesky, solve_dense
from simulator.model.model import ContactParameters, Supports, make_model
from simulator.mechanics import equilibrium_system
from simulator.steps import initial_state

pytestmark = pytest.mark.skipif(not _jit.AVAILABLE, reason="numba not installed")


def _gripper_with_contacts():
    """A gripper after its residual fold and gravity, with points of three panels placed
    inside the activation distance of other panels' triangles: on the face, beyond an edge
    and beyond a corner (all three distance zones)."""
    from design.devices.gripper import GripperDesign, make_gripper_model
    from simulator.simulation import simulate

    model, pre = make_gripper_model(GripperDesign())
    state = simulate(model, pre).state
    system = equilibrium_system(model)
    X, u = model.mesh.nodes, state.u.copy()
    search = system.contact
    p, t = search.static
    rng = np.random.default_rng(3)
    moved = set()
    for k, offset in zip(rng.permutation(len(p)), range(40)):
        node, tri = search.points[p[k]], search.tri[t[k]]
        if node in moved or model.fixed_mask[node].any():
            continue
        xt = X[tri] + u[tri]
        n = np.cross(xt[1] - xt[0], xt[2] - xt[0])
        n /= np.linalg.norm(n)
        zone = len(moved) % 3            # inside (face), beyond edge 0-1, beyond vertex 0
        inside = xt.mean(axis=0)
        target = {0: inside, 1: xt[0] + 0.5 * (xt[1] - xt[0]) - 0.3 * (inside - xt[0]),
                  2: xt[0] - 0.2 * (inside - xt[0])}[zone]
        u[node] = target + 15e-6 * n - X[node]
        moved.add(node)
        if len(moved) == 9:
            break
    return system, u, state.spring_rest


def _single_crease_states():
    """States of the single crease over its substrate with and without active contact."""
    from simulator.solvers.newton import newton as real_newton
    import simulator.solvers.newton as nw

    seen = []

    def spy(system, u0, f_ext, rest, options=nw.NewtonOptions()):
        res = real_newton(system, u0, f_ext, rest, options)
        seen.append((system, res.u, rest.copy()))
        return res
    nw_newton, nw.newton = nw.newton, spy
    try:
        get_case("single_fold", gravity=True, residual_fold_deg=-10.0, thermal_steps=8).run()
    finally:
        nw.newton = nw_newton
    return seen


def _miura():
    """A Miura sheet squeezed to a third of its length (panels over each other) with some
    noise, clamped at one panel, with elastic supports and large contact distances: many
    active pairs, of all zones."""
    model = make_model(miura_sheet_pattern(m=2, n=2), None,
                       contact=ContactParameters(2e-5, 300e-6, 250e-6))
    panel0 = model.mesh.panel_nodes(0)
    elastic = [(int(n), "z", 5.0) for n in range(model.mesh.n_nodes) if n not in panel0][:4]
    model = make_model(model.mesh, Supports({int(n): "xyz" for n in panel0}, elastic=elastic),
                       contact=ContactParameters(2e-5, 300e-6, 250e-6))
    rng = np.random.default_rng(1)
    X = model.mesh.nodes
    u = rng.normal(size=X.shape) * 1e-4
    u[:, 0] -= 0.67 * (X[:, 0] - X[:, 0].min())
    u[panel0] = 0
    return EquilibriumSystem(model), u, initial_state(model).spring_rest + 0.3


def _scale(system, u, rest):
    """Per-DOF sum of |element force| over bars, springs and contact pairs (the rounding scale
    of f_int) and the largest |Hessian entry|."""
    mesh = system.model.mesh
    x = mesh.nodes + u
    _, gb, hb = bar_kernel(system.bar_dX, u[mesh.bars[:, 1]] - u[mesh.bars[:, 0]],
                           system.bar_L0, system.bar_EA)
    _, gs, hs = spring_kernel(x[mesh.springs], system.spr_k, rest)
    f = assemble_vector(system.n_dof, system.bar_dofs, np.abs(gb)) \
        + assemble_vector(system.n_dof, system.spr_dofs, np.abs(gs))
    h = max(np.abs(hb).max(), np.abs(hs).max())
    if system.contact is not None:
        conn, d0, _ = system.contact.candidates(x)
        if len(conn):
            _, gc, hc = contact_kernel(x[conn], d0, system.model.contact.stiffness)
            f = f + assemble_vector(system.n_dof, element_dofs(conn), np.abs(gc))
            h = max(h, np.abs(hc).max())
    return f, h


def _compare(system, u, rest):
    ref = system._evaluate_numpy(u, rest)
    ev = system.evaluate(u, rest)
    assert isinstance(ev.tangent, np.ndarray) and isinstance(ref.tangent, sp.csr_matrix)
    f_scale, h_scale = _scale(system, u, rest)
    np.testing.assert_allclose(ev.f_int, ref.f_int, rtol=0, atol=1e-12 * f_scale.max())
    np.testing.assert_allclose(ev.tangent, ref.K.toarray(), rtol=0, atol=1e-12 * h_scale)
    e_scale = sum(abs(v) for v in ref.energies.values())
    for kind in ENERGY_KINDS:
        assert ev.energies[kind] == pytest.approx(ref.energies[kind], rel=1e-12,
                                                  abs=1e-12 * e_scale), kind
    assert ev.n_contacts == ref.n_contacts
    if system.contact is not None:         # the same active pairs as the numpy path
        x = system.model.mesh.nodes + u
        conn, d0, index = system.contact.candidates(x)
        e = contact_kernel(x[conn], d0, system.model.contact.stiffness)[0]
        assert sorted(ev.contact_pairs.tolist()) == sorted(index[e > 0].tolist())
    return ev, ref


def test_fused_kernel_equals_numpy_on_the_gripper_with_contact():
    system, u, rest = _gripper_with_contacts()
    assert system.uses_fused and system.n_free == 96
    ev, ref = _compare(system, u, rest)
    assert ev.n_contacts >= 6 and ev.energies["contact"] > 0


def test_fused_kernel_equals_numpy_on_the_single_crease():
    states = _single_crease_states()
    counts = set()
    for system, u, rest in states[::4]:
        ev, _ = _compare(system, u, rest)
        counts.add(ev.n_contacts)
    assert 0 in counts and max(counts) > 0            # with and without active contact


def test_fused_kernel_equals_numpy_on_a_miura_sheet():
    system, u, rest = _miura()
    assert system.uses_fused and len(system.elastic_k) == 4
    ev, ref = _compare(system, u, rest)
    assert ev.n_contacts >= 3 and ev.energies["elastic_support"] > 0
    no_hessian = system.evaluate(u, rest, hessian=False)
    assert no_hessian.K is None and no_hessian.tangent is None
    np.testing.assert_array_equal(no_hessian.f_int, ev.f_int)


def test_without_contact_the_fused_kernel_gives_the_numpy_floats():
    """Bars in the numpy kernel's operation order, the shared spring element, the numpy
    summation order: bit for bit (compiled spring kernel in the reference path)."""
    model = make_model(miura_sheet_pattern(m=2, n=2), None)
    panel0 = model.mesh.panel_nodes(0)
    model = make_model(model.mesh, Supports.nodes(panel0))
    system = EquilibriumSystem(model)
    u = np.random.default_rng(2).normal(size=(model.mesh.n_nodes, 3)) * 1e-5
    u[panel0] = 0
    rest = initial_state(model).spring_rest + 0.1
    ev, ref = system.evaluate(u, rest), system._evaluate_numpy(u, rest)
    np.testing.assert_array_equal(ev.f_int, ref.f_int)
    np.testing.assert_array_equal(ev.tangent, ref.K.toarray())
    assert ev.energies == ref.energies


def test_evaluation_K_is_csr_in_the_cached_pattern():
    """Consumers of SystemValues.K get CSR whichever path ran; the dense tangent is what Newton
    solves with."""
    system, u, rest = _miura()
    ev, ref = system.evaluate(u, rest), system._evaluate_numpy(u, rest)
    assert isinstance(ev.K, sp.csr_matrix) and ev.K is ev.K          # built once
    np.testing.assert_array_equal(ev.K.indptr, ref.K.indptr)
    np.testing.assert_array_equal(ev.K.indices, ref.K.indices)
    np.testing.assert_array_equal(ev.K.toarray(), ev.tangent)
    with pytest.raises(ValueError, match="dense tangent needs to_csr"):
        SystemValues(ev.f_int, ev.tangent, {})


def test_the_numpy_backend_keeps_the_reference_path():
    system, u, rest = _miura()
    with spring_kernel_backend("numpy"):
        assert not system.uses_fused
        ev = system.evaluate(u, rest)
    assert isinstance(ev.tangent, sp.csr_matrix) and ev.contact_pairs is None
    assert system.uses_fused


def test_a_failed_compilation_falls_back_to_numpy(monkeypatch, caplog):
    """numba is an accelerator: if it cannot compile, the numpy path and LAPACK take over."""
    from simulator.linalg import _cholesky_jit
    from simulator.mechanics.elements import _fused_jit

    def fail():
        raise RuntimeError("no compiler today")
    for module in (_fused_jit, _cholesky_jit):
        monkeypatch.setattr(module, "_compiled", None)
        monkeypatch.setattr(module, "broken", False)
    monkeypatch.setattr(_fused_jit, "_compile", fail)
    import numba
    monkeypatch.setattr(numba, "njit", lambda *a, **k: fail())
    system, u, rest = _miura()
    ev = system.evaluate(u, rest)
    assert isinstance(ev.tangent, sp.csr_matrix) and _fused_jit.broken
    assert not system.uses_fused
    K, r = _spd(20, 0.2, 0)
    np.testing.assert_allclose(_structure(K).solve(K, r), scipy.linalg.solve(K, r), rtol=1e-10)
    assert _cholesky_jit.broken
    assert "could not compile the fused kernel" in caplog.text
    assert "could not compile the sparse Cholesky" in caplog.text


def test_small_models_only():
    model = make_model(miura_sheet_pattern(m=6, n=5), None)
    panel0 = model.mesh.panel_nodes(0)
    system = EquilibriumSystem(make_model(model.mesh, Supports.nodes(panel0)))
    assert system.n_free > 150 and not system.uses_fused


def test_single_crease_fold_angle_is_the_same_on_both_backends():
    """The fused evaluation and sparse solve against the numpy reference path, over a heating
    run with contact: the same fold angle to 1e-9."""
    case = get_case("single_fold", gravity=True, residual_fold_deg=-10.0, thermal_steps=20)
    fused = case.run()
    with spring_kernel_backend("numpy"):
        ref = case.run()
    a, b = np.degrees(fused.fold_angle[-1]), np.degrees(ref.fold_angle[-1])
    np.testing.assert_allclose(a, b, rtol=1e-9)


# ----------------------------------------------------------------------------- linear solves


def _spd(n, density, seed):
    rng = np.random.default_rng(seed)
    A = sp.random(n, n, density=density, random_state=rng)
    A = (A + A.T).toarray()
    return A + np.diag(np.abs(A).sum(axis=1) + 1.0), rng.normal(size=n)


def _structure(K):
    rows, cols = np.nonzero(K)
    return SparseCholesky(rows, cols, len(K))


@pytest.mark.parametrize("n, density", [(1, 1.0), (2, 1.0), (40, 0.05), (120, 0.03)])
def test_sparse_cholesky_solves_like_lapack(n, density):
    K, r = _spd(n, density, n)
    chol = _structure(K)
    du = chol.solve(K, r)
    np.testing.assert_allclose(du, scipy.linalg.solve(K, r), rtol=1e-12, atol=1e-12)
    assert chol.nnz >= np.count_nonzero(np.tril(K))


def test_sparse_cholesky_condition_estimate_is_lapacks():
    """The compiled dlacn2 estimate on K: the same rcond as LAPACK's dpocon (the order of
    the unknowns aside, the same algorithm) on matrices from well to badly conditioned."""
    from simulator.linalg._cholesky_jit import cholesky_solve

    for seed, spread in enumerate((1.0, 1e6, 1e12)):
        K, r = _spd(60, 0.06, seed)
        d = np.logspace(0, np.log10(spread), len(K))
        K = K * np.sqrt(d)[:, None] * np.sqrt(d)[None, :]
        chol = _structure(K)
        du, work = np.empty(len(K)), np.empty(4 * len(K))
        rcond = cholesky_solve()(K, r, chol.order, chol.Lp, chol.Li, np.empty(chol.nnz),
                                 chol.rp, chol.rk, chol.rpos, du, work)
        c, _ = scipy.linalg.lapack.dpotrf(K)
        ref, _ = scipy.linalg.lapack.dpocon(c, np.abs(K).sum(axis=0).max())
        assert rcond == pytest.approx(ref, rel=1e-6)


def test_singular_ill_conditioned_and_indefinite_tangents():
    K, r = _spd(30, 0.1, 7)
    chol = _structure(K)
    singular = K.copy()
    singular[:, 3] = singular[3, :] = 0.0              # a free DOF with no stiffness
    for solve in (solve_dense, solve_linear, chol.solve):
        assert solve(singular, r) is None
    Q = np.linalg.qr(np.random.default_rng(0).normal(size=(30, 30)))[0]
    nearly = (Q * np.logspace(0, -17, 30)) @ Q.T      # SPD up to rounding, rcond ~1e-17
    for solve in (solve_dense, _structure(np.ones((30, 30))).solve):
        assert solve(nearly, r) is None
    indefinite = K - 1.5 * np.diag(np.diag(K)) * (np.arange(30) % 2)
    assert np.linalg.eigvalsh(indefinite).min() < 0
    expected = scipy.linalg.solve(indefinite, r)
    for solve in (solve_dense, chol.solve):           # LU with partial pivoting
        np.testing.assert_allclose(solve(indefinite, r), expected, rtol=1e-10)
    nan = K.copy()
    nan[2, 2] = np.nan
    assert solve_dense(nan, r) is None and chol.solve(nan, r) is None


def test_the_gripper_tangent_is_factored_sparsely():
    system, u, rest = _gripper_with_contacts()
    ev = system.evaluate(u, rest)                  # artificial contacts: an indefinite tangent
    r = -ev.f_int[system.free]
    expected = solve_dense(ev.tangent, r)
    du = system.solve_dense_tangent(ev, r)                       # (LU fallback, like solve_dense)
    assert (du is None) == (expected is None)
    chol = system._chol[0]
    assert chol.nnz < 0.3 * system.n_free ** 2                # sparse: far below dense
    assert system._chol[1][ev.contact_pairs].all()            # the active pairs are in it
    state = initial_state(system.model)                       # no contact: positive definite
    ev = system.evaluate(state.u, rest)
    r = np.random.default_rng(0).normal(size=system.n_free) * 1e-9
    du = system.solve_dense_tangent(ev, r)
    np.testing.assert_allclose(du, solve_dense(ev.tangent, r), rtol=1e-8)
    assert system._chol[0] is chol                            # structure kept
