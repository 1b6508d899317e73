"""Heating power as a function of time: step, ramp, square wave (PWM), sine, piecewise linear.

The power schedules are the non-negative members of :class:`simulator.schedules.Schedule`
(whose module also has the signed signals for mechanical drives and the shared formulas).

Every schedule is a frozen dataclass mapping time t [s] to a power [W] >= 0, vectorised over
``t`` (a float gives a float, an array an array of the same shape) and validated on
construction. Schedules are applied per crease or per heater circuit with a mapping like the
one of :class:`~simulator.steps.heating.Heat`: ``{crease id or tuple of crease ids: schedule
or constant power [W]}``; :func:`crease_power_function` turns such a mapping into a function
t -> (C,) crease powers for a mesh.

Example::

    power = {2: SquareWave(power=20e-3, period=0.1, duty=0.25), (5, 6): Ramp(10e-3, 0.05)}
"""

from __future__ import annotations

import math
from abc import abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .._validate import finite, non_negative, number, positive
from ..errors import ParameterError
from ..schedules import (Schedule, check_table, ramp_integral, ramp_values, sine_integral,
                         sine_values, square_integral, square_switches, square_values,
                         step_integral, step_values, table_integral, table_values)

__all__ = ["PowerSchedule", "StepPower", "Ramp", "SquareWave", "Sine", "PiecewiseLinear",
           "check_power_mapping", "describe_power_mapping", "crease_power_function",
           "CreasePowers"]


def _number(owner, name: str, value, ok=math.isfinite, allowed: str = "a finite number",
            unit: str = ""):
    """``value`` as a float, or :class:`ParameterError` naming the field and the allowed range."""
    return number(f"{type(owner).__name__}.{name}", value, ok, allowed, unit)


def _power(owner, name, value):
    return non_negative(f"{type(owner).__name__}.{name}", value, "W")


def _time(owner, name, value):
    return finite(f"{type(owner).__name__}.{name}", value, "s")


def _positive(owner, name, value, unit):
    return positive(f"{type(owner).__name__}.{name}", value, unit)


class PowerSchedule(Schedule):
    """Power [W] as a function of time [s] (a non-negative :class:`~simulator.schedules.Schedule`);
    subclasses implement ``_values`` and ``_energy``."""

    @abstractmethod
    def _energy(self, t: np.ndarray) -> np.ndarray:
        """An antiderivative of the power [J] at the times ``t`` (differences are energies)."""

    def _integral(self, t):
        return self._energy(t)


@dataclass(frozen=True)
class StepPower(PowerSchedule):
    """``power`` [W] for ``t_on <= t < t_off`` [s], zero otherwise (constant power by default)."""

    power: float
    t_on: float = 0.0
    t_off: float = math.inf

    def __post_init__(self):
        object.__setattr__(self, "power", _power(self, "power", self.power))
        object.__setattr__(self, "t_on", _time(self, "t_on", self.t_on))
        t_on = self.t_on
        object.__setattr__(self, "t_off", _number(self, "t_off", self.t_off, lambda v: v > t_on,
                                                  f"a time after t_on = {t_on}", "s"))

    def _values(self, t):
        return step_values(t, self.power, self.t_on, self.t_off)

    def _energy(self, t):
        return step_integral(t, self.power, self.t_on, self.t_off)

    def switch_times(self, t):
        return (self.t_on, self.t_off)


@dataclass(frozen=True)
class Ramp(PowerSchedule):
    """Zero before ``t_start``, linear to ``power`` [W] over ``duration`` [s], then held."""

    power: float
    duration: float
    t_start: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "power", _power(self, "power", self.power))
        object.__setattr__(self, "duration", _positive(self, "duration", self.duration, "s"))
        object.__setattr__(self, "t_start", _time(self, "t_start", self.t_start))

    def _values(self, t):
        return ramp_values(t, self.power, self.duration, self.t_start)

    def _energy(self, t):
        return ramp_integral(t, self.power, self.duration, self.t_start)


@dataclass(frozen=True)
class SquareWave(PowerSchedule):
    """Pulse-width modulation: ``power`` [W] during the first ``duty`` fraction of every
    ``period`` [s] from ``t_start`` [s] on, zero otherwise (and before ``t_start``).

    ``duty`` is in (0, 1); the mean power over whole periods is ``duty * power``.
    """

    power: float
    period: float
    duty: float = 0.5
    t_start: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "power", _power(self, "power", self.power))
        object.__setattr__(self, "period", _positive(self, "period", self.period, "s"))
        object.__setattr__(self, "duty", _number(self, "duty", self.duty, lambda v: 0 < v < 1,
                                                 "in (0, 1) (use StepPower for 0 or 1)"))
        object.__setattr__(self, "t_start", _time(self, "t_start", self.t_start))

    def _values(self, t):
        return square_values(t, self.power, self.period, self.duty, self.t_start)

    def _energy(self, t):
        return square_integral(t, self.power, self.period, self.duty, self.t_start)

    def switch_times(self, t):
        return square_switches(t, self.period, self.duty, self.t_start)


