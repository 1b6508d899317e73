"""Time schedules (simulator.schedules): signed signals and the power schedules built on the same
shapes."""

import math

import numpy as np
import pytest

from simulator import ParameterError
from simulator.schedules import (PiecewiseLinear, PiecewiseLinearSignal, PowerSchedule, Ramp,
                                 RampSignal, Schedule, Sine, SineSignal, SquareWave,
                                 SquareWaveSignal, StepPower, StepSignal)
from simulator.schedules import next_switch

SIGNALS = [StepSignal(-0.3, t_on=0.2, t_off=0.7, offset=0.1),
           RampSignal(-0.5, duration=0.4, t_start=0.1, offset=0.2),
           SquareWaveSignal(0.4, period=0.3, duty=0.25, t_start=0.05, offset=-0.1),
           SineSignal(amplitude=0.2, frequency=3.0, offset=-0.05, phase=0.4),
           PiecewiseLinearSignal((0.0, 0.3, 0.6), (0.1, -0.4, 0.2))]


@pytest.mark.parametrize("signal", SIGNALS, ids=lambda s: type(s).__name__)
def test_signal_mean_is_the_exact_integral(signal):
    t = np.linspace(-0.1, 1.0, 400001)
    v = signal(t)
    numeric = np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(t)) / (t[-1] - t[0])
    assert signal.mean(-0.1, 1.0) == pytest.approx(numeric, abs=1e-5)
    assert isinstance(signal(0.3), float) and signal(t.reshape(-1, 1)).shape == (t.size, 1)
    assert signal.describe()["schedule"] == type(signal).__name__


def test_signals_take_negative_values_and_power_schedules_do_not():
    assert SineSignal(0.2, 1.0)(0.75) == pytest.approx(-0.2)
    assert StepSignal(-1.0)(0.0) == -1.0
    with pytest.raises(ParameterError, match="offset"):
        Sine(amplitude=1e-3, frequency=1.0, offset=0.0)
    with pytest.raises(ParameterError, match="values"):
        PiecewiseLinear((0, 1), (1e-3, -1e-3))
    assert issubclass(PowerSchedule, Schedule)


@pytest.mark.parametrize("power, signal", [
    (StepPower(2e-3, t_on=0.1, t_off=0.5), StepSignal(2e-3, t_on=0.1, t_off=0.5)),
    (Ramp(2e-3, 0.3, t_start=0.1), RampSignal(2e-3, 0.3, t_start=0.1)),
    (SquareWave(2e-3, 0.2, duty=0.3, t_start=0.05), SquareWaveSignal(2e-3, 0.2, duty=0.3,
                                                                      t_start=0.05)),
    (Sine(1e-3, 5.0, offset=2e-3), SineSignal(1e-3, 5.0, offset=2e-3)),
    (PiecewiseLinear((0, 0.5), (0, 3e-3)), PiecewiseLinearSignal((0, 0.5), (0, 3e-3)))])
def test_power_schedules_and_signals_share_their_shapes(power, signal):
    t = np.linspace(-0.2, 1.2, 1001)
    np.testing.assert_array_equal(power(t), signal(t))
    np.testing.assert_allclose(power.mean(0.0, 0.77), signal.mean(0.0, 0.77), rtol=1e-14)
    assert power.switch_times(0.0) == signal.switch_times(0.0)


def test_next_switch():
    s = [StepSignal(1.0, t_on=0.2, t_off=0.6), SquareWaveSignal(1.0, period=0.25, duty=0.5),
         SineSignal(1.0, 2.0)]
    assert next_switch(s, 0.0) == pytest.approx(0.125)
    assert next_switch(s, 0.13) == pytest.approx(0.2)
    assert next_switch(s[2:], 0.0) == math.inf


def test_bad_tables_are_refused():
    with pytest.raises(ParameterError, match="strictly increasing"):
        PiecewiseLinearSignal((0.0, 0.0), (1.0, 2.0))
    with pytest.raises(ParameterError, match="equal length"):
        PiecewiseLinearSignal((0.0, 1.0), (1.0,))
