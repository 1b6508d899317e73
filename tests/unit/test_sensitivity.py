"""Adjoint sensitivities of steady coupled states (simulator.sensitivity, theory 11) against
central finite differences of the whole coupled solve.

Finite-difference rule: ``h = eps^(1/3) max(|p|, scale)`` (eps = 2.2e-16, eps^(1/3) = 6.1e-6;
``scale`` the parameter kind's typical size: 1 mW, 0.1 rad, 1e-5 /K, 1 GPa, 0.1 um, 0.01
W/(m K)); every run re-solves the steady state from scratch with Newton's residual tolerance
1e-15 N (relative 1e-14) and coupling_tol 1e-10 K, so that the values carry noise of about
1e-13 of themselves and the differences about 1e-8 of the derivative (the truncation error,
``h^2``, is below 1e-10): the agreement asked for is 1e-5.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from simulator import ChainLoss, Heat, IntegralLoss, NewtonOptions, SelfFold, simulate
from simulator.cases import get_case
from simulator.errors import ParameterError
from simulator.sensitivity import (CreaseTemperature, FoldAngle, NodeCoordinate,
                                   SensitivityNotSupported, differentiate,
                                   differentiate_state)
from simulator.sensitivity.chain import ChainOperator
from simulator.state import initial_state
from simulator.thermal import thermal_model

OPTIONS = NewtonOptions(atol=1e-15, rtol=1e-14)
EPS3 = np.finfo(float).eps ** (1 / 3)
SCALE = {"power": 1e-3, "rest_offset": 0.1, "delta_alpha": 1e-5, "E": 1e9, "t": 1e-7,
         "medium_conductivity": 0.01}
RTOL = 1e-5


def _step(value: float, kind: str) -> float:
    return EPS3 * max(abs(value), SCALE[kind])


@dataclasses.dataclass(frozen=True)
class Setup:
    """A case heated to a steady coupled state: its model, self-fold angles, heater powers."""

    name: str
    model: object
    folds: dict
    power: dict

    def run(self, model=None, folds=None, power=None):
        case = get_case(self.name, thermal_steps=5, coupling="settled")
        steps = list(case.steps)
        steps[0] = SelfFold(self.folds if folds is None else folds, increments=20)
        steps[-1] = Heat(self.power if power is None else power, increments=5,
                         coupling="settled", coupling_tol=1e-10)
        result = simulate(self.model if model is None else model, steps, options=OPTIONS)
        assert result.success, result.message
        return result


def _value(result, objective):
    state = result.steps[-1].state
    return objective.terms(result.model, state.u, state.temperature)[0]


def _central(setup, objectives, h, **plus_minus):
    """Central differences of the objectives: ``plus_minus`` maps a run() keyword to the pair
    of values at p + h and p - h."""
    plus = setup.run(**{k: v[0] for k, v in plus_minus.items()})
    minus = setup.run(**{k: v[1] for k, v in plus_minus.items()})
    return [(_value(plus, o) - _value(minus, o)) / (2 * h) for o in objectives]


def _error(adjoint, fd) -> float:
    """Relative difference of the adjoint gradient from the central difference ``fd``
    (infinite where ``fd`` is 0: a difference that moves nothing checks nothing)."""
    return abs(adjoint - fd) / abs(fd) if fd != 0 else math.inf


@pytest.fixture(scope="module")
def single():
    case = get_case("single_fold", power_mW=20.0)
    setup = Setup("single_fold", case.model, {2: 0.0}, {2: 0.02})
    return setup, setup.run()


@pytest.fixture(scope="module")
def double():
    case = get_case("double_fold")
    setup = Setup("double_fold", case.model, {2: 0.0, 5: 0.0}, {2: 0.01, 5: 0.012})
    return setup, setup.run()


OBJECTIVES = (FoldAngle(2), CreaseTemperature(2, "centre_line"), NodeCoordinate(6, "z"))


def test_single_fold_power_and_rest_offset(single):
    """Heater power and residual fold: fold angle, crease temperature, a node's height."""
    setup, result = single
    grads = [differentiate(result, o, ("power", "rest_offset")) for o in OBJECTIVES]
    check_power_and_rest_offset(setup, grads, OBJECTIVES, rest=[0])
    assert grads[0].units["power[2]"] == "rad/W" and grads[1].units["power[2]"] == "K/W"


