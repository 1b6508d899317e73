"""Electrical drive (issue 30 item 4, theory 8.8): heaters with a temperature coefficient of
resistance in circuits driven by voltage, current or power, in the steady and the transient
heating steps.

The analytic checks use the single and double fold with the actuators removed: the shape then
stays put, the steady heat problem is linear, and a crease's actuation temperature rises by
dT = P / G (G measured from the model at a small power), so a heater of base resistance R0 and
coefficient a at constant voltage V reaches the root of G dT (1 + a dT) = V^2 / R0, and at
constant current I the rise dT = k / (a (1 - k)), k = I^2 R0 a / G, below the run-away threshold
k = 1 and none above it.
"""

import dataclasses
import logging

import numpy as np
import pytest

from simulator import (Circuit, Drive, ElectroThermal, Heat, Heater, ParameterError, TransientHeat,
                       get_case, simulate)
from simulator.schedules import SquareWaveSignal
from simulator.thermal.circuits import RUNAWAY_TEMPERATURE

ROOM = 21.0


@pytest.fixture(scope="module")
def fold():
    """(model without actuators, crease id, conductance G [W/K] of its actuation measure)."""
    case = get_case("single_fold")
    model = dataclasses.replace(case.model, actuators=None)
    crease = int(model.mesh.crease_ids[0])
    r = simulate(model, [Heat({crease: 1e-4}, increments=1)])
    return model, crease, 1e-4 / (r.crease_temperature[-1, 0] - ROOM)


@pytest.fixture(scope="module")
def double():
    case = get_case("double_fold")
    model = dataclasses.replace(case.model, actuators=None)
    return model, [int(c) for c in model.mesh.crease_ids]


def _rise(result) -> np.ndarray:
    return result.crease_temperature[-1] - ROOM


def _last(result, name):
    return result.history["columns"][name][-1]


def test_constant_voltage_reaches_the_root_of_the_quadratic(fold):
    model, c, G = fold
    R0, a, V = 0.4, 0.0034, 0.3
    circuit = Circuit((Heater(c, resistance=R0, tcr=a),))
    result = simulate(model, [Heat(circuits={circuit: Drive(voltage=V)}, increments=4)])
    assert result.success, result.message
    exact = (-1 + np.sqrt(1 + 4 * a * V**2 / (R0 * G))) / (2 * a)
    assert _rise(result)[0] == pytest.approx(exact, rel=1e-6)
    linear = V**2 / (R0 * G)                    # without the coefficient: 23 % hotter
    assert linear > 1.1 * exact
    # the power is I^2 R(T), below V^2 / R0 by the factor R(T) / R0
    P = result.history["power"][-1, 0]
    assert P == pytest.approx(V**2 / (R0 * (1 + a * exact)), rel=1e-6)
    assert _last(result, "heater_resistance [Ohm]")[0] == pytest.approx(R0 * (1 + a * exact),
                                                                         rel=1e-6)
    assert _last(result, "circuit_1_voltage [V]") == pytest.approx(V, rel=1e-12)


def test_voltage_self_limits_where_its_room_temperature_current_runs_away(fold, caplog):
    model, c, G = fold
    R0, a = 0.4, 0.0034
    circuit = Circuit((Heater(c, resistance=R0, tcr=a),))
    V = np.sqrt(5 * R0 * G / a)                       # a V^2 / (R0 G) = 5
    at_voltage = simulate(model, [Heat(circuits={circuit: Drive(voltage=V)}, increments=10)])
    assert at_voltage.success
    exact = (-1 + np.sqrt(21)) / (2 * a)              # 527 K, bounded
    assert _rise(at_voltage)[0] == pytest.approx(exact, rel=1e-6)
    # the operating point is stable at constant current too (k < 1) ...
    k = _last(at_voltage, "circuit_1_current [A]") ** 2 * R0 * a / G
    assert k == pytest.approx(5 / (1 + a * exact) ** 2, rel=1e-9) and k < 1
    # ... but the current V drives at room temperature, held, runs away (k = 5)
    current = V / R0
    with caplog.at_level(logging.WARNING):
        at_current = simulate(model, [Heat(circuits={circuit: Drive(current=current)},
                                           increments=10)])
    assert not at_current.success and at_current.status == "thermal_runaway"
    assert "run-away" in at_current.message and "Drive by voltage" in at_current.message
    assert any("run-away" in r.getMessage() for r in caplog.records)
    assert np.all(np.isfinite(at_current.history["temperature"]))


