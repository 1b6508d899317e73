"""The one Newton iteration and the one cut-and-retry driver (simulator.solvers.nonlinear):
stopping tests, step limit, failures as data, halving and growing back, and that the solvers
use them instead of loops of their own."""

import pathlib
import re

import numpy as np
import pytest

from types import SimpleNamespace as NS

from simulator.solvers.nonlinear import GROWTH_PATIENCE, ROUND_OFF, bisect, iterate, limit_step, march

ROOT = pathlib.Path(__file__).resolve().parents[2]


class Cubic:
    """r(x) = b - (x + x^3) per component, tangent 1 + 3 x^2: a stiffening spring."""

    def __init__(self, b, singular_at=None):
        self.x, self.b, self.lam, self.singular_at = np.zeros(len(b)), np.asarray(b), 0.0, \
            singular_at
        self.evaluations = 0

    def evaluate(self):
        self.evaluations += 1
        return self.b - (self.x + self.x ** 3), self.x.copy()

    def correct(self, x, r):
        if self.singular_at is not None and self.evaluations > self.singular_at:
            return "tangent is singular"
        return r / (1 + 3 * x ** 2)

    def apply(self, dx, scale):
        self.x += dx
        self.lam += scale


def test_iterate_converges_quadratically_on_the_residual():
    p = Cubic([2.0, 10.0])
    out = iterate(p, max_iter=30, atol=1e-14, rtol=0.0, size=1e-6)     # floor below the test
    assert out.success and out.message == "converged" and out.reason == "converged"
    np.testing.assert_allclose(p.x + p.x ** 3, [2.0, 10.0], rtol=0, atol=1e-14)
    assert out.residual_norms[-1] <= 1e-14 and len(out.residual_norms) == out.iterations + 1
    r = out.residual_norms
    assert r[-2] <= 10 * r[-3] ** 2          # quadratic near the solution


def test_displacement_criterion_and_round_off_floor():
    p = Cubic([2.0])
    out = iterate(p, max_iter=30, atol=0.0, rtol=1e-6, size=1.0, criterion="displacement")
    assert out.success and out.message == "converged"
    assert out.correction_norms[-1] <= 1e-6 * out.correction_norms[0]
    assert len(out.residual_norms) == out.iterations        # the last evaluation not recorded
    p = Cubic([2.0])                                         # a large model: its floor is high
    out = iterate(p, max_iter=30, atol=0.0, rtol=0.0, size=1e10, record_final=True)
    assert out.success and out.message == "converged (correction at round-off level)"
    assert out.correction_norms[-1] <= ROUND_OFF * 1e10 < out.correction_norms[-2]
    assert len(out.residual_norms) == out.iterations + 1    # record_final: it is


def test_failures_are_data():
    out = iterate(Cubic([2.0]), max_iter=2, atol=1e-14, rtol=0.0, size=1.0)
    assert not out.success and out.reason == "max_iter" and out.iterations == 2
    assert out.message.startswith("no convergence in 2 iterations (last residual")
    out = iterate(Cubic([2.0], singular_at=2), max_iter=30, atol=1e-14, rtol=0.0, size=1.0)
    assert (out.success, out.reason, out.message, out.iterations) == (
        False, "no correction", "tangent is singular", 2)
    p = Cubic([np.nan])
    out = iterate(p, max_iter=30, atol=1e-14, rtol=0.0, size=1.0)
    assert out.reason == "not finite" and out.message == "residual is not finite"


class Oscillating(Cubic):
    """A residual that falls, then rises again: Newton on it never converges."""

    norms = (3.0, 1.0, 2.0, 1.0, 4.0)

    def evaluate(self):
        self.evaluations += 1
        return np.array([self.norms[self.evaluations - 1]]), self.evaluations

    def correct(self, point, r):
        return np.array([0.5])