def check_power_and_rest_offset(setup, grads, objectives, rest):
    """Every gradient converged; crease 2's power (at 20 mW) for every objective and its rest
    offset for the objectives ``rest`` (indices) against central differences."""
    assert all(g.success and g.status == "converged" for g in grads), grads[0].message
    h = _step(0.02, "power")
    for g, fd in zip(grads, _central(setup, objectives, h,
                                     power=({2: 0.02 + h}, {2: 0.02 - h}))):
        assert _error(g.gradient["power[2]"], fd) <= RTOL
    h = _step(0.0, "rest_offset")
    for i, fd in zip(rest, _central(setup, [objectives[i] for i in rest], h,
                                    folds=({2: h}, {2: -h}))):
        assert _error(grads[i].gradient["rest_offset[2]"], fd) <= RTOL


def test_single_fold_actuation_and_medium(single):
    """Expansion mismatch and the medium's conductivity (the chains' conductance)."""
    setup, result = single
    model = setup.model
    g = differentiate(result, FoldAngle(2), ("delta_alpha", "medium_conductivity"))
    acts, da = model.actuators, model.actuators.delta_alpha[2]
    h = _step(da, "delta_alpha")
    models = [dataclasses.replace(model, actuators=dataclasses.replace(
        acts, delta_alpha={2: da + s * h})) for s in (1, -1)]
    fd = _central(setup, [FoldAngle(2)], h, model=models)[0]
    assert _error(g.gradient["delta_alpha[2]"], fd) <= RTOL
    h, models = _medium_models(model)
    fd = _central(setup, [FoldAngle(2)], h, model=models)[0]
    assert _error(g.gradient["medium_conductivity"], fd) <= RTOL


def _medium_models(model):
    """The step and the models with the medium's conductivity moved by +- it."""
    medium = model.thermal.medium
    k = medium.thermal_conductivity
    h = _step(k, "medium_conductivity")
    return h, [dataclasses.replace(model, thermal=dataclasses.replace(
        model.thermal, medium=medium.with_properties(thermal_conductivity=k + s * h)))
        for s in (1, -1)]


def _bimorph_models(model, name, kind):
    acts = model.actuators
    b = acts.bimorph
    v = getattr(b, name)
    h = _step(v, kind)
    return h, [dataclasses.replace(model, actuators=dataclasses.replace(
        acts, bimorph=dataclasses.replace(b, **{name: v + s * h}))) for s in (1, -1)]


@pytest.mark.parametrize("name", ["E1", "t2", "E2", "t1"])
def test_single_fold_bimorph_layers(single, name):
    setup, result = single
    g = differentiate(result, FoldAngle(2), "bimorph")
    h, models = _bimorph_models(setup.model, name, name[0])
    fd = _central(setup, [FoldAngle(2)], h, model=models)[0]
    assert _error(g.gradient[name], fd) <= RTOL


def test_double_fold_powers(double):
    """Both creases heated, contact inactive: each crease's power moves both folds."""
    setup, result = double
    objectives = (FoldAngle(5), FoldAngle(2), CreaseTemperature(5, "actuation"))
    grads = [differentiate(result, o, "power") for o in objectives]
    assert all(g.success for g in grads), grads[0].message
    for c in (2, 5):
        h = _step(setup.power[c], "power")
        pm = [{**setup.power, c: setup.power[c] + s * h} for s in (1, -1)]
        for g, fd in zip(grads, _central(setup, objectives, h, power=pm)):
            assert _error(g.gradient[f"power[{c}]"], fd) <= RTOL


def test_double_fold_rest_offset_and_medium(double):
    setup, result = double
    g = differentiate(result, FoldAngle(5), ("rest_offset", "medium_conductivity"))
    h = _step(0.0, "rest_offset")
    fd = _central(setup, [FoldAngle(5)], h, folds=({2: h, 5: 0.0}, {2: -h, 5: 0.0}))[0]
    assert _error(g.gradient["rest_offset[2]"], fd) <= RTOL
    h, models = _medium_models(setup.model)
    fd = _central(setup, [FoldAngle(5)], h, model=models)[0]
    assert _error(g.gradient["medium_conductivity"], fd) <= RTOL


def test_double_fold_actuation(double):
    setup, result = double
    g = differentiate(result, FoldAngle(5), ("delta_alpha", "bimorph"))
    acts = setup.model.actuators
    da = acts.delta_alpha[2]
    h = _step(da, "delta_alpha")
    models = [dataclasses.replace(setup.model, actuators=dataclasses.replace(
        acts, delta_alpha={2: da + s * h, 5: acts.delta_alpha[5]})) for s in (1, -1)]
    fd = _central(setup, [FoldAngle(5)], h, model=models)[0]
    assert _error(g.gradient["delta_alpha[2]"], fd) <= RTOL
    h, models = _bimorph_models(setup.model, "t1", "t")
    fd = _central(setup, [FoldAngle(5)], h, model=models)[0]
    assert _error(g.gradient["t1"], fd) <= RTOL


