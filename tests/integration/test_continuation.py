"""Arc length (MGDCM), displacement control and stability on a von Mises two-bar truss.

The truss: two bars (Green-Lagrange strain, axial stiffness EA) from supports at (-L, 0, 0)
and (L, 0, 0) to an apex at (0, 0, h) loaded downwards. With z the apex height, the load in
equilibrium is F(z) = EA z (h^2 - z^2) / l0^3 (l0 = sqrt(L^2 + h^2)), with limit points at
z = +-h / sqrt(3), F = +-2 EA h^3 / (3 sqrt(3) l0^3). The same continuation code that runs on
bar-and-hinge models runs on this bar-only system.
"""

from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp

from simulator.solvers import LoadPath, mgdcm
from simulator.solvers import control_displacement as displacement_control
from simulator.mechanics.elements.bars import bar_kernel
from simulator.errors import ParameterError
from simulator.solvers.stability import tangent_stability

L, H, EA = 1.0, 0.2, 1e3
L0 = np.hypot(L, H)
F_LIMIT = 2 * EA * H**3 / (3 * np.sqrt(3) * L0**3)


class Truss:
    """Bar-only system with the EquilibriumSystem interface (free DOFs: apex x and z)."""

    def __init__(self):
        self.nodes = np.array([[-L, 0, 0], [L, 0, 0], [0, 0, H]], float)
        self.bars = np.array([[0, 2], [1, 2]])
        self.free, self.n_dof, self.max_step = np.array([6, 8]), 9, None
        self.dX = self.nodes[self.bars[:, 1]] - self.nodes[self.bars[:, 0]]
        self.L0 = np.linalg.norm(self.dX, axis=1)
        self.dofs = (3 * self.bars[:, :, None] + np.arange(3)).reshape(-1, 6)

    def evaluate(self, u, rest, hessian=True):
        du = u[self.bars[:, 1]] - u[self.bars[:, 0]]
        _, g, Hs = bar_kernel(self.dX, du, self.L0, np.full(2, EA), hessian)
        f = np.bincount(self.dofs.ravel(), g.ravel(), minlength=9)
        K = None
        if hessian:
            rows = np.repeat(self.dofs, 6, axis=1).ravel()
            cols = np.tile(self.dofs, 6).ravel()
            Kf = sp.coo_matrix((Hs.ravel(), (rows, cols)), shape=(9, 9)).toarray()
            K = sp.csr_matrix(Kf[np.ix_(self.free, self.free)])
        return SimpleNamespace(f_int=f, K=K, energies={})


def load_of_height(z):
    return EA * z * (H**2 - z**2) / L0**3


@pytest.fixture
def path():
    P = np.zeros(9)
    P[8] = -1.0                                          # 1 N down at the apex
    return LoadPath(Truss(), np.zeros(9), P, np.zeros(0))


DOWN = np.zeros(9)
DOWN[8] = -1.0                                           # c . u = downward apex displacement


def test_arc_length_passes_both_limit_points(path):
    res = mgdcm(path, np.zeros((3, 3)), arc_length=0.2, max_increments=400,
                target_displacement=(DOWN, 2.5 * H), max_arc_length=0.4)
    assert res.success, res.message
    lam = np.array([h[0] for h in res.history])
    z = H + np.array([h[1][2, 2] for h in res.history])
    # every point is on the closed-form path
    np.testing.assert_allclose(lam, load_of_height(z), rtol=1e-8, atol=1e-9 * F_LIMIT)
    assert z[-1] == pytest.approx(-1.5 * H, rel=1e-10)                # ended at the target
    limits = [c for c in res.critical_points if c.kind == "limit_point"]
    assert len(limits) == 2
    assert limits[0].maximum and not limits[1].maximum
    assert limits[0].load_factor == pytest.approx(F_LIMIT, rel=5e-3)
    assert limits[1].load_factor == pytest.approx(-F_LIMIT, rel=5e-3)
    assert limits[0].displacement == pytest.approx(H - H / np.sqrt(3), rel=5e-2)
    # stable outside the limit points, one negative eigenvalue between them
    stable = np.array([s.stable for s in res.stability])
    inside = np.abs(z) < H / np.sqrt(3) * 0.98
    outside = np.abs(z) > H / np.sqrt(3) * 1.02
    assert not stable[inside].any() and stable[outside].all()
    assert {s.negative for s in np.array(res.stability)[inside]} == {1}
    assert not [c for c in res.critical_points if c.kind == "bifurcation"]


