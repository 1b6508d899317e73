"""Electro-thermal loading steps: the paper's three-step loop per heating increment.

For every increment of a :class:`Heat` step (theory 6.6):

1. heat transfer: node temperatures for the current crease powers, with the conductivity
   assembled on the current shape (so folding changes heat loss);
2. Timoshenko bimorph: crease rest angles = rest angles at the start of the step plus
   ``W kappa(dT)``, dT = 7-node crease temperature minus its value at the start of the step;
3. bar-and-hinge equilibrium (contact, persisting gravity) by Newton with step cutting.

``coupling="staggered"`` (the reference's behaviour, the paper cases' setting) uses the shape
of the previous increment in step 1; ``coupling="iterated"`` repeats steps 1-3 within the increment until
temperature and shape agree; ``coupling="settled"`` is staggered but repeats them in the last
increment, so that the step ends on a coupled equilibrium whatever the increment count (the
staggered end lags by one increment: an error of order 1 / increments); it is the default. :class:`AmbientTemperature` ramps the room temperature instead
(theory 6.7).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..model.bimorph import crease_temperature_weights
from .._validate import finite, integer, one_of, positive
from ..errors import ConvergenceError, ParameterError
from ..events import CrossingWatch, stops
from ..solvers.newton import LOCATE_TOL, follow_path
from ..mechanics.rest_angles import spring_rest_angles
from ..state import at_rest
from .base import Step, StepContext, StepOutcome, StepRecorder, check_increments
from ..thermal.circuits import check_circuits, describe_circuits
from ..thermal.electrical import (CircuitIncrements, HeatingPoint, held_network,
                                  ramped_values)
from .limit import HeatPath, check_on_limit_point, continue_past_limit

logger = logging.getLogger(__name__)

__all__ = ["Heat", "AmbientTemperature", "coupled_increments"]


def _rotation_per_kelvin(model) -> np.ndarray:
    if model.actuators is None:
        return np.zeros(model.mesh.n_creases)
    return model.actuators.rotation_per_kelvin(model.mesh)


def thermal_actuation(model, state):
    """Timoshenko bimorph actuation measured from the start of a step (theory 6.6, step 2).

    Returns ``rest(temp) -> (crease_rest, spring_rest)``: crease rest angles [rad] =
    ``state.crease_rest + W kappa(dT)`` with dT the 7-node crease temperature [K] of the node
    temperatures ``temp`` (n_nodes,) [deg C] minus that of ``state.temperature``, and the spring
    rest angles they give (:func:`~simulator.mechanics.rest_angles.spring_rest_angles`).
    """
    mesh = model.mesh
    rot, w = _rotation_per_kelvin(model), crease_temperature_weights()
    t_ref, rest0 = state.temperature, state.crease_rest

    def rest(temp):
        target = rest0 + rot * ((temp - t_ref)[mesh.crease_nodes] @ w)
        return target, spring_rest_angles(mesh, target, model.params)
    return rest


@dataclass(frozen=True)
class _Coupling:
    """How heat and shape are coupled within an increment (internal: :class:`Heat` takes these
    settings as its own fields ``coupling``, ``coupling_tol`` and ``max_coupling_iterations``,
    which is what FOLD model files store; ``fixed_shape`` is :class:`AmbientTemperature`'s).

    Parameters
    ----------
    mode : {"staggered", "iterated", "settled"}
        "staggered" (the reference's behaviour): temperatures on the previous increment's
        shape; "iterated": repeat heat / rest angles / equilibrium until temperatures agree;
        "settled": staggered, the last increment iterated.
    tol : float
        Temperature agreement [K] that ends an "iterated" increment.
    max_iterations : int
        Coupling iterations per iterated increment.
    fixed_shape : bool
        Conductivity assembled once on the start shape (the reference's ambient step).
    """

    mode: str = "staggered"
    tol: float = 1e-6
    max_iterations: int = 20
    fixed_shape: bool = False


def steady_temperatures(tm, x, q, room):
    """``tm.solve(x, q, room)``, or the message where its nonlinear heat balance (theory 4.12)
    did not converge: a failure as data, for the step to report."""
    try:
        return tm.solve(x, q, room)
    except ConvergenceError as error:
        return str(error)


def coupled_increments(context: StepContext, state, powers: np.ndarray, ambient: np.ndarray,
                       coupling: _Coupling = _Coupling(), lam=None,
                       heating=None) -> StepOutcome:
    """The paper's three-step loop over increments s = 1..S (theory 6.6).

    Per increment: node temperatures for crease powers ``powers[s]`` (S, C) [W] and room
    temperature ``ambient[s]`` [deg C] on the current shape; crease rest angles from the
    Timoshenko bimorph (temperature change since the start of the step); equilibrium by
    Newton with step cutting. Returns the outcome with one record per increment; stops at the
    first increment whose equilibrium fails (status "failed") or in which a crease folds past
    +-180 deg (status "panel_crossing", with its event). ``lam`` (S + 1,): the step's load
    factor at the start and after every increment (default ``s / S``), for the records and
    events of a step that resumes part-way. ``heating`` (:class:`CircuitIncrements`): crease
    powers that depend on the temperatures (heater circuits); its operating point replaces
    ``powers[s]``, and a drive that runs away ends the step (status "thermal_runaway").
    """
    model, tm = context.model, context.thermal
    mesh = model.mesh
    actuate = thermal_actuation(model, state)
    u, spring, f = state.u, state.spring_rest, state.applied_load.ravel()
    x_start = mesh.nodes + state.u
    rec = StepRecorder(state)
    watch = CrossingWatch(mesh, state.u, model.supports)
    n_inc = len(powers)
    temp, target, evaluation, previous = state.temperature, state.crease_rest, None, None
    iterated = coupling.mode == "iterated" and not coupling.fixed_shape
    settled = coupling.mode == "settled" and not coupling.fixed_shape
    solve = _fixed_powers(tm) if heating is None else heating
    columns = {}
    for s, (base, room) in enumerate(zip(powers, ambient), start=1):
        point = solve(s, x_start if coupling.fixed_shape else mesh.nodes + u, base, room)
        if point.status != "converged":
            return _stopped(rec, state, point, u, spring, f, evaluation, s, n_inc)
        temp, power, columns = point.temperature, point.power, point.columns
        iterate = iterated or (settled and s == n_inc)
        change, done = math.inf, False         # no change measured yet
        u_from, spring_from, came, switched = u, spring, previous, False
        for _ in range(coupling.max_iterations if iterate else 1):
            target, rest = actuate(temp)
            # a coupling iteration after the first starts from the last one's equilibrium: its
            # rest angles move by the (small) change of the temperatures, not by the whole
            # increment's, so it needs no step cuts (the end state is the same equilibrium,
            # reached along the branch the first iteration followed)
            path = follow_path(context.system, u_from, f, f, spring_from, rest, 1,
                               context.options, locate_tol=LOCATE_TOL * n_inc, previous=came)
            rec.iterations += path.iterations
            rec.cuts += path.cuts
            switched = switched or bool(path.switches)
            if not path.success:
                last = rec._rows["temperature"][-1] if len(rec) else state.temperature
                message = (f"increment {s}/{n_inc} (crease power up to "
                           f"{1e3 * np.max(power, initial=0):.4g} mW): {path.message}")
                return rec.finish(False, "failed", message,
                                  at_rest(state, u=u, spring_rest=spring, temperature=last),
                                  f, evaluation)
            if not iterate:
                break
            u_from, spring_from, came = path.u, rest, None
            for _ in range(2):      # again, once, on the accurate loss at the end shape
                point = solve(s, mesh.nodes + path.u, base, room)
                if point.status != "converged":
                    return _stopped(rec, state, point, u, spring, f, evaluation, s, n_inc)
                change, before = float(np.max(np.abs(point.temperature - temp))), change
                temp, power, columns = point.temperature, point.power, point.columns
                done = _agreed(change, before, coupling.tol, temp - room)
                # at the end shape: rebuilt unless its last build was there (then the end
                # state is the accurate operator's own, whatever the corrections on the way)
                if not (done and s == n_inc and tm.exact_loss_at(mesh.nodes + path.u)):
                    break
            if done:
                break
        if iterate and not done:
            logger.warning("increment %d/%d: heat and shape still differ after %d coupling "
                           "iterations (temperatures change by %.3g K, coupling_tol %.3g K); "
                           "raise max_coupling_iterations", s, n_inc, coupling.max_iterations,
                           change, coupling.tol)
        previous = None if switched else (1.0, u)     # the direction the path came
        u, spring, evaluation = path.u, rest, path.evaluation
        lam0, lam1 = (s - 1) / n_inc, s / n_inc
        if lam is not None:
            lam0, lam1 = lam[s - 1], lam[s]
        rec.note_stability(path, temp, power,
                           lambda t, a=lam0, b=lam1: a + t * (b - a), one_record=True)
        rec.record(lam1, u, temp, np.asarray(power, float), path.iterations,
                   np.concatenate(path.residual_norms) if path.residual_norms else (),
                   **columns)
        crossing = watch.check(u, len(rec) - 1, lam1, power, temp)
        if crossing is not None:
            rec.events.append(crossing)
        if stops(crossing):
            return rec.finish(False, "panel_crossing", crossing.message,
                              at_rest(state, u=u, spring_rest=spring, temperature=temp,
                                      crease_rest=target, crease_power=np.asarray(power, float),
                                      room_temperature=float(room)), f, evaluation)
        context.report(s, n_inc)
    end = at_rest(state, u=u, spring_rest=spring, temperature=temp, crease_rest=target,
                  crease_power=np.asarray(power if heating else powers[-1], float),
                  room_temperature=float(ambient[-1]),
                  **({} if heating is None else heating.end_state()))
    return rec.finish(True, "converged", "converged", end, f, evaluation)


def _fixed_powers(tm):
    """The heat solve of fixed crease powers: ``(s, x, power, room) -> HeatingPoint`` (status
    "failed" where the nonlinear heat balance of theory 4.12 did not converge)."""
    def solve(s, x, power, room):
        temp = steady_temperatures(tm, x, tm.heat_vector(power), room)
        if isinstance(temp, str):
            return HeatingPoint(None, power, status="failed",
                                message=f"crease power up to "
                                        f"{1e3 * np.max(power, initial=0):.4g} mW: {temp}")
        return HeatingPoint(temp, power)
    return solve


def _stopped(rec, state, point, u, spring, f, evaluation, s, n_inc) -> StepOutcome:
    """The outcome of increment ``s`` of ``n_inc`` whose electrical drive has no operating
    point."""
    last = rec._rows["temperature"][-1] if len(rec) else state.temperature
    return rec.finish(False, point.status, f"increment {s}/{n_inc}: {point.message}",
                      at_rest(state, u=u, spring_rest=spring, temperature=last), f, evaluation)


#: The coupling iterations also end where the temperatures change by less than this fraction
#: of the largest rise and no longer shrink (by :data:`COUPLING_STALL` from one iteration to
#: the next): the precision of the thermal solve. The 36 x 36-cell Miura sheet's iterative
#: thermal solve (theory 4.7) settled to 1.1e-6 K at a 16.6 K rise and stalled there for 18 of
#: its 20 iterations against ``Heat.coupling_tol`` = 1e-6 K.
COUPLING_RTOL = 1e-6
#: The factor by which a change must shrink from one coupling iteration to the next to count
#: as progress (:data:`COUPLING_RTOL`).
COUPLING_STALL = 0.9


def _agreed(change: float, last: float, tol: float, rise) -> bool:
    """Whether coupling iterations whose temperatures changed by ``change`` [K] (``last`` the
    change before) have agreed: within ``tol`` [K], or within :data:`COUPLING_RTOL` of the
    largest ``rise`` [K] and no longer shrinking (the thermal solve's precision)."""
    if change <= tol:
        return True
    return change <= COUPLING_RTOL * float(np.max(np.abs(rise))) and \
        change >= COUPLING_STALL * last

#: The coupling modes of :class:`Heat` (``Heat.coupling``).
COUPLINGS = ("staggered", "iterated", "settled")


def _coupling(step) -> _Coupling:
    """Validate a step's coupling fields and return them as a :class:`_Coupling`."""
    owner = type(step).__name__
    mode = one_of(f"{owner}.coupling", step.coupling, COUPLINGS,
                  hint="the tolerance and iteration limit are the fields coupling_tol and "
                  "max_coupling_iterations")
    n = integer(f"{owner}.max_coupling_iterations", step.max_coupling_iterations)
    tol = positive(f"{owner}.coupling_tol", step.coupling_tol, "K")
    return _Coupling(mode, tol, n)


@dataclass(frozen=True)
class Heat(Step):
    """Ramp crease heating powers linearly over ``increments`` (theory 6.6).

    Parameters
    ----------
    power : mapping
        Power ADDED by this step on top of the current one [W], keyed by crease id, or by a
        tuple of crease ids for a heater circuit (each crease of the circuit gets the value).
    increments : int
        Heating increments (each solves temperature, rest angles and equilibrium).
    coupling : {"settled", "staggered", "iterated"}
        "settled" (default since 7 Dec 2026; before, "staggered"): see below. "staggered"
        (the reference's behaviour, the paper cases' setting): the temperatures of an increment are solved on
        the previous increment's shape, so the end state lags by one increment (an error of
        order 1 / ``increments``, larger where folding changes the heat loss much, as with the
        integral loss); "iterated": heat, rest angles and equilibrium are repeated within
        every increment until the temperatures agree within ``coupling_tol``; "settled":
        staggered, with the last increment iterated, so that the step ends on a coupled
        equilibrium whatever the increment count (a WARNING if it does not settle).
    coupling_tol : float
        Temperature agreement [K] that ends the loop of an iterated increment, > 0; the loop
        also ends where the change is within :data:`COUPLING_RTOL` of the largest rise and no
        longer shrinks (the thermal solve's own precision: on a large sheet's iterative path
        the temperatures settle to some 1e-7 of the rise, not to 1e-6 K).
    max_coupling_iterations : int
        Coupling iterations per iterated increment, >= 1.
    on_limit_point : {"stop", "continue"}
        When the heated structure reaches a limit point (it snaps): end with status
        "limit_point" (default), or continue by arc length in the power (temperatures on the
        current shape, :class:`~simulator.steps.limit.HeatPath`) through the unstable branch
        to the step's final power.
    circuits : mapping {Circuit: Drive}
        Heater circuits (theory 8.8) driven by a constant voltage, current or power at the end
        of the step, ramped linearly from their value at the state (0 if the state does not
        drive them); the circuits the state drives keep their drives. Their powers follow from
        the temperatures (each increment's steady operating point; a drive with none ends the
        step with status "thermal_runaway"), on top of ``power``. With circuits a failed
        increment ends the step "failed" (no limit point is located).
    """

    power: Mapping = field(default_factory=dict)
    increments: int = 200
    coupling: str = "settled"
    coupling_tol: float = 1e-6
    max_coupling_iterations: int = 20
    name: str = "heat"
    on_limit_point: str = "stop"
    circuits: Mapping = field(default_factory=dict)

    def __post_init__(self):
        check_increments(self)
        check_on_limit_point(self)
        _coupling(self)
        for key, v in dict(self.power).items():
            finite(f"Heat: power of crease {key}", v, "W")
        for circuit, drive in check_circuits("Heat", self.circuits).items():
            if drive.schedules:
                raise ParameterError(
                    f"Heat.circuits: circuit {circuit.name or circuit.creases} has the drive "
                    f"{drive.value!r}; Heat ramps to a constant: give a number, or use "
                    "TransientHeat / ElectroThermal for a schedule of the time.")
        if self.circuits and self.on_limit_point == "continue":
            raise ParameterError("Heat: on_limit_point = 'continue' follows the powers by arc "
                                 "length, which circuits do not give; use 'stop' with circuits.")

    def power_array(self, mesh) -> np.ndarray:
        """(C,) power added per crease row [W]."""
        out = np.zeros(mesh.n_creases)
        for key, v in dict(self.power).items():
            for c in (key if isinstance(key, tuple) else (key,)):
                out[mesh.crease_row_of(c)] += float(v)
        return out

    def run(self, context: StepContext, state) -> StepOutcome:
        mesh = context.model.mesh
        network, base = held_network(mesh, state, self.circuits, "Heat")
        if network is not None:
            return self._run_circuits(context, state, network, base)
        dP = self.power_array(mesh)
        end = state.crease_power + dP
        if np.any(end < 0):
            row = int(np.argmin(end))
            raise ParameterError(
                f"Heat: crease {int(mesh.crease_ids[row])} would end at "
                f"{1e3 * end[row]:.4g} mW; a step may lower the power (negative values) but not "
                "below zero.")
        s = np.arange(1, self.increments + 1)[:, None] / self.increments
        powers = state.crease_power + s * dP
        ambient = np.full(self.increments, state.room_temperature)
        outcome = coupled_increments(context, state, powers, ambient, _coupling(self))
        if outcome.success:
            return outcome
        # arc length traces the coupled equilibria (temperatures on the current shape) with
        # either coupling: staggered temperatures would lag by one arc-length increment,
        # whose size the continuation chooses, and the snap found would depend on it
        path = HeatPath(context, state, dP, _rotation_per_kelvin(context.model), iterated=True)

        def resume(mid, lam):
            n = max(1, round((1 - lam) * self.increments))
            s = lam + (1 - lam) * np.arange(1, n + 1)[:, None] / n
            return coupled_increments(context, mid, state.crease_power + s * dP,
                                      np.full(n, state.room_temperature), _coupling(self),
                                      lam=np.concatenate([[lam], s[:, 0]]))

        return continue_past_limit(context, state, outcome, path, self.increments,
                                   self.on_limit_point, path.state_at, resume, path.powers)

    def _run_circuits(self, context, state, network, base) -> StepOutcome:
        """:meth:`run` with heater circuits: the other powers ramp on top of ``base`` (the
        state's powers without its circuits' part), the circuits' drives as
        :func:`~simulator.thermal.electrical.ramped_values` says."""
        dP = self.power_array(context.model.mesh)
        if np.any(base + dP < 0):
            raise ParameterError("Heat: the powers would end below zero; a step may lower "
                                 "the power but not below zero.")
        s = np.arange(1, self.increments + 1)[:, None] / self.increments
        values = ramped_values(context.model.mesh, state, network,
                               check_circuits("Heat", self.circuits), self.increments)
        heating = CircuitIncrements(context.thermal, network, values)
        return coupled_increments(context, state, base + s * dP,
                                  np.full(self.increments, state.room_temperature),
                                  _coupling(self), heating=heating)

    def describe(self) -> dict:
        out = {"power_added [mW]": {str(k): 1e3 * float(v) for k, v in
                                    dict(self.power).items()},
               "increments": self.increments, "coupling": self.coupling,
               "on_limit_point": self.on_limit_point}
        if self.circuits:
            out["circuits"] = describe_circuits(self.circuits)
        return out


@dataclass(frozen=True)
class AmbientTemperature(Step):
    """Ramp the room temperature to ``target`` [deg C] with the heating unchanged (theory 6.7).

    The conductivity is assembled once on the shape at the start of the step, as in the
    reference.
    """

    target: float = 21.0
    increments: int = 50
    name: str = "ambient_temperature"

    def __post_init__(self):
        check_increments(self)
        finite("AmbientTemperature.target", self.target, "deg C", hint="a temperature")

    def run(self, context: StepContext, state) -> StepOutcome:
        if state.circuits:
            logger.warning("AmbientTemperature holds the crease powers; the heater circuits' "
                           "powers stay at their values at the start of the step (their "
                           "resistances are not updated)")
        s = np.arange(1, self.increments + 1) / self.increments
        ambient = state.room_temperature + s * (self.target - state.room_temperature)
        powers = np.repeat(state.crease_power[None], self.increments, axis=0)
        return coupled_increments(context, state, powers, ambient, _Coupling(fixed_shape=True))

    def describe(self) -> dict:
        return {"target [degC]": self.target, "increments": self.increments}
