"""Newton's residual criterion at the round-off level of the internal force (issue 28: large
flat-folder sheets whose residual cannot reach 1e-13 N): a model far from the origin, where the
node positions carry a large rounding error, converges to the same shape as at the origin;
the criterion accepts only the best iterate of a stalled iteration, and only at round-off
level."""

import dataclasses

import numpy as np
import pytest


from simulator.steps import initial_state
from simulator.cases import single_fold_model
from simulator.model import spring_rest_angles
from simulator.solvers.newton import NewtonOptions, newton
from simulator.solvers.nonlinear import STALL_PATIENCE, iterate, residual_at_round_off
from simulator.mechanics import equilibrium_system


def _moved(offset):
    """The free single fold with its nodes moved ``offset`` metres along every axis."""
    m = single_fold_model(contact=False, substrate=False)
    return dataclasses.replace(m, mesh=m.mesh.with_nodes(m.mesh.nodes + offset))


def _solve(model, deg=30.0):
    system, state = equilibrium_system(model), initial_state(model)
    rest = spring_rest_angles(model.mesh, np.array([np.pi + np.radians(deg)]))
    return system, rest, newton(system, state.u, state.applied_load.ravel(), rest,
                                NewtonOptions())


def test_a_model_far_from_the_origin_converges_at_round_off_to_the_same_shape():
    _, _, home = _solve(_moved(0.0))
    system, rest, far = _solve(_moved(100.0))
    assert home.success and home.message == "converged"          # as before: 1e-13 N reached
    # 100 m from the origin an ulp of a position is 1.4e-14 m: with bars of 4.7e6 N/m the
    # residual stalls at 1.5e-12 to 5e-12 N (it failed after 30 iterations before)
    assert far.success, far.message
    assert "round-off level" in far.message
    assert far.residual_norms.min() > NewtonOptions().atol
    np.testing.assert_allclose(far.u, home.u, rtol=0, atol=1e-13)
    # the accepted state is the best iterate, and its evaluation is that of the state
    ev = system.evaluate(far.u, rest)
    r = -ev.f_int[system.free]
    assert np.linalg.norm(r) == pytest.approx(far.residual_norms.min(), rel=1e-6)


def test_the_round_off_test_refuses_a_residual_above_the_rounding_of_the_positions():
    system, rest, far = _solve(_moved(100.0))
    at_round_off = residual_at_round_off(system, system.free)
    start = initial_state(_moved(100.0)).u
    for u, expected in ((far.u, True), (start, False)):
        ev = system.evaluate(u, rest)
        r = -ev.f_int[system.free]
        assert at_round_off(ev, r, u.ravel()) is expected


class Noisy:
    """r = b - x with noise of amplitude ``noise`` added to every evaluation: Newton reaches
    the noise and wanders there."""

    def __init__(self, noise, seed=0):
        self.x, self.noise, self.rng = np.zeros(3), noise, np.random.default_rng(seed)

    def evaluate(self):
        return np.ones(3) - self.x + self.noise * self.rng.standard_normal(3), self.x.copy()

    def correct(self, x, r):
        return r.copy()

    def apply(self, dx, scale):
        self.x += dx


@pytest.mark.parametrize("floor, accepted", [(1e-6, True), (1e-12, False)])
def test_a_stalled_iteration_stops_with_its_best_iterate_only_at_its_round_off_level(
        floor, accepted):
    p, asked = Noisy(1e-9), []

    def at_round_off(point, r, u):
        asked.append(float(np.linalg.norm(r)))
        return bool(np.all(np.abs(r) <= floor))
    out = iterate(p, max_iter=30, atol=1e-13, rtol=0.0, size=1.0, keep_best=p.x.copy,
                  at_round_off=at_round_off)
    assert out.success is accepted
    if accepted:
        assert out.reason == "round-off" and "round-off level" in out.message
        rn, _, x = out.best
        assert rn == min(out.residual_norms)
        assert out.iterations - out.residual_norms.index(rn) == STALL_PATIENCE
        np.testing.assert_allclose(x, 1.0, atol=1e-8)
        assert len(asked) == 1                                   # asked once, of the best
    else:
        assert out.reason == "max_iter"
        assert asked                       # asked, and refused: no state is accepted


def test_a_converging_iteration_never_asks_the_round_off_test():
    p = Noisy(0.0)
    asked = []
    out = iterate(p, max_iter=30, atol=1e-13, rtol=0.0, size=1.0, keep_best=p.x.copy,
                  at_round_off=lambda *a: asked.append(a) or True)
    assert out.success and out.reason == "converged" and not asked
