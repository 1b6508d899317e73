"""Heating by circuits: crease powers that depend on the temperatures (theory 8.8).

A heater's power depends on its resistance, and so on its temperature
(:mod:`simulator.thermal.circuits`). Two couplings:

* steady (:class:`SteadyCircuits`, the :class:`~simulator.steps.Heat` step): on a given shape
  the heat problem is linear, so the temperatures are those of the other powers plus the rise
  per heater watt times the heater powers p (one factorisation, k + 1 right-hand sides). The
  heater powers then solve the small system p = F(T_h0 + H p) (k unknowns, F the power split of
  the circuits at the resistances R(T_h)) by Newton, its Jacobian by complex steps (F is
  analytic in the resistances): exact for the coupled steady state, checked by one more solve.
  A root with a resistance <= 0 or a heater above
  :data:`~simulator.thermal.circuits.RUNAWAY_TEMPERATURE` is no operating point: the drive
  runs away (constant current with tcr > 0 beyond I^2 R0 tcr / G = 1).
* transient (:class:`CircuitPowers`, :class:`~simulator.steps.TransientHeat` and
  :class:`~simulator.steps.ElectroThermal`): semi-implicit, the resistances at the temperatures
  at the start of each time step, the power of the step the exact mean of the drive's level at
  those resistances. An error of order dt in the power during fast changes, none at a steady
  state (it is the steady coupled one) and no iteration per step; a run-away shows as
  temperatures growing past the run-away temperature, which ends the step.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from ..linalg.small_solve import solve_dense
from .circuits import Drive, HeaterNetwork
from .measures import crease_temperatures

__all__ = ["SteadyCircuits", "HeatingPoint", "CircuitIncrements", "CircuitPowers",
           "held_network", "ramped_values"]

logger = logging.getLogger(__name__)

#: Relative agreement of the heater powers that ends the steady Newton iteration.
POWER_RTOL = 1e-12
#: Newton iterations of the steady coupling (and chord corrections of the superposition).
MAX_ITERATIONS = 60
#: Complex step of the Jacobian [W] (exact to round-off for any small value).
_H = 1e-30


@dataclass(frozen=True, eq=False)
class HeatingPoint:
    """One steady operating point: node temperatures (n,) [deg C], crease powers (C,) [W],
    the result columns of the circuits, and ``status`` ("converged", "thermal_runaway" or
    "failed") with its ``message``."""

    temperature: np.ndarray
    power: np.ndarray
    columns: dict = field(default_factory=dict)
    status: str = "converged"
    message: str = ""


class SteadyCircuits:
    """The steady temperatures of a model whose creases are heated by circuits.

    Parameters
    ----------
    tm : ThermalModel
    network : HeaterNetwork
    """

    def __init__(self, tm, network: HeaterNetwork):
        self.tm, self.net = tm, network
        unit = np.zeros((tm.mesh.n_creases, len(network.rows)))
        unit[network.rows, np.arange(len(network.rows))] = 1.0
        self.q_unit = np.column_stack([tm.heat_vector(u) for u in unit.T])      # (n, k)
        self.p = np.zeros(len(network.rows))          # the last heater powers: Newton's start

    def solve(self, x, base, levels, room) -> HeatingPoint:
        """Operating point on the shape ``x`` (n, 3) [m] with the other crease powers ``base``
        (C,) [W], the circuits at ``levels`` (m,) (V^2, I^2 or W) and room temperature ``room``
        [deg C]."""
        tm, net = self.tm, self.net
        q0 = tm.heat_vector(base)
        T = tm.solve(x, np.column_stack([q0, self.q_unit]), room)
        T0, U = T[:, 0], T[:, 1:] - room                               # rises per heater watt
        Th0 = net.crease_measure(T0)
        H = crease_temperatures(U, tm.mesh)[net.rows]                   # (k, k) [K/W]
        for _ in range(MAX_ITERATIONS):
            p, status, why = _newton(net, Th0, H, levels, self.p)
            if status != "converged":
                return self._failed(T0, base, p, levels, status, why)
            power = base + net.crease_powers(p)
            temp = tm.solve(x, tm.heat_vector(power), room)              # the check
            gap = net.crease_measure(temp) - (Th0 + H @ p)
            self.p = p
            if np.max(np.abs(gap)) <= 1e-9 * max(1.0, np.max(np.abs(Th0 + H @ p - room))):
                return HeatingPoint(temp, power, net.columns(temp, levels))
            Th0 = Th0 + gap                           # a nonlinear heat solve: chord step
        return self._failed(temp, base, p, levels, "failed",
                            f"the superposed and solved temperatures still differ by "
                            f"{np.max(np.abs(gap)):.3g} K")

    def _failed(self, T0, base, p, levels, status, why) -> HeatingPoint:
        net = self.net
        message = net.runaway_message(why) if status == "thermal_runaway" else \
            f"the electrical drive's steady coupling did not converge: {why}"
        logger.warning("%s", message)
        return HeatingPoint(T0, base, {}, status, message)


class CircuitIncrements:
    """The heating of a :class:`~simulator.steps.Heat` step with circuits: increment s's
    operating point for its other crease powers (what ``coupled_increments`` calls).

    Parameters
    ----------
    tm : ThermalModel
    network : HeaterNetwork
    values : (S, m) array
        Every circuit's drive value [V, A or W] at the end of each increment.
    """

    def __init__(self, tm, network: HeaterNetwork, values):
        self.net, self.steady = network, SteadyCircuits(tm, network)
        self.values = np.asarray(values, float)
        self.levels = np.abs(self.values) ** np.array([2 if d.kind != "power" else 1
                                                      for d in network.drives])
        self.last = None

    def __call__(self, s: int, x, base, room) -> HeatingPoint:
        point = self.steady.solve(x, base, self.levels[s - 1], room)
        self.last = (point, np.asarray(base, float), s)
        return point

    def end_state(self) -> dict:
        """The end state's circuits (drives held at the last increment's values) and their
        part of the crease powers."""
        point, base, s = self.last
        held = tuple((c, Drive(**{d.kind: float(v)})) for c, d, v in
                     zip(self.net.circuits, self.net.drives, self.values[s - 1]))
        return {"circuits": held, "circuit_power": point.power - base}


def ramped_values(mesh, state, network: HeaterNetwork, targets: dict, increments: int):
    """(S, m) drive values of a :class:`~simulator.steps.Heat` step: the circuits of
    ``targets`` ({Circuit: constant Drive}) ramp linearly from the value of the same kind at
    the state (its drive, or its operating point at the state's temperatures if driven in
    another kind, else 0) to the target; the others keep the state's value."""
    held = dict(state.circuits)
    at_start = _state_values(mesh, state)
    s = np.arange(1, increments + 1)[:, None] / increments
    out = np.zeros((increments, len(network.circuits)))
    for j, (c, d) in enumerate(zip(network.circuits, network.drives)):
        start = at_start.get((c, d.kind), 0.0)
        end = float(targets[c].value) if c in targets else float(held[c].value)
        out[:, j] = start + s[:, 0] * (end - start)
    return out


