"""Coupled electro-thermal dynamics: the ElectroThermal step and single_fold_step_response."""

import dataclasses

import numpy as np
import pandas as pd
import pytest

from simulator import ElectroThermal, Heat, ParameterError, get_case, simulate
from simulator.schedules import SquareWave, StepPower
from simulator.thermal import REFERENCE_THETA

P = 3e-3                                          # W, the case's default power


@pytest.fixture(scope="module")
def prepared():
    """The step-response case (short phases) and its state after self-fold and gravity."""
    case = get_case("single_fold_step_response", t_on=0.6, t_off=0.6, dt_max=1e-2)
    pre = simulate(case.model, case.steps[:-1])
    assert pre.success, pre.message
    return case, pre.state, np.degrees(pre.fold_angle[-1, 0])


@pytest.fixture(scope="module")
def response(prepared):
    case, state, _ = prepared
    res = simulate(case.model, case.steps[-1:], state=state)
    assert res.success, res.message
    return res


def _fold_deg(res):
    """Fold [deg] of every record after the initial one (aligned with the step's columns)."""
    return np.degrees(res.fold_angle[1:, 0])


def test_reaches_the_static_fold_and_cools_back(prepared, response):
    case, state, start = prepared
    static = simulate(case.model, [Heat({2: P}, increments=10, coupling="iterated")],
                      state=state)
    t = response.steps[0].columns["time [s]"]
    on = np.searchsorted(t, 0.6 - 1e-12)
    assert t[on] == pytest.approx(0.6)
    assert abs(_fold_deg(response)[on] - np.degrees(static.fold_angle[-1, 0])) < 0.05
    assert abs(response.crease_temperature[on + 1, 0] - static.crease_temperature[-1, 0]) < 0.05
    room = state.room_temperature
    assert np.max(np.abs(response.state.temperature - room)) < 0.5
    # the fold rose on heating and came back to the pre-heating fold
    assert _fold_deg(response).max() > start + 10
    assert abs(_fold_deg(response)[-1] - start) < 0.05
    assert response.state.velocity is not None and response.state.time == pytest.approx(1.2)


def test_energy_and_time_columns(response):
    cols = response.steps[0].columns
    t = cols["time [s]"]
    assert t[0] == 0.0 and np.all(np.diff(t) > 0) and t[-1] == pytest.approx(1.2)
    assert cols["dt [s]"][0] is None                           # the start record: no step
    dt = cols["dt [s]"][1:].astype(float)
    np.testing.assert_allclose(np.diff(t), dt, rtol=1e-9, atol=1e-15)
    for name in ("heat_in [J]", "heat_out [J]", "dissipated_energy [J]", "external_work [J]"):
        assert cols[name][0] == 0.0                             # counted from the start
    # the heat put in is the integral of the power, exactly (mean power per step)
    assert cols["heat_in [J]"][-1] == pytest.approx(P * 0.6, rel=1e-12)
    # nearly all of it has left again after cooling
    assert cols["heat_out [J]"][-1] == pytest.approx(P * 0.6, rel=1e-3)
    assert np.all(cols["kinetic_energy [J]"] >= 0) and np.all(cols["strain_energy [J]"] >= 0)
    dissipated = cols["dissipated_energy [J]"]        # trapezoidal estimate: ~monotone
    assert dissipated[-1] > 0 and np.all(np.diff(dissipated) >= -1e-3 * dissipated[-1])
    assert 1e-5 <= dt.min() and dt.max() <= 1e-2 * (1 + 1e-12)


def test_identical_between_runs_and_csv_has_time(prepared, response, tmp_path):
    case, state, _ = prepared
    again = simulate(case.model, case.steps[-1:], state=state)
    a, b = response.to_frame(), again.to_frame()
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    response.save(tmp_path)
    csv = pd.read_csv(tmp_path / "creases.csv")
    assert "time [s]" in csv and "kinetic_energy [J]" in csv and "heat_in [J]" in csv


def test_quasi_static_mechanics_and_fixed_steps(prepared):
    case, state, _ = prepared
    step = ElectroThermal({2: StepPower(P, 0.0, 0.02)}, duration=0.04, dt=2e-3,
                          mechanics="quasi_static")
    res = simulate(case.model, [step], state=state)
    assert res.success, res.message
    cols = res.steps[0].columns
    assert cols["dt [s]"][0] is None                           # the start record
    np.testing.assert_allclose(cols["dt [s]"][1:].astype(float), 2e-3)
    assert len(cols["dt [s]"]) == 21
    assert np.all(cols["kinetic_energy [J]"] == 0) and res.state.velocity is None
    assert all(v is None for v in cols["dissipated_energy [J]"])
    assert _fold_deg(res)[10] > _fold_deg(res)[0] + 5         # heated: folds up