@pytest.mark.parametrize("k", [0.7, 0.95, 1.05])
def test_constant_current_runs_away_above_the_analytic_threshold(fold, k):
    model, c, G = fold
    R0 = 0.4
    a = 0.0034 if k < 0.9 else 0.2      # a large coefficient keeps k = 0.95 below 1000 degC
    circuit = Circuit((Heater(c, resistance=R0, tcr=a),))
    current = np.sqrt(k * G / (R0 * a))
    result = simulate(model, [Heat(circuits={circuit: Drive(current=current)}, increments=1)])
    if k < 1:
        assert result.success, result.message
        assert _rise(result)[0] == pytest.approx(k / (a * (1 - k)), rel=1e-6)
    else:
        assert result.status == "thermal_runaway"
        assert "resistance" in result.message and "<= 0" in result.message


def test_series_circuit_puts_more_power_into_the_hotter_crease(double):
    model, (a, b) = double
    R0, tcr, lead, V = 0.4, 0.0034, 0.5, 0.3
    circuit = Circuit((Heater(a, resistance=R0, tcr=tcr), Heater(b, resistance=R0, tcr=tcr)),
                      lead_resistance=lead)
    result = simulate(model, [Heat({a: 5e-3}, increments=1),          # crease a the hotter
                              Heat(circuits={circuit: Drive(voltage=V)}, increments=5)])
    assert result.success, result.message
    T = result.crease_temperature[-1]
    p = result.history["power"][-1] - np.array([5e-3, 0.0])
    R = R0 * (1 + tcr * (T - ROOM))
    assert T[0] > T[1] + 5 and p[0] > 1.02 * p[1]
    assert p[0] / p[1] == pytest.approx(R[0] / R[1], rel=1e-9)
    np.testing.assert_allclose(_last(result, "heater_resistance [Ohm]"), R, rtol=1e-12)
    I = _last(result, "circuit_1_current [A]")
    assert I == pytest.approx(V / (R.sum() + lead), rel=1e-9)
    assert _last(result, "circuit_1_lead_loss [W]") == pytest.approx(I**2 * lead, rel=1e-12)
    assert _last(result, "circuit_1_lead_loss [W]") > 0.2 * p.sum()
    assert _last(result, "circuit_1_power [W]") == pytest.approx(
        p.sum() + I**2 * lead, rel=1e-9)
    assert _last(result, "circuit_1_voltage [V]") == pytest.approx(V, rel=1e-12)


def test_parallel_circuit_puts_less_power_into_the_hotter_crease(double):
    model, (a, b) = double
    R0, tcr, lead, V = 0.4, 0.0034, 0.1, 0.1
    circuit = Circuit((Heater(a, resistance=R0, tcr=tcr), Heater(b, resistance=R0, tcr=tcr)),
                      connection="parallel", lead_resistance=lead)
    result = simulate(model, [Heat({a: 5e-3}, increments=1),
                              Heat(circuits={circuit: Drive(voltage=V)}, increments=5)])
    assert result.success, result.message
    T = result.crease_temperature[-1]
    p = result.history["power"][-1] - np.array([5e-3, 0.0])
    R = R0 * (1 + tcr * (T - ROOM))
    assert T[0] > T[1] and p[0] < p[1]
    I = _last(result, "circuit_1_current [A]")
    v_heaters = V - I * lead
    np.testing.assert_allclose(p, v_heaters**2 / R, rtol=1e-9)
    assert I == pytest.approx(np.sum(v_heaters / R), rel=1e-9)


