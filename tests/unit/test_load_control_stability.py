"""Load control checks every accepted state and leaves an unstable one (theory 6.12).

The pitchfork of tests/unit/test_branch_switch.py (node with free DOFs x, y, energy
E = x^2/2 + (1 - x) y^2/2 + y^4/4, load lambda along x): the fundamental branch y = 0 is exactly
invariant under Newton, stable up to lambda = 1 and unstable after; the stable branches are
x = 1 + y^2, lambda = 1 + y^2 / 2. Load control to lambda = 1.5 must end on them (y = +-1,
x = 2) whatever the increment count, and report the switch.
"""

from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp

from simulator.linalg.ladder import factorize
from simulator.solvers.newton import NewtonOptions, follow_path
from simulator.solvers.stability import quick_stability, tangent_stability


class Pitchfork:
    """Two nodes, node 0 fixed, node 1 free in x and y (the EquilibriumSystem interface)."""

    size, max_step = 1.0, None

    def __init__(self):
        self.nodes = np.array([[0.0, 0, 0], [1.0, 0, 0]])
        self.free, self.n_dof = np.array([3, 4]), 6

    def evaluate(self, u, rest, hessian=True):
        x, y = u[1, 0], u[1, 1]
        f = np.zeros(6)
        f[3], f[4] = x - 0.5 * y**2, y * (1 - x) + y**3
        K = np.array([[1.0, -y], [-y, 1 - x + 3 * y**2]]) if hessian else None
        e = 0.5 * x**2 + 0.5 * (1 - x) * y**2 + 0.25 * y**4
        return SimpleNamespace(f_int=f, K=K, energies={"toy": e})


def _run(increments, **options):
    f_end = np.zeros(6)
    f_end[3] = 1.5
    return follow_path(Pitchfork(), np.zeros((2, 3)), np.zeros(6), f_end, np.zeros(0),
                       np.zeros(0), increments, NewtonOptions(**options))


@pytest.mark.parametrize("increments", [2, 3, 7, 15, 40])  # 3, 15: through lambda = 1
def test_load_control_ends_on_the_stable_branch_at_any_increment_count(increments):
    res = _run(increments)
    assert res.success and res.stable is True
    x, y = res.u[1, 0], res.u[1, 1]
    # a tie (E is even in y): the critical mode's positive sign, y > 0
    assert y == pytest.approx(1.0, rel=1e-8) and x == pytest.approx(2.0, rel=1e-8)
    sw, = res.switches
    assert sw.switched and sw.choice.tie and sw.choice.sign == 1
    if increments % 3:                       # the first state past lambda = 1: unstable
        assert sw.t > 2 / 3 and sw.unstable.negative == 1
    else:               # an increment ends exactly at lambda = 1 (a singular tangent): the
        assert sw.t == pytest.approx(2 / 3 + 1 / increments)    # next one leaves it
        assert sw.unstable.negative == 0 and sw.unstable.lowest == 0.0
    assert "NewtonOptions(branch='other')" in sw.describe()


def test_the_other_branch_on_request():
    res = _run(10, branch="other")
    assert res.success and res.stable is True
    assert res.u[1, 1] == pytest.approx(-1.0, rel=1e-8)


def test_check_only_reports_the_unstable_state():
    res = _run(10, stability="check")
    assert res.u[1, 1] == 0.0 and res.u[1, 0] == pytest.approx(1.5)
    assert res.stable is False
    assert [s.switched for s in res.switches] == [False] and res.switches[0].t == 0.7


def test_off_checks_nothing():
    res = _run(10, stability="off")
    assert res.stable is None and res.switches == [] and res.u[1, 1] == 0.0


def test_options_are_checked():
    with pytest.raises(Exception, match="NewtonOptions.stability"):
        NewtonOptions(stability="yes")
    with pytest.raises(Exception, match="NewtonOptions.branch"):
        NewtonOptions(branch="upper")


def _spd(n, seed=0):
    a = np.random.default_rng(seed).normal(size=(n, n))
    return a @ a.T + n * np.eye(n)


def test_quick_stability_is_cheap_on_a_positive_definite_tangent_and_exact_otherwise():
    K = _spd(30)
    st = quick_stability(K)
    assert st.stable and st.lowest is None and st.mode is None
    K[0, 0] = -5.0 * K[0, 0]
    st = quick_stability(K)
    w = np.linalg.eigvalsh(K)
    assert not st.stable and st.negative == int(np.sum(w < 0))
    assert st.lowest == pytest.approx(w[0])


