"""Branch switching of the continuation driver at a pitchfork with a closed-form answer.

A node with free DOFs (x, y) and potential energy

    E(x, y) = x^2 / 2 + (1 - x) y^2 / 2 + c y^4 / 4,    load lambda along x,

has the fundamental branch y = 0, x = lambda, whose tangent diag(1, 1 - lambda) loses
stability at lambda = 1 (critical mode along y, orthogonal to the load: a bifurcation), and,
for c > 1/2, the stable branches x = 1 + c y^2 ... here (c = 1) x = 1 + y^2, lambda = 1 + y^2 / 2
(Hessian determinant y^2 (2c - 1) > 0). Newton never leaves y = 0 by itself (it is exactly
invariant); ``mgdcm(switch_branches=True)`` must find the bifurcation and follow the stable
branch.
"""

from types import SimpleNamespace

import numpy as np
import pytest

from simulator.solvers import LoadPath, mgdcm
from simulator.solvers.descent import descend, switch_branch
from simulator.solvers.newton import NewtonOptions
from simulator.solvers.stability import tangent_stability

C = 1.0


class Pitchfork:
    """Two nodes, node 0 fixed, node 1 free in x and y (the EquilibriumSystem interface)."""

    def __init__(self):
        self.nodes = np.array([[0.0, 0, 0], [1.0, 0, 0]])
        self.free, self.n_dof, self.max_step = np.array([3, 4]), 6, None

    def evaluate(self, u, rest, hessian=True):
        x, y = u[1, 0], u[1, 1]
        f = np.zeros(6)
        f[3], f[4] = x - 0.5 * y**2, y * (1 - x) + C * y**3
        K = np.array([[1.0, -y], [-y, 1 - x + 3 * C * y**2]]) if hessian else None
        e = 0.5 * x**2 + 0.5 * (1 - x) * y**2 + 0.25 * C * y**4
        return SimpleNamespace(f_int=f, K=K, energies={"toy": e})


@pytest.fixture
def path():
    P = np.zeros(6)
    P[3] = 1.0
    return LoadPath(Pitchfork(), np.zeros(6), P, np.zeros(0))


def test_without_switching_the_path_stays_on_the_unstable_fundamental_branch(path):
    res = mgdcm(path, np.zeros((2, 3)), arc_length=0.1, target_load_factor=1.5)
    assert res.success and res.load_factor == 1.5
    assert res.u[1, 1] == 0.0 and res.u[1, 0] == pytest.approx(1.5, rel=1e-10)
    assert not res.stability[-1].stable and res.jumps == ()
    assert [c.kind for c in res.critical_points] == ["bifurcation"]


def test_switching_follows_the_stable_branch_from_the_bifurcation(path):
    res = mgdcm(path, np.zeros((2, 3)), arc_length=0.1, target_load_factor=1.5,
                switch_branches=True)
    assert res.success, res.message
    x, y = res.u[1, 0], res.u[1, 1]
    # on the stable branch: lambda = 1 + y^2 / 2 = 1.5, x = 1 + y^2 (the push takes y > 0)
    assert y == pytest.approx(1.0, rel=1e-8) and x == pytest.approx(2.0, rel=1e-8)
    assert res.stability[-1].stable
    (before, after, kind), = res.jumps
    assert kind == "bifurcation" and after == before + 2
    lam_b = res.history[after][0]
    assert res.history[before][0] < 1.0 < lam_b <= 1.0 + 0.1 / 16 + 1e-12  # located
    bif = [c for c in res.critical_points if c.kind == "bifurcation"]
    assert len(bif) == 1 and bif[0].load_factor == pytest.approx(1.0, abs=0.1 / 16)
    # every point after the jump is a stable point of the closed-form branch
    for lam, u, _ in res.history[after:]:
        assert lam == pytest.approx(1 + 0.5 * u[1, 1]**2, rel=1e-8)
        assert u[1, 0] == pytest.approx(1 + u[1, 1]**2, rel=1e-8)