def test_keep_best_returns_the_first_smallest_residual_when_out_of_corrections():
    p = Oscillating([0.0])
    out = iterate(p, max_iter=4, atol=1e-14, rtol=0.0, size=1.0, keep_best=p.x.copy)
    assert out.reason == "max_iter" and out.residual_norms == list(Oscillating.norms)
    rn, point, state = out.best
    assert (rn, point) == (1.0, 2)                 # evaluation 2, not the equal one at 4
    assert np.array_equal(state, [0.5])            # the iterate then (one correction applied)
    assert state is not p.x                        # a copy, not the live iterate
    assert iterate(Oscillating([0.0]), max_iter=4, atol=1e-14, rtol=0.0, size=1.0).best is None
    p = Cubic([2.0])
    assert iterate(p, max_iter=30, atol=1e-14, rtol=0.0, size=1.0, keep_best=p.x.copy).best \
        is None                                    # converged: nothing to fall back on


def test_step_limit_scales_the_correction_and_reports_the_factor():
    dx = np.array([3.0, -6.0])
    assert limit_step(dx, None) == (1.0, 6.0) and limit_step(dx, 10.0) == (1.0, 6.0)
    scale, step = limit_step(dx, 2.0)
    assert scale == pytest.approx(1 / 3) and step == 2.0 and np.allclose(dx, [1.0, -2.0])
    p = Cubic([1e3])
    out = iterate(p, max_iter=100, atol=1e-9, rtol=0.0, size=1.0, max_step=0.5)
    assert out.success
    assert max(out.correction_norms) <= 0.5 + 1e-15          # no correction longer than that
    assert p.lam < len(out.correction_norms)                 # some were scaled down


def test_march_halves_failures_and_grows_back():
    tried = []

    def attempt(t):
        tried.append(round(t, 6))
        return not (t == 0.5 and t - tried_from[0] > 0.2), t

    tried_from = [0.0]

    def accept(t, outcome):
        tried_from[0] = t
        return False
    run = march(attempt, accept, 4, max_cuts=5, max_total_cuts=20)
    assert run.status == "converged" and run.t == 1.0 and run.cuts == 1
    assert tried == [0.25, 0.5, 0.375, 0.5, 0.75, 1.0]    # halved once at 0.5, then doubled


def test_march_gives_up_after_max_cuts_in_a_row_and_stops_on_request():
    run = march(lambda t: (t <= 0.5, "no"), lambda t, o: False, 2, max_cuts=3,
                max_total_cuts=60)
    assert run.status == "failed" and run.t == 0.5 and run.in_row == 3 and run.failure == "no"
    run = march(lambda t: (True, t), lambda t, o: t >= 0.5, 4, max_cuts=3, max_total_cuts=60)
    assert run.status == "stopped" and run.t == 0.5
    run = march(lambda t: (False, "never"), lambda t, o: False, 1, max_cuts=10,
                max_total_cuts=2)
    assert run.status == "failed" and run.cuts == 2


def test_bisect_covers_the_span_with_halves_to_a_bounded_depth():
    tried = []

    def attempt(start, span):                   # spans longer than 0.25 fail
        tried.append(span)
        return NS(success=span[1] - span[0] <= 0.25, state=span[1], cuts=0, parts=[span])

    def halves(start, span):
        mid = 0.5 * (span[0] + span[1])
        return (span[0], mid), (mid, span[1])

    def join(first, second):
        if second is None:
            return NS(success=False, state=first.state, cuts=first.cuts + 1, parts=first.parts)
        return NS(success=second.success, state=second.state,
                  cuts=first.cuts + second.cuts + 1, parts=first.parts + second.parts)
    out = bisect(attempt, halves, join, 0.0, (0.0, 1.0), 3)
    assert out.success and out.cuts == 3
    assert out.parts == [(0.0, 0.25), (0.25, 0.5), (0.5, 0.75), (0.75, 1.0)]
    assert tried[:3] == [(0.0, 1.0), (0.0, 0.5), (0.0, 0.25)]
    out = bisect(attempt, halves, join, 0.0, (0.0, 1.0), 1)      # too shallow
    assert not out.success and out.cuts == 1