def test_arc_length_ends_at_target_load_factor(path):
    res = mgdcm(path, np.zeros((3, 3)), arc_length=0.3, target_load_factor=0.5 * F_LIMIT)
    assert res.success and res.load_factor == 0.5 * F_LIMIT
    z = H + res.u[2, 2]
    assert load_of_height(z) == pytest.approx(0.5 * F_LIMIT, rel=1e-10)
    assert z > H / np.sqrt(3)                            # on the first stable branch


def test_until_stable_ends_where_the_handover_accepts_the_stable_point(path):
    """``mgdcm(until_stable=True)`` ends at the first stable point past the snap; with
    ``handover`` it goes on along the stable branch to the first one that it accepts, and
    asks only at stable points past the snap, with each point's tangent and stability."""
    kw = dict(arc_length=0.2, max_increments=400, target_load_factor=3 * F_LIMIT,
              max_arc_length=0.4, until_stable=True)
    first = mgdcm(path, np.zeros((3, 3)), **kw)
    assert first.success and "stable again past the limit point" in first.message
    assert F_LIMIT < first.load_factor < 1.5 * F_LIMIT
    asked = []

    def handover(u, lam, point, st):
        assert st.stable and lam > F_LIMIT and point.K.shape == (2, 2)
        assert st.lowest == pytest.approx(np.linalg.eigvalsh(point.K.toarray())[0])
        asked.append((lam, u))
        return lam >= 1.5 * F_LIMIT

    res = mgdcm(path, np.zeros((3, 3)), handover=handover, **kw)
    assert res.success and "stable again past the limit point" in res.message
    assert 1.5 * F_LIMIT <= res.load_factor < 3 * F_LIMIT
    assert asked[-1][0] == res.load_factor and np.array_equal(asked[-1][1], res.u)
    assert [lam for lam, _ in asked[:-1]] == [h[0] for h in res.history[-len(asked):-1]]
    assert asked[0][0] == first.load_factor           # the same trace up to there
    z = H + res.u[2, 2]
    assert load_of_height(z) == pytest.approx(res.load_factor, rel=1e-8)


def test_displacement_control_traces_same_path(path):
    res = displacement_control(path, np.zeros((3, 3)), 0.0, DOWN, 2.5 * H, increments=100)
    assert res.success, res.message
    w = np.array([float(DOWN @ h[1].ravel()) for h in res.history])
    np.testing.assert_allclose(w, 2.5 * H * np.arange(1, 101) / 100, rtol=1e-12)
    lam = np.array([h[0] for h in res.history])
    np.testing.assert_allclose(lam, load_of_height(H - w), rtol=1e-8, atol=1e-9 * F_LIMIT)
    assert lam[w < H].max() == pytest.approx(F_LIMIT, rel=5e-3)       # sampled every 5 mm
    assert lam[w < 2 * H].min() == pytest.approx(-F_LIMIT, rel=5e-3)


def test_tangent_stability_counts_negative_eigenvalues():
    K = sp.diags([3.0, -1.0, 2.0, -0.5]).tocsr()
    st = tangent_stability(K)
    assert st.negative == 2 and not st.stable and st.lowest == -1.0
    assert st.load_alignment(np.array([0.0, 1.0, 0, 0])) == pytest.approx(1.0)
    assert st.load_alignment(np.array([1.0, 0, 0, 0])) == pytest.approx(0.0)


