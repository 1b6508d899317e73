"""Arc length at a flat fold: a limit point whose load factor stays near its maximum over a
long stretch of the path (the gripper's arm tips snap at such a fold).

A node with free DOFs (x, y) and internal force ``f_x = x (1 - x / L)^2``, ``f_y = y`` under
a load lambda along x: the path ``lambda = x (1 - x / L)^2`` has its maximum 4 L / 27 at
x = L / 3 and its minimum 0 at x = L; near the maximum ``lambda ~ 4 L / 27 - (x - L / 3)^2 / L``,
so for a large L the load factor stays within a resolution r of the maximum over
``2 sqrt(r L)`` of x: the arc length at the initial rate (x per unit lambda = 1) that capped
its steps at r there took ``2 sqrt(L / r)`` increments (310 for L = 3000, r = 1/8).
"""

from types import SimpleNamespace

import numpy as np
import pytest

from simulator.solvers import LoadPath, mgdcm

RESOLUTION = 1 / 8


class Fold:
    """Two nodes, node 0 fixed, node 1 free in x and y (the EquilibriumSystem interface)."""

    def __init__(self, length):
        self.L = length
        self.nodes = np.array([[0.0, 0, 0], [1.0, 0, 0]])
        self.free, self.n_dof, self.max_step = np.array([3, 4]), 6, None

    def load(self, x):
        return x * (1 - x / self.L) ** 2

    def evaluate(self, u, rest, hessian=True):
        x, y, L = u[1, 0], u[1, 1], self.L
        f = np.zeros(6)
        f[3], f[4] = self.load(x), y
        K = np.diag([1 - 4 * x / L + 3 * x**2 / L**2, 1.0]) if hessian else None
        e = x**2 / 2 - 2 * x**3 / (3 * L) + x**4 / (4 * L**2) + y**2 / 2
        return SimpleNamespace(f_int=f, K=K, energies={"toy": e})


def fold_path(length):
    P = np.zeros(6)
    P[3] = 1.0
    return LoadPath(Fold(length), np.zeros(6), P, np.zeros(0))


def along_x():
    c = np.zeros(6)
    c[3] = 1.0
    return c


def test_a_flat_fold_is_passed_in_a_few_increments_and_located_at_the_resolution():
    """L = 3000 from x = L/3 - 20 to L/3 + 20 (arc length 1, at most 4 per increment): 16
    increments; with the arc length capped at the resolution while the load factor was within
    it of the maximum's, 173. The maximum is still located well within the resolution."""
    L = 3000.0
    system = fold_path(L)
    x0 = L / 3 - 20
    u0 = np.zeros((2, 3))
    u0[1, 0] = x0
    res = mgdcm(system, u0, system.system.load(x0), arc_length=1.0, step_norm=1.0,
                resolution=RESOLUTION, target_displacement=(along_x(), L / 3 + 20),
                max_increments=1000, monitor=along_x())
    assert res.success and len(res.history) < 30
    (top,) = res.critical_points
    assert top.kind == "limit_point" and top.maximum
    assert top.load_factor == pytest.approx(4 * L / 27, abs=1e-3 * RESOLUTION)
    assert top.displacement == pytest.approx(L / 3, abs=RESOLUTION)


def test_a_run_that_runs_out_of_increments_past_a_maximum_jumps_where_the_snap_lands():
    """``lost_fold_jump``: 40 increments end on the unstable branch past the maximum (x = 100,
    L = 300); the run lands by energy descent on the far stable branch (x > L) at the
    resolution above the highest point reached, with success."""
    L = 300.0
    system = fold_path(L)
    res = mgdcm(system, np.zeros((2, 3)), arc_length=1.0, resolution=RESOLUTION,
                target_load_factor=4 * L / 27 + 1, max_increments=40, monitor=along_x(),
                lost_fold_jump=RESOLUTION)
    assert res.success and "target not reached in 40 increments" in res.message
    assert "jump from load factor" in res.message
    peak = max(h[0] for h in res.history)
    assert res.load_factor == pytest.approx(peak + RESOLUTION, rel=1e-12)
    x = res.u[1, 0]
    assert x > 4 * L / 3 and system.system.load(x) == pytest.approx(res.load_factor, rel=1e-9)
    without = mgdcm(system, np.zeros((2, 3)), arc_length=1.0, resolution=RESOLUTION,
                    target_load_factor=4 * L / 27 + 1, max_increments=40, monitor=along_x())
    assert not without.success and without.status == "failed"


def _wiggle(stable):
    """A continuation result: two maxima 2e-8 apart with a dip of 1e-8 between them (the
    corrector's load factor at a flat top), then a fall by 0.13 and a rise past them;
    ``stable`` per point."""
    from simulator.solvers.path_trace import CriticalPoint

    lams = (0.5, 0.52270001, 0.52270000, 0.52270002, 0.52269, 0.39, 0.45, 0.53)
    u = [np.array([[0.0, 0, 0], [1e-6 * k, 0, 0]]) for k in range(len(lams))]
    first = CriticalPoint("limit_point", 0.52270001, 2, 1e-6, maximum=True)
    dip = CriticalPoint("limit_point", 0.52270000, 3, 2e-6, maximum=False)
    second = CriticalPoint("limit_point", 0.52270002, 4, 3e-6, maximum=True)
    low = CriticalPoint("limit_point", 0.39, 6, 5e-6, maximum=False)
    return SimpleNamespace(history=[(lam, v, 2) for lam, v in zip(lams, u)],
                           critical_points=(first, dip, second, low), jumps=(),
                           stability=[SimpleNamespace(stable=s) for s in stable])


def test_a_wiggle_of_the_load_factor_at_a_flat_top_is_no_snap():
    """One snap, from the second maximum: the path from the first crosses its load factor
    again on stable points within 1e-8 of it; from the second it falls by 0.13 (or, with a
    drop above that, it is unstable on the way)."""
    from simulator.steps.limit import _snaps

    c = np.zeros(6)
    c[3] = 1.0
    res = _wiggle([True] * 4 + [False, False, True, True])
    ((p, after),) = _snaps(res, c, drop=RESOLUTION / 100)
    assert p is res.critical_points[2] and 6e-6 < after < 7e-6   # between 0.45 and 0.53
    assert [q for q, _ in _snaps(res, c, drop=1.0)] == [p]       # unstable on the way
    assert len(_snaps(res, c)) == 2                              # every turn, without a drop
    assert _snaps(_wiggle([True] * 8), c, drop=1.0) == []        # stable, fell by < 1