def test_the_solvers_have_no_newton_loop_or_round_off_floor_of_their_own():
    loop = re.compile(r"for \w+ in range\(\w*\.?max_iter \+ 1\)")
    floor = re.compile(r"1e-13 \* \w*size")
    offenders = []
    for path in (ROOT / "simulator").rglob("*.py"):
        if path.name == "nonlinear.py":
            continue
        text = path.read_text()
        offenders += [f"{path.name}: {m.group(0)}" for m in loop.finditer(text)]
        offenders += [f"{path.name}: {m.group(0)}" for m in floor.finditer(text)]
    assert offenders == []


def test_reference_loop_measures_before_the_update():
    """iterate(reference_loop=True): the residual measured before each update, so one update
    follows the one that meets atol; at most max_iter - 1 updates, then 'max_iter' (the
    caller accepts it); a missing correction is a failure."""
    p = Cubic([2.0])
    out = iterate(p, max_iter=30, atol=1e-8, rtol=0.0, size=1.0, reference_loop=True)
    assert out.success and out.message == f"reference loop: {out.iterations} updates"
    r = out.residual_norms
    assert len(r) == out.iterations and r[-1] <= 1e-8 < r[-2]     # measured, then updated
    assert p.evaluations == out.iterations + 1                    # and the final evaluation
    assert abs(2.0 - (p.x[0] + p.x[0] ** 3)) < r[-1]              # one update past it
    p = Cubic([2.0])
    out = iterate(p, max_iter=3, atol=1e-8, rtol=0.0, size=1.0, reference_loop=True)
    assert not out.success and out.reason == "max_iter" and out.iterations == 2
    assert "accepted unconverged after 2 updates (residual" in out.message
    out = iterate(Cubic([2.0], singular_at=1), max_iter=30, atol=1e-8, rtol=0.0, size=1.0,
                  reference_loop=True)
    assert not out.success and out.reason == "no correction" and out.iterations == 1


def test_march_grows_only_after_an_easy_success():
    """``grow(outcome)`` False keeps the increment cut (a hard success's double would fail);
    True (or no ``grow``) doubles it after two successes in a row."""
    def run(grow):
        tried, last = [], [0.0]

        def attempt(t):
            tried.append(round(t, 6))
            return t - last[0] <= 0.25 + 1e-12, ("hard" if t <= 0.5 else "easy")

        def accept(t, outcome):
            last[0] = t
            return False
        out = march(attempt, accept, 1, max_cuts=5, max_total_cuts=20, grow=grow)
        assert out.status == "converged" and out.t == 1.0
        return tried
    assert run(None) == [1.0, 0.5, 0.25, 0.5, 1.0, 0.75, 1.0]
    assert run(lambda o: o == "easy") == [1.0, 0.5, 0.25, 0.5, 0.75, 1.0]   # no failed double


def test_march_grows_after_patience_successes_even_if_none_was_easy():
    """A path of hard increments (``grow`` never True) still doubles its increment after
    GROWTH_PATIENCE successes at it (a path accepted by Newton's stall rule must not crawl)."""
    def run(grow):
        tried = []

        def attempt(t):
            tried.append(round(t, 6))
            return len(tried) > 3, t                   # the first three attempts fail
        out = march(attempt, lambda t, o: False, 1, max_cuts=5, max_total_cuts=20, grow=grow)
        assert out.status == "converged" and out.cuts == 3
        return tried
    assert GROWTH_PATIENCE == 4
    assert run(lambda o: False) == [1.0, 0.5, 0.25, 0.125, 0.25, 0.375, 0.5, 0.75, 1.0]
    assert run(None) == [1.0, 0.5, 0.25, 0.125, 0.25, 0.5, 1.0]