def test_switch_branch_lands_on_the_stable_equilibrium_at_the_load(path):
    lam = 1.2                                     # fundamental branch unstable here
    u = np.zeros((2, 3))
    u[1, 0] = lam
    st = tangent_stability(path.at(u, lam).K)
    assert st.negative == 1
    w = switch_branch(path, u, lam, st.mode, NewtonOptions())
    assert w[1, 1] == pytest.approx(np.sqrt(2 * (lam - 1)), rel=1e-8)
    assert w[1, 0] == pytest.approx(1 + 2 * (lam - 1), rel=1e-8)
    assert tangent_stability(path.at(w, lam).K).stable
    # descend from a point near the stable branch stays there
    near = w.copy()
    near[1, :2] += 1e-3
    v = descend(path, near, lam, NewtonOptions())
    np.testing.assert_allclose(v, w, atol=1e-10)


def test_locating_without_switching_bisects_to_the_bifurcation(path):
    """``locate_stability_loss`` bisects the arc length where stability is lost while the
    load factor goes on, and stays on the (unstable) branch it follows."""
    plain = mgdcm(path, np.zeros((2, 3)), arc_length=0.1, target_load_factor=1.5)
    res = mgdcm(path, np.zeros((2, 3)), arc_length=0.1, target_load_factor=1.5,
                locate_stability_loss=True)
    assert res.success and res.u[1, 1] == 0.0 and res.jumps == ()
    lam = np.array([h[0] for h in res.history])
    stable = np.array([s.stable for s in res.stability])
    k = int(np.argmin(stable))                           # first unstable point
    assert lam[k - 1] < 1.0 < lam[k] and lam[k] - lam[k - 1] <= 0.1 / 16 + 1e-12
    (bif,) = res.critical_points
    assert bif.kind == "bifurcation" and abs(bif.load_factor - 1.0) <= 0.1 / 32 + 1e-12
    (coarse,) = plain.critical_points
    assert abs(coarse.load_factor - 1.0) > abs(bif.load_factor - 1.0)


@pytest.mark.parametrize("arc_length", [0.1, 0.07, 0.13])
def test_locating_with_stop_ends_at_the_first_unstable_point(path, arc_length):
    """``locate_stability_loss="stop"`` ends the run (success) at the located first unstable
    point, the last stable one before it: within arc_length / 16 of the bifurcation at
    lambda = 1 whatever the arc length the path arrived with (what a restart from there,
    as the heating continuation makes, relies on)."""
    res = mgdcm(path, np.zeros((2, 3)), arc_length=arc_length, target_load_factor=1.5,
                locate_stability_loss="stop")
    assert res.success and res.status == "stability_lost"
    assert res.message.startswith(f"stability lost at load factor {res.load_factor:.6g}")
    assert not res.stability[-1].stable and res.stability[-2].stable
    (lam_s, u_s, _), (lam_u, u_u, _) = res.history[-2:]
    assert lam_s < 1.0 < lam_u == res.load_factor and lam_u - lam_s <= arc_length / 16 + 1e-12
    assert u_u[1, 0] == pytest.approx(lam_u, rel=1e-12) and u_u[1, 1] == 0.0
    assert [c.kind for c in res.critical_points] == ["bifurcation"]


def test_locating_with_stop_runs_on_where_stability_is_never_lost(path):
    """Short of the bifurcation, ``"stop"`` changes nothing: the same points as a plain run."""
    plain = mgdcm(path, np.zeros((2, 3)), arc_length=0.1, target_load_factor=0.9)
    res = mgdcm(path, np.zeros((2, 3)), arc_length=0.1, target_load_factor=0.9,
                locate_stability_loss="stop")
    assert res.success and res.load_factor == 0.9 and res.stability[-1].stable
    assert [h[0] for h in res.history] == [h[0] for h in plain.history]


def test_locate_stability_loss_rejects_unknown_values(path):
    from simulator.errors import ParameterError
    with pytest.raises(ParameterError, match="locate_stability_loss"):
        mgdcm(path, np.zeros((2, 3)), locate_stability_loss="halt")
