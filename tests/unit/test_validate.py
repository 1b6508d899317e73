"""The shared input checks (simulator/_validate.py) and the parameter classes that use them."""

import math
import re

import numpy as np
import pytest

import design
import simulator
from doors import public_names, public_object
from simulator import ParameterError
from simulator import _validate as v

NAN = float("nan")


# ------------------------------------------------------------------ one test per helper
def test_is_number():
    assert v.is_number(1) and v.is_number(2.5) and v.is_number(np.float32(1)) and v.is_number(NAN)
    assert not v.is_number(True) and not v.is_number(np.bool_(True)) and not v.is_number("1")


def test_number_with_a_custom_rule():
    assert v.number("x", 3, lambda x: x > 2, "a number > 2") == 3.0
    with pytest.raises(ParameterError, match=r"^x = 1 must be a number > 2 \[m\]; try 3\.$"):
        v.number("x", 1, lambda x: x > 2, "a number > 2", "m", hint="try 3")
    assert v.number("x", None, bool, "?", allow_none=True) is None


def test_positive():
    assert v.positive("dt", 2) == 2.0 and isinstance(v.positive("dt", 2), float)
    for bad in (0, -1.0, NAN, math.inf, "1", None):
        with pytest.raises(ParameterError, match=r"dt = .* must be a finite number > 0 \[s\]"):
            v.positive("dt", bad, "s")
    with pytest.raises(ParameterError, match=r"dt = True \(a bool is not a number\)"):
        v.positive("dt", True, "s")
    assert v.positive("dt", None, allow_none=True) is None


def test_non_negative():
    assert v.non_negative("g", 0) == 0.0
    for bad in (-1e-300, NAN, math.inf, False):
        with pytest.raises(ParameterError, match=r"g = .* must be a finite number >= 0 \[m/s\^2\]"):
            v.non_negative("g", bad, "m/s^2")


def test_finite():
    assert v.finite("T", -40) == -40.0
    for bad in (NAN, -math.inf, True, "hot"):
        with pytest.raises(ParameterError, match=r"T = .* must be a finite number \[deg C\]"):
            v.finite("T", bad, "deg C")


def test_in_range():
    assert v.in_range("theta", 0.5, 0.5, 1) == 0.5
    with pytest.raises(ParameterError, match=r"theta = 0.4 must be a number in \[0.5, 1\]"):
        v.in_range("theta", 0.4, 0.5, 1)
    with pytest.raises(ParameterError, match=r"must be a number in \(-1, 0.5\)"):
        v.in_range("nu", 0.5, -1, 0.5, open_low=True, open_high=True)
    with pytest.raises(ParameterError):
        v.in_range("theta", NAN, 0.5, 1)


def test_probability():
    assert v.probability("p", 1) == 1.0 and v.probability("p", 0) == 0.0
    for bad in (-0.1, 1.1, NAN, True):
        with pytest.raises(ParameterError, match=r"p = .* must be a probability in \[0, 1\]"):
            v.probability("p", bad)


def test_integer():
    assert v.integer("n", np.int64(3)) == 3 and type(v.integer("n", np.int64(3))) is int
    with pytest.raises(ParameterError, match=r"n = 0 must be a positive integer \(>= 1\)"):
        v.integer("n", 0)
    with pytest.raises(ParameterError, match=r"n = -1 must be a non-negative integer"):
        v.integer("n", -1, 0)
    with pytest.raises(ParameterError, match=r"n = 1 must be an integer >= 2"):
        v.integer("n", 1, 2)
    with pytest.raises(ParameterError, match=r"n = 9 must be an integer from 1 to 8"):
        v.integer("n", 9, 1, 8)
    for bad in (True, 2.0, NAN, "3"):
        with pytest.raises(ParameterError, match="n = "):
            v.integer("n", bad)


def test_one_of():
    assert v.one_of("mode", "a", ("a", "b")) == "a"
    with pytest.raises(ParameterError, match=r"mode = 'c' must be one of 'a', 'b'; see docs\."):
        v.one_of("mode", "c", ("a", "b"), hint="see docs")
    with pytest.raises(ParameterError):                 # True == 1, but a bool is no choice
        v.one_of("k", True, (1, 2))
    with pytest.raises(ParameterError):                 # 1.0 == 1, but of another type
        v.one_of("k", 1.0, (1, 2))