@pytest.mark.parametrize("arc", [0.0, -0.1, float("nan")])
def test_mgdcm_rejects_bad_arc_length(path, arc):
    with pytest.raises(ParameterError, match="arc_length"):
        mgdcm(path, np.zeros((3, 3)), arc_length=arc)


def test_displacement_control_rejects_supported_dof(path):
    c = np.zeros(9)
    c[2] = 1.0                                           # z of support node 0
    with pytest.raises(ParameterError, match="supported DOF"):
        displacement_control(path, np.zeros((3, 3)), 0.0, c, 0.1)


def test_displacement_control_rejects_uncontrollable_dof(path):
    c = np.zeros(9)
    c[6] = 1.0                                           # apex x: a vertical load never moves it
    with pytest.raises(ParameterError, match="cannot be controlled"):
        displacement_control(path, np.zeros((3, 3)), 0.0, c, 0.1)


class Column(Truss):
    """One vertical bar (EA, length 1) on a pin, its top held sideways by a spring k = 1 N/m:
    under a vertical load it bifurcates (buckles sideways) at N = k L = 1 N."""

    def __init__(self):
        super().__init__()
        self.nodes = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 1.0]])
        self.bars = np.array([[0, 2]])
        self.dX = self.nodes[[2]] - self.nodes[[0]]
        self.L0 = np.linalg.norm(self.dX, axis=1)
        self.dofs = self.dofs[:1]

    def evaluate(self, u, rest, hessian=True):
        du = u[[2]] - u[[0]]
        _, g, Hs = bar_kernel(self.dX, du, self.L0, np.full(1, EA), hessian)
        f = np.bincount(self.dofs.ravel(), g.ravel(), minlength=9)
        f[6] += 1.0 * u[2, 0]                                # lateral spring
        K = None
        if hessian:
            Kf = np.zeros((9, 9))
            Kf[np.ix_(self.dofs[0], self.dofs[0])] = Hs[0]
            Kf[6, 6] += 1.0
            K = sp.csr_matrix(Kf[np.ix_(self.free, self.free)])
        return SimpleNamespace(f_int=f, K=K, energies={})


def test_bifurcation_located_on_the_primary_path():
    P = np.zeros(9)
    P[8] = -1.0
    path = LoadPath(Column(), np.zeros(9), P, np.zeros(0))
    res = mgdcm(path, np.zeros((3, 3)), arc_length=0.1, target_load_factor=2.0,
                max_arc_length=0.1)
    assert res.success
    kinds = [c.kind for c in res.critical_points]
    assert kinds == ["bifurcation"]
    # lateral stiffness k - N / L with N = EA eps (1 + eps) ... zero at N ~ 1 N
    assert res.critical_points[0].load_factor == pytest.approx(1.0, abs=0.06)
    assert res.stability[0].stable and not res.stability[-1].stable


def test_load_derivative_exact_when_the_rest_change_crosses_the_spring_kink():
    """q = dr/dlambda of a rest-angle path whose unit change R (here 4 rad) would carry the
    rest angle past the kink of the spring law at theta0 +- pi (issue 18: the unit-lambda
    secant was wrong there, and the arc-length corrector converged linearly)."""
    from simulator import get_case
    from simulator.mechanics.equilibrium import EquilibriumSystem

    model = get_case("single_fold").model
    system = EquilibriumSystem(model)
    rest0 = np.full(model.mesh.springs.shape[0], np.pi)
    path = LoadPath(system, np.zeros(model.mesh.n_dof), np.zeros(model.mesh.n_dof), rest0,
                    np.full(rest0.shape, 4.0))
    u = np.zeros((model.mesh.n_nodes, 3))
    pt = path.at(u, 0.1)
    h = 1e-6
    fd = (path.at(u, 0.1 + h).r - path.at(u, 0.1 - h).r) / (2 * h)
    assert np.linalg.norm(fd - pt.q) <= 1e-6 * np.linalg.norm(pt.q)
