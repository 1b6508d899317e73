"""The integral heat-loss model in time (issue 29 item 4; theory 8.1): the transient steps use
it, with the medium taken as quasi-static, instead of switching silently to the chains."""

import dataclasses
import logging

import numpy as np
import pytest

import simulator as S
from simulator.thermal import thermal_model
from simulator.thermal.transient import heat_system, medium_diffusion_time


@pytest.fixture(scope="module")
def fold():
    """The single fold with the integral loss over its substrate plane; (model, steps before
    the heating, the heating step)."""
    case = S.get_case("single_fold")
    model = case.model
    plane = S.thermal.boundary_panel_plane(model)
    th = dataclasses.replace(model.thermal.with_loss("integral"),
                             substrate=S.Substrate.plane(plane[:3], plane[3:]))
    model = dataclasses.replace(model, thermal=th)
    heat = [s for s in case.steps if isinstance(s, S.Heat)][0]
    pre = [s for s in case.steps if not isinstance(s, S.Heat)]
    return model, pre, heat


def test_a_step_response_ends_at_the_steady_integral_state(fold):
    """ElectroThermal held at the Heat step's power for 3 s (about 1000 thermal time
    constants of the medium over the device) ends where the steady coupled solve ends."""
    model, pre, heat = fold
    steady = S.simulate(model, pre + [dataclasses.replace(heat, increments=50)])
    step = S.ElectroThermal(power=dict(heat.power), duration=3.0, dt=1e-3,
                            mechanics="quasi_static")
    timed = S.simulate(model, pre + [step])
    assert steady.success and timed.success
    room = model.thermal.room_temperature
    a = steady.history["temperature"][-1] - room
    b = timed.history["temperature"][-1] - room
    assert a.max() > 90.0          # heated hard (97.2 K on the sheet refined, theory 4.11)
    # within 1 % (the issue); measured 0.27 % of the largest rise (3e-5 without the plane,
    # where the operator is not rebuilt at other shapes than the steady solve's)
    assert np.abs(b - a).max() < 5e-3 * a.max()
    # 0.13 deg of 79.9 (0.04 of 78.8 with the T3 sheet conduction, before theory 4.9)
    assert np.degrees(np.abs(timed.fold_angle[-1] - steady.fold_angle[-1])).max() < 0.2


def test_heat_then_electrothermal_keeps_the_integral_loss(fold):
    """[Heat, ElectroThermal adding no power]: the temperatures stay at the steady integral
    state (the chains' steady state differs from it by tens of percent)."""
    model, pre, heat = fold
    held = S.ElectroThermal(power={}, duration=0.05, dt=1e-3, mechanics="quasi_static")
    res = S.simulate(model, pre + [dataclasses.replace(heat, increments=50), held])
    assert res.success
    room = model.thermal.room_temperature
    T = res.history["temperature"] - room
    k = res.history["stage"]
    start, end = T[np.flatnonzero(k == len(pre))[-1]], T[-1]
    assert np.abs(end - start).max() < 5e-3 * start.max()           # (measured 0.22 %)
    chains = S.simulate(S.get_case("single_fold").model,
                        pre + [dataclasses.replace(heat, increments=50)])
    assert abs(chains.history["temperature"][-1].max() - room - start.max()) > 0.1 * start.max()


def test_the_integral_heat_system_has_the_structure_nodes_only_and_conserves_heat(fold):
    model, pre, heat = fold
    tm = thermal_model(model)
    x = model.mesh.nodes
    system = heat_system(tm, x)
    n = model.mesh.n_nodes
    assert system.free.max() < n and len(system.free) == n - len(tm.held_nodes(x))
    # the heat leaving the free nodes: into the held nodes and the medium, all positive
    assert np.all(system.outflow > -1e-12 * np.abs(system.outflow).max())
    step = S.ElectroThermal(power=dict(heat.power), duration=0.02, dt=1e-3,
                            mechanics="quasi_static")
    res = S.simulate(model, pre + [step])
    cols = res.history["columns"]
    heat_in, heat_out = cols["heat_in [J]"][-1], cols["heat_out [J]"][-1]
    rise = res.history["temperature"][-1] - model.thermal.room_temperature
    stored = float(heat_system(tm, x).C @ rise[system.free])
    # backward Euler keeps the balance exactly (the shape barely moves in 20 ms here)
    assert heat_in > 0 and stored == pytest.approx(heat_in - heat_out, rel=2e-2)


def test_a_time_step_shorter_than_the_medium_diffusion_time_is_a_warning(fold, caplog):
    model, _, heat = fold
    tm = thermal_model(model)
    tau = medium_diffusion_time(tm, model.mesh.nodes)
    D = float(np.ptp(model.mesh.nodes, axis=0).max())
    medium = model.thermal.medium
    assert tau == pytest.approx(D**2 * medium.density * medium.specific_heat
                                / medium.thermal_conductivity)
    for dt, warned in ((0.5 * tau, True), (2 * tau, False)):
        caplog.clear()
        with caplog.at_level(logging.WARNING):
            S.simulate(model, [S.ElectroThermal(power=dict(heat.power), duration=2 * dt,
                                                dt=dt, mechanics="quasi_static")])
        hits = [r for r in caplog.records if "quasi-static" in r.getMessage()]
        assert bool(hits) is warned
        if warned:
            assert "diffusion time over the device" in hits[0].getMessage()
