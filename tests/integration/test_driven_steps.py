"""Time schedules as mechanical drives of Dynamics and ElectroThermal (simulator.steps.drives)."""

import dataclasses

import numpy as np
import pytest

from simulator import Dynamics, DynamicsOptions, ElectroThermal, ParameterError, get_case, simulate
from simulator.cases import single_fold_model
from simulator.steps import initial_state
from simulator.schedules import PiecewiseLinearSignal, RampSignal, SineSignal, StepSignal


@pytest.fixture(scope="module")
def prepared():
    """The single fold without substrate (nothing to touch), unloaded, and its free tip node."""
    case = get_case("single_fold_step_response")
    thermal = dataclasses.replace(case.model.thermal, boundary_panels=(),
                                  room_temperature_nodes=(0, 1, 2, 3))
    model = single_fold_model(contact=False, substrate=False, thermal=thermal,
                              actuators=case.model.actuators)
    free = np.flatnonzero(~model.fixed_mask.any(axis=1))
    tip = int(free[np.argmax(model.mesh.nodes[free, 0])])
    return model, initial_state(model), tip


def test_quasi_static_electrothermal_follows_a_driven_rest_angle(prepared):
    """Without power or load, a crease whose rest angle is ramped follows it quasi-statically."""
    model, state, _ = prepared
    ramp = RampSignal(value=0.3, duration=0.05)
    step = ElectroThermal(duration=0.1, dt=1e-2, mechanics="quasi_static", folds={2: ramp})
    res = simulate(model, [step], state=state)
    assert res.success, res.message
    t = res.steps[0].columns["time [s]"] - state.time
    np.testing.assert_allclose(res.fold_angle[1:, 0], ramp(t), atol=1e-6)
    assert res.state.crease_rest[0] == pytest.approx(np.pi + 0.3)


def test_a_scheduled_force_does_work_and_stays_applied(prepared):
    model, state, tip = prepared
    push = StepSignal(1.0, t_on=0.02)
    step = ElectroThermal(duration=0.05, dt=1e-2, mechanics="quasi_static",
                          forces={tip: ((0.0, 0.0, 1e-7), push)})
    res = simulate(model, [step], state=state)
    assert res.success, res.message
    t = res.steps[0].columns["time [s]"] - state.time
    assert np.any(np.isclose(t, 0.02))               # a step ends on the switch
    assert res.state.applied_load[tip, 2] == pytest.approx(state.applied_load[tip, 2] + 1e-7)
    assert res.steps[0].columns["external_work [J]"][-1] > 0


def test_dynamics_force_schedule_equals_the_constant_force_when_it_is_one(prepared):
    model, state, tip = prepared
    opts = DynamicsOptions(method="generalized_alpha", rho_inf=0.5)
    const = Dynamics(duration=2e-3, dt=5e-4, forces={tip: (0, 0, 1e-7)}, options=opts)
    timed = Dynamics(duration=2e-3, dt=5e-4, options=opts,
                     forces={tip: ((0, 0, 1e-7), PiecewiseLinearSignal((0.0, 1.0), (1.0, 1.0)))})
    a, b = (simulate(model, [s], state=state) for s in (const, timed))
    np.testing.assert_allclose(a.state.u, b.state.u, rtol=0, atol=1e-15)
    assert np.abs(a.state.u).max() > 1e-9
    assert timed.describe()["forces [N]"][str(tip)]["schedule"] == "PiecewiseLinearSignal"


def test_bad_drives_are_refused():
    with pytest.raises(ParameterError, match="force of node 3"):
        Dynamics(duration=1e-3, dt=1e-4, forces={3: ((0, 0, 1), "sine")})
    with pytest.raises(ParameterError, match="fold angle of crease 2"):
        Dynamics(duration=1e-3, dt=1e-4, folds={2: "fast"})
    with pytest.raises(ParameterError, match="folds"):
        ElectroThermal(duration=1e-3, dt=1e-4, folds=[(2, SineSignal(0.1, 10.0))])