def test_a_mechanism_zero_eigenvalue_is_not_a_loss_of_stability():
    # rank-deficient positive semi-definite: the zero eigenvalue with round-off
    a = np.random.default_rng(1).normal(size=(40, 39))
    K = a @ a.T
    assert np.linalg.eigvalsh(K)[0] < 1e-12
    assert quick_stability(K).stable
    assert tangent_stability(K, rtol=100.0).stable


def test_superlu_gives_the_inertia_of_a_symmetric_indefinite_matrix():
    n = 900
    A = sp.random(n, n, density=0.01, random_state=3)
    A = (A + A.T + sp.diags(np.linspace(-3.0, 50.0, n))).tocsr()
    w = np.linalg.eigvalsh(A.toarray())
    factor = factorize(A, kind="symmetric", backend="superlu")
    assert factor.backend.startswith("superlu")
    assert factor.inertia == (int(np.sum(w > 0)), int(np.sum(w < 0)), 0)
    st = quick_stability(A, linear_solver="superlu")
    assert st.negative == int(np.sum(w < 0)) or not st.exact


# ------------------------------------------- a bifurcation passed between two stable states
def test_an_increment_that_turns_sharply_is_measured_against_the_path_direction():
    from simulator.solvers.newton import TURN_TOLERANCE, _turns

    u0 = np.zeros((2, 3))
    slope = np.zeros((2, 3))
    slope[1, 0] = 1.0                                   # the path went along x
    ahead, aside = u0.copy(), u0.copy()
    ahead[1, 0], aside[1] = 0.1, [0.1, 0.1, 0.0]
    assert not _turns(ahead, u0, slope, 0.1)           # straight on
    assert _turns(aside, u0, slope, 0.1)               # |(0, 0.1)| / |(0.1, 0.1)| = 0.71
    tilt = u0.copy()
    tilt[1] = [0.1, 0.1 * TURN_TOLERANCE * 0.9, 0.0]
    assert not _turns(tilt, u0, slope, 0.1)


def test_the_turn_test_decides_as_with_numpys_norms():
    """_turns takes sqrt(v . v) for np.linalg.norm(v) (what norm computes): the same floats, so
    the same decision, at random and on the tolerance's boundary (found by bisection)."""
    from simulator.solvers.newton import TURN_TOLERANCE, _turns

    def by_norms(u_new, u_old, slope, dt):
        du, pred = u_new - u_old, slope * dt
        scale = max(float(np.linalg.norm(du)), float(np.linalg.norm(pred)))
        return scale > 0 and float(np.linalg.norm(du - pred)) > TURN_TOLERANCE * scale

    rng = np.random.default_rng(8)
    cases = [(np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((4, 3)), 0.3)]    # scale 0
    for _ in range(300):
        u_old, slope = rng.normal(size=(2, 7, 3)) * 1e-5
        u_new = u_old + 0.2 * slope + rng.normal(size=(7, 3)) * 1e-6 * rng.uniform(0, 3)
        cases.append((u_new, u_old, slope, 0.2))
    u_old, slope, side = rng.normal(size=(3, 7, 3))
    lo, hi = 0.0, 1.0                   # u_new = u_old + slope dt + s side: the turn's edge
    for _ in range(80):
        s = 0.5 * (lo + hi)
        lo, hi = (lo, s) if by_norms(u_old + 0.5 * slope + s * side, u_old, slope, 0.5) else \
            (s, hi)
    cases += [(u_old + 0.5 * slope + s * side, u_old, slope, 0.5) for s in (lo, hi)]
    decisions = [by_norms(*c) for c in cases]
    assert [_turns(*c) for c in cases] == decisions and True in decisions and \
        False in decisions


def _ends(lam):
    f = np.zeros(6)
    f[3] = lam
    return (np.zeros(6), f, np.zeros(0), np.zeros(0))


def test_a_turn_before_a_bifurcation_is_left_along_the_soft_mode_and_not_before_a_limit():
    """At x = lambda = 0.99 the pitchfork's fundamental state is stable, its soft mode (y)
    orthogonal to the load (x): a bifurcation lies ahead. An increment to lambda = 1.2 that
    Newton took to the y < 0 branch is replaced by the branch the critical mode's choice
    gives (a tie: y > 0), recorded as a switch."""
    from simulator.solvers.branches import leave_turn, soft_mode
    from simulator.solvers.newton import newton

    system, opts = Pitchfork(), NewtonOptions()
    u = np.zeros((2, 3))
    u[1, 0] = 0.99
    st = soft_mode(system, u, None, 0.99, _ends(1.0), opts)
    assert st is not None and st.lowest == pytest.approx(0.01)
    assert abs(st.mode[1]) == pytest.approx(1.0)
    start = u.copy()
    start[1, 1] = -0.5
    f = np.zeros(6)
    f[3] = 1.2
    below = newton(system, start, f, np.zeros(0), opts)
    assert below.success and below.u[1, 1] < -0.5             # Newton's branch: y < 0
    switches = []
    res, landed = leave_turn(system, below, u, st, 1.2, _ends(1.0), opts, switches)
    assert landed.stable and res.u[1, 1] == pytest.approx(np.sqrt(0.4), rel=1e-8)
    (sw,) = switches
    assert sw.switched and sw.choice.tie
    assert "a bifurcation passed between two stable states" in sw.describe()


