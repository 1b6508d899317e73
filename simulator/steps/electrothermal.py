"""Coupled electro-thermal dynamics: heat and motion advanced together per time step.

:class:`ElectroThermal` is the time-domain version of the paper's three-step loop
(:func:`~simulator.steps.heating.coupled_increments`, theory 8.5). Per time step
``[t, t + h]``:

1. heat: one theta-method step of the transient heat equation
   (:mod:`simulator.thermal.transient`) with the conductivity and capacity assembled on the shape
   at the start of the step, and the exact mean crease power over the step;
2. Timoshenko bimorph: crease rest angles from the crease temperature change since the start
   of the step (:func:`~simulator.steps.heating.thermal_actuation`, the same formula as
   :class:`~simulator.steps.Heat`);
3. mechanics: one implicit time step of the equation of motion
   (:class:`~simulator.solvers.generalized_alpha.TimeIntegrator`, Newton iterations and dead loads such as
   gravity kept, unlike the reference, theory 8.6 and 8.4), or with
   ``mechanics="quasi_static"`` an equilibrium solve by Newton (inertia neglected), the rest
   angles moved from the previous step's with step cutting
   (:func:`~simulator.solvers.newton.follow_path`).

The coupling is staggered as in the reference: the heat step sees the shape at the start of
the step. Re-assembling K and C and factorising costs almost as much as the mechanics (single
fold, 2000 fixed steps, ``benchmarks/bench_step_response.py``: re-assembling every step takes
1.8 times as long as with ``shape_tol = 5 um``); ``shape_tol`` [m] lets the heat step keep the
previous assembly (and its factorisation) while no node has moved more than that since the last
assembly, for at most :data:`REFRESH_STEPS` steps (0, the default, re-assembles whenever the
shape changed).

Time steps adapt between ``dt_min`` and ``dt_max`` and end on the switching times of step,
square-wave and piecewise-linear schedules (so a power jump falls between steps): a step whose
mechanics fails, or whose largest node temperature change exceeds ``2 * temperature_step``, is
rejected and retried with half the step; the next step doubles after an easy step (mechanics
in at most :data:`EASY_ITERATIONS` Newton iterations and a temperature change below
``temperature_step / 2``) and halves after a large temperature change; a step cut short to
end on a switching time does not change the step size. With ``dt_min = dt_max`` (the default:
both equal ``dt``) every step is ``dt``.

The first record (increment 0) is the start state at the start time (``dt [s]`` empty, the
powers those at the start). Every record carries ``time [s]`` (the simulation clock,
``SimulationState.time`` plus the time in the step), ``dt [s]`` (the time step ending at the
record), and the energy bookkeeping since the start of the step:
``kinetic_energy [J]``, ``strain_energy [J]`` (bars, springs, contact at the current rest
angles), ``dissipated_energy [J]`` (Rayleigh and air damping; empty for quasi-static
mechanics), ``external_work [J]`` (dead loads), ``heat_in [J]`` (electrical heat put in, the
integral of the crease powers) and ``heat_out [J]`` (heat lost to room temperature, including
the share of the heater power that lands on room-temperature nodes). The end state carries
the velocities (None after quasi-static mechanics).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from .._validate import integer, non_negative, one_of, positive
from ..solvers.dynamics_options import DynamicsOptions
from ..errors import ParameterError
from ..events import CrossingWatch, stops
from ..solvers.generalized_alpha import TimeIntegrator
from ..solvers.newton import follow_path
from ..schedules import next_switch
from ..thermal.circuits import check_circuits, describe_circuits
from ..thermal.schedules import check_power_mapping, describe_power_mapping
from ..thermal.transient import (DEFAULT_THETA, check_quasi_static_medium, check_theta,
                                 check_time_step, free_heat_input, heat_out_rate, heat_system,
                                 initial_rise, stepper_for)
from .base import Step, StepContext, StepOutcome, StepRecorder
from ..mechanics.rest_angles import spring_rest_angles
from .drives import MechanicalDrive, check_fold_drive, check_force_drive, describe_drive
from .heating import thermal_actuation
from .transient import circuit_end, step_powers

__all__ = ["ElectroThermal", "MECHANICS", "EASY_ITERATIONS", "REFRESH_STEPS"]

logger = logging.getLogger(__name__)

MECHANICS = ("dynamic", "quasi_static")
#: A mechanical step that converges in at most this many Newton iterations lets dt grow.
EASY_ITERATIONS = 8
#: With ``shape_tol > 0`` the heat matrices are still re-assembled after this many steps if the
#: shape changed at all, so a settled shape is eventually assembled exactly (no lasting bias).
REFRESH_STEPS = 16


@dataclass(frozen=True)
class ElectroThermal(Step):
    """Heat and motion together over ``duration`` [s] (see the module docstring).

    Parameters
    ----------
    power : mapping
        Power ADDED on top of the state's crease powers, keyed by crease id or by a tuple of
        crease ids (a heater circuit): a :class:`~simulator.thermal.schedules.PowerSchedule`
        (time from the start of this step) or a constant power [W].
    duration : float
        Length of the step [s], > 0.
    dt : float
        First time step [s], > 0.
    dt_min, dt_max : float, optional
        Bounds of the adaptive time step [s] (default: both ``dt``, i.e. fixed steps);
        ``dt_min <= dt <= dt_max``.
    mechanics : {"dynamic", "quasi_static"}
        "dynamic": one implicit time step with inertia and damping (``options``);
        "quasi_static": equilibrium at every time (inertia negligible).
    theta : float
        Weight of the new time level of the heat step, in [1/2, 1] (default 1, backward Euler:
        L-stable; ``REFERENCE_THETA`` = 2/3 is the reference's).
    options : DynamicsOptions
        Scheme and damping of the dynamic mechanics. The default, generalized-alpha with
        ``rho_inf = 0.5``, damps the stiff crease-node modes that a fast rest-angle change
        excites, and for steps much longer than a vibration period it tends to the
        quasi-static answer.
    temperature_step : float
        Node temperature change per step [K] that steers the adaptive step (see the module
        docstring), > 0.
    shape_tol : float
        Largest node movement [m] since the last assembly of the heat matrices for which they
        are kept (for at most :data:`REFRESH_STEPS` steps), >= 0 (0: re-assemble whenever the
        shape changed).
    record_every : int
        Record every k-th accepted time step (the last one is always recorded).
    forces : mapping {node: (fx, fy, fz) or ((fx, fy, fz), schedule)} or array, optional
        Mechanical load [N] added to the dead loads, constant or times a schedule of the step
        time (:mod:`simulator.steps.drives`); the value at the end stays applied.
    folds : mapping {crease id: fold angle [rad] or schedule}, optional
        Rest fold angles of creases driven mechanically; they replace the thermally actuated
        rest angles of those creases.
    circuits : mapping {Circuit: Drive}
        Heater circuits (theory 8.8) driven by a voltage, current or power, constant or a
        schedule of the step time (steps end on its switching times); the circuits the state
        drives keep their drives. Their powers follow from the temperatures at the start of
        each time step (semi-implicit); a heater past
        :data:`~simulator.thermal.circuits.RUNAWAY_TEMPERATURE` ends the step with status
        "thermal_runaway".
    """

    power: Mapping = field(default_factory=dict)
    duration: float = 1.0
    dt: float = 1e-3
    dt_min: float | None = None
    dt_max: float | None = None
    mechanics: str = "dynamic"
    theta: float = DEFAULT_THETA
    options: DynamicsOptions = DynamicsOptions(method="generalized_alpha", rho_inf=0.5)
    temperature_step: float = 2.0
    shape_tol: float = 0.0
    record_every: int = 1
    forces: object = None
    folds: Mapping = field(default_factory=dict)
    name: str = "electro_thermal"
    circuits: Mapping = field(default_factory=dict)

    def __post_init__(self):
        owner = type(self).__name__
        check_power_mapping(owner, self.power)
        positive(f"{owner}.duration", self.duration, "s")
        dt = check_time_step(self.dt, f"{owner}.dt")
        lo = positive(f"{owner}.dt_min", self.dt_min, "s", allow_none=True)
        hi = positive(f"{owner}.dt_max", self.dt_max, "s", allow_none=True)
        lo, hi = dt if lo is None else lo, dt if hi is None else hi
        if not lo <= hi:
            raise ParameterError(f"{owner}: dt_min = {lo!r} s > dt_max = {hi!r} s; give "
                                 "dt_min <= dt <= dt_max.")
        if not lo <= dt <= hi:
            raise ParameterError(f"{owner}: dt = {dt!r} s lies outside [dt_min, dt_max] = "
                                 f"[{lo!r}, {hi!r}] s.")
        one_of(f"{owner}.mechanics", self.mechanics, MECHANICS)
        check_theta(self.theta)
        if not isinstance(self.options, DynamicsOptions):
            raise ParameterError(f"{owner}.options is a {type(self.options).__name__}; give "
                                 "DynamicsOptions(...).")
        positive(f"{owner}.temperature_step", self.temperature_step, "K")
        non_negative(f"{owner}.shape_tol", self.shape_tol, "m")
        integer(f"{owner}.record_every", self.record_every)
        check_force_drive(owner, self.forces)
        check_fold_drive(owner, self.folds)
        check_circuits(owner, self.circuits)

    @property
    def bounds(self) -> tuple[float, float]:
        """(dt_min, dt_max) [s] with the defaults filled in."""
        return (self.dt if self.dt_min is None else float(self.dt_min),
                self.dt if self.dt_max is None else float(self.dt_max))

    def run(self, context: StepContext, state) -> StepOutcome:
        drive = MechanicalDrive(context.model, state, self.forces, self.folds, "ElectroThermal")
        heat = _HeatPart(context, state, self)
        mech = _MechanicsPart(context, state, self, drive.load0)
        actuate = _driven(thermal_actuation(context.model, state), drive)
        powers = step_powers(context.model.mesh, state, self.power, self.circuits,
                             "ElectroThermal")
        circuit_columns = getattr(powers, "columns", lambda temp, t: {})
        switches = powers.schedules + drive.schedules
        rec = StepRecorder(state)
        watch = CrossingWatch(context.model.mesh, state.u, context.model.supports)
        rec.record_start(power=powers(0.0), velocity=mech.velocity,
                         **{"time [s]": state.time, "dt [s]": None, **mech.energies(),
                            **heat.energies(), **circuit_columns(state.temperature, 0.0)})
        dt_min, dt_max = self.bounds
        t, h, k, temp = 0.0, float(self.dt), 0, state.temperature
        target, rest = state.crease_rest, state.spring_rest
        status, message = "converged", ""
        while t < self.duration * (1 - 1e-12):
            h_try = min(h, self.duration - t, next_switch(switches, t) - t)
            new_temp = heat.trial(mech.x, powers.mean(t, t + h_try), h_try)
            change = float(np.max(np.abs(new_temp - temp)))
            if change > 2 * self.temperature_step and h_try > dt_min:
                h = max(dt_min, h_try / 2)                           # reject: too fast heating
                continue
            new_target, new_rest = actuate(new_temp, t + h_try)
            report = mech.trial(h_try, new_rest, drive.load(t + h_try))
            if not report.success:
                if h_try > dt_min:
                    h = max(dt_min, h_try / 2)
                    continue
                status = "failed"
                message = (f"time step {k + 1} at t = {state.time + t:.6g} s failed with the "
                           f"smallest step {h_try:.3g} s: {report.message}")
                break
            heat.accept()
            mech.accept(report)
            t, k, temp, target, rest = t + h_try, k + 1, new_temp, new_target, new_rest
            rec.iterations += report.iterations
            rec.cuts += report.cuts
            runaway = _runaway(powers, temp, state.time + t)
            crossing = watch.check(mech.u, len(rec), t / self.duration, powers(t), temp)
            if k % self.record_every == 0 or t >= self.duration * (1 - 1e-12) or crossing \
                    or runaway:
                rec.record(t / self.duration, mech.u, temp, powers(t), report.iterations,
                           np.concatenate(report.residual_norms) if report.residual_norms
                           else (), velocity=mech.velocity,
                           **{"time [s]": state.time + t, "dt [s]": h_try,
                              **mech.energies(), **heat.energies(),
                              **circuit_columns(temp, t)})
            if crossing is not None:                  # (recorded above)
                rec.events.append(crossing)
            if stops(crossing):                       # panels through each other: stop
                status, message = "panel_crossing", f"at t = {state.time + t:.6g} s: " + \
                    crossing.message
                break
            if runaway:
                status, message = "thermal_runaway", runaway
                break
            context.report(k, k + math.ceil((self.duration - t) / h_try - 1e-9))
            if change > self.temperature_step:
                h = max(dt_min, h_try / 2)
            elif (h_try == h and report.iterations <= EASY_ITERATIONS  # not cut short by a
                  and change <= self.temperature_step / 2):             # switch or the end
                h = min(dt_max, 2 * h)
        if status == "converged":
            message = (f"reached t = {self.duration:g} s in {k} time steps ({heat.assemblies} "
                       "heat assemblies)")
        logger.info("ElectroThermal: %s", message)
        end = replace(state, u=mech.u, velocity=mech.velocity, temperature=temp,
                      crease_rest=target, spring_rest=rest, crease_power=powers(t),
                      time=state.time + t, applied_load=mech.f.reshape(state.u.shape),
                      **circuit_end(powers, temp, t))
        return rec.finish(status == "converged", status, message, end, mech.f, mech.evaluation)

    def describe(self) -> dict:
        dt_min, dt_max = self.bounds
        return {"power_added": describe_power_mapping(self.power),
                "duration [s]": self.duration, "dt [s]": self.dt, "dt_min [s]": dt_min,
                "dt_max [s]": dt_max, "mechanics": self.mechanics, "theta": self.theta,
                "temperature_step [K]": self.temperature_step, "shape_tol [m]": self.shape_tol,
                "record_every": self.record_every, **describe_drive(self.forces, self.folds),
                **self.options.to_dict(),
                **({"circuits": describe_circuits(self.circuits)} if self.circuits else {})}


def _runaway(powers, temp, time: float) -> str:
    """Give heater circuits the accepted temperatures (n,) [deg C]; the message of a run-away
    at ``time`` [s] if they are no operating point, else ""."""
    why = powers.observe(temp) if hasattr(powers, "observe") else ""
    if not why:
        return ""
    message = f"at t = {time:.6g} s: {powers.runaway_message(why)}"
    logger.warning("ElectroThermal: %s", message)
    return message


def _driven(actuate, drive):
    """``(temp, t) -> (crease_rest, spring_rest)``: the thermal actuation with the creases the
    drive lists at their driven rest angles at step time t."""
    if not (drive.fold_terms or drive.fixed):
        return lambda temp, t: actuate(temp)

    def rest(temp, t):
        target = drive.crease_rest(t, base=actuate(temp)[0])
        return target, spring_rest_angles(drive.mesh, target, drive.params)
    return rest


class _HeatPart:
    """Transient heat of one step: rises of the free unknowns, assembly and factorisation
    cache, heat bookkeeping. ``trial`` proposes a time step, ``accept`` keeps it."""

    def __init__(self, context, state, step: ElectroThermal):
        self.tm, self.theta, self.tol = context.thermal, step.theta, step.shape_tol
        self.room, self.n = state.room_temperature, context.model.mesh.n_nodes
        x = context.model.mesh.nodes + state.u
        check_quasi_static_medium(self.tm, x, step.dt, "ElectroThermal")
        self._assemble(x)
        self.assemblies = 1
        self.rise = initial_rise(self.tm, x, state.temperature, self.room)
        self.T = self.rise[self.system.free]
        self.heat_in = self.heat_out = 0.0

    def _assemble(self, x):
        self.x_assembled, self.system, self.stepper = x, heat_system(self.tm, x), None
        self.age = 0

    def trial(self, x, power, h) -> np.ndarray:
        """Node temperatures [deg C] (n,) after a step of ``h`` [s] with mean crease powers
        ``power`` (C,) [W], the heat matrices on the shape ``x`` (n, 3) [m]."""
        moved = np.max(np.abs(x - self.x_assembled), initial=0.0)
        if moved > self.tol or (moved > 0 and self.age >= REFRESH_STEPS):
            self._assemble(x)
            self.assemblies += 1
        self.age += 1
        if self.stepper is None or self.stepper.dt != h:
            self.stepper = stepper_for(self.system, h, self.theta, self.room)
        self._q = free_heat_input(self.tm, self.system.free, power, self.system.load)
        self._electric = float(np.sum(power))      # W (the rest of _q heats fixed nodes)
        self._T = self.stepper.step(self.T, self._q, self._q)
        self._out = heat_out_rate(self.system, self.stepper, self.T, self._T)
        self._h = h
        rise = self.rise.copy()
        rise[self.system.free] = self._T
        self._rise = rise
        return self.room + rise[:self.n]

    def accept(self) -> None:
        h = self._h
        self.heat_in += h * self._electric
        self.heat_out += h * (self._electric - float(np.sum(self._q)) + float(self._out))
        self.T, self.rise = self._T, self._rise

    def energies(self) -> dict:
        return {"heat_in [J]": self.heat_in, "heat_out [J]": self.heat_out}


class _MechanicsPart:
    """The mechanical half of a step: a dynamic time step or a quasi-static Newton solve."""

    def __init__(self, context, state, step: ElectroThermal, load):
        self.context, self.dynamic = context, step.mechanics == "dynamic"
        self.f = load
        self.nodes = context.model.mesh.nodes
        self.dissipated = self.work = 0.0
        if self.dynamic:
            self.integ = TimeIntegrator(context.system, step.options)
            self.motion = self.integ.initial_state(state.u, state.node_velocity, self.f,
                                                   state.spring_rest, 0.0)
            self.u, self.evaluation = self.motion.u, self.motion.evaluation
        else:                                       # (for the energies of the start record)
            self.u = state.u
            self.evaluation = context.system.evaluate(state.u, state.spring_rest,
                                                      hessian=False)
        self.rest = state.spring_rest

    @property
    def x(self) -> np.ndarray:
        return self.nodes + self.u

    @property
    def velocity(self):
        return self.motion.v if self.dynamic else None

    def trial(self, h, rest, f):
        self.rest_trial, self.f_trial = rest, f
        if self.dynamic:
            return self.integ.step(self.motion, h, f, rest)
        return _QuasiStatic(follow_path(self.context.system, self.u, self.f, f,
                                        self.rest, rest, 1, self.context.options))

    def accept(self, report) -> None:
        if self.dynamic:
            du = (report.state.u - self.u).ravel()
            self.motion, self.evaluation = report.state, report.state.evaluation
            self.dissipated += report.dissipated
        else:
            du = (report.result.u - self.u).ravel()
            self.evaluation, self.rest = report.result.evaluation, self.rest_trial
        self.work += float(du @ (0.5 * (self.f + self.f_trial)))
        self.f = self.f_trial
        self.u = self.motion.u if self.dynamic else report.result.u

    def energies(self) -> dict:
        strain = float(sum(self.evaluation.energies.values()))
        if self.dynamic:
            vf = self.motion.v.ravel()[self.integ.system.free]
            kinetic, dissipated = 0.5 * float(vf @ (self.integ.m * vf)), self.dissipated
        else:
            kinetic, dissipated = 0.0, None
        return {"kinetic_energy [J]": kinetic, "strain_energy [J]": strain,
                "dissipated_energy [J]": dissipated, "external_work [J]": self.work}


@dataclass(frozen=True, eq=False)
class _QuasiStatic:
    """An equilibrium path (one increment, halved on failure) dressed as a time-step report."""

    result: object

    def __getattr__(self, name):              # success, message, iterations, cuts
        return getattr(self.result, name)

    @property
    def residual_norms(self) -> tuple:
        return tuple(self.result.residual_norms)