def test_power_drive_delivers_its_power_to_heaters_and_leads(double):
    model, (a, b) = double
    P, lead = 20e-3, 0.3
    circuit = Circuit((a, b), lead_resistance=lead)            # gold films over the creases
    result = simulate(model, [Heat(circuits={circuit: Drive(power=P)}, increments=3)])
    assert result.success
    heaters = result.history["power"][-1].sum()
    assert _last(result, "circuit_1_power [W]") == pytest.approx(P, rel=1e-12)
    assert heaters + _last(result, "circuit_1_lead_loss [W]") == pytest.approx(P, rel=1e-9)
    # the default heater: 0.15 Ohm/sq times the crease's length over its width, at room temp
    pattern = model.mesh.pattern
    i, j = pattern.edges[a]
    squares = np.linalg.norm(pattern.vertices[i] - pattern.vertices[j]) / \
        pattern.crease_width[a]
    T = result.crease_temperature[-1, 0]
    assert _last(result, "heater_resistance [Ohm]")[0] == pytest.approx(
        0.15 * squares * (1 + 0.0034 * (T - ROOM)), rel=1e-12)


def test_a_drive_ramps_from_the_state_and_a_later_step_keeps_driving_the_circuit(double):
    model, (a, b) = double
    circuit = Circuit((Heater(a, resistance=0.4),))
    result = simulate(model, [Heat(circuits={circuit: Drive(voltage=0.05)}, increments=2),
                              Heat(circuits={circuit: Drive(voltage=0.09)}, increments=4),
                              Heat({b: 20e-3}, increments=2)])
    assert result.success
    volts = result.history["columns"]["circuit_1_voltage [V]"]
    np.testing.assert_allclose(volts[1:], [0.025, 0.05, 0.06, 0.07, 0.08, 0.09, 0.09, 0.09])
    power_a = result.history["power"][:, 0]
    # heating crease b warms crease a: its heater's resistance rises, its power falls
    assert power_a[-1] < power_a[-3] * (1 - 1e-4)
    assert result.history["power"][-1, 1] == pytest.approx(20e-3, rel=1e-12)


def test_a_drive_of_another_kind_ramps_from_the_state_s_operating_point(double):
    model, (a, b) = double
    circuit = Circuit((Heater(a, resistance=0.4),), lead_resistance=0.2)
    result = simulate(model, [Heat(circuits={circuit: Drive(voltage=0.1)}, increments=2),
                              Heat(circuits={circuit: Drive(current=0.3)}, increments=4)])
    assert result.success
    amps = np.array(result.history["columns"]["circuit_1_current [A]"][1:], float)
    R = result.history["columns"]["heater_resistance [Ohm]"][2][0]
    assert R > 0.41 and amps[1] == pytest.approx(0.1 / (R + 0.2), rel=1e-12)   # 0.1 V there
    np.testing.assert_allclose(amps[2:], amps[1] + (0.3 - amps[1]) * np.arange(1, 5) / 4,
                               rtol=1e-12)


def test_transient_at_constant_voltage_settles_on_the_steady_operating_point(fold):
    model, c, G = fold
    circuit = Circuit((Heater(c, resistance=0.4),))
    drive = {circuit: Drive(voltage=0.12)}
    steady = simulate(model, [Heat(circuits=drive, increments=2)])
    transient = simulate(model, [TransientHeat(circuits=drive, duration=3.0, dt=0.01,
                                               record_every=50)])
    assert transient.success, transient.message
    assert _rise(transient)[0] == pytest.approx(_rise(steady)[0], rel=1e-6)
    assert _last(transient, "circuit_1_current [A]") == pytest.approx(
        _last(steady, "circuit_1_current [A]"), rel=1e-6)


def test_transient_at_constant_current_above_the_threshold_is_reported(fold):
    model, c, G = fold
    R0, a = 0.4, 0.0034
    circuit = Circuit((Heater(c, resistance=R0, tcr=a),))
    current = np.sqrt(1.2 * G / (R0 * a))
    result = simulate(model, [TransientHeat(circuits={circuit: Drive(current=current)},
                                            duration=100.0, dt=0.01)])
    assert result.status == "thermal_runaway" and not result.success
    assert "run-away" in result.message
    T = result.crease_temperature[-1, 0]
    assert RUNAWAY_TEMPERATURE < T < 2 * RUNAWAY_TEMPERATURE
    assert result.steps[0].state.time < 100.0         # stopped, not run to the end