def test_shape_tolerance_keeps_the_assembly(prepared):
    case, state, _ = prepared
    base = ElectroThermal({2: P}, duration=0.02, dt=2e-3, mechanics="quasi_static",
                          theta=REFERENCE_THETA)                 # the counts below are theta's
    exact = simulate(case.model, [base], state=state)
    lazy = simulate(case.model, [dataclasses.replace(base, shape_tol=5e-6)], state=state)
    frozen = simulate(case.model, [dataclasses.replace(base, shape_tol=1.0)], state=state)
    assert "(10 heat assemblies)" in exact.steps[0].message
    assert "(6 heat assemblies)" in lazy.steps[0].message
    assert "(1 heat assemblies)" in frozen.steps[0].message
    # folding changes the heat loss: a frozen shape is 0.6 deg off after 13 deg of folding
    assert abs(_fold_deg(lazy)[-1] - _fold_deg(exact)[-1]) < 0.05
    assert 0.3 < abs(_fold_deg(frozen)[-1] - _fold_deg(exact)[-1]) < 1.0


def test_square_wave_and_record_every(prepared):
    case, state, _ = prepared
    step = ElectroThermal({2: SquareWave(P, period=0.01, duty=0.5)}, duration=0.02, dt=1e-3,
                          record_every=5)
    res = simulate(case.model, [step], state=state)
    assert res.success, res.message
    np.testing.assert_allclose(res.steps[0].columns["time [s]"],
                               [0.0, 0.005, 0.01, 0.015, 0.02])
    assert res.steps[0].columns["heat_in [J]"][-1] == pytest.approx(P * 0.01, rel=1e-12)


@pytest.mark.parametrize("make, match", [
    (lambda: ElectroThermal({2: P}, duration=1.0, dt=0.0), "dt = 0"),
    (lambda: ElectroThermal({2: P}, duration=1.0, dt=-1e-3), "dt = -0.001"),
    (lambda: ElectroThermal({2: P}, duration=0.0, dt=1e-3), "duration"),
    (lambda: ElectroThermal({2: P}, dt=1e-3, dt_min=1e-2, dt_max=1e-3), "dt_min .* > dt_max"),
    (lambda: ElectroThermal({2: P}, dt=1e-1, dt_min=1e-3, dt_max=1e-2), "outside"),
    (lambda: ElectroThermal({2: P}, mechanics="static"), "mechanics"),
    (lambda: ElectroThermal({2: P}, shape_tol=-1.0), "shape_tol"),
    (lambda: ElectroThermal({2: P}, temperature_step=0), "temperature_step"),
    (lambda: ElectroThermal({2: P}, record_every=0), "record_every"),
    (lambda: ElectroThermal({2: P}, options="fast"), "DynamicsOptions"),
    (lambda: ElectroThermal({2: -1.0}), "power"),
    (lambda: ElectroThermal({2: SquareWave(P, period=0.1, duty=1.0)}), "duty"),
    (lambda: ElectroThermal({2: SquareWave(P, period=0.1, duty=0.0)}), "duty"),
    (lambda: get_case("single_fold_step_response", t_on=0.0), "t_on"),
    (lambda: get_case("single_fold_step_response", air_damping=-1.0), "air_damping"),
    (lambda: get_case("single_fold_step_response", dt_min=1e-2, dt_max=1e-3),
     "dt_min .* > dt_max"),
])
def test_bad_inputs(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


@pytest.mark.slow
def test_default_case_acceptance():
    """Issue 10 acceptance on the case as shipped (1 s on, 1 s off; ~15 s)."""
    case = get_case("single-fold-step-response")
    res = case.run()
    assert res.success, res.message
    pre = simulate(case.model, case.steps[:-1])
    static = simulate(case.model, [Heat({2: P}, increments=10, coupling="iterated")],
                      state=pre.state)
    t = res.steps[-1].columns["time [s]"]
    on = len(res.fold_angle) - len(t) + np.searchsorted(t, 1.0 - 1e-12)
    assert abs(np.degrees(res.fold_angle[on, 0]) - np.degrees(static.fold_angle[-1, 0])) < 0.05
    assert np.max(np.abs(res.state.temperature - res.state.room_temperature)) < 0.5


def test_case_is_registered_with_units():
    from simulator.cases import describe_cases

    case = get_case("single-fold-step-response", power_mW=5.0, t_on=0.5, t_off=0.25)
    step = case.steps[-1]
    assert isinstance(step, ElectroThermal) and step.duration == pytest.approx(0.75)
    assert step.power[2](0.49) == pytest.approx(5e-3) and step.power[2](0.5) == 0.0
    assert step.bounds == (1e-5, 5e-3) and step.options.air_damping == 2.0
    entry = {name: params for name, _, params in describe_cases()}["single_fold_step_response"]
    assert ("power_mW", 3.0, "mW") in entry and ("t_on", 1.0, "s") in entry
