"""The integral heat-loss model where the sheet touches the substrate plane (the 3-D FE's rule),
its Richardson extrapolation in the refinement, and fixed_shape_temperatures."""

import dataclasses
import logging
import sys
from pathlib import Path

import numpy as np
import pytest

from simulator import ChainLoss, IntegralLoss, ParameterError, Substrate, ThermalParameters
from simulator.thermal import FixedShapeTemperatures, fixed_shape_temperatures
from simulator.cases import verification_strip
from simulator.thermal.integral import IntegralOperator
from simulator.thermal import ThermalModel

sys.path.insert(0, str(Path(__file__).parent))
from test_integral_loss import disk_mesh  # noqa: E402

PANEL_0 = [0, 1, 2, 3, 11]         # the strip's first panel (nodes 1, 2 also crease edge nodes)


def _strip_model(**kw):
    """The strip over the plane z = 0 with the plain integral operator (m = 2 unless given;
    no correction between rebuilds unless given)."""
    model = verification_strip().model
    loss = IntegralLoss(**{"refinement": 2, "correction_tol": 0.0, **kw})
    return model, ThermalModel(model.mesh, dataclasses.replace(
        model.thermal, loss=loss, room_temperature_nodes=(), sheet_refinement=1,
        substrate=Substrate.plane((0, 0, 0), (0, 0, 1))))


def _lying_shape(model, lift=0.0):
    """The strip with its first panel lying on z = 0 (plus ``lift``), the rest rising."""
    x = model.mesh.nodes.copy()
    x[:, 2] = 0.3 * np.maximum(x[:, 0] - 1.0, 0.0) + lift
    return x


def test_nodes_on_the_plane_touch_it_and_are_held_at_room_temperature():
    model, tm = _strip_model()
    x = _lying_shape(model)
    assert np.array_equal(np.flatnonzero(tm.integral.touching(x)), PANEL_0)
    assert np.array_equal(tm.held_nodes(x), PANEL_0)
    T = tm.solve(x, tm.heat_vector([4e-3]))
    assert np.all(np.isfinite(T))
    assert np.all(T[PANEL_0] == model.thermal.room_temperature)
    assert T[10] > 0.01                                     # the crease centre is heated
    assert not tm.integral.touching(x + [0, 0, 1e-3]).any()


def test_the_sub_triangles_in_the_plane_leave_the_operator():
    model, tm = _strip_model()
    x = _lying_shape(model)
    heat = tm.integral._operator(x).heat        # sheet rises -> sub-triangle heats [W]
    P = np.column_stack([heat(e) for e in np.eye(len(tm.integral.nodes))])
    flat = np.isin(np.repeat(tm.integral.triangles, 4, axis=0), PANEL_0).all(axis=1)
    assert flat.sum() == 4 * 4                              # panel 0's fan: 4 triangles
    assert np.all(P[flat] == 0) and np.all(np.isfinite(P)) and np.any(P[~flat] != 0)


def test_a_sheet_approaching_the_plane_tends_to_the_touching_solution():
    """The image term conducts ~ k A / h across the gap: continuous as h -> 0."""
    model, tm = _strip_model()
    q = tm.heat_vector([4e-3])
    T0 = tm.solve(_lying_shape(model), q)
    gaps = [np.abs(_strip_model()[1].solve(_lying_shape(model, h), q) - T0).max()
            for h in (1e-2, 1e-3, 1e-4)]
    assert gaps[0] > 5 * gaps[1] > 25 * gaps[2]
    assert gaps[2] < 0.005 * T0.max()


def test_nodes_below_the_plane_are_pressed_onto_it(caplog):
    model, tm = _strip_model()
    x = _lying_shape(model)
    q = tm.heat_vector([4e-3])
    T0 = tm.solve(x, q)
    below = x.copy()
    below[[0, 3, 11], 2] = -0.01
    with caplog.at_level(logging.WARNING, logger="simulator.thermal.integral"):
        T = _strip_model()[1].solve(below, q)
    assert "3 node(s) up to 0.01 m below the substrate plane" in caplog.text
    assert np.all(T[PANEL_0] == model.thermal.room_temperature)
    np.testing.assert_allclose(T, T0, rtol=0.02, atol=1e-3 * T0.max())


def test_the_rule_is_the_fe_references():
    """solve_fe3d holds the same nodes (and does not embed the same triangles)."""
    pytest.importorskip("skfem")
    from simulator.thermal.fe.solve3d import _embedded
    model, tm = _strip_model()
    x = _lying_shape(model)
    emb, on_plane = _embedded(model.mesh, x, True, 1e-9 * np.ptp(x, axis=0).max())
    assert np.array_equal(np.flatnonzero(on_plane), np.flatnonzero(tm.integral.touching(x)))
    flat = np.isin(model.mesh.triangles, PANEL_0).all(axis=1)
    assert np.array_equal(np.sort(emb), np.flatnonzero(~flat))