def test_array():
    out = v.array("x", [[0, 1, 2]], (None, 3), "m")
    assert out.dtype == float and out.shape == (1, 3)
    with pytest.raises(ParameterError, match=r"x must be a finite array of shape \(k, 3\) \[m\]; "
                                             r"got shape \(3,\)"):
        v.array("x", [0, 1, 2], (None, 3), "m")
    with pytest.raises(ParameterError, match=r"got nan at index \(0, 1\); one row per node\."):
        v.array("x", [[0, NAN, 2]], (1, 3), hint="one row per node")
    with pytest.raises(ParameterError, match="got 'abc'"):
        v.array("x", "abc", (3,))
    assert np.isnan(v.array("x", [NAN], (1,), finite_values=False)[0])
    with pytest.raises(ParameterError, match=r"got nan at index \(1, 2\)"):   # every entry
        v.array("x", [[0, 1, 2], [3, 4, NAN]], (2, 3))                    # (exact shape)


# ------------------------------------------------------------------ the wrong message of issue 18
def test_electrothermal_temperature_step_is_a_temperature():
    with pytest.raises(ParameterError) as err:
        simulator.ElectroThermal(temperature_step=-1)
    text = str(err.value)
    assert "ElectroThermal.temperature_step = -1" in text and "[K]" in text
    assert "time step" not in text and "[s]" not in text


def test_durations_are_not_called_time_steps():
    with pytest.raises(ParameterError) as err:
        simulator.TransientHeat({2: 1e-3}, duration=-1.0)
    assert "TransientHeat.duration = -1.0" in str(err.value) and "time step" not in str(err.value)
    with pytest.raises(ParameterError, match=r"TransientHeat.dt = 0.0 .*time step"):
        simulator.TransientHeat({2: 1e-3}, dt=0.0)


# ------------------------------------------------------------------ every public parameter class
def _with(cls, **base):
    return lambda **kw: cls(**{**base, **kw})


