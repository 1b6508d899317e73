"""Time-domain steps: transient heat transfer on a fixed shape (theory 8.1).

:class:`TransientHeat` integrates the heat equation with the theta-method of
:mod:`simulator.thermal.transient` over ``duration`` seconds, with time-varying crease or circuit
powers (:mod:`simulator.thermal.schedules`) added on top of the state's crease powers. The shape
is the state's shape for the whole step and the crease rest angles are not updated (heat
only; the thermo-mechanical coupling is a later step). The first record (increment 0) is the
start state at the start time. Each record carries ``time [s]`` (the simulation clock,
``SimulationState.time``, continued by every time-domain step) and the energy bookkeeping since
the start of the step: ``heat_in [J]``
(heat put in), ``heat_out [J]`` (heat lost to room temperature) and ``heat_stored [J]``
(change of the heat stored above room temperature); ``heat_stored = heat_in - heat_out``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from .._validate import integer, positive
from ..thermal.circuits import check_circuits, describe_circuits
from ..thermal.electrical import CircuitPowers, held_network
from ..thermal.schedules import CreasePowers, check_power_mapping, describe_power_mapping
from ..thermal.transient import DEFAULT_THETA, check_theta, check_time_step, integrate_heat
from .base import Step, StepContext, StepOutcome, StepRecorder

__all__ = ["TransientHeat", "step_powers", "circuit_end"]


@dataclass(frozen=True)
class TransientHeat(Step):
    """Transient heating over ``duration`` [s] with time steps ``dt`` [s] on the current shape.

    Parameters
    ----------
    power : mapping
        Power ADDED on top of the state's crease powers, keyed by crease id or by a tuple of
        crease ids (a heater circuit): a :class:`~simulator.thermal.schedules.PowerSchedule`
        (time from the start of this step) or a constant power [W].
    duration : float
        Length of the step [s], > 0.
    dt : float
        Time step [s], > 0 (reduced to ``duration / ceil(duration / dt)`` if it does not divide
        the duration).
    theta : float
        Weight of the new time level in [1/2, 1] (default 1, backward Euler: L-stable, never
        below room temperature; ``REFERENCE_THETA`` = 2/3 is the reference's).
    record_every : int
        Record every k-th time step (the last one is always recorded).
    circuits : mapping {Circuit: Drive}
        Heater circuits (theory 8.8) driven by a voltage, current or power, constant or a
        schedule of the step time; the circuits the state drives keep their drives. Their
        powers follow from the temperatures at the start of each time step (semi-implicit);
        a heater past :data:`~simulator.thermal.circuits.RUNAWAY_TEMPERATURE` ends the step
        with status "thermal_runaway".

    Notes
    -----
    The start temperatures are the state's node temperatures with a quasi-steady environment
    (:func:`~simulator.thermal.transient.environment_profile`), so a steady state stays steady.
    """

    power: Mapping = field(default_factory=dict)
    duration: float = 1.0
    dt: float = 1e-3
    theta: float = DEFAULT_THETA
    record_every: int = 1
    name: str = "transient_heat"
    circuits: Mapping = field(default_factory=dict)

    def __post_init__(self):
        check_power_mapping("TransientHeat", self.power)
        check_circuits("TransientHeat", self.circuits)
        positive("TransientHeat.duration", self.duration, "s")
        check_time_step(self.dt, "TransientHeat.dt")
        check_theta(self.theta)
        integer("TransientHeat.record_every", self.record_every)

    def run(self, context: StepContext, state) -> StepOutcome:
        mesh, tm = context.model.mesh, context.thermal
        powers = step_powers(mesh, state, self.power, self.circuits, "TransientHeat")
        result = integrate_heat(
            tm, mesh.nodes + state.u, powers, self.duration, self.dt, self.theta,
            state.room_temperature, state.temperature, self.record_every,
            callback=lambda k, n, t, T: context.report(k, n))
        rec = StepRecorder(state)
        for k in range(len(result.time)):              # record 0: the start, at its time
            columns = {"time [s]": state.time + result.time[k],     # no step ends at 0:
                       "mean_power [mW]": None if k == 0 else 1e3 * result.mean_power[k],
                       "heat_in [J]": result.heat_in[k], "heat_out [J]": result.heat_out[k],
                       "heat_stored [J]": result.heat_stored[k] - result.heat_stored[0]}
            if hasattr(powers, "columns"):
                columns.update(powers.columns(result.temperature[k], result.time[k]))
            if k == 0:
                rec.record_start(result.temperature[0], result.power[0], **columns)
            else:
                rec.record(result.time[k] / self.duration, state.u, result.temperature[k],
                           result.power[k], 0, (), **columns)
        end = replace(state, temperature=result.temperature[-1], crease_power=result.power[-1],
                      time=state.time + float(result.time[-1]),
                      **circuit_end(powers, result.temperature[-1], float(result.time[-1])))
        return rec.finish(result.success, result.status, result.message, end,
                          state.applied_load.ravel())

    def describe(self) -> dict:
        return {"power_added": describe_power_mapping(self.power),
                "duration [s]": self.duration, "dt [s]": self.dt, "theta": self.theta,
                "record_every": self.record_every,
                **({"circuits": describe_circuits(self.circuits)} if self.circuits else {})}


def step_powers(mesh, state, power, circuits, owner: str):
    """Crease powers of a time-domain step as a function of the step time: the step's
    ``power`` mapping on top of the state's powers (a
    :class:`~simulator.thermal.schedules.CreasePowers`), or with heater circuits (the step's
    and the state's, :func:`~simulator.thermal.electrical.held_network`) a
    :class:`~simulator.thermal.electrical.CircuitPowers`."""
    network, base = held_network(mesh, state, circuits, owner)
    if network is None:
        return CreasePowers(mesh, power, base=state.crease_power)
    return CircuitPowers(CreasePowers(mesh, power, base=base), network, state.temperature)


def circuit_end(powers, temperature, t: float) -> dict:
    """The end state's circuit fields after a time-domain step ending at step time t [s] with
    node temperatures (n,) [deg C] (none without circuits)."""
    if not isinstance(powers, CircuitPowers):
        return {}
    powers.observe(temperature)
    return {"circuits": powers.held(t), "circuit_power": powers.circuit_power(t)}
