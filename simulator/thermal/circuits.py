"""Electrical drive: heaters as resistors with a temperature coefficient, joined in circuits
(theory 8.8).

A :class:`Heater` is the thin-film resistor on one crease. Its resistance at the reference
temperature is given (``resistance`` [Ohm]) or follows from the film's sheet resistance and its
number of squares, R0 = R_s n (``squares``; by default the crease's length over its width, a
straight film along the crease). At temperature T it is

    R(T) = R0 (1 + alpha (T - T_ref)),

with T the crease's actuation temperature (the 7-node weighted mean that also drives the
bimorph, measure ``"actuation"`` of :func:`~simulator.thermal.measures.crease_temperatures`,
theory 5.1). A :class:`Circuit` joins heaters in series or in parallel, with a lead resistance
[Ohm] (leads and traces) in series with them. A :class:`Drive` is the source: a voltage [V]
across the circuit's terminals (leads included), a current [A] through them, or the power [W]
the source delivers to the circuit (heaters and leads), each a constant or a time schedule
(:mod:`simulator.schedules`). Heating does not depend on polarity: a voltage or current schedule
may change sign.

The power a heater dissipates is I_h^2 R(T) at the operating point (I_h its current), what the
heat equation receives; the often quoted V^2 / R0 (resistance at room temperature) is larger by
the factor R(T) / R0 at constant voltage, 1.44-1.51 at the paper's assembly temperature.

Default material: a 0.2 um gold film, sheet resistance :data:`GOLD_SHEET_RESISTANCE` = 0.15
Ohm/sq (issue 30: 0.12-0.18 Ohm/sq; bulk gold, 2.2-2.4e-8 Ohm m, gives 0.11-0.12 Ohm/sq at this
thickness, grain-boundary and surface scattering raise a film's resistivity) and temperature
coefficient :data:`GOLD_TCR` = 0.0034 /K. A film's coefficient lies below the bulk metal's
(bulk gold 0.0034-0.0039 /K by the tables): Belser and Hicklin (J. Appl. Phys. 30, 313, 1959)
measured 1/3 to 2/3 of the bulk value on sputtered films of 7.5-200 nm, and the same scattering
that raises the resistivity lowers the coefficient (Matthiessen's rule). 0.0034 /K is thus the
upper end for a thin film (a well annealed, evaporated one); give the value measured on a
device where it is known.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import capped, finite, non_negative, one_of, positive
from ..errors import ParameterError, PatternError
from ..schedules import Schedule
from .measures import crease_temperatures

__all__ = ["GOLD_TCR", "GOLD_SHEET_RESISTANCE", "RUNAWAY_TEMPERATURE", "CONNECTIONS",
           "Heater", "Circuit", "Drive", "HeaterNetwork", "check_circuits", "describe_circuits"]

#: Temperature coefficient of resistance of a thin gold film [1/K] (module docstring).
GOLD_TCR = 0.0034
#: Sheet resistance of a 0.2 um gold film [Ohm/sq] (issue 30: 0.12-0.18 Ohm/sq).
GOLD_SHEET_RESISTANCE = 0.15
#: A driven crease hotter than this [deg C] has run away (no thin-film heater on a polymer
#: survives it; gold melts at 1064 deg C): a step stops with status "thermal_runaway".
RUNAWAY_TEMPERATURE = 1000.0
#: How the heaters of a circuit are joined.
CONNECTIONS = ("series", "parallel")
#: The drive quantities, their units and the exponent that makes them a heating level.
_KINDS = {"voltage": ("V", 2), "current": ("A", 2), "power": ("W", 1)}


def _is_id(value) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


@dataclass(frozen=True)
class Heater:
    """The thin-film resistor on one crease.

    Parameters
    ----------
    crease : int
        The crease (edge id) it heats.
    resistance : float, optional
        Resistance R0 at ``reference_temperature`` [Ohm], > 0. Give it, or ``squares``, or
        neither (then the squares are the crease's length over its width).
    squares : float, optional
        Number of squares of the film (length over width along the current), > 0.
    sheet_resistance : float
        Sheet resistance of the film at ``reference_temperature`` [Ohm/sq], > 0 (default a
        0.2 um gold film, :data:`GOLD_SHEET_RESISTANCE`).
    tcr : float
        Temperature coefficient of resistance alpha [1/K] (default thin-film gold,
        :data:`GOLD_TCR`); negative for a film whose resistance falls with temperature.
    reference_temperature : float
        Temperature at which the resistance is R0 [deg C] (default 21, room temperature).
    """

    crease: int
    resistance: float | None = None
    squares: float | None = None
    sheet_resistance: float = GOLD_SHEET_RESISTANCE
    tcr: float = GOLD_TCR
    reference_temperature: float = 21.0

    def __post_init__(self):
        if not _is_id(self.crease) or self.crease < 0:
            raise ParameterError(f"Heater.crease = {self.crease!r} must be a crease id (an "
                                 "integer >= 0, the pattern's edge id of the heated crease).")
        fix = "give resistance [Ohm] at reference_temperature, or squares and sheet_resistance"
        positive("Heater.resistance", self.resistance, "Ohm", fix, allow_none=True)
        positive("Heater.squares", self.squares, "", fix, allow_none=True)
        if self.resistance is not None and self.squares is not None:
            raise ParameterError(
                f"Heater: resistance = {self.resistance!r} Ohm and squares = {self.squares!r} "
                "are both given; give one of them (R0 = sheet_resistance * squares).")
        positive("Heater.sheet_resistance", self.sheet_resistance, "Ohm/sq",
                 "0.12-0.18 Ohm/sq for 0.2 um gold")
        finite("Heater.tcr", self.tcr, "1/K", f"{GOLD_TCR} /K for thin-film gold")
        finite("Heater.reference_temperature", self.reference_temperature, "deg C")

    def base_resistance(self, pattern) -> float:
        """R0 [Ohm]: ``resistance``, else ``sheet_resistance`` times the squares (given, or
        the crease's length over its width in ``pattern``)."""
        if self.resistance is not None:
            return float(self.resistance)
        if self.squares is not None:
            return self.sheet_resistance * float(self.squares)
        a, b = pattern.edges[self.crease]
        length = float(np.linalg.norm(pattern.vertices[a] - pattern.vertices[b]))
        return self.sheet_resistance * length / float(pattern.crease_width[self.crease])

    def describe(self) -> dict:
        return {"crease": int(self.crease), "resistance [Ohm]": self.resistance,
                "squares": self.squares, "sheet_resistance [Ohm/sq]": self.sheet_resistance,
                "tcr [1/K]": self.tcr, "reference_temperature [degC]": self.reference_temperature}


@dataclass(frozen=True)
class Circuit:
    """Heaters joined in series or in parallel, with a lead resistance in series.

    Parameters
    ----------
    heaters : tuple of Heater or crease ids
        The heaters (a crease id stands for ``Heater(crease)``, a gold film over the crease).
    connection : {"series", "parallel"}
    lead_resistance : float
        Resistance of the leads and traces in series with the heaters [Ohm], >= 0.
    name : str
        Label of the result columns (``circuit_<name>_voltage [V]``); default: the circuit's
        number in the step, from 1.
    """

    heaters: tuple
    connection: str = "series"
    lead_resistance: float = 0.0
    name: str = ""

    def __post_init__(self):
        items = self.heaters if isinstance(self.heaters, (tuple, list)) else (self.heaters,)
        heaters = tuple(Heater(h) if _is_id(h) else h for h in items)
        bad = [h for h in heaters if not isinstance(h, Heater)]
        if not heaters or bad:
            raise ParameterError(f"Circuit.heaters = {self.heaters!r} must be a non-empty tuple "
                                 "of Heater(crease, ...) or crease ids.")
        creases = [h.crease for h in heaters]
        twice = sorted({c for c in creases if creases.count(c) > 1})
        if twice:
            raise ParameterError(f"Circuit.heaters: crease {twice[0]} has two heaters; give "
                                 "each crease one Heater.")
        object.__setattr__(self, "heaters", heaters)
        one_of("Circuit.connection", self.connection, CONNECTIONS)
        non_negative("Circuit.lead_resistance", self.lead_resistance, "Ohm",
                     "0 without leads; e.g. 20 squares of the film: 20 * sheet_resistance")
        if not isinstance(self.name, str):
            raise ParameterError(f"Circuit.name = {self.name!r} must be a string.")

    @property
    def creases(self) -> tuple:
        """The heated crease ids, in heater order."""
        return tuple(h.crease for h in self.heaters)

    def describe(self) -> dict:
        return {"name": self.name, "connection": self.connection,
                "lead_resistance [Ohm]": self.lead_resistance,
                "heaters": [h.describe() for h in self.heaters]}


@dataclass(frozen=True)
class Drive:
    """The source of a circuit: exactly one of ``voltage`` [V], ``current`` [A] or ``power``
    [W], each a constant or a :class:`~simulator.schedules.Schedule` of the step time.

    ``voltage`` is across the circuit's terminals (leads included), ``current`` through them,
    ``power`` what the source delivers to the circuit (heaters plus leads). A constant must be
    >= 0; a voltage or current schedule may change sign (heating does not depend on polarity),
    a power schedule must be a :class:`~simulator.thermal.schedules.PowerSchedule` (>= 0).
    """

    voltage: object = None
    current: object = None
    power: object = None

    def __post_init__(self):
        given = [k for k in _KINDS if getattr(self, k) is not None]
        if len(given) != 1:
            what = " and ".join(f"{k} = {getattr(self, k)!r} {_KINDS[k][0]}" for k in given)
            raise ParameterError(
                f"Drive: {what or 'nothing'} given; a circuit is driven by one source: give "
                "exactly one of voltage [V], current [A] or power [W].")
        kind, value = given[0], getattr(self, given[0])
        if isinstance(value, Schedule):
            from .schedules import PowerSchedule

            if kind == "power" and not isinstance(value, PowerSchedule):
                raise ParameterError(f"Drive.power = {value!r} must be a constant >= 0 [W] or a "
                                     "PowerSchedule (StepPower, Ramp, SquareWave, ...).")
        else:
            non_negative(f"Drive.{kind}", value, _KINDS[kind][0], "or a Schedule of the time")

    @property
    def kind(self) -> str:
        """"voltage", "current" or "power"."""
        return next(k for k in _KINDS if getattr(self, k) is not None)

    @property
    def value(self):
        """The constant or schedule of :attr:`kind`."""
        return getattr(self, self.kind)

    @property
    def schedules(self) -> list:
        """The drive's schedule in a list (empty for a constant), for switch times."""
        return [self.value] if isinstance(self.value, Schedule) else []

    def at(self, t: float) -> float:
        """The drive's value at step time t [s] (V, A or W)."""
        v = self.value
        return float(v(t)) if isinstance(v, Schedule) else float(v)

    def level(self, t: float) -> float:
        """Heating level at t: V^2 [V^2], I^2 [A^2] or P [W]."""
        return abs(self.at(t)) ** _KINDS[self.kind][1]

    def mean_level(self, t0: float, t1: float) -> float:
        """Mean heating level over the step ``[t0, t1]`` [s]: exact for constants, powers, steps, square
        waves and tables (3-point Gauss between switching times), else to the rule's order."""
        v = self.value
        if not isinstance(v, Schedule):
            return self.level(t0)
        if self.kind == "power":
            return float(v.mean(t0, t1))
        cuts = [t0, *sorted({x for x in _switches(v, t0, t1)}), t1]
        x, w = np.polynomial.legendre.leggauss(3)
        total = 0.0
        for a, b in zip(cuts[:-1], cuts[1:]):
            total += 0.5 * (b - a) * float(w @ np.square(v(0.5 * (a + b) + 0.5 * (b - a) * x)))
        return total / (t1 - t0)

    def held(self, t: float) -> "Drive":
        """The constant drive of this kind at its value at t (what a state keeps)."""
        return Drive(**{self.kind: abs(self.at(t))})

    def describe(self) -> dict:
        v = self.value
        unit = _KINDS[self.kind][0]
        return {f"{self.kind} [{unit}]": v.describe() if isinstance(v, Schedule) else float(v)}


def _switches(schedule, t0: float, t1: float) -> list:
    """The switching times of ``schedule`` strictly inside (t0, t1)."""
    out, t = [], t0
    for _ in range(10_000):
        later = [x for x in schedule.switch_times(t) if t < x < t1]
        if not later:
            break
        t = min(later)
        out.append(t)
    return out


def check_circuits(owner: str, circuits) -> dict:
    """``circuits`` as a dict {Circuit: Drive}, validated: a mapping of circuits to drives, no
    crease in two circuits; ``owner`` names the step in messages."""
    if not isinstance(circuits, dict):
        try:
            circuits = dict(circuits)
        except (TypeError, ValueError):
            raise ParameterError(f"{owner}.circuits = {circuits!r:.80} must be a mapping "
                                 "{Circuit: Drive}.") from None
    seen = {}
    for k, (circuit, drive) in enumerate(circuits.items(), start=1):
        if not isinstance(circuit, Circuit) or not isinstance(drive, Drive):
            raise ParameterError(
                f"{owner}.circuits: entry {k} is {type(circuit).__name__}: "
                f"{type(drive).__name__}; give Circuit(...): Drive(voltage=...) (or current=, "
                "power=).")
        for c in circuit.creases:
            if c in seen:
                raise ParameterError(
                    f"{owner}.circuits: crease {c} is in circuit {seen[c]} and in circuit "
                    f"{circuit.name or k}; a crease has one heater: join them in one Circuit.")
            seen[c] = circuit.name or k
    return circuits


def describe_circuits(circuits) -> list:
    """JSON-able description of a {Circuit: Drive} mapping, for ``meta.json``."""
    return [{**c.describe(), **d.describe()} for c, d in dict(circuits).items()]


def _operating_point(R, lead, series: bool, kind: str, level):
    """Heater powers (k,) [W], the squared current I^2 [A^2] and the total resistance [Ohm]
    of one circuit with heater resistances ``R`` (k,) [Ohm] at the heating ``level`` (V^2, I^2
    or W); analytic in ``R`` (complex steps pass through)."""
    R_net = np.sum(R) if series else 1.0 / np.sum(1.0 / R)
    R_tot = R_net + lead
    i2 = level / R_tot**2 if kind == "voltage" else level if kind == "current" \
        else level / R_tot
    return (i2 * R if series else i2 * R_net**2 / R), i2, R_tot


class HeaterNetwork:
    """The circuits of a step on a mesh: heater rows, resistances and the power split.

    Parameters
    ----------
    mesh : BarHingeMesh
    circuits : mapping {Circuit: Drive}
        Validated by :func:`check_circuits`.
    owner : str
        Step name for error messages.

    Attributes
    ----------
    circuits, drives : lists in circuit order
    rows : (k,) crease rows of the heaters, circuit by circuit
    R0, alpha, t_ref : (k,) base resistances [Ohm], coefficients [1/K], reference temperatures
        [deg C]
    labels : list of str, the circuits' column labels
    """

    def __init__(self, mesh, circuits, owner: str):
        circuits = check_circuits(owner, circuits)
        self.mesh, self.circuits, self.drives = mesh, list(circuits), list(circuits.values())
        heaters = [h for c in self.circuits for h in c.heaters]
        self.rows = np.array([_row(mesh, h.crease, owner) for h in heaters], int)
        self.R0 = np.array([h.base_resistance(mesh.pattern) for h in heaters])
        self.alpha = np.array([h.tcr for h in heaters])
        self.t_ref = np.array([h.reference_temperature for h in heaters])
        sizes = [len(c.heaters) for c in self.circuits]
        self.slices = [slice(a, a + n) for a, n in zip(np.cumsum([0] + sizes), sizes)]
        self.labels = [c.name or str(k) for k, c in enumerate(self.circuits, start=1)]

    @property
    def schedules(self) -> list:
        return [s for d in self.drives for s in d.schedules]

    def crease_measure(self, temperature) -> np.ndarray:
        """(k,) heater temperatures [deg C] (actuation measure) of node temperatures (n,)."""
        return crease_temperatures(temperature, self.mesh)[self.rows]

    def resistances(self, Th):
        """(k,) heater resistances [Ohm] at heater temperatures ``Th`` (k,) [deg C]."""
        return self.R0 * (1.0 + self.alpha * (Th - self.t_ref))

    def heater_powers(self, Th, levels):
        """(k,) heater powers [W] at heater temperatures ``Th`` and circuit levels (m,)."""
        R = self.resistances(Th)
        out = np.zeros(len(R), dtype=np.result_type(R, float))
        for j, (c, d, sl) in enumerate(zip(self.circuits, self.drives, self.slices)):
            out[sl] = _operating_point(R[sl], c.lead_resistance, c.connection == "series",
                                       d.kind, levels[j])[0]
        return out

    def crease_powers(self, p) -> np.ndarray:
        """(C,) crease powers [W] of heater powers ``p`` (k,)."""
        out = np.zeros(self.mesh.n_creases)
        out[self.rows] = p
        return out

    def unphysical(self, Th) -> str:
        """Why heater temperatures ``Th`` (k,) [deg C] are no operating point ("" if they are):
        a heater above :data:`RUNAWAY_TEMPERATURE` or with a resistance <= 0."""
        R = self.resistances(Th)
        if not np.all(np.isfinite(Th)) or np.max(Th) > RUNAWAY_TEMPERATURE:
            i = int(np.nanargmax(np.where(np.isfinite(Th), Th, np.inf)))
            return (f"crease {self.crease_of(i)} reaches {Th[i]:.4g} degC > "
                    f"{RUNAWAY_TEMPERATURE:g} degC")
        if np.any(R <= 0):
            i = int(np.argmin(R))
            return f"crease {self.crease_of(i)} would need a resistance {R[i]:.3g} Ohm <= 0"
        return ""

    def crease_of(self, i: int) -> int:
        return int(self.mesh.crease_ids[self.rows[i]])

    def runaway_message(self, why: str) -> str:
        """The message of a thermal run-away: what happened and what to change."""
        driven = [lb for lb, d in zip(self.labels, self.drives) if d.kind == "current"]
        return (f"thermal run-away of the electrical drive: {why}; a heater whose resistance "
                "rises with temperature (tcr > 0) heats itself further at constant current: "
                "there is no steady state once I^2 R0 tcr / G >= 1 (G the crease's "
                "conductance to room temperature). Drive by voltage (self-limiting) or lower "
                "the drive" + (f" (current-driven circuits {capped(driven)})" if driven
                               else ""))

    def columns(self, temperature, levels) -> dict:
        """Result columns at node temperatures (n,) [deg C] and circuit levels (m,): per circuit
        ``circuit_<label>_voltage [V]``, ``_current [A]``, ``_power [W]`` (delivered, leads
        included) and ``_lead_loss [W]``, and per crease ``heater_resistance [Ohm]`` (NaN on
        creases without a heater)."""
        R = self.resistances(self.crease_measure(temperature))
        out = {}
        for lb, c, d, sl, lvl in zip(self.labels, self.circuits, self.drives, self.slices,
                                     levels):
            _, i2, R_tot = _operating_point(R[sl], c.lead_resistance,
                                            c.connection == "series", d.kind, lvl)
            i = math.sqrt(max(float(i2), 0.0))
            out.update({f"circuit_{lb}_voltage [V]": i * float(R_tot),
                        f"circuit_{lb}_current [A]": i,
                        f"circuit_{lb}_power [W]": i * i * float(R_tot),
                        f"circuit_{lb}_lead_loss [W]": i * i * c.lead_resistance})
        res = np.full(self.mesh.n_creases, np.nan)
        res[self.rows] = R
        out["heater_resistance [Ohm]"] = res
        return out


def _row(mesh, crease: int, owner: str) -> int:
    """The crease row of a heater's crease, or an error naming the step, the crease and the fix."""
    try:
        return mesh.crease_row_of(crease)
    except PatternError as error:
        raise ParameterError(f"{owner}: Heater.crease = {crease!r} is not a crease of the "
                             f"model ({error}); give one of its crease ids.") from None