P, I, F = "positive", "integer", "finite"       # what a field must be (which values are wrong)
BAD = {P: (-1.0, NAN, True), I: (-1, NAN, True), F: (NAN, math.inf, True)}
CLASSES = {
    "ThermalParameters": (_with(simulator.ThermalParameters), {"room_temperature": F}),
    "ChainLoss": (_with(simulator.ChainLoss, thickness=1e-3), {
        "thickness": P, "dissipation_angle": P, "layers": I}),
    "IntegralLoss": (_with(simulator.IntegralLoss), {
        "refinement": I, "shape_tol": P, "correction_tol": P}),
    "SharpHingeParameters": (_with(simulator.model.SharpHingeParameters), {
        "fold_stiffness": P, "panel_bending_width": P}),
    "StepSignal": (_with(simulator.schedules.StepSignal, value=0.1), {"value": F, "t_on": F,
                                                              "offset": F}),
    "RampSignal": (_with(simulator.schedules.RampSignal, value=0.1, duration=1.0), {
        "value": F, "duration": P, "t_start": F, "offset": F}),
    "SquareWaveSignal": (_with(simulator.schedules.SquareWaveSignal, value=0.1, period=0.1), {
        "value": F, "period": P, "duty": P, "t_start": F, "offset": F}),
    "SineSignal": (_with(simulator.schedules.SineSignal, amplitude=0.1, frequency=10.0), {
        "amplitude": F, "frequency": P, "offset": F, "phase": F}),
    "BarHingeParameters": (_with(simulator.BarHingeParameters), {
        "diagonal_rate": P, "panel_bending_width": P, "centre_line_share": P}),
    "ContactParameters": (_with(simulator.ContactParameters), {
        "stiffness": P, "d0_corner": P, "d0_centre": P, "max_step_fraction": P}),
    "Bimorph": (_with(simulator.Bimorph, E1=79e9, t1=0.2e-6, E2=2e9, t2=0.8e-6), {
        "E1": P, "t1": P, "E2": P, "t2": P}),
    "Material": (_with(simulator.Material, name="m", youngs_modulus=2e9), {
        "youngs_modulus": P, "poisson_ratio": P, "density": P, "thermal_conductivity": P,
        "specific_heat": P, "glass_transition": F}),
    "Fluid": (_with(simulator.materials.Fluid, name="f", density=1.0, specific_heat=1e3,
                    thermal_conductivity=0.03), {
        "density": P, "specific_heat": P, "thermal_conductivity": P}),
    "NewtonOptions": (_with(simulator.NewtonOptions), {
        "atol": P, "rtol": P, "stall_rtol": P, "max_iter": I, "max_cuts": I,
        "max_total_cuts": I}),
    "DynamicsOptions": (_with(simulator.DynamicsOptions), {
        "rho_inf": P, "rayleigh_alpha": P, "rayleigh_beta": P, "air_damping": P, "rtol": P,
        "atol": P, "max_iter": I, "max_cuts": I}),
    "SelfFold": (_with(simulator.SelfFold, folds={2: 0.1}), {"increments": I}),
    "Load": (_with(simulator.Load, forces={0: (0, 0, 1e-6)}), {"increments": I}),
    "Gravity": (_with(simulator.Gravity), {"increments": I, "g": F, "scale": F}),
    "Heat": (_with(simulator.Heat, power={2: 1e-3}), {
        "increments": I, "coupling_tol": P, "max_coupling_iterations": I}),
    "AmbientTemperature": (_with(simulator.AmbientTemperature), {"target": F, "increments": I}),
    "TransientHeat": (_with(simulator.TransientHeat, power={2: 1e-3}), {
        "duration": P, "dt": P, "theta": P, "record_every": I}),
    "ElectroThermal": (_with(simulator.ElectroThermal, power={2: 1e-3}), {
        "duration": P, "dt": P, "dt_min": P, "dt_max": P, "theta": P, "temperature_step": P,
        "shape_tol": P, "record_every": I}),
    "Dynamics": (_with(simulator.Dynamics, duration=1e-3, dt=1e-5), {
        "duration": P, "dt": P, "record_every": I}),
    "ArcLengthLoad": (_with(simulator.ArcLengthLoad, forces={0: (0, 0, 1e-6)}), {
        "arc_length": P, "max_arc_length": P, "max_increments": I, "target_load_factor": F,
        "target_displacement": F}),
    "DisplacementControl": (_with(simulator.DisplacementControl), {
        "target": F, "increments": I}),
    "StepPower": (_with(simulator.schedules.StepPower, power=1e-3), {"power": P, "t_on": F}),
    "Ramp": (_with(simulator.schedules.Ramp, power=1e-3, duration=1.0), {
        "power": P, "duration": P, "t_start": F}),
    "SquareWave": (_with(simulator.schedules.SquareWave, power=1e-3, period=0.1), {
        "power": P, "period": P, "duty": P, "t_start": F}),
    "Sine": (_with(simulator.schedules.Sine, amplitude=1e-3, frequency=10.0), {
        "amplitude": F, "frequency": P, "phase": F}),
    "GripperDesign": (_with(design.GripperDesign), {
        "W": P, "L1": P, "L2": P, "La": P, "t_gold": P, "t_su8": P, "grip_range": P,
        "undercut": P, "panel_thickness": P, "delta_alpha": P, "env_conductivity": P,
        "residual_fold": F}),
    "MiuraDesign": (_with(design.MiuraDesign), {
        "a": P, "b": P, "gamma": P, "cells_x": I, "cells_y": I, "W": P, "t_gold": P,
        "t_su8": P, "panel_thickness": P, "undercut": P}),
    "Variable": (_with(design.Variable, name="W", lower=1e-4, upper=3e-4, step=1e-5,
                       start=2e-4), {"step": P, "lower": F}),
}
CASES = [(cls, fieldname, bad) for cls, (_, fields) in CLASSES.items()
         for fieldname, kind in fields.items() for bad in BAD[kind]]


def test_the_list_covers_the_public_parameter_classes():
    for cls in CLASSES:
        assert cls in public_names(simulator) or cls in public_names(design), cls
    steps = {n for n in public_names(simulator) if isinstance(public_object(simulator, n), type)
             and issubclass(public_object(simulator, n), simulator.steps.Step) and n != "Step"}
    assert steps <= set(CLASSES), steps - set(CLASSES)


@pytest.mark.parametrize("cls, fieldname, bad", CASES,
                         ids=[f"{c}.{f}={b!r}" for c, f, b in CASES])
def test_bad_values_are_refused_with_the_field_named(cls, fieldname, bad):
    make, _ = CLASSES[cls]
    with pytest.raises(ParameterError) as err:
        make(**{fieldname: bad})
    text = str(err.value)
    assert re.search(rf"\b{re.escape(fieldname)}\b", text), text
    assert repr(bad) in text or (fieldname == "residual_fold" and "rad" in text), text
