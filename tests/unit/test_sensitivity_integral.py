"""Adjoint sensitivities with the integral heat loss (simulator.sensitivity.integral, theory
12.6): the shape derivative of the single-layer operator's product, of the loss conductance at
its levels, of the monotone conduction, and the whole adjoint gradient against central finite
differences of the coupled solve (the rule of ``test_sensitivity.py``: ``h = eps^(1/3)
max(|p|, scale)``, Newton 1e-15 N, coupling 1e-10 K, agreement 1e-5).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from test_sensitivity import (RTOL, Setup, _central, _error, _medium_models, _step,
                              check_power_and_rest_offset)

from simulator import IntegralLoss
from simulator.cases import get_case
from simulator.sensitivity import (CreaseTemperature, FoldAngle, NodeCoordinate,
                                   SensitivityNotSupported, differentiate)
from simulator.sensitivity import _integral_jit
from simulator.sensitivity.conduction import monotone_jacobian
from simulator.sensitivity.integral import (IntegralShapeOperator, _Level, loss_levels,
                                            pair_derivative)
from simulator.thermal import thermal_model
from simulator.thermal._single_layer import (single_layer_operator, sub_triangle_corners,
                                             subdivision)


def _integral(model, **loss):
    """``model`` with the integral loss rebuilt at every shape (no correction between
    rebuilds) on its unrefined sheet."""
    return dataclasses.replace(model, thermal=dataclasses.replace(
        model.thermal, loss=IntegralLoss(shape_tol=0.0, correction_tol=0.0, **loss),
        sheet_refinement=1))


@pytest.mark.parametrize("level", [1, 2, 3])
@pytest.mark.parametrize("plane", [False, True])
def test_pair_derivative_against_differences(level, plane):
    """``d(S p)/dx`` of three bent triangles refined ``level`` (closed-form, 3-point and
    centroid pairs, the self terms; with a substrate plane their images) against central
    differences of the operator's own assembly."""
    rng = np.random.default_rng(level + 10 * plane)
    nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.3], [0.5, 1.6, 0.5]]) * 1e-3
    nodes = nodes + 1e-5 * rng.standard_normal(nodes.shape)
    tris = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]])
    sub_plane = (np.array([0, 0, -2e-4]), np.array([0, 0, 1.0])) if plane else None
    bary, _ = subdivision(level)

    def product(x):
        sub = sub_triangle_corners(x, tris, bary, compiled=False)
        return single_layer_operator(sub, 0.026, sub_plane, compiled=False)[0] @ p

    sub = sub_triangle_corners(nodes, tris, bary, compiled=False)
    p = rng.random(len(sub))
    D = pair_derivative(sub, np.repeat(tris, len(bary), axis=0),
                        np.tile(bary, (len(tris), 1, 1)), p, 0.026, sub_plane, len(nodes))
    d = rng.standard_normal(nodes.shape)
    h = 1e-9
    fd = (product(nodes + h * d) - product(nodes - h * d)) / (2 * h)
    assert np.abs(fd - D @ d.ravel()).max() <= 1e-7 * np.abs(fd).max()


@pytest.mark.parametrize("plane", [False, True])
def test_pair_derivative_compiled_against_numpy(plane):
    """The compiled kernel (simulator.sensitivity._integral_jit) gives numpy's ``D`` on 432
    sub-triangles of three bent triangles (every rule), to the central differences' round-off."""
    rng = np.random.default_rng(7)
    nodes = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.3], [0.5, 1.6, 0.5]]) * 1e-3
    tris = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]])
    bary, _ = subdivision(12)
    sub = sub_triangle_corners(nodes, tris, bary, compiled=False)
    args = (sub, np.repeat(tris, len(bary), axis=0), np.tile(bary, (len(tris), 1, 1)),
            rng.random(len(sub)), 0.026,
            (np.array([0, 0, -2e-4]), np.array([0, 0, 1.0])) if plane else None, len(nodes))
    assert _integral_jit.use_compiled()
    numpy = pair_derivative(*args, compiled=False)
    assert np.abs(pair_derivative(*args, compiled=True) - numpy).max() \
        <= 1e-8 * np.abs(numpy).max()