def _state_values(mesh, state) -> dict:
    """{(circuit, kind): value} of the state's circuits at its temperatures, every kind."""
    if not state.circuits:
        return {}
    net = HeaterNetwork(mesh, dict(state.circuits), "the state's circuits")
    levels = [d.level(0.0) for d in net.drives]
    cols = net.columns(state.temperature, levels)
    out = {}
    for c, lb in zip(net.circuits, net.labels):
        for kind, name in (("voltage", "voltage [V]"), ("current", "current [A]"),
                           ("power", "power [W]")):
            out[(c, kind)] = cols[f"circuit_{lb}_{name}"]
    return out


def _newton(net: HeaterNetwork, Th0, H, levels, p0):
    """Heater powers p (k,) [W] with p = F(Th0 + H p): (p, status, why)."""
    p = np.maximum(np.asarray(p0, float), 0.0)
    k = len(p)

    def residual(p):
        return p - net.heater_powers(Th0 + H @ p, levels)

    r = residual(p)
    for _ in range(MAX_ITERATIONS):
        scale = max(float(np.max(np.abs(p - r))), 1e-300)
        if np.max(np.abs(r)) <= POWER_RTOL * scale:
            why = net.unphysical(Th0 + H @ p)
            return p, ("thermal_runaway" if why else "converged"), why
        J = np.eye(k) - np.array([np.imag(net.heater_powers(Th0 + H @ (p + 1j * _H * e),
                                                            levels)) / _H
                                  for e in np.eye(k)]).T
        dp = solve_dense(J, -r, cholesky_first=False)
        if dp is None:
            return p, "thermal_runaway", "the coupling is singular (the run-away threshold)"
        step = 1.0
        while step > 2**-20:
            trial = residual(p + step * dp)
            if np.all(np.isfinite(trial)) and np.linalg.norm(trial) < np.linalg.norm(r):
                break
            step /= 2
        p, r = p + step * dp, trial
    why = net.unphysical(Th0 + H @ p)
    if why:
        return p, "thermal_runaway", why
    return p, "failed", (f"the heater powers still change by {np.max(np.abs(r)):.3g} W after "
                         f"{MAX_ITERATIONS} Newton iterations")