def test_adjoint_equals_forward_and_callable(double):
    """One transposed solve gives what one solve per parameter gives, to the round-off of the
    coupled Jacobian (condition number 6e10 equilibrated: the two differ by up to 4e-8); a
    callable objective (the sum of the two fold angles by their own gradients) is the sum of
    the two."""
    _, result = double
    a = differentiate(result, FoldAngle(5))
    f = differentiate(result, FoldAngle(5), method="forward")
    assert list(a.gradient) == list(f.gradient)
    for k in a.gradient:
        assert a.gradient[k] == pytest.approx(f.gradient[k], rel=2e-7, abs=1e-12 * max(
            abs(v) for v in a.gradient.values()))
    model = result.model

    def both(u, T):
        terms = [FoldAngle(c).terms(model, u, T) for c in (2, 5)]
        return sum(t[0] for t in terms), terms[0][1] + terms[1][1], np.zeros(len(T))
    s = differentiate(result, both, "power")
    two = differentiate(result, FoldAngle(2), "power")
    assert s.value == pytest.approx(two.value + a.value)
    assert s.gradient["power[5]"] == pytest.approx(two.gradient["power[5]"]
                                                   + a.gradient["power[5]"], rel=1e-12)


def test_a_list_of_objectives_shares_one_factorisation(double):
    """A list of objectives gives, in its order, what one call per objective gives (the same
    Jacobian factored once, solved with several right-hand sides), adjoint and forward; an
    empty list is refused."""
    _, result = double
    objectives = [FoldAngle(2), CreaseTemperature(5, "crease_max"), NodeCoordinate(6, "z")]
    for method in ("adjoint", "forward"):
        many = differentiate(result, objectives, "power", method=method)
        assert isinstance(many, tuple) and len(many) == 3
        for objective, got in zip(objectives, many):
            one = differentiate(result, objective, "power", method=method)
            assert got.value == one.value and got.status == one.status == "converged"
            assert list(got.gradient) == list(one.gradient)
            for k in one.gradient:
                assert got.gradient[k] == pytest.approx(one.gradient[k], rel=1e-10, abs=1e-14)
    with pytest.raises(ParameterError, match="at least one objective"):
        differentiate(result, [], "power")


def test_shape_jacobian_of_the_chain_operator(single):
    """``d(A(x) dT)/dx`` against central differences of the operator (a mixed check of the
    T3, area and tcap terms; most triangles of the heated single fold are capped)."""
    _, result = single
    tm = thermal_model(result.model)
    state = result.steps[-1].state
    x = result.model.mesh.nodes + state.u
    rise = state.temperature - state.room_temperature
    op = ChainOperator(tm, x)
    assert op.capped.sum() > len(op.capped) // 2 and not op.nonsmooth
    every = np.arange(len(x))
    C = op.shape_jacobian(rise).toarray()
    h = 1e-6 * np.ptp(x)
    fd = np.empty_like(C)
    for j in range(x.size):
        d = np.zeros(x.size)
        d[j] = h
        d = d.reshape(x.shape)
        fd[:, j] = (ChainOperator(tm, x + d).matrix(every) @ rise
                    - ChainOperator(tm, x - d).matrix(every) @ rise) / (2 * h)
    assert np.abs(C - fd).max() <= 1e-6 * np.abs(C).max()


def test_a_switch_is_reported():
    """A state on the switch t_air = min(t_env, tcap): the unheated single fold with t_env
    equal to the cap of one of its triangles (any heating changes nothing at zero power, so
    the state is exactly steady): status "nonsmooth", the triangle named."""
    case = get_case("single_fold", power_mW=20.0)
    model = case.model
    tm = thermal_model(model)
    cap = tm.environment.tcap(model.mesh.nodes)
    e = int(np.flatnonzero(~tm.is_boundary & (cap < 1e-3))[0])
    chains = model.thermal.loss
    thermal = dataclasses.replace(model.thermal, loss=ChainLoss(
        thickness=float(cap[e]), layers=chains.layers,
        dissipation_angle=chains.dissipation_angle))
    switched = dataclasses.replace(model, thermal=thermal)
    result = simulate(switched, [SelfFold({2: 0.0}, increments=2),
                                 Heat({2: 0.0}, increments=1, coupling="settled")])
    s = differentiate(result, FoldAngle(2), "power")
    assert not s.success and s.status == "nonsmooth"
    assert f"triangle(s) [{e}" in s.message and s.nonsmooth