def test_electrothermal_follows_a_voltage_schedule(double):
    model = get_case("double_fold").model                # with its actuators
    a, b = (int(c) for c in model.mesh.crease_ids)
    circuit = Circuit((a, b), name="both")
    pulse = SquareWaveSignal(0.2, period=0.2, duty=0.5)
    result = simulate(model, [ElectroThermal(circuits={circuit: Drive(voltage=pulse)},
                                             duration=0.3, dt=0.01,
                                             mechanics="quasi_static")])
    assert result.success, result.message
    cols = result.history["columns"]
    t = np.array(cols["time [s]"][1:], float)
    volts = np.array(cols["circuit_both_voltage [V]"][1:], float)
    np.testing.assert_allclose(volts, pulse(t), atol=1e-12)
    assert abs(np.degrees(result.fold_angle[-1])).max() > 1
    assert result.state.circuits and result.state.circuits[0][1].voltage == pulse(0.3)


def test_no_circuit_leaves_the_state_without_circuits(fold):
    model, c, _ = fold
    result = simulate(model, [Heat({c: 1e-3}, increments=2)])
    assert result.state.circuits == () and result.state.circuit_power is None
    assert not any(n.startswith("circuit_") for n in result.history["columns"])


def test_write_model_refuses_circuits(fold, tmp_path):
    from simulator.fold import write_model

    model, c, _ = fold
    step = Heat(circuits={Circuit((c,)): Drive(voltage=0.1)})
    with pytest.raises(ParameterError, match="circuits: heater circuits have no FOLD form"):
        write_model(model, [step], tmp_path / "m.fold")


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("build, match", [
    (lambda: Heater(2, resistance=-1.0),
     r"Heater.resistance = -1.0 must be a finite number > 0 \[Ohm\]; give resistance"),
    (lambda: Heater(2, resistance=1.0, squares=3),
     "resistance = 1.0 Ohm and squares = 3 are both given; give one"),
    (lambda: Heater(2, sheet_resistance=0.0), r"Heater.sheet_resistance = 0.0 .* 0.12-0.18"),
    (lambda: Heater(-3), r"Heater.crease = -3 must be a crease id"),
    (lambda: Drive(voltage=1.0, current=2e-3),
     r"voltage = 1.0 V and current = 0.002 A given; .* give exactly one of voltage"),
    (lambda: Drive(), "nothing given; .* give exactly one"),
    (lambda: Drive(current=-1e-3), r"Drive.current = -0.001 must be a finite number >= 0 \[A\]"),
    (lambda: Drive(power=SquareWaveSignal(1.0, period=1.0)), "must be a constant >= 0 .* "
                                                             "PowerSchedule"),
    (lambda: Circuit((2, 2)), "crease 2 has two heaters; give each crease one Heater"),
    (lambda: Circuit((2,), connection="star"), r"Circuit.connection = 'star' must be one of"),
    (lambda: Circuit((2,), lead_resistance=-1), r"Circuit.lead_resistance = -1 must be .* >= 0"),
    (lambda: Heat(circuits={Circuit((2,)): Drive(voltage=1.0), Circuit((2, 5)): Drive(
        current=1e-3)}), "crease 2 is in circuit 1 and in circuit 2; .* join them in one"),
    (lambda: Heat(circuits={Circuit((2,)): 1.0}),
     r"give Circuit\(\.\.\.\): Drive\(voltage=\.\.\.\)"),
    (lambda: Heat(circuits={Circuit((2,)): Drive(voltage=SquareWaveSignal(1.0, period=1.0))}),
     "Heat ramps to a constant: give a number, or use TransientHeat / ElectroThermal"),
])
def test_bad_input_names_field_value_and_fix(build, match):
    with pytest.raises(ParameterError, match=match):
        build()


def test_a_heater_on_a_crease_that_does_not_exist_is_refused(fold):
    model, c, _ = fold
    step = Heat(circuits={Circuit((Heater(99, resistance=1.0),)): Drive(voltage=0.1)})
    with pytest.raises(ParameterError, match=r"Heat: Heater.crease = 99 is not a crease of the "
                                             r"model .*interior creases are \[2\]"):
        simulate(model, [step])
