"""Geometry sensitivities (simulator.sensitivity.Geometry, theory 12.5) against central finite
differences of the whole coupled solve, the model rebuilt at p +- h.

Finite-difference rule of the whole solve (as tests/unit/test_sensitivity.py):
``h = eps^(1/3) |p|``, every run re-solved from scratch with Newton's residual tolerance 1e-15 N
(relative 1e-14) and coupling_tol 1e-10 K: the differences carry about 1e-8 of the derivative.
The agreement asked for is 1e-5.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from simulator import Heat, IntegralLoss, NewtonOptions, SelfFold, simulate
from simulator.cases import get_case, miura_sheet_model, single_fold_model
from simulator.errors import ParameterError
from simulator.geometry.example_patterns import double_fold_pattern, single_fold_pattern
from simulator.model.mesh import make_mesh
from simulator.model.model import make_model
from simulator.sensitivity import (CreaseTemperature, FoldAngle, Geometry, NodeCoordinate,
                                   SensitivityNotSupported, differentiate, differentiate_state)
from simulator.sensitivity.geometry import with_reference_nodes
from simulator.state import initial_state

OPTIONS = NewtonOptions(atol=1e-15, rtol=1e-14)
EPS3 = np.finfo(float).eps ** (1 / 3)
RTOL = 1e-5


def _value(result, objective):
    state = result.steps[-1].state
    return objective.terms(result.model, state.u, state.temperature)[0]


def _error(adjoint, fd) -> float:
    return abs(adjoint - fd) / abs(fd) if fd != 0 else math.inf


def _check(run, build, values, name, grads, objectives):
    """Each gradient's entry for ``name`` against central differences of ``run``."""
    h = EPS3 * abs(values[name])
    plus, minus = (run(build({**values, name: values[name] + s * h})) for s in (1, -1))
    errors = []
    for g, o in zip(grads, objectives):
        fd = (_value(plus, o) - _value(minus, o)) / (2 * h)
        errors.append(_error(g.gradient[f"geometry[{name}]"], fd))
    assert max(errors) <= RTOL, (name, errors)
    return errors


# ------------------------------------------------------------------ single fold: panel length
SINGLE = get_case("single_fold", power_mW=20.0).model
SINGLE_KW = dict(W=200e-6, undercut=150e-6, panel_thickness=21e-6, crease_thickness=0.5e-6)


def _single_model(p):
    return single_fold_model(thermal=SINGLE.thermal, actuators=SINGLE.actuators, L=p["L"],
                             **SINGLE_KW)


def _single_nodes(p):
    return make_mesh(single_fold_pattern(L=p["L"], **SINGLE_KW)).nodes


def _single_run(model):
    steps = [SelfFold({2: 0.0}, increments=20),
             Heat({2: 0.02}, increments=5, coupling="settled", coupling_tol=1e-10)]
    result = simulate(model, steps, options=OPTIONS)
    assert result.success, result.message
    return result


@pytest.fixture(scope="module")
def single():
    return _single_run(_single_model({"L": 0.5e-3}))


def test_single_fold_panel_length(single):
    """The panel length L (both panels and the substrate scale): the fold angle, the crease
    temperature and a node's height, by a model builder and by reference nodes alone (the
    same derivative: L is no datum of the pattern besides its vertices)."""
    objectives = (FoldAngle(2), CreaseTemperature(2, "centre_line"), NodeCoordinate(6, "z"))
    values = {"L": 0.5e-3}
    grads = [differentiate(single, o, (), geometry=Geometry(_single_model, values))
             for o in objectives]
    assert all(g.success and g.status == "converged" for g in grads), grads[0].message
    assert grads[0].units["geometry[L]"] == "rad/m" and list(grads[0].gradient) == ["geometry[L]"]
    _check(_single_run, _single_model, values, "L", grads, objectives)
    by_nodes = [differentiate(single, o, (), geometry=Geometry(_single_nodes, values))
                for o in objectives]
    for a, b in zip(grads, by_nodes):
        assert b.gradient["geometry[L]"] == pytest.approx(a.gradient["geometry[L]"], rel=1e-9)