def test_refusals(single):
    """What is not differentiated is refused in one line naming what is."""
    setup, result = single
    with pytest.raises(SensitivityNotSupported, match="crease width moves the mesh.*supported: "
                                                      "power"):
        differentiate(result, FoldAngle(2), "crease_width")
    with pytest.raises(ParameterError, match="unknown kind 'power_mW'"):
        differentiate(result, FoldAngle(2), "power_mW")
    integral = _lumped_integral()
    start = initial_state(integral)
    with pytest.raises(SensitivityNotSupported, match="the lumped integral loss.*not supported; "
                                                      "supported: the chain"):
        differentiate_state(integral, start, start, FoldAngle(2))
    staggered = simulate(setup.model, [SelfFold({2: 0.0}, increments=2),
                                       Heat({2: 0.02}, increments=2, coupling="staggered")])
    s = differentiate(staggered, FoldAngle(2), "power")
    assert not s.success and s.status == "not_steady"


def test_miura_lifter_over_a_substrate():
    """A 2 x 2-cell Miura lifter over a substrate (its creases' t_air capped by the distance to
    the substrate panel): the fold of its last crease and the lift of its highest node per watt
    on that crease."""
    case = get_case("miura_lifter", substrate=True, coupling="settled", thermal_steps=20)
    (key, power), = case.steps[0].power.items()
    c = key[-1]
    powers = {k: power for k in key}

    def run(p):
        step = Heat(p, increments=20, coupling="settled", coupling_tol=1e-10)
        result = simulate(case.model, [step], options=OPTIONS)
        assert result.success, result.message
        return result
    result = run(powers)
    node = int(np.argmax(np.abs(result.steps[-1].state.u[:, 2])))
    objectives = (FoldAngle(c), NodeCoordinate(node, "z"))
    grads = [differentiate(result, o, "power") for o in objectives]
    assert all(g.success for g in grads), grads[0].message
    h = _step(power, "power")
    plus, minus = run({**powers, c: power + h}), run({**powers, c: power - h})
    for g, o in zip(grads, objectives):
        fd = (_value(plus, o) - _value(minus, o)) / (2 * h)
        assert _error(g.gradient[f"power[{c}]"], fd) <= RTOL


def test_fold_angle_gradient_on_bent_panels(double):
    """The panel-to-panel fold angle's gradient (Newell normals, axis, atan2) against central
    differences at positions with every panel bent out of plane."""
    from simulator.mechanics.kinematics import fold_angles

    _, result = double
    mesh = result.model.mesh
    x = mesh.nodes + result.steps[-1].state.u
    x = x + 1e-5 * np.random.default_rng(1).standard_normal(x.shape)
    u = x - mesh.nodes
    for c in (2, 5):
        row = mesh.crease_row_of(c)
        g = FoldAngle(c).terms(result.model, u, np.zeros(len(x)))[1].ravel()
        h = 1e-7 * np.ptp(x)
        fd = np.empty(x.size)
        for j in range(x.size):
            d = np.zeros(x.size)
            d[j] = h
            d = d.reshape(x.shape)
            fd[j] = (fold_angles(mesh, x + d)[row] - fold_angles(mesh, x - d)[row]) / (2 * h)
        assert np.abs(g - fd).max() <= 1e-7 * np.abs(fd).max()


def test_single_fold_resting_on_the_substrate():
    """Contact active (the panel, folded down by -20 deg and by gravity, rests on the substrate
    with two contact pairs): the fold per watt."""
    from simulator.mechanics.equilibrium import equilibrium_system

    case = get_case("single_fold", residual_fold_deg=-20.0, gravity=True)

    def run(p):
        steps = [SelfFold({2: np.radians(-20.0)}, increments=20), case.steps[1],
                 Heat({2: p}, increments=5, coupling="settled", coupling_tol=1e-10)]
        result = simulate(case.model, steps, options=OPTIONS)
        assert result.success, result.message
        return result
    power = 0.005
    result = run(power)
    state = result.steps[-1].state
    assert equilibrium_system(case.model).evaluate(state.u, state.spring_rest).n_contacts == 2
    g = differentiate(result, FoldAngle(2), "power")
    assert g.success, g.message
    h = _step(power, "power")
    fd = (_value(run(power + h), FoldAngle(2)) - _value(run(power - h), FoldAngle(2))) / (2 * h)
    assert _error(g.gradient["power[2]"], fd) <= RTOL


def _lumped_integral():
    """The single fold with the lumped integral loss (the one loss model not differentiated)."""
    model = get_case("single_fold", loss_model="integral").model
    return dataclasses.replace(model, thermal=dataclasses.replace(
        model.thermal, loss=IntegralLoss(lumped=True)))
