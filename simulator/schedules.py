"""Time schedules: a value as a function of time, for heating powers and mechanical drives.

:class:`Schedule` is the common base: a frozen dataclass mapping time t [s] to a value,
vectorised over ``t`` (a float gives a float, an array an array of the same shape), with the
exact mean over an interval and a JSON-able description. Two families share its shapes (step,
ramp, square wave, sine, piecewise linear; the formulas are the functions below):

* the **power schedules** (:class:`StepPower`, :class:`Ramp`, :class:`SquareWave`,
  :class:`Sine`, :class:`PiecewiseLinear`, defined in :mod:`simulator.thermal.schedules`):
  non-negative powers [W] of heaters, the field ``power``;
* the **signals** (:class:`StepSignal`, :class:`RampSignal`, :class:`SquareWaveSignal`,
  :class:`SineSignal`, :class:`PiecewiseLinearSignal`): signed values of any unit, for the
  mechanical drives of :class:`~simulator.steps.Dynamics` and
  :class:`~simulator.steps.ElectroThermal` (a crease's rest fold angle [rad], or the
  dimensionless factor of a force vector).

The two families are not aliases of each other: a power schedule refuses a negative power and
its sine's offset defaults to ``|amplitude|`` (a heater cannot cool), while a signal is signed
about ``offset`` (default 0). The heating steps take power schedules (or constant watts); every
schedule may be used where a signal is expected (a power schedule is a non-negative signal).
``switch_times(t)`` lists the times at which a schedule jumps (steps, square waves) or kinks
(tables), so that adaptive time steppers end their steps there; ramps and sines list none.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import asdict, dataclass

import numpy as np

from ._lazy import attach as _attach
from ._validate import finite, number, positive
from .errors import ParameterError

# the power schedules live beside the heat they drive and import the shapes from here
__getattr__, __dir__ = _attach(__name__, {
    ".thermal.schedules": ("PowerSchedule", "StepPower", "Ramp", "SquareWave", "Sine",
                           "PiecewiseLinear"),
})

__all__ = ["Schedule",  # noqa: F822 - the power schedules come from __getattr__
           # power schedules [W] >= 0: Heat, TransientHeat, ElectroThermal heaters
           "PowerSchedule", "StepPower", "Ramp", "SquareWave", "Sine", "PiecewiseLinear",
           # signed signals: the mechanical drives of Dynamics and ElectroThermal
           "StepSignal", "RampSignal", "SquareWaveSignal", "SineSignal", "PiecewiseLinearSignal"]


class Schedule(ABC):
    """A value as a function of time [s]; subclasses implement :meth:`_values` and
    :meth:`_integral`."""

    def __call__(self, t):
        """Value at time(s) ``t`` [s] (float -> float, array -> array of the same shape)."""
        arr = np.asarray(t, float)
        out = self._values(arr)
        return float(out) if arr.ndim == 0 else out

    @abstractmethod
    def _values(self, t: np.ndarray) -> np.ndarray:
        """Values at the times ``t`` (any shape)."""

    @abstractmethod
    def _integral(self, t: np.ndarray) -> np.ndarray:
        """An antiderivative of the value at the times ``t`` (differences are integrals)."""

    def mean(self, t0, t1):
        """Mean value over ``[t0, t1]`` [s] (exact; arrays broadcast; t1 > t0)."""
        t0, t1 = np.asarray(t0, float), np.asarray(t1, float)
        out = (self._integral(t1) - self._integral(t0)) / (t1 - t0)
        return float(out) if out.ndim == 0 else out

    def switch_times(self, t: float) -> tuple:
        """Times near and after ``t`` [s] at which the value jumps or kinks (none: smooth)."""
        return ()

    def describe(self) -> dict:
        """JSON-able description (class name and fields, SI units; infinite times as None)."""
        fields = {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                  for k, v in asdict(self).items()}
        return {"schedule": type(self).__name__, **fields}


def next_switch(schedules, t: float) -> float:
    """Earliest time after ``t`` [s] at which one of ``schedules`` jumps or kinks (inf if none)."""
    later = [x for s in schedules for x in s.switch_times(t) if x > t * (1 + 1e-12) + 1e-15]
    return min(later, default=math.inf)


# ------------------------------------------------------------------ the shapes (shared formulas)
def step_values(t, level, t_on, t_off):
    """``level`` for ``t_on <= t < t_off``, else 0."""
    return np.where((t >= t_on) & (t < t_off), level, 0.0)


def step_integral(t, level, t_on, t_off):
    return level * (np.clip(t, t_on, t_off) - t_on)


def ramp_values(t, level, duration, t_start):
    """0 before ``t_start``, linear to ``level`` over ``duration``, then held."""
    return level * np.clip((t - t_start) / duration, 0.0, 1.0)


def ramp_integral(t, level, duration, t_start):
    u = np.clip((t - t_start) / duration, 0.0, 1.0)
    held = np.maximum(t - t_start - duration, 0.0)
    return level * (0.5 * duration * u**2 + held)


def square_values(t, level, period, duty, t_start):
    """``level`` during the first ``duty`` of every ``period`` from ``t_start`` on, else 0."""
    phase = (t - t_start) / period
    on = (phase >= 0) & (phase - np.floor(phase) < duty)
    return np.where(on, level, 0.0)


def square_integral(t, level, period, duty, t_start):
    phase = np.maximum((t - t_start) / period, 0.0)
    whole = np.floor(phase)
    return level * period * (whole * duty + np.minimum(phase - whole, duty))


def square_switches(t, period, duty, t_start) -> tuple:
    k = max(0.0, math.floor((t - t_start) / period))
    start = t_start + k * period
    return (start, start + duty * period, start + period)


def sine_values(t, amplitude, frequency, offset, phase):
    return offset + amplitude * np.sin(2 * np.pi * frequency * t + phase)


def sine_integral(t, amplitude, frequency, offset, phase):
    w = 2 * np.pi * frequency
    return offset * t - amplitude / w * np.cos(w * t + phase)


def table_values(t, times, values):
    """Linear interpolation, held at the first and last values outside the table."""
    return np.interp(t, times, values)


def table_integral(t, times, values):
    tk, pk = np.array(times), np.array(values)
    if len(tk) == 1:
        return pk[0] * (t - tk[0])
    ek = np.r_[0.0, np.cumsum(0.5 * (pk[1:] + pk[:-1]) * np.diff(tk))]
    i = np.clip(np.searchsorted(tk, t, side="right") - 1, 0, len(tk) - 2)
    s = np.clip(t, tk[0], tk[-1]) - tk[i]
    slope = (pk[i + 1] - pk[i]) / (tk[i + 1] - tk[i])
    inside = ek[i] + pk[i] * s + 0.5 * slope * s**2
    return inside + pk[0] * np.minimum(t - tk[0], 0.0) + pk[-1] * np.maximum(t - tk[-1], 0.0)


def check_table(owner: str, times, values, value_check):
    """(times, values) tuples of a table, validated: non-empty, equal lengths, strictly
    increasing finite times [s]; ``value_check(field, v)`` checks every value."""
    times, values = (np.asarray(v, dtype=object).ravel() for v in (times, values))
    if len(times) < 1 or len(times) != len(values):
        raise ParameterError(f"{owner}: times ({len(times)} entries) and values "
                             f"({len(values)}) must be non-empty and of equal length.")
    t = tuple(finite(f"{owner}.times[{k}]", v, "s") for k, v in enumerate(times))
    p = tuple(value_check(f"{owner}.values[{k}]", v) for k, v in enumerate(values))
    bad = np.flatnonzero(np.diff(t) <= 0)
    if len(bad):
        k = int(bad[0])
        raise ParameterError(f"{owner}.times must be strictly increasing; times[{k}] "
                             f"= {t[k]} s is followed by times[{k + 1}] = {t[k + 1]} s.")
    return t, p


# ------------------------------------------------------------------ signed signals
def _set(obj, name, value):
    object.__setattr__(obj, name, value)


def _field(obj, name: str) -> str:
    return f"{type(obj).__name__}.{name}"


def _level(obj, name):
    _set(obj, name, finite(_field(obj, name), getattr(obj, name)))


def _times(obj, *names):
    for name in names:
        _set(obj, name, finite(_field(obj, name), getattr(obj, name), "s"))


class _Shifted(Schedule):
    """A shape (``_shape``, ``_shape_integral``) plus the constant ``offset``; its level fields
    (``_LEVELS``) are finite numbers."""

    _LEVELS = ("value", "offset")

    def _check_levels(self):
        for name in self._LEVELS:
            _level(self, name)

    def _values(self, t):
        return self.offset + self._shape(t)

    def _integral(self, t):
        return self.offset * t + self._shape_integral(t)


@dataclass(frozen=True)
class StepSignal(_Shifted):
    """``offset + value`` for ``t_on <= t < t_off`` [s], ``offset`` otherwise."""

    value: float
    t_on: float = 0.0
    t_off: float = math.inf
    offset: float = 0.0

    def __post_init__(self):
        self._check_levels()
        _times(self, "t_on")
        t_on = self.t_on
        _set(self, "t_off", number(_field(self, "t_off"), self.t_off, lambda v: v > t_on,
                                   f"a time after t_on = {t_on}", "s"))

    def _shape(self, t):
        return step_values(t, self.value, self.t_on, self.t_off)

    def _shape_integral(self, t):
        return step_integral(t, self.value, self.t_on, self.t_off)

    def switch_times(self, t):
        return (self.t_on, self.t_off)


@dataclass(frozen=True)
class RampSignal(_Shifted):
    """``offset`` before ``t_start``, linear to ``offset + value`` over ``duration`` [s], held."""

    value: float
    duration: float
    t_start: float = 0.0
    offset: float = 0.0

    def __post_init__(self):
        self._check_levels()
        _set(self, "duration", positive(_field(self, "duration"), self.duration, "s"))
        _times(self, "t_start")

    def _shape(self, t):
        return ramp_values(t, self.value, self.duration, self.t_start)

    def _shape_integral(self, t):
        return ramp_integral(t, self.value, self.duration, self.t_start)


@dataclass(frozen=True)
class SquareWaveSignal(_Shifted):
    """``offset + value`` during the first ``duty`` (in (0, 1)) of every ``period`` [s] from
    ``t_start`` [s] on, ``offset`` otherwise."""

    value: float
    period: float
    duty: float = 0.5
    t_start: float = 0.0
    offset: float = 0.0

    def __post_init__(self):
        self._check_levels()
        _set(self, "period", positive(_field(self, "period"), self.period, "s"))
        _set(self, "duty", number(_field(self, "duty"), self.duty, lambda v: 0 < v < 1,
                                  "in (0, 1) (use StepSignal for 0 or 1)"))
        _times(self, "t_start")

    def _shape(self, t):
        return square_values(t, self.value, self.period, self.duty, self.t_start)

    def _shape_integral(self, t):
        return square_integral(t, self.value, self.period, self.duty, self.t_start)

    def switch_times(self, t):
        return square_switches(t, self.period, self.duty, self.t_start)


@dataclass(frozen=True)
class SineSignal(Schedule):
    """``offset + amplitude sin(2 pi frequency t + phase)`` (any sign)."""

    amplitude: float
    frequency: float
    offset: float = 0.0
    phase: float = 0.0

    def __post_init__(self):
        for name in ("amplitude", "offset"):
            _level(self, name)
        _set(self, "frequency", positive(_field(self, "frequency"), self.frequency, "Hz"))
        _set(self, "phase", finite(_field(self, "phase"), self.phase, "rad"))

    def _values(self, t):
        return sine_values(t, self.amplitude, self.frequency, self.offset, self.phase)

    def _integral(self, t):
        return sine_integral(t, self.amplitude, self.frequency, self.offset, self.phase)


@dataclass(frozen=True)
class PiecewiseLinearSignal(Schedule):
    """Linear interpolation of a table ``times`` [s] (strictly increasing) -> ``values`` (any
    sign); held at the first value before and at the last value after the table."""

    times: tuple
    values: tuple

    def __post_init__(self):
        t, v = check_table(type(self).__name__, self.times, self.values,
                           lambda name, x: finite(name, x))
        _set(self, "times", t)
        _set(self, "values", v)

    def _values(self, t):
        return table_values(t, self.times, self.values)

    def _integral(self, t):
        return table_integral(t, self.times, self.values)

    def switch_times(self, t):
        return self.times