def test_no_plane_touches_nothing():
    model = verification_strip().model
    tm = ThermalModel(model.mesh, model.thermal.with_loss("integral"))
    assert not tm.integral.touching(model.mesh.nodes).any()
    assert np.array_equal(tm.held_nodes(model.mesh.nodes), tm.fixed_nodes)


# ------------------------------------------------------------------ Richardson extrapolation
def test_extrapolated_loss_is_the_richardson_combination():
    model, tm = _strip_model(refinement=4, extrapolation=True)
    x = _lying_shape(model, 0.1)
    plain = {m: _strip_model(refinement=m, extrapolation=False)[1]
             .integral.loss_matrix(x) for m in (2, 4)}
    np.testing.assert_allclose(tm.integral_loss_matrix(x), 2 * plain[4] - plain[2],
                               rtol=1e-12, atol=1e-12 * np.abs(plain[4]).max())
    T = tm.solve(x, tm.heat_vector([4e-3]))
    loss = tm.environment_loss(x, T)
    assert loss.sum() == pytest.approx(4e-3, rel=1e-9)        # the conductance the solve used


def test_extrapolation_brings_the_disk_closer_to_8_k_a():
    nodes, tris = disk_mesh(1.0, rings=3, sectors=12, grading=1.0)
    q = {m: IntegralOperator(tris, len(nodes), 1.0, m).loss_matrix(nodes).sum() / 8 for m in (2, 4)}
    assert abs(2 * q[4] - q[2] - 1) < 0.7 * abs(q[4] - 1)


def test_extrapolation_needs_a_refinement_of_3():
    # the old spelling's refusals name its fields
    with pytest.raises(ParameterError, match=r"integral_extrapolation = True needs "
                       r"integral_refinement >= 3, got 2"), pytest.deprecated_call():
        ThermalParameters(loss=ChainLoss(thickness=1e-3), integral_extrapolation=True,
                          integral_refinement=2)
    with pytest.raises(ParameterError, match="integral_extrapolation = 'yes' must be True, "
                       "False or None"), pytest.deprecated_call():
        ThermalParameters(loss=ChainLoss(thickness=1e-3), integral_extrapolation="yes")
    # the same refusals in the heat loss's own spelling
    with pytest.raises(ParameterError, match=r"IntegralLoss.extrapolation = True needs "
                       r"refinement >= 3, got 2"):
        IntegralLoss(refinement=2, extrapolation=True)
    with pytest.raises(ParameterError, match="IntegralLoss.extrapolation = 'yes' must be True, "
                       "False or None"):
        ThermalParameters(loss=IntegralLoss(extrapolation="yes"))


# ------------------------------------------------------------------ fixed_shape_temperatures
def test_fixed_shape_chain_is_the_chain_model():
    model = verification_strip().model
    r = fixed_shape_temperatures(model, "chain", [4e-3])
    tm = ThermalModel(model.mesh, model.thermal)
    assert isinstance(r, FixedShapeTemperatures) and r.success and r.status == "converged"
    np.testing.assert_array_equal(r.temperature, tm.solve(model.mesh.nodes,
                                                          tm.heat_vector([4e-3])))
    assert r.heat_input == pytest.approx(4e-3)
    assert r.crease_t_ave[0] == pytest.approx(r.temperature[[8, 9, 10]].mean())
    assert r.to_frame().shape == (1, 5)


def test_fixed_shape_integral_uses_the_boundary_panel_plane():
    model = verification_strip().model
    model = dataclasses.replace(model, thermal=dataclasses.replace(model.thermal,
                                                                   boundary_panels=(0,)))
    x = model.mesh.nodes + [0, 0, 0]
    x[:, 2] = 0.2 * np.maximum(x[:, 0] - 1.0, 0.0)
    r = fixed_shape_temperatures(model, "integral", [4e-3], positions=x, refinement=4,
                                 extrapolation=True)
    assert r.thermal.substrate.as_tuple() == pytest.approx((0.5, 0.5, 0, 0, 0, 1), abs=1e-12)
    assert r.thermal.loss.refinement == 4 and r.thermal.loss.extrapolation
    free = fixed_shape_temperatures(model, "integral", [4e-3], positions=x, substrate=None)
    assert free.thermal.substrate is None
    assert r.crease_temperature[0] < free.crease_temperature[0]   # the substrate cools


@pytest.mark.parametrize("kw, match", [
    (dict(loss_model="bem"), "loss_model = 'bem'"),
    (dict(crease_power=[1e-3], heat=np.zeros(13)), "crease_power or heat, not both"),
    (dict(), r"crease_power \(C,\) \[W\] is required"),
    (dict(crease_power=[1e-3], substrate="floor"), "substrate = 'floor'"),
])
def test_fixed_shape_bad_input_is_named(kw, match):
    with pytest.raises(ParameterError, match=match):
        fixed_shape_temperatures(verification_strip().model, **kw)