class Fold:
    """One free DOF x with E = x^2/2 - x^3/3 under a load along x: a limit point at x = 1/2
    (lambda = 1/4), where the soft mode is along the load."""

    size, max_step = 1.0, None

    def __init__(self):
        self.nodes = np.array([[0.0, 0, 0], [1.0, 0, 0]])
        self.free, self.n_dof = np.array([3]), 6

    def evaluate(self, u, rest, hessian=True):
        x = u[1, 0]
        f = np.zeros(6)
        f[3] = x - x**2
        return SimpleNamespace(f_int=f, K=np.array([[1.0 - 2 * x]]) if hessian else None,
                               energies={"toy": 0.5 * x**2 - x**3 / 3})


def test_a_turn_before_a_limit_point_is_left_to_the_limit_point_handling():
    from simulator.solvers.branches import soft_mode

    u = np.zeros((2, 3))
    u[1, 0] = 0.45
    assert soft_mode(Fold(), u, None, 1.0, _ends(0.2475), NewtonOptions()) is None


class Mechanism(Pitchfork):
    """Node 1 held by a spring along x only: y is a zero-stiffness mode (a mechanism)."""

    def evaluate(self, u, rest, hessian=True):
        x = u[1, 0]
        f = np.zeros(6)
        f[3] = x
        K = np.array([[1.0, 0.0], [0.0, 0.0]]) if hessian else None
        return SimpleNamespace(f_int=f, K=K, energies={"toy": 0.5 * x**2})


def test_a_path_that_gives_up_names_the_critical_state_it_gave_up_at():
    """Issue 28 (FOLD corpus: Rabbit Ear's crane-cp, flat-folder's Pig and Kirby ended 'gave up
    at t = ...: no convergence' with no cause): the message says what the last state is, here
    critical (a zero eigenvalue) with its mode across the load."""
    f_end = np.zeros(6)
    f_end[3] = 1.0
    res = follow_path(Mechanism(), np.zeros((2, 3)), np.zeros(6), f_end, np.zeros(0),
                      np.zeros(0), 4, NewtonOptions())
    assert not res.success and res.status == "failed"
    assert "the state there is critical, a bifurcation" in res.message
    assert "lowest eigenvalue 0 N/m, zero within round-off" in res.message
    off = follow_path(Mechanism(), np.zeros((2, 3)), np.zeros(6), f_end, np.zeros(0),
                      np.zeros(0), 4, NewtonOptions(stability="off"))
    assert "critical" not in off.message                   # not analysed: checks nothing


def test_a_heating_increment_records_its_branch_switch_at_its_own_record():
    """A heating increment is one record whatever its sub-increments after step cuts (issue 28
    follow-up): a loss of stability found in its second of three sub-increments is an event
    at that record, not two records further on (``note_stability(one_record=True)``)."""
    from simulator import get_case, simulate
    from simulator.solvers.branches import BranchSwitch
    from simulator.solvers.stability import Stability
    from simulator.steps.base import StepRecorder

    start = simulate(get_case("single_fold", thermal_steps=1).model, []).state
    lost = BranchSwitch(0.5, Stability(negative=1, lowest=-2.0, mode=None))
    path = SimpleNamespace(switches=[lost], stable=False,
                           history=[(t, start.u, 1) for t in (0.25, 0.5, 1.0)])
    for one_record, expected in ((True, 3), (False, 4)):
        rec = StepRecorder(start)
        for _ in range(3):                               # three increments recorded before
            rec.record(0.0, start.u, start.temperature, start.crease_power)
        rec.note_stability(path, start.temperature, start.crease_power,
                           lambda t: 0.4 + 0.1 * t, one_record=one_record)
        (event,) = rec.events
        assert event.kind == "stability_lost" and event.load_factor == pytest.approx(0.45)
        assert event.increment == expected and rec.stable is False