@pytest.mark.parametrize("method", ["adjoint", "forward"])
def test_a_list_of_objectives_with_geometry_is_each_objective_alone(single, method):
    """One call for several objectives (one factorisation, several right-hand sides) gives
    each objective's own geometry derivative, its explicit term included (the node height's
    is not 0), to round-off: the gradients carry about 1e-8 of themselves (theory 12, the
    equilibrated Jacobian's condition), 2e-9 measured here."""
    objectives = [FoldAngle(2), CreaseTemperature(2, "centre_line"), NodeCoordinate(6, "z")]
    geo = Geometry(_single_model, {"L": 0.5e-3})
    many = differentiate(single, objectives, ("power",), geometry=geo, method=method)
    assert isinstance(many, tuple) and len(many) == 3
    for o, g in zip(objectives, many):
        alone = differentiate(single, o, ("power",), geometry=geo, method=method)
        assert g.success and list(g.gradient) == list(alone.gradient)
        for k in g.gradient:
            assert g.gradient[k] == pytest.approx(alone.gradient[k], rel=1e-7)
    assert many[0].gradient["geometry[L]"] != many[2].gradient["geometry[L]"]


def test_geometry_with_other_parameters_and_forward(single):
    """Geometry columns beside the other kinds; the forward mode gives the same."""
    geo = Geometry(_single_model, {"L": 0.5e-3})
    a = differentiate(single, FoldAngle(2), ("power", "rest_offset"), geometry=geo)
    f = differentiate(single, FoldAngle(2), ("power", "rest_offset"), geometry=geo,
                      method="forward")
    alone = differentiate(single, FoldAngle(2), ("power", "rest_offset"))
    assert list(a.gradient) == ["power[2]", "rest_offset[2]", "geometry[L]"]
    assert a.gradient["power[2]"] == alone.gradient["power[2]"]
    for k in a.gradient:
        assert f.gradient[k] == pytest.approx(a.gradient[k], rel=1e-7)


def test_single_fold_resting_on_the_substrate_panel_length():
    """Contact active (folded down by -20 deg and by gravity onto the substrate, two contact
    pairs) and the Gravity step's load on the panel: the fold per metre of panel length."""
    from simulator.mechanics.equilibrium import equilibrium_system

    case = get_case("single_fold", residual_fold_deg=-20.0, gravity=True)

    def run(model):
        steps = [SelfFold({2: np.radians(-20.0)}, increments=20), case.steps[1],
                 Heat({2: 0.005}, increments=5, coupling="settled", coupling_tol=1e-10)]
        result = simulate(model, steps, options=OPTIONS)
        assert result.success, result.message
        return result
    values = {"L": 0.5e-3}
    result = run(_single_model(values))
    state = result.steps[-1].state
    assert equilibrium_system(result.model).evaluate(state.u, state.spring_rest).n_contacts == 2
    g = differentiate(result, FoldAngle(2), (), geometry=Geometry(_single_model, values))
    assert g.success, g.message
    _check(run, _single_model, values, "L", [g], [FoldAngle(2)])


def _folded_nodes(p):
    """The single fold's reference with its folding panel (the nodes beyond the crease's
    centre line, x > 0.6 mm, the substrate's left out) turned up by ``p["phi"]`` [rad] about
    that line: a mesh that starts folded."""
    x = SINGLE_FLAT.mesh.nodes.copy()
    beyond = (x[:, 0] > 0.6e-3 + 1e-12) & (x[:, 2] > -1e-9)
    r = x[beyond, 0] - 0.6e-3
    x[beyond, 0], x[beyond, 2] = 0.6e-3 + r * np.cos(p["phi"]), r * np.sin(p["phi"])
    return x


SINGLE_FLAT = _single_model({"L": 0.5e-3})