class CircuitPowers:
    """Crease powers [W] as a function of time with circuits whose resistances are taken at
    the last observed temperatures (the transient, semi-implicit coupling).

    Parameters
    ----------
    base : CreasePowers
        The other crease powers (schedules and constants) [W].
    network : HeaterNetwork
    temperature : (n,) array
        Node temperatures at the start [deg C].

    ``powers(t)`` gives (C,) at a float time t [s], ``powers.mean(t0, t1)`` the mean over a
    time step; :meth:`observe` takes the temperatures at the start of the next step and says
    whether they are an operating point (else why: a run-away).
    """

    def __init__(self, base, network: HeaterNetwork, temperature):
        self.base, self.net = base, network
        self.schedules = list(base.schedules) + network.schedules
        self.observe(temperature)

    def observe(self, temperature) -> str:
        """Take node temperatures (n,) [deg C]; "" or why they are no operating point."""
        self.Th = self.net.crease_measure(temperature)
        return self.net.unphysical(self.Th)

    def levels(self, t: float) -> np.ndarray:
        return np.array([d.level(t) for d in self.net.drives])

    def circuit_power(self, t: float) -> np.ndarray:
        """(C,) the circuits' part of the crease powers at step time t [W]."""
        return self.net.crease_powers(self.net.heater_powers(self.Th, self.levels(t)))

    def __call__(self, t):
        return self.base(t) + self.circuit_power(float(t))

    def mean(self, t0: float, t1: float) -> np.ndarray:
        levels = np.array([d.mean_level(t0, t1) for d in self.net.drives])
        return self.base.mean(t0, t1) + self.net.crease_powers(
            self.net.heater_powers(self.Th, levels))

    def runaway_message(self, why: str) -> str:
        return self.net.runaway_message(why)

    def columns(self, temperature, t: float) -> dict:
        """The circuits' result columns at node temperatures (n,) and step time t [s]."""
        return self.net.columns(temperature, self.levels(t))

    def held(self, t: float) -> tuple:
        """The circuits with their drives held at the values at t, for the end state."""
        return tuple((c, d.held(t)) for c, d in zip(self.net.circuits, self.net.drives))


def held_network(mesh, state, circuits, owner: str):
    """The circuits a step drives: those of the state (held at their constant drives) that
    share no crease with the step's ``circuits``, then the step's. Returns (HeaterNetwork or
    None, the state's crease powers without its circuits' part (C,) [W])."""
    from .circuits import check_circuits

    step = check_circuits(owner, circuits)
    mine = {c for k in step for c in k.creases}
    kept = {k: d for k, d in state.circuits if not mine & set(k.creases)}
    merged = {**kept, **step}
    base = state.crease_power - (0.0 if state.circuit_power is None else state.circuit_power)
    return (HeaterNetwork(mesh, merged, owner) if merged else None), base
