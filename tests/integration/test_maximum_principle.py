"""Discrete maximum principle (theory 4.9, 4.11): under heating alone no node is below room
temperature, with the monotone sheet conduction, on the crane and the gripper; with the
integral loss on the sheet refined within the mesh triangles (its default where the dense
operator allows), or on the mesh triangles when its conductance is lumped
(``IntegralLoss(lumped=True)``)."""

import dataclasses

import numpy as np
import pytest

from design.devices.gripper import (ARM_CREASES, BASE_CREASES, GripperDesign, GripperHeatModel,
                                    make_gripper_model)
from simulator import Heat
from simulator.cases import get_case
from simulator.simulation import simulate
from simulator.thermal import ThermalModel

#: room temperature within round-off [K]
_TOL = 1e-9


def _crane(loss_model, conduction, power_mW=5.0):
    case = get_case("crane", loss_model=loss_model, power_mW=power_mW, thermal_steps=30)
    model = dataclasses.replace(case.model, thermal=dataclasses.replace(
        case.model.thermal, conduction=conduction))
    return model, case.steps, case.steps[0].power_array(model.mesh)


def _gripper(loss_model, conduction, creases, power=15e-3, sheet_refinement=1):
    """The gripper flat, ``power`` [W] on ``creases``; on the mesh triangles by default."""
    model, pre = make_gripper_model(GripperDesign(), heat=GripperHeatModel(loss_model=loss_model))
    model = dataclasses.replace(model, thermal=dataclasses.replace(
        model.thermal, conduction=conduction, sheet_refinement=sheet_refinement))
    p = np.zeros(model.mesh.n_creases)
    p[[model.mesh.crease_row_of(c) for c in creases]] = power
    return model, p


def _rise(model, power, x=None):
    tm = ThermalModel(model.mesh, model.thermal)
    x = model.mesh.nodes if x is None else x
    return tm.solve(x, tm.heat_vector(power)) - model.thermal.room_temperature


@pytest.mark.parametrize("loss_model", ["chain", "integral"])
def test_heated_crane_has_no_node_below_room_temperature(loss_model):
    model, _, power = _crane(loss_model, "monotone")
    rise = _rise(model, power)
    assert rise.min() >= -_TOL and rise.max() > 200


def test_the_t3_crane_has_nodes_below_room_temperature():
    """What the monotone conduction removes: the sliver panels' tips at -0.30 K (chains)."""
    model, _, power = _crane("chain", "t3")
    rise = _rise(model, power)
    assert rise.min() == pytest.approx(-0.298, abs=0.005)
    assert (rise < -_TOL).sum() == 2


@pytest.mark.parametrize("creases", [BASE_CREASES, ARM_CREASES], ids=["assembly", "grip"])
def test_heated_gripper_with_chains_has_no_node_below_room_temperature(creases):
    model, power = _gripper("chain", "monotone", creases)
    assert _rise(model, power).min() >= -_TOL
    model, power = _gripper("chain", "t3", creases)
    assert _rise(model, power).min() < -0.01                    # T3: -0.07 K at the assembly


@pytest.mark.parametrize("creases", [BASE_CREASES, ARM_CREASES], ids=["assembly", "grip"])
def test_heated_gripper_with_the_default_integral_loss_has_no_node_below_room_temperature(
        creases):
    """The default integral model (the sheet refined, r = 2, theory 4.11): not one fine node
    below room temperature, where the mesh model puts the gripper's lowest node at -7.6 K (the
    consistent loss conductance couples neighbouring mesh nodes positively, theory 4.9)."""
    model, power = _gripper("integral", None, creases, sheet_refinement=None)
    tm = ThermalModel(model.mesh, model.thermal)
    assert tm.sheet is not None and tm.sheet.r == 2
    rise = tm.solve(model.mesh.nodes, tm.heat_vector(power)) - model.thermal.room_temperature
    assert tm.fine_temperatures.min() >= model.thermal.room_temperature - _TOL
    assert rise.max() > 100
    mesh_model, _ = _gripper("integral", None, creases)
    assert _rise(mesh_model, power).min() < -1.0


def test_folding_with_the_default_integral_loss_keeps_every_node_above_room_temperature():
    """Along the heating, folded (the gripper's base creases to 26 mW, the double fold to 10
    mW per crease), every recorded temperature of the default integral model is at least room
    temperature, and on the folded gripper at 15 mW every fine node (the mesh model: -2.0 K,
    lumped: 0)."""
    model, pre = make_gripper_model(GripperDesign(), heat=GripperHeatModel(loss_model="integral"))
    case = get_case("double_fold", thermal_steps=20)
    double = dataclasses.replace(case.model, thermal=case.model.thermal.with_loss("integral"))
    res, _ = _fold_both_above_room_temperature(model, pre, double, case.steps)
    p = _base_power(model)
    tm = ThermalModel(model.mesh, model.thermal)
    tm.solve(model.mesh.nodes + res.state.u, tm.heat_vector(p))
    assert tm.sheet.r == 2 and tm.fine_temperatures.min() >= model.thermal.room_temperature - _TOL


