"""What load-controlled steps do at a limit point, and the heating path for continuation.

Load control fails where the equilibrium path turns back (a limit point: the tangent is
singular there and Newton stalls). :func:`continue_past_limit` is called by
:class:`~simulator.steps.SelfFold`, :class:`~simulator.steps.Load` and
:class:`~simulator.steps.Heat` when their load control fails:

* ``on_limit_point="stop"`` (default): a short arc-length probe from the last converged state;
  if it passes a load-factor maximum the step ends with status ``"limit_point"`` and the load
  factor and displacement there in the message and in a ``"limit_point"`` event, otherwise
  (and when the step failed in its first increment) the failure is unchanged;
* ``on_limit_point="continue"``: the step carries on by arc length (MGDCM) with its path
  parameter as the unknown load factor until it reaches 1 on a stable branch, recording the
  unstable branch in between (column ``stable``); the message gives the snaps (load factor,
  power for heating, and the jump of the most-moving node's displacement), and so do the
  step's events (:class:`~simulator.events.Event`: the critical points of the arc-length
  stretches, and a ``"snap"`` per snap). On a heating path the arc length stops where the
  tangent loses stability while the power still rises (located by bisection) and restarts
  there with settings of that point alone, so that the branch it follows past it, and the
  snap, do not depend on the step's increments; and it hands back to load control only where
  the coupling of the load-controlled increments converges (:data:`COUPLING_GAIN_LIMIT`),
  going on along the stable branch until then. If arc length fails after the load factor turned
  back, the continuation driver jumps from the highest point reached to the equilibrium just
  above it that descent on the potential energy finds (where the snap lands; ``mgdcm``'s
  ``lost_fold_jump``), and load control resumes there.

Heating continuation (:class:`HeatPath`): crease power ``P0 + lambda dP``. On a given shape the
temperatures are affine in lambda (the heat problem is linear in the power), which gives the
rest angles ``rest0 + lambda R`` and ``q = dr/dlambda`` exactly. Which shape: with the step's
``coupling="staggered"`` (default, as the load-controlled increments) the temperatures are
solved on the shape of the last converged point at the start of every increment, so the
corrector is a true Newton method; with ``"iterated"`` they are solved on the current shape at
every corrector iteration (the fixed point of the iterated coupling, so the traced curve does
not depend on the increments), whose tangent ignores the shape dependence of the conductivity
(the corrector then converges linearly in that weak coupling).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..model.bimorph import crease_temperature_weights
from ..solvers.continuation import FAST_ITERATIONS, mgdcm
from ..errors import ParameterError
from ..solvers.load_path import (LoadPath, PathConstraint, correct_point, model_size,
                                 solve_path_system)
from ..mechanics.rest_angles import spring_rest_angles
from ..state import at_rest
from ..mechanics.substrate import not_physical
from ..events import CrossingWatch, Event, crossing_stop, event_at, monitored_node, stops
from .base import StepOutcome, StepRecorder

__all__ = ["LIMIT_POINT_ACTIONS", "HeatPath", "check_on_limit_point",
           "continue_past_limit", "record_continuation"]

#: Allowed values of ``on_limit_point``.
LIMIT_POINT_ACTIONS = ("stop", "continue")
#: Arc-length increments at most of the probe that looks for a limit point after a failure
#: (it stops as soon as the load factor turns).
PROBE_INCREMENTS = 40
#: Arc-length increments at most per snap with on_limit_point="continue". At the arc length
#: of ARC_LOAD_STEP (at most four times that) a run covers at most 16 load factors' worth of
#: the load-controlled motion: the gripper's arm-tip snap (start design with a residual fold
#: of 45 deg, first grip trial) takes 235, most of them on its unstable branch, which is long
#: against the motion of the load-controlled part.
CONTINUATION_INCREMENTS = 400
#: Arc length of the continuation in load-factor units: the first predictor moves the
#: displacements as far as the load-controlled part would over this load factor (the step's
#: own increments play no part, so the traced snap does not depend on them).
ARC_LOAD_STEP = 0.01
#: Near a limit point the continuation's arc length is at most ARC_LOAD_STEP / RESOLVE, or at
#: a flat fold what changes the load factor by that much
#: (:func:`~simulator.solvers.continuation.mgdcm`'s ``resolution``): the snap's load factor and jump
#: are located at that resolution.
RESOLVE = 8
#: Switch to the stable branch at a loss of stability without a load-factor turn
#: (:func:`~simulator.solvers.continuation.mgdcm`'s ``switch_branches``). Off: on the heated
#: Miura (a = 0.5 mm, gamma = 45 deg) the loss at load factor 0.767372 is located, but the
#: landing's rounds of (temperatures on the shape, energy descent) alternate between two
#: shapes 0.5 mm apart instead of converging: at the temperatures of the loss, descent
#: lands 125 um further on, where the creases run 8.5 K cooler, and at those temperatures it
#: falls back 266 um behind the loss. There is no stable coupled equilibrium near the loss at
#: its power (the traced far branch is stable from load factor 0.7743 on).
SWITCH_BRANCHES = False
#: On a heating path (temperatures on the current shape) the continuation ends where the
#: tangent loses stability while the load factor still rises (located by bisection to
#: ARC_LOAD_STEP / RESOLVE / 16, ``mgdcm(locate_stability_loss="stop")``) and restarts from
#: there with settings of that point alone (:func:`_restart`): the heated Miura's tangent
#: loses stability at load factor 0.767372 before the fold at 0.767986, and past it the
#: coupled path has several branches; arc length arriving with the step size of a given
#: increment count followed different ones (the snap's jump 47.0 / 35.1 / 48.0 / 49.6 um at 30
#: / 60 / 120 / 240 increments; 52.26 um at all four with the restart).
RESTART_AT_STABILITY_LOSS = True
#: Shape change (fraction of the model size) of the difference that gives
#: :meth:`HeatPath.coupling_gain`.
GAIN_PROBE = 1e-4
#: On a heating path the continuation hands back to load control only at a stable point where
#: the coupling's gain along the softest mode (:meth:`HeatPath.coupling_gain`) is below this
#: in magnitude (``mgdcm``'s ``handover``); before, it goes on along the stable branch. Load
#: control solves the temperatures on the shape of the increment before (staggered, or
#: iterated to a fixed point by the same pass), which multiplies a shape error along the mode
#: by the gain: above 1 in magnitude it diverges from the coupled path. Where the path
#: turns stable again the lowest eigenvalue is near zero and the gain large: on the heated
#: Miura (a = 0.5 mm, gamma = 45 deg) -41 at load factor 0.7745, the first stable point past
#: its snap (eigenvalue 1.9e-6 N/m), -3.4 at 0.7788, -1.0 at 0.796, -0.5 at 0.829. Resumed
#: at 0.7745, load control ended 50 um off the coupled path after one increment at 120
#: increments; at 240 its second increment turned sharply at 0.7816, left along the soft
#: mode for a state 338 um back (whose coupled equilibrium is on the unsnapped branch, at
#: load factor 0.754) and the step failed. Half: the error at least halves per increment.
COUPLING_GAIN_LIMIT = 0.5
#: Load-control failures (snaps) passed by arc length at most within one step.
MAX_SNAPS = 5
#: Statuses of a load-controlled outcome that end the step as they are: stopped by a callback,
#: a crease folded past +-180 deg, an end state known to be unstable (no limit point to pass).
_NOT_LIMITS = ("stopped", "panel_crossing", "unstable")


def check_on_limit_point(step) -> None:
    """Raise :class:`ParameterError` unless ``step.on_limit_point`` is allowed."""
    if step.on_limit_point not in LIMIT_POINT_ACTIONS:
        raise ParameterError(f"{type(step).__name__}.on_limit_point = {step.on_limit_point!r}; "
                             "use 'stop' (end with status 'limit_point') or 'continue' (arc "
                             "length past it).")


def record_continuation(rec: StepRecorder, res, temperature, power, c, powers=None,
                        extra=None, *, mesh, critical: list | None = None,
                        supports=None) -> Event | None:
    """Record every accepted point of a ContinuationResult with its stability columns, and
    its critical points as events (:class:`~simulator.events.Event`), up to the first point
    where panels of ``mesh`` passed through each other since the point before (the last
    record of ``rec``, or the step's start for its first; :class:`~simulator.events.
    CrossingWatch`): that point is recorded with its ``"panel_crossing"`` event, which is
    returned (None if none crossed); the points after it and their critical points are not.
    A crease of finite width folding past 180 deg on the way is a ``"fold_past_flat"`` event.

    ``powers(lam)`` gives the crease powers of a point (default ``power``); ``extra(lam)`` more
    named columns; ``c`` (n_dof,) weighs the recorded ``displacement [m]`` (None: none);
    ``critical``, a list, receives the events of the recorded critical points too, in the
    order of ``res.critical_points`` (the events of ``rec`` mix them with the crossing
    watch's). ``supports`` (the model's): a node below a substrate is a crossing too
    (:class:`~simulator.events.CrossingWatch`).
    """
    node, offset = monitored_node(c), len(rec)
    watch = CrossingWatch(mesh, rec.last_u, supports)
    crossing, recorded, found = None, len(res.history), []
    for k, (lam, u, _) in enumerate(res.history):
        temp = res.temperatures[k] if res.temperatures[k] is not None else temperature
        event = watch.check(u, offset + k, lam, power if powers is None else powers(lam), temp)
        if event is not None:
            found.append(event)
        if stops(event):
            crossing, recorded = event, k + 1
            break
    events = [event_at(p, res, power if powers is None else powers(p.load_factor),
                       temperature, offset, node) for p in res.critical_points
              if p.increment < recorded]
    rec.events += events
    if critical is not None:
        critical += events
    rec.iterations += res.iterations
    rec.cuts += res.cuts
    for k, ((lam, u, its), norms) in enumerate(zip(res.history[:recorded],
                                                   res.residual_norms)):
        st = res.stability[k] if res.stability else None
        temp = res.temperatures[k] if res.temperatures[k] is not None else temperature
        cols = {} if st is None else {"stable": st.stable, "negative_eigenvalues": st.negative,
                                      "lowest_eigenvalue [N/m]": st.lowest}
        if c is not None:
            cols["displacement [m]"] = float(c @ u.ravel())
        if extra is not None:
            cols.update(extra(lam))
        rec.record(lam, u, temp, power if powers is None else powers(lam), its, norms, **cols)
    rec.events += found
    return crossing


class HeatPath(LoadPath):
    """Heating path: crease powers ``P0 + lambda dP`` with temperatures on the current shape.

    Parameters
    ----------
    context : StepContext
    start : SimulationState at the start of the heating step (reference temperatures and rest
        angles of the bimorph actuation, powers P0)
    dP : (C,) power added per crease row over the step [W]
    rotation_per_kelvin : (C,) actuator rest-angle change per kelvin [rad/K]
    iterated : bool
        Temperatures on the current shape at every evaluation (True) or on the shape given to
        :meth:`begin_increment` (False, staggered).
    """

    def __init__(self, context, start, dP, rotation_per_kelvin, iterated=False):
        model = context.model
        self.mesh, self.params, self.tm = model.mesh, model.params, context.thermal
        self.rot, self.w = rotation_per_kelvin, crease_temperature_weights()
        self.start, self.dP = start, np.asarray(dP, float)
        self.q = np.column_stack([self.tm.heat_vector(start.crease_power),
                                  self.tm.heat_vector(self.dP)])
        super().__init__(context.system, start.applied_load.ravel(),
                         np.zeros(self.mesh.n_dof), start.spring_rest)
        self.iterated, self._lin = iterated, None

    def begin_increment(self, u):
        """Staggered coupling: solve the temperatures on the shape ``u`` for the increment."""
        if not self.iterated:
            self._lin = self.linearise(u)

    def linearise(self, u):
        """Temperatures at lambda = 0 and per unit lambda on the shape ``u``; sets the
        rest angles ``rest0 + lambda R``. Returns (T0, dT, crease rest at 0, per unit)."""
        T0, dT, c0, dc = self._on_shape(u)
        self.rest0, self.R = self._spring_rest(c0, dc)
        return T0, dT, c0, dc

    def _on_shape(self, u):
        """(T0, dT, crease rest at 0, per unit lambda) with the temperatures on ``u``."""
        room = self.start.room_temperature
        x = self.mesh.nodes + u
        if not self.tm.nonlinear:
            T = self.tm.solve(x, self.q, room)
            T0, dT = T[:, 0], T[:, 1] - room
        else:       # heat inputs do not superpose (theory 4.12): the secant from 0 to 1
            T0 = self.tm.solve(x, self.q[:, 0], room)
            dT = self.tm.solve(x, self.q[:, 0] + self.q[:, 1], room) - T0
        cn = self.mesh.crease_nodes
        c0 = self.start.crease_rest + self.rot * ((T0 - self.start.temperature)[cn] @ self.w)
        return T0, dT, c0, self.rot * (dT[cn] @ self.w)

    def _spring_rest(self, c0, dc):
        """Spring rest angles at lambda = 0 and per unit lambda of crease rest ``c0 + lambda
        dc``."""
        rest0 = spring_rest_angles(self.mesh, c0, self.params)
        return rest0, spring_rest_angles(self.mesh, c0 + dc, self.params) - rest0

    def coupling_gain(self, u, lam, K, mode, linear_solver="auto") -> float:
        """Amplification of a displacement error along ``mode`` (n_free,) by one pass of the
        staggered coupling at the equilibrium ``u`` at ``lam`` (tangent ``K``): temperatures
        solved on ``u + e mode`` and the equilibrium of their rest angles found from ``u``
        (linearised: ``-mode . K^-1 df / e``, ``df`` the change of the internal force at
        ``u`` [N]). Load control (either coupling: the iterated one repeats the same pass)
        follows the coupled path only where it is below 1 in magnitude along the softest
        mode; near a singular tangent it grows as the inverse of the lowest eigenvalue.
        nan if the solve fails."""
        mode = np.asarray(mode, float)
        e = GAIN_PROBE * model_size(self.system) / float(np.max(np.abs(mode)))
        shifted = np.array(u, float).ravel()
        shifted[self.free] += e * mode
        forces = []
        for shape in (np.asarray(u, float), shifted.reshape(-1, 3)):
            _, _, c0, dc = self._on_shape(shape)
            rest0, R = self._spring_rest(c0, dc)
            forces.append(self.system.evaluate(u, rest0 + lam * R, hessian=False)
                          .f_int[self.free])
        du = solve_path_system(K, forces[0] - forces[1], linear_solver)
        return float("nan") if du is None else float(mode @ du) / e

    def at(self, u, lam):
        if self.iterated or self._lin is None:
            self._lin = self.linearise(u)
        T0, dT, _, _ = self._lin
        return replace(super().at(u, lam), temperature=T0 + lam * dT)

    def powers(self, lam):
        return self.start.crease_power + lam * self.dP

    def state_at(self, u, lam):
        """Simulation state at a converged point of the path: with iterated coupling the
        temperatures and rest angles on ``u`` itself (the last evaluation may have been at
        another shape: a failed corrector's), else the increment's linearisation."""
        if self.iterated or self._lin is None:
            self._lin = self.linearise(u)
        T0, dT, c0, dc = self._lin
        return at_rest(self.start, u=u, spring_rest=self.rest(lam), temperature=T0 + lam * dT,
                       crease_rest=c0 + lam * dc, crease_power=self.powers(lam))


def _replay(rec: StepRecorder, outcome: StepOutcome) -> None:
    """Copy the records of a (failed) load-controlled outcome into ``rec``, with its events
    (their increments counted in ``rec``) and the stability of its end."""
    rec.iterations += outcome.iterations
    rec.cuts += outcome.cuts
    offset = len(rec)
    rec.events += [e if e.increment is None else replace(e, increment=e.increment + offset)
                   for e in outcome.events]
    if outcome.stable is not None:
        rec.stable = outcome.stable
    for k in range(len(outcome.load_factor)):
        rec.record(outcome.load_factor[k], outcome.u[k], outcome.temperature[k],
                   outcome.power[k], int(outcome.increment_iterations[k]),
                   outcome.residual_norms[k], **{n: v[k] for n, v in outcome.columns.items()})


def _motion_monitor(u0, u) -> np.ndarray:
    """(n_dof,) weights of the displacement of the node that moves most from ``u0`` to ``u``
    (n_nodes, 3), along that motion."""
    du = np.asarray(u, float) - u0
    node = int(np.argmax(np.linalg.norm(du, axis=1)))
    c = np.zeros(du.size)
    n = np.linalg.norm(du[node])
    c[3 * node:3 * node + 3] = du[node] / n if n > 0 else (0.0, 0.0, 1.0)
    return c


def _snaps(res, c, drop=0.0) -> list:
    """[(critical point, displacement after)] of every snap: a limit point (maximum) where the
    path turned back, and the point where it crosses that load factor again moving forward,
    if in between it was unstable (where ``res`` has the stability of every point) or fell by
    more than ``drop`` [load factor]. Other turns are no snaps: at a flat top the corrector's
    load factor wiggles (the gripper's arm tips: by 3e-9 and 4e-8 at its maximum, on stable
    points, before the path falls by 0.13)."""
    lam = np.array([h[0] for h in res.history])
    m = np.array([float(c @ h[1].ravel()) for h in res.history])
    stab = res.stability if len(res.stability) == len(lam) else None
    out, used = [], set()
    for before, after, kind in res.jumps:     # a branch switch: last stable to landed
        p = next(p for p in res.critical_points if p.kind == kind and
                 p.increment == before + 1)
        out.append((p, m[after]))
    for p in res.critical_points:
        k = p.increment
        if p.kind != "limit_point" or not p.maximum:
            continue                                   # only maxima (the path heads up)
        for j in range(k + 1, len(lam)):
            if lam[j - 1] < p.load_factor <= lam[j]:
                snapped = lam[k:j].min() < p.load_factor - drop or (
                    stab is not None and not all(st.stable for st in stab[k:j]))
                if snapped and j not in used:  # wiggles near one maximum land on one segment
                    a = (p.load_factor - lam[j - 1]) / (lam[j] - lam[j - 1])
                    out.append((p, m[j - 1] + a * (m[j] - m[j - 1])))
                    used.add(j)
                break
    return out


def continue_past_limit(context, start, outcome: StepOutcome, path, increments: int,
                        action: str, end_state, resume, powers=None) -> StepOutcome:
    """After a failed load-controlled step: look for a limit point, or continue past it.

    Parameters
    ----------
    context : StepContext
    start : SimulationState at the start of the step
    outcome : StepOutcome of the load-controlled part (returned unchanged if it succeeded, was
        stopped, or ended on a panel crossing or an unstable state: no limit point to pass)
    path : LoadPath whose load factor is the step's path parameter (0 at the start, 1 at the
        end); ``outcome.state`` lies on it at the last recorded load factor
    increments : int
        The step's nominal increments (the arc length is ``1 / increments``, the first
        predictor as long as the last load-controlled increment; the arc length doubles after
        increments as easy as the median load-controlled one).
    action : "stop" or "continue"
    end_state : callable ``(u, lam) -> SimulationState`` at a converged point
    resume : callable ``(state, lam) -> StepOutcome``
        Load control from a converged state at ``lam`` to the end of the step (records with
        the step's load factor).
    powers : callable ``lam -> (C,) powers [W]``, optional (heating steps)

    With "continue", arc length takes over from the last converged state until the path is
    stable again beyond the snap (or reaches the end), on a heating path at a point where the
    coupling converges (:data:`COUPLING_GAIN_LIMIT`), then load control resumes; this repeats
    for up to :data:`MAX_SNAPS` failures. Where arc length fails after the load factor turned
    back (a branch that falls away from the step's end, or a corrector stalled in contact
    chatter on it), the step jumps from the highest point it reached to the equilibrium at
    ``ARC_LOAD_STEP / RESOLVE`` above it that
    :func:`~simulator.solvers.descent.descend` finds (or, failing that, resumes
    load control from that point), then load control resumes (message "jump from load factor
    ...", the load factor where it resumed).
    """
    if outcome.success or outcome.status in _NOT_LIMITS:
        return outcome
    if action == "stop":        # a step failing in its first increment stays "failed"
        return _probe(context, start, outcome, path, increments, powers) \
            if len(outcome.load_factor) else outcome
    rec = StepRecorder(start)
    _replay(rec, outcome)
    notes, current, c = [], outcome, _motion_monitor(start.u, outcome.state.u)
    origin = (start.u, 0.0)                 # where the load control of ``current`` began
    for k in range(MAX_SNAPS):
        parts, c = _continuation(context, origin, current, path, increments, c,
                                 None if k else start.u)
        texts = []
        for res in parts:
            limits = []
            crossing = record_continuation(rec, res, current.state.temperature,
                                           current.state.crease_power, c, powers=powers,
                                           mesh=context.model.mesh, critical=limits,
                                           supports=context.model.supports)
            if crossing is not None:     # the arc length stopped where panels crossed
                return _crossed(rec, res, crossing, end_state, notes)
            texts.append(res.message + _snap_text(rec, res, c, powers, limits))
        state = end_state(res.u, res.load_factor) if res.history or res.success else \
            current.state
        lam0 = float(current.load_factor[-1]) if len(current.load_factor) else origin[1]
        why = not_physical(current.message)       # a refused state stopped it (theory 6.11)
        notes.append(f"load control stopped at load factor {lam0:.6g}"
                     + (f" (not physical beyond: {why})" if why else "") + "; arc length: "
                     + "; restarted there: ".join(texts))
        lam1 = res.load_factor
        if not res.success or lam1 >= 1.0 - 1e-12:
            return rec.finish(res.success, res.status, "; ".join(notes), state,
                              state.applied_load.ravel(), res.evaluation)
        current, origin = resume(state, lam1), (state.u, lam1)
        _replay(rec, current)
        if current.success or current.status in _NOT_LIMITS:
            notes.append(f"load control from load factor {lam1:.6g}: {current.message}")
            return rec.finish(current.success, current.status, "; ".join(notes),
                              current.state, current.f_ext, current.evaluation)
    return rec.finish(False, "failed", "; ".join(notes) + f"; more than {MAX_SNAPS} snaps",
                      current.state, current.f_ext, current.evaluation)


def _crossed(rec, res, crossing, end_state, notes) -> StepOutcome:
    """The outcome of a continuation stopped by a panel crossing (its last record)."""
    state = end_state(rec.last_u, crossing.load_factor)
    evaluation = res.evaluation if np.array_equal(res.u, rec.last_u) else None
    return rec.finish(False, "panel_crossing", "; ".join(
        notes + [f"arc length: {crossing.message}"]), state, state.applied_load.ravel(),
        evaluation)


def _continuation(context, origin, outcome, path, increments, c, u0=None):
    """``([ContinuationResult], c)`` from the last state of a failed load-controlled outcome
    to a stable point past the snap (or the end): one :func:`_arc`, or, on a heating path with
    temperatures on the current shape (:data:`RESTART_AT_STABILITY_LOSS`), two: the first
    ends at a loss of stability located by bisection (``mgdcm(locate_stability_loss=
    "stop")``), the second restarts from there (:func:`_restart`).

    ``c`` (n_dof,) weighs the monitored displacement; with ``u0`` (the step's start
    displacements, for its first continuation) a restart re-bases it on the motion from
    ``u0`` to the located point, which does not depend on where load control failed (the
    first run, whose path the monitor does not change, is then redone to measure with it).
    """
    restart = RESTART_AT_STABILITY_LOSS and getattr(path, "iterated", False)
    locate = "stop" if restart else False
    first = _arc(context, origin, outcome, path, increments, c, True, locate)
    if first.status != "stability_lost":
        return [first], c
    if u0 is not None:
        c = _motion_monitor(u0, first.u)
        first = _arc(context, origin, outcome, path, increments, c, True, locate)
    return [first, _restart(context, origin, first, path, c)], c




def _restart(context, origin, located, path, c):
    """MGDCM from the first unstable point of ``located`` (a run ended at a located loss of
    stability) towards load factor 1, with settings that depend only on that point and on
    ``origin`` = (u, load factor) where the step's load control began: the first predictor
    moves the displacements by the mean rate from ``origin`` to the point times
    :data:`ARC_LOAD_STEP`, along the step from the last stable point, which is the prior
    (bisection puts both points within ``ARC_LOAD_STEP / RESOLVE / 16`` of the loss at any
    increment count, so the traced snap does not depend on it)."""
    (lam_s, u_s, _), (lam_u, u_u, _) = located.history[-2], located.history[-1]
    moved = float(np.linalg.norm((u_u - origin[0]).ravel()[path.free]))
    step = moved / (lam_u - float(origin[1])) * ARC_LOAD_STEP
    return mgdcm(path, u_u, lam_u, arc_length=ARC_LOAD_STEP,
                 max_increments=CONTINUATION_INCREMENTS, target_load_factor=1.0, monitor=c,
                 options=context.options, step_norm=step, stability=True, until_stable=True,
                 direction=u_u - u_s, prior=(u_s, lam_s), resolution=ARC_LOAD_STEP / RESOLVE,
                 lost_fold_jump=ARC_LOAD_STEP / RESOLVE,
                 callback=crossing_stop(context.model.mesh, u_u,
                                       supports=context.model.supports),
                 handover=_handover(path, context.options))


def _arc(context, origin, outcome, path, increments, c, until_stable, locate=False):
    """MGDCM from the last state of a failed load-controlled outcome towards load factor 1;
    ``origin`` = (u, load factor) where that load control began (the step's start, or where
    it resumed after a snap).

    The arc length does not depend on the step's ``increments``: the first predictor moves
    the displacements by the mean rate of the load-controlled part since ``origin``
    (displacement per unit load factor) times :data:`ARC_LOAD_STEP`, and the adaptation
    works from there, so every increment count traces the snap with the same resolution.
    """
    n = len(outcome.u)
    lam0 = float(outcome.load_factor[-1]) if n else float(origin[1])
    # the mean rate since ``origin`` (not since the step's start: after a snap the resumed
    # increments would carry the whole motion), along the recent motion (the last increments
    # before a failure can be vanishingly small)
    span = lam0 - float(origin[1])
    moved = float(np.linalg.norm((outcome.state.u - origin[0]).ravel()[path.free]))
    step = moved / span * ARC_LOAD_STEP if span > 0 else 0.0
    prior = (outcome.u[-4], float(outcome.load_factor[-4])) if n >= 4 else origin
    recent = outcome.state.u - prior[0]
    if not np.any(recent):
        prior, recent = origin, outcome.state.u - origin[0]
    u0 = outcome.state.u
    if getattr(path, "iterated", False):
        # load control with staggered coupling lags behind the coupled path that arc length
        # follows: start from the coupled equilibrium at lam0 (a start off the path would
        # make the first increments turn, a limit point that is not there)
        u0, lam0, projected = _on_path(context, path, u0, lam0, recent)
        prior = None if projected else prior
    its = outcome.increment_iterations
    fast = max(FAST_ITERATIONS, int(np.median(its))) if len(its) else FAST_ITERATIONS
    lams = [lam0]

    def turned(lam, u):                 # the probe stops once the load factor turns back
        lams.append(lam)
        return len(lams) > 2 and (lams[-1] - lams[-2]) * (lams[-2] - lams[-3]) < 0

    return mgdcm(path, u0, lam0, arc_length=ARC_LOAD_STEP,
                 max_increments=CONTINUATION_INCREMENTS if until_stable else PROBE_INCREMENTS,
                 target_load_factor=1.0, monitor=c, options=context.options,
                 step_norm=step if step > 0 else None, fast_iterations=fast,
                 stability=until_stable, until_stable=until_stable,
                 direction=recent, prior=prior,
                 callback=crossing_stop(context.model.mesh, u0, None if until_stable else turned,
                                       context.model.supports),
                 resolution=ARC_LOAD_STEP / RESOLVE if until_stable else None,
                 switch_branches=until_stable and SWITCH_BRANCHES,
                 locate_stability_loss=locate,
                 lost_fold_jump=ARC_LOAD_STEP / RESOLVE if until_stable else None,
                 handover=_handover(path, context.options) if until_stable else None)


def _handover(path, options):
    """``mgdcm``'s ``handover`` on a heating path (None on others): a stable point where
    the coupling's gain along the softest mode (:meth:`HeatPath.coupling_gain`) is below
    :data:`COUPLING_GAIN_LIMIT` in magnitude (or cannot be measured)."""
    gain = getattr(path, "coupling_gain", None)
    if gain is None:
        return None

    def converges(u, lam, point, st):
        if st is None or st.mode is None or point is None:
            return True
        return not abs(gain(u, lam, point.K, st.mode, options.linear_solver)) >= \
            COUPLING_GAIN_LIMIT
    return converges


def _on_path(context, path, u, lam, direction):
    """``(u, lam, moved)``: ``(u, lam)`` corrected onto ``path`` with the displacement along
    ``direction`` (n_nodes, 3) held (near a limit point, where lambda fixed would be
    singular), moved True, if it is not in equilibrium there and the correction converges;
    else unchanged."""
    c = np.asarray(direction, float).ravel()[path.free]
    if not np.any(c):
        return u, lam, False
    c = c / np.linalg.norm(c)
    held = PathConstraint(c, float(c @ np.asarray(u, float).ravel()[path.free]))
    ok, u1, lam1, _, its, _, _ = correct_point(path, u, lam, held, context.options,
                                          model_size(path.system))
    return (u1, float(lam1), True) if ok and its > 0 else (u, lam, False)


def _probe(context, start, outcome, path, increments, powers=None) -> StepOutcome:
    """Status "limit_point" if a short arc-length probe passes a load-factor maximum."""
    c = _motion_monitor(start.u, outcome.state.u)
    res = _arc(context, (start.u, 0.0), outcome, path, increments, c, until_stable=False)
    limits = [p for p in res.critical_points if p.kind == "limit_point"]
    if not limits:
        return outcome
    p = limits[0]
    where = "" if p.displacement is None else \
        f", displacement {p.displacement * 1e6:.4g} um of the most-moving node"
    if powers is not None:
        where = f" ({1e3 * np.max(powers(p.load_factor)):.4g} mW per crease){where}"
    what = f"limit point at load factor {p.load_factor:.6g}{where}"
    msg = (f"{what}: load control cannot pass it (on_limit_point='continue' follows the path by "
           f"arc length); {outcome.message}")
    event = event_at(p, res, outcome.state.crease_power if powers is None else
                     powers(p.load_factor), outcome.state.temperature, None,
                     monitored_node(c), message=what)
    return replace(outcome, status="limit_point", message=msg,
                   events=outcome.events + (event,))


def _snap_text(rec: StepRecorder, res, c, powers, limits) -> str:
    """The snaps of ``res`` (just recorded in ``rec`` by :func:`record_continuation`) for the
    step's message; adds their events to ``rec``, each a copy of its limit point's event
    (``limits``: the events of ``res.critical_points``, in their order)."""
    text = []
    for p, after in _snaps(res, c, ARC_LOAD_STEP / RESOLVE):
        lam, before = p.load_factor, p.displacement
        text.append(f"snap at load factor {lam:.6g}"
                    + ("" if powers is None else f" ({1e3 * np.max(powers(lam)):.4g} mW per "
                                                 "crease)")
                    + f": displacement jumps {1e6 * (after - before):.4g} um")
        rec.events.append(replace(limits[res.critical_points.index(p)], kind="snap",
                                  jump=after - before, message=text[-1]))
    return "".join(f"; {t}" for t in text)