@dataclass(frozen=True)
class Sine(PowerSchedule):
    """``offset + amplitude sin(2 pi frequency t + phase)`` [W]; ``offset`` defaults to
    ``|amplitude|`` and must be at least that (a heater cannot cool)."""

    amplitude: float
    frequency: float
    offset: float | None = None
    phase: float = 0.0

    def __post_init__(self):
        a = finite(f"{type(self).__name__}.amplitude", self.amplitude, "W")
        object.__setattr__(self, "amplitude", a)
        object.__setattr__(self, "frequency", _positive(self, "frequency", self.frequency, "Hz"))
        offset = abs(a) if self.offset is None else self.offset
        object.__setattr__(self, "offset", _number(
            self, "offset", offset, lambda v: abs(a) <= v < math.inf,
            f"a finite power >= |amplitude| = {abs(a)} W so that the power stays >= 0"))
        object.__setattr__(self, "phase", _number(self, "phase", self.phase, unit="rad"))

    def _values(self, t):
        return sine_values(t, self.amplitude, self.frequency, self.offset, self.phase)

    def _energy(self, t):
        return sine_integral(t, self.amplitude, self.frequency, self.offset, self.phase)


@dataclass(frozen=True)
class PiecewiseLinear(PowerSchedule):
    """Linear interpolation of a table ``times`` [s] (strictly increasing) -> ``values`` [W]
    (>= 0); held at the first value before and at the last value after the table."""

    times: tuple
    values: tuple

    def __post_init__(self):
        t, p = check_table(type(self).__name__, self.times, self.values,
                           lambda name, v: non_negative(name, v, "W"))
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "values", p)

    def _values(self, t):
        return table_values(t, self.times, self.values)

    def _energy(self, t):
        return table_integral(t, self.times, self.values)

    def switch_times(self, t):
        return self.times


def check_power_mapping(owner: str, power) -> dict:
    """Validate ``{crease id or tuple of ids: PowerSchedule or constant power [W]}``.

    Returns the mapping with constants turned into :class:`StepPower`; ``owner`` names the
    caller in error messages.
    """
    if not isinstance(power, Mapping):
        raise ParameterError(f"{owner}: power = {power!r} must be a mapping {{crease id or tuple "
                             "of crease ids: PowerSchedule or watts}.")
    out = {}
    for key, value in power.items():
        ids = key if isinstance(key, tuple) else (key,)
        if not ids or any(not isinstance(c, (int, np.integer)) or isinstance(c, bool)
                          for c in ids):
            raise ParameterError(f"{owner}: power key {key!r} must be a crease id or a tuple of "
                                 "crease ids (a heater circuit).")
        if not isinstance(value, PowerSchedule):
            value = StepPower(number(f"{owner}: power of {key!r}", value,
                                     lambda v: 0 <= v < math.inf,
                                     "a PowerSchedule or a constant power >= 0", "W"))
        out[key] = value
    return out


def describe_power_mapping(power) -> dict:
    """JSON-able ``{str(key): schedule description}`` of a power mapping (constants as
    ``{"schedule": "constant", "power [W]": value}``), for ``meta.json``."""
    return {str(k): (v.describe() if hasattr(v, "describe") else
                     {"schedule": "constant", "power [W]": float(v)})
            for k, v in dict(power).items()}


class CreasePowers:
    """Crease powers [W] of a mesh from a mapping of schedules (see :func:`crease_power_function`).

    ``powers(t)`` gives (C,) for a float t and (m, C) for m times; ``powers.mean(t0, t1)`` the
    exact (C,) mean power over ``[t0, t1]`` [s]. ``base`` (C,) [W] is a constant power added
    to every crease row (e.g. the powers already on before a step).
    """

    def __init__(self, mesh, power, base=None):
        power = check_power_mapping("crease powers", power)
        self.schedules = list(power.values())
        self.n_creases = mesh.n_creases
        self.base = np.zeros(mesh.n_creases) if base is None else np.asarray(base, float)
        self.share = np.zeros((len(self.schedules), mesh.n_creases))
        for j, key in enumerate(power):
            for c in (key if isinstance(key, tuple) else (key,)):
                self.share[j, mesh.crease_row_of(int(c))] += 1.0

    def _combine(self, values, shape):
        if not self.schedules:
            return np.broadcast_to(self.base, (*shape, self.n_creases)).copy()
        out = np.array(values).reshape(len(self.schedules), -1).T @ self.share + self.base
        return out.reshape(*shape, self.n_creases)

    def __call__(self, t):
        t = np.asarray(t, float)
        if not np.all(np.isfinite(t)):
            raise ParameterError("crease powers: times must be finite [s].")
        return self._combine([s(t.ravel()) for s in self.schedules], t.shape)

    def mean(self, t0: float, t1: float) -> np.ndarray:
        """(C,) mean crease powers [W] over ``[t0, t1]`` [s], t1 > t0."""
        return self._combine([s.mean(t0, t1) for s in self.schedules], ())


def crease_power_function(mesh, power) -> CreasePowers:
    """Function t -> crease powers [W] for a mesh: (C,) for a float t, (m, C) for m times.

    ``power`` maps crease ids or tuples of crease ids (a circuit: each of its creases gets the
    schedule's value) to schedules or constant powers; creases listed twice add up. The result
    also has ``mean(t0, t1)``, the exact mean crease powers over an interval.
    """
    return CreasePowers(mesh, power)