def _moving(model, tm):
    """A random shape near the reference and a direction that move only the nodes above the
    substrate plane (those on it are supported)."""
    rng = np.random.default_rng(3)
    up = (((model.mesh.nodes - tm.plane[0]) @ tm.plane[1]) > 1e-7)[:, None]
    x = model.mesh.nodes + 1e-5 * rng.standard_normal(model.mesh.nodes.shape) * up
    return x, rng.standard_normal(x.shape) * up, rng.random(model.mesh.n_nodes)


@pytest.mark.parametrize("loss", [dict(refinement=2, extrapolation=False), dict()])
def test_loss_levels_and_operator(loss):
    """Each level's ``d(L dT)/dx`` against central differences of the level rebuilt (a step of
    1e-10 m: the pairs exactly at a rule threshold of the structured subdivision are not
    crossed), and the operator's loss conductance equal to the steady model's."""
    model = _integral(get_case("single_fold").model, **loss)
    tm = thermal_model(model)
    x, d, rise = _moving(model, tm)
    op = IntegralShapeOperator(tm, x)
    tm.exact_loss_at(x)
    assert np.abs(op.L - tm.integral_loss_matrix(x)).max() <= 1e-12 * np.abs(op.L).max()
    nodes = tm.integral.nodes
    h = 1e-10
    for level, weight in loss_levels(tm.integral):
        J = _Level(level, weight, x).jacobian(rise[nodes])
        fd = (_Level(level, weight, x + h * d).L - _Level(level, weight, x - h * d).L) \
            @ rise[nodes] / (2 * h)
        assert np.abs(fd - J @ d.ravel()).max() <= 1e-7 * np.abs(fd).max()


@pytest.mark.parametrize("name", ["single_fold", "double_fold"])
def test_monotone_conduction_jacobian(name):
    """``d(K_c dT)/dx`` of the monotone conduction (Steiner points condensed) against central
    differences of the steady model's conduction matrix."""
    model = _integral(get_case(name).model)
    tm = thermal_model(model)
    assert tm.conduction.monotone.n_steiner > 0          # the condensation is exercised
    rng = np.random.default_rng(5)
    x = model.mesh.nodes + 1e-5 * rng.standard_normal(model.mesh.nodes.shape)
    rise, d = rng.random(model.mesh.n_nodes), rng.standard_normal(x.shape)
    J = monotone_jacobian(tm.conduction.monotone, x, rise)
    h = 1e-9
    fd = (tm.conduction.matrix(x + h * d) @ rise - tm.conduction.matrix(x - h * d) @ rise) / (2 * h)
    assert np.abs(fd - J @ d.ravel()).max() <= 1e-7 * np.abs(fd).max()


@pytest.fixture(scope="module")
def single():
    model = _integral(get_case("single_fold").model)
    setup = Setup("single_fold", model, {2: 0.0}, {2: 0.02})
    return setup, setup.run()


OBJECTIVES = (FoldAngle(2), CreaseTemperature(2, "centre_line"), NodeCoordinate(6, "z"))


def test_single_fold_integral_power_rest_offset_medium(single):
    """The single fold with the integral loss (extrapolated levels 3 and 2, monotone
    conduction, over the substrate plane): power, residual fold and the medium's conductivity
    against central differences of the whole coupled solve."""
    setup, result = single
    grads = differentiate(result, list(OBJECTIVES),
                          ("power", "rest_offset", "medium_conductivity"))
    check_power_and_rest_offset(setup, grads, OBJECTIVES, rest=[0, 2])
    h, models = _medium_models(setup.model)
    for g, fd in zip(grads, _central(setup, OBJECTIVES, h, model=models)):
        assert _error(g.gradient["medium_conductivity"], fd) <= RTOL