def _base_power(model, power=15e-3):
    """(C,) crease powers [W]: ``power`` on the gripper's base creases."""
    p = np.zeros(model.mesh.n_creases)
    p[[model.mesh.crease_row_of(c) for c in BASE_CREASES]] = power
    return p


def _fold_both_above_room_temperature(gripper, pre, double, double_steps, **heat):
    """The gripper's base creases heated to 26 mW in 5 increments after its steps ``pre``
    (``heat``: more ``Heat`` fields) and the double fold along ``double_steps``: both succeed,
    hot, with every recorded temperature at least room temperature. Returns their results."""
    start = simulate(gripper, pre)
    res = simulate(gripper, [Heat({BASE_CREASES: 26e-3}, increments=5, **heat)],
                   state=start.state)
    folded = simulate(double, double_steps)
    for m, r in ((gripper, res), (double, folded)):
        assert r.success
        T = r.history["temperature"]
        assert T.min() >= m.thermal.room_temperature - _TOL and T.max() > 300
    return res, folded


def _lumped(model, lumped=True):
    return dataclasses.replace(model, thermal=model.thermal.with_loss(lumped=lumped))


def _double_fold(lumped=True):
    case = get_case("double_fold", thermal_steps=20)
    model = dataclasses.replace(case.model, thermal=dataclasses.replace(
        case.model.thermal.with_loss("integral"), sheet_refinement=1))
    return _lumped(model, lumped), case.steps, np.full(model.mesh.n_creases, 10e-3)


def test_flat_devices_with_the_lumped_integral_loss_have_no_node_below_room_temperature():
    """Flat, heated alone: the gripper at 15 mW on its base creases (-7.60 K consistent), the
    double fold at 10 mW per crease (-3.49 K consistent)."""
    gripper, p_gripper = _gripper("integral", "monotone", BASE_CREASES)
    double, _, p_double = _double_fold()
    for model, power, consistent in ((gripper, p_gripper, -7.600), (double, p_double, -3.494)):
        rise = _rise(_lumped(model), power)
        assert rise.min() >= -_TOL and rise.max() > 150
        assert _rise(_lumped(model, False), power).min() == pytest.approx(consistent, abs=2e-3)


def test_folding_with_the_lumped_integral_loss_keeps_every_node_above_room_temperature():
    """Along the heating (folded shapes, the corrected operator between its rebuilds) every
    recorded node temperature is at least room temperature: the gripper's base creases at
    26 mW in 5 increments (folded, the consistent loss gives -2.0 K at 15 mW) and the double
    fold at 10 mW per crease in 20."""
    model, pre = make_gripper_model(GripperDesign(), heat=GripperHeatModel(sheet_refinement=1))
    model = _lumped(model)
    double, steps, p_double = _double_fold()
    res, folded = _fold_both_above_room_temperature(model, pre, double, steps,
                                                    coupling="iterated")
    p = _base_power(model)
    x = model.mesh.nodes + res.state.u
    assert _rise(model, p, x).min() >= -_TOL
    assert _rise(_lumped(model, False), p, x).min() < -1.0
    assert _rise(double, p_double, double.mesh.nodes + folded.state.u).min() >= -_TOL


def test_the_fe_reference_on_the_same_sheet_also_has_nodes_below_room_temperature():
    """The 3-D FE (level 0) on the flat gripper heated alone: -7.95 K (level 1: -7.99 K),
    where the consistent integral loss gives -7.60 K: the P1 sheet's, not the integral
    discretisation's (theory 4.9)."""
    pytest.importorskip("skfem")
    pytest.importorskip("gmsh")
    from simulator.thermal import fixed_shape_temperatures

    model, power = _gripper("integral", None, BASE_CREASES)
    fe = fixed_shape_temperatures(model, "fe", power, fe_level=0)
    assert fe.success
    assert fe.temperature.min() - fe.room_temperature == pytest.approx(-7.95, abs=0.1)
    assert _rise(model, power).min() == pytest.approx(-7.600, abs=2e-3)


def test_crane_folding_with_chains_keeps_every_node_above_room_temperature():
    """Along 30 heating increments at 4 mW (folded shapes: the triangulation chosen flat
    follows the shape) every recorded node temperature is at least room temperature and the
    conduction stays an M-matrix."""
    model, steps, _ = _crane("chain", "monotone", power_mW=4.0)
    res = simulate(model, steps)
    assert res.success
    T = res.history["temperature"]
    assert T.min() >= model.thermal.room_temperature - _TOL and T.max() > 100
    tm = ThermalModel(model.mesh, model.thermal)
    A = tm.sheet_conduction(model.mesh.nodes + res.state.u).toarray()
    assert (A - np.diag(np.diag(A))).max() <= 1e-12 * np.abs(A).max()