def _folded_run(model):
    step = Heat({2: 0.02}, increments=5, coupling="settled", coupling_tol=1e-10)
    result = simulate(model, [step], options=OPTIONS)
    assert result.success, result.message
    return result


def test_single_fold_reference_fold_angle():
    """A reference that starts folded (by phi), heated from it without a self-fold: its rest
    angles are the reference's and follow phi (held, the derivatives are wrong by 100 %)."""
    values = {"phi": 0.3}

    def build(p):
        return with_reference_nodes(SINGLE_FLAT, _folded_nodes(p))
    result = _folded_run(build(values))
    assert result.initial_state.crease_rest[0] == pytest.approx(np.pi + 0.3, rel=1e-9)
    objectives = (FoldAngle(2), CreaseTemperature(2, "centre_line"), NodeCoordinate(6, "z"))
    geo = Geometry(_folded_nodes, values, units={"phi": "rad"})
    grads = [differentiate(result, o, (), geometry=geo) for o in objectives]
    assert all(g.success for g in grads), grads[0].message
    _check(_folded_run, build, values, "phi", grads, objectives)
    held = differentiate_state(result.model, result.steps[-1].state, result.initial_state,
                               FoldAngle(2), (), geometry=geo)
    assert _error(held.gradient["geometry[phi]"], grads[0].gradient["geometry[phi]"]) > 0.5


# ------------------------------------------------------------------ double fold: panel length
DOUBLE = get_case("double_fold").model


def _double_model(p):
    m = DOUBLE
    return make_model(double_fold_pattern(L=p["L"]), m.supports, m.params, m.contact, m.thermal,
                      m.actuators)


def _double_run(model):
    case = get_case("double_fold", thermal_steps=5, coupling="settled")
    steps = list(case.steps)
    steps[0] = SelfFold({2: 0.0, 5: 0.0}, increments=20)
    steps[-1] = Heat({2: 0.01, 5: 0.012}, increments=5, coupling="settled", coupling_tol=1e-10)
    result = simulate(model, steps, options=OPTIONS)
    assert result.success, result.message
    return result


def test_double_fold_panel_length():
    """Both folds and a crease temperature per metre of panel length, gravity on (the Gravity
    step's dead loads follow the panel areas)."""
    values = {"L": 450e-6}
    result = _double_run(_double_model(values))
    assert any(r.name == "gravity" for r in result.steps)
    objectives = (FoldAngle(5), FoldAngle(2), CreaseTemperature(5, "actuation"))
    geo = Geometry(_double_model, values)
    grads = [differentiate(result, o, (), geometry=geo) for o in objectives]
    assert all(g.success for g in grads), grads[0].message
    _check(_double_run, _double_model, values, "L", grads, objectives)


# ------------------------------------------------------------------ Miura lifter: cell geometry
MIURA = {"a": 1e-3, "b": 1e-3, "gamma": math.radians(60.0), "crease_width": 200e-6}


def _miura_model(p):
    """The 2 x 2-cell lifter over a substrate, its sheet exactly flat: the builder's
    ``acos`` leaves a round-off wiggle of ~1e-11 m in z that jumps with the parameters (not
    differentiable at the steps' scale), set to 0 here."""
    m = miura_sheet_model(p["a"], p["b"], p["gamma"], 2, 2, p["crease_width"], substrate=True)
    x = m.mesh.nodes.copy()
    x[np.abs(x[:, 2]) < 1e-9, 2] = 0.0
    return with_reference_nodes(m, x)


def _miura_run(model):
    case = get_case("miura_lifter", substrate=True)
    (key, power), = case.steps[0].power.items()
    step = Heat({k: power for k in key}, increments=20, coupling="settled", coupling_tol=1e-10)
    result = simulate(model, [step], options=OPTIONS)
    assert result.success, result.message
    return result