def test_lumped_integral_loss_refused(single):
    setup, result = single
    model = dataclasses.replace(setup.model, thermal=dataclasses.replace(
        setup.model.thermal, loss=IntegralLoss(lumped=True)))
    with pytest.raises(SensitivityNotSupported, match="lumped"):
        differentiate(dataclasses.replace(result, model=model), FoldAngle(2))


def test_double_fold_integral(double_integral):
    """The double fold with the integral loss over its substrate: both creases' powers and the
    medium's conductivity, a fold and a crease temperature."""
    setup, result = double_integral
    objectives = (FoldAngle(5), CreaseTemperature(2, "centre_line"))
    grads = differentiate(result, list(objectives), ("power", "medium_conductivity"))
    assert all(g.success for g in grads), grads[0].message
    for c, p in setup.power.items():
        h = _step(p, "power")
        for g, fd in zip(grads, _central(setup, objectives, h, power=(
                {**setup.power, c: p + h}, {**setup.power, c: p - h}))):
            assert _error(g.gradient[f"power[{c}]"], fd) <= RTOL


@pytest.fixture(scope="module")
def double_integral():
    model = _integral(get_case("double_fold").model)
    setup = Setup("double_fold", model, {2: 0.0, 5: 0.0}, {2: 0.004, 5: 0.005})
    return setup, setup.run()


def test_refined_sheet(single):
    """The single fold on its default refined sheet (r = 2, its fine nodes the heat balance's
    unknowns): the medium's conductivity to 1e-5 at the rule's step; the power at 10 times that
    step to 1e-4, because the refined sheet's structured sub-triangles sit exactly at the
    operator's rule thresholds, where its entries jump by the rules' difference (theory 12.6):
    at the rule's step the differences cross such a jump (1.5e-4 off, 1.5e-5 at 10 times the
    step)."""
    base = get_case("single_fold", loss_model="integral").model
    model = dataclasses.replace(base, thermal=dataclasses.replace(
        base.thermal, loss=IntegralLoss(shape_tol=0.0, correction_tol=0.0)))
    setup = Setup("single_fold", model, {2: 0.0}, {2: 0.02})
    result = setup.run()
    g = differentiate(result, FoldAngle(2), ("power", "medium_conductivity"))
    assert g.success and g.status == "converged", g.message
    h, models = _medium_models(model)
    fd = _central(setup, [FoldAngle(2)], h, model=models)[0]
    assert _error(g.gradient["medium_conductivity"], fd) <= RTOL
    h = 10 * _step(0.02, "power")
    fd = _central(setup, [FoldAngle(2)], h, power=({2: 0.02 + h}, {2: 0.02 - h}))[0]
    assert _error(g.gradient["power[2]"], fd) <= 1e-4


def test_geometry_with_the_integral_loss():
    """Geometry parameters with the integral loss (its operator and the monotone conduction
    rebuilt on the moved reference): the single fold's panel length L and crease width W."""
    from test_sensitivity_geometry import SINGLE_KW, _check, _single_run

    from simulator.cases import single_fold_model
    from simulator.sensitivity import Geometry

    base = _integral(get_case("single_fold").model)

    def build(p):
        kw = {**SINGLE_KW, "W": p["W"]}
        return single_fold_model(thermal=base.thermal, actuators=base.actuators, L=p["L"], **kw)

    values = {"L": 0.5e-3, "W": SINGLE_KW["W"]}
    result = _single_run(build(values))
    objectives = (FoldAngle(2), CreaseTemperature(2, "centre_line"))
    grads = [differentiate(result, o, (), geometry=Geometry(build, values)) for o in objectives]
    assert all(g.success and g.status == "converged" for g in grads), grads[0].message
    for name in values:
        _check(_single_run, build, values, name, grads, objectives)