def test_miura_lifter_cell_geometry():
    """A 2 x 2-cell Miura lifter over a substrate: its last crease's fold and its highest
    node's lift in the panel sides a, b, the sector angle gamma and the crease width (a datum
    of the pattern: the hinge stiffness and the bimorph's rotation follow it)."""
    result = _miura_run(_miura_model(MIURA))
    (key, _), = get_case("miura_lifter").steps[0].power.items()
    c = key[-1]
    node = int(np.argmax(np.abs(result.steps[-1].state.u[:, 2])))
    objectives = (FoldAngle(c), NodeCoordinate(node, "z"))
    geo = Geometry(_miura_model, MIURA, units={"gamma": "rad"})
    grads = [differentiate(result, o, (), geometry=geo) for o in objectives]
    assert all(g.success for g in grads), grads[0].message
    assert grads[0].units["geometry[gamma]"] == "rad/rad"
    for name in MIURA:
        _check(_miura_run, _miura_model, MIURA, name, grads, objectives)


def test_a_rough_builder_is_reported():
    """The Miura builder as it is (its sheet's z a round-off wiggle of ~1e-11 m that jumps
    with gamma): the residual's differences at h and 4 h disagree, status "nonsmooth"."""
    def build(p):
        return miura_sheet_model(MIURA["a"], MIURA["b"], p["gamma"], 2, 2,
                                 MIURA["crease_width"], substrate=True)
    result = _miura_run(build(MIURA))
    g = differentiate(result, NodeCoordinate(0, "z"), (), geometry=Geometry(
        build, {"gamma": MIURA["gamma"]}, units={"gamma": "rad"}))
    assert not g.success and g.status == "nonsmooth"
    assert "geometry[gamma]" in g.message and "not smooth" in g.message


# ------------------------------------------------------------------ refusals
def test_geometry_refusals(single):
    """A topology that changes, values that are not the model's, nodes of another shape, the
    kinds 'geometry' and 'crease_width', a Geometry without values, the integral loss."""
    with pytest.raises(SensitivityNotSupported, match="another topology"):
        differentiate(single, FoldAngle(2), (), geometry=Geometry(
            lambda p: _double_model({"L": 450e-6}) if p["L"] != 0.5e-3 else _single_model(p),
            {"L": 0.5e-3}))
    with pytest.raises(ParameterError, match="build\\(values\\) moves the reference nodes"):
        differentiate(single, FoldAngle(2), (), geometry=Geometry(_single_model, {"L": 0.6e-3}))
    with pytest.raises(ParameterError, match="nodes of shape \\(3, 3\\)"):
        differentiate(single, FoldAngle(2), (), geometry=Geometry(lambda p: np.zeros((3, 3)),
                                                                 {"L": 0.5e-3}))
    with pytest.raises(SensitivityNotSupported, match="geometry=Geometry"):
        differentiate(single, FoldAngle(2), "geometry")
    with pytest.raises(SensitivityNotSupported, match="crease width .*geometry=Geometry"):
        differentiate(single, FoldAngle(2), "crease_width")
    with pytest.raises(ParameterError, match="Geometry.values"):
        Geometry(_single_model, {})
    with pytest.raises(ParameterError, match="give a simulator.sensitivity.Geometry"):
        differentiate(single, FoldAngle(2), (), geometry={"L": 0.5e-3})
    with pytest.raises(ParameterError, match="Geometry.scale\\['L'\\] = -1"):
        Geometry(_single_model, {"L": 0.5e-3}, scale={"L": -1})
    integral = _lumped_integral()
    start = initial_state(integral)
    with pytest.raises(SensitivityNotSupported, match="the lumped integral loss.*not supported; "
                                                      "supported: the chain"):
        differentiate_state(integral, start, start, FoldAngle(2),
                            geometry=Geometry(_single_model, {"L": 0.5e-3}))


def _lumped_integral():
    """The single fold with the lumped integral loss (the one loss model not differentiated)."""
    model = get_case("single_fold", loss_model="integral").model
    return dataclasses.replace(model, thermal=dataclasses.replace(
        model.thermal, loss=IntegralLoss(lumped=True)))
