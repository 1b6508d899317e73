"""Path following through limit points: arc-length (MGDCM) and displacement control.

Load control (:func:`~simulator.solvers.newton.follow_path`) prescribes the load factor and fails where
the path turns back (a limit point: the tangent becomes singular). Here the load factor lambda is
an unknown. A *path* gives the residual ``r(u, lambda) = f_ext - f_int`` on the free DOFs, the
tangent ``K = -dr/du`` and the load derivative ``q = dr/dlambda`` (:class:`LoadPath`: dead loads
``f0 + lambda P`` and spring rest angles ``rest0 + lambda R``; heating paths add temperatures).
Paths and the corrector shared by both methods are in :mod:`simulator.solvers.load_path`.

:func:`mgdcm` is the modified generalized displacement control method (theory 6.8):

* predictor: ``u_hat = K^-1 q``; the load step ``dlambda = sig ds |u_hat_1| / |u_hat_i|`` keeps
  the predictor's displacement norm at ``ds |u_hat_1|`` (``ds`` = arc length, the first load
  factor increment); ``sig`` flips whenever two successive tangents point into opposite
  half-spaces (``u_hat_{i-1} . u_hat_i < 0``), which is how limit points are passed;
* corrector: Newton on (u, lambda) with the correction orthogonal to the predictor,
  ``dlambda = -(u_hat . K^-1 r) / (u_hat . K^-1 q)``;
* adaptive increments: the arc length doubles after an increment that converged in at most
  :data:`FAST_ITERATIONS` corrections (up to ``max_arc_length``) and halves after a slow one
  or a failure.

Unlike the reference (theory 6.8): convergence uses the residual test of
:class:`~simulator.solvers.newton.NewtonOptions`, a failed increment is retried with half the arc
length, the arc length has a maximum, and a path can end exactly at a target load factor or a
target displacement (the last increment is then solved with lambda, or the displacement, fixed).

:func:`~simulator.solvers.displacement_control.displacement_control` prescribes ``c . u`` (a DOF or a node's displacement along a direction) in equal
increments with the load factor unknown (theory 6.9; the increment is prescribed rather than
derived from ``lambdaBar``). Every accepted point carries the inertia of its tangent
(:mod:`simulator.solvers.stability`).
"""

from __future__ import annotations

import logging

import numpy as np

from .._validate import finite, integer, one_of, positive
from ..errors import ParameterError
from ..mechanics.crossing import wrap_refusal
from ..mechanics.substrate import substrate_refusal
from .load_path import (PathConstraint, begin_point, correct_point, free_added, model_size,
                        path_tangent)
from .newton import NewtonOptions
from .path_trace import ContinuationResult, PathTrace, lost_peak
from .stability import tangent_stability

__all__ = ["mgdcm"]

logger = logging.getLogger(__name__)

#: Arc-length adaptation: double after increments converging in at most this many corrections
#: (one more than the reference's 2: our residual test is tighter than its displacement test),
#: halve after those needing at least :data:`SLOW_ITERATIONS`.
FAST_ITERATIONS = 4
SLOW_ITERATIONS = 13
#: With ``switch_branches``, a loss of stability is located to this fraction of the
#: resolution (or of the arc length) before the branch switch.
LOCATE = 1 / 16


# ---------------------------------------------------------------------------- the algorithms
def mgdcm(path, u0, lam0: float = 0.0, *, arc_length: float = 0.05, max_increments: int = 100,
          target_load_factor: float | None = None, target_displacement=None, monitor=None,
          options: NewtonOptions = NewtonOptions(), adapt: bool = True,
          max_arc_length: float | None = None, step_norm: float | None = None,
          fast_iterations: int = FAST_ITERATIONS, stability: bool = True,
          until_stable: bool = False, direction=None, prior=None,
          callback=None, resolution: float | None = None, switch_branches: bool = False,
          locate_stability_loss: bool | str = False,
          lost_fold_jump: float | None = None, handover=None) -> ContinuationResult:
    """Trace the equilibrium path of ``path`` by MGDCM arc-length from ``(u0, lam0)``.

    Parameters
    ----------
    path : LoadPath (or an object with ``free``, ``system`` and ``at(u, lam)``)
    u0 : (n_nodes, 3) start displacements [m], in equilibrium at ``lam0``
    lam0 : float
        Start load factor.
    arc_length : float
        Load-factor increment of the first step (the reference's ``lambdaBar``); every predictor
        then moves the displacements by ``arc_length |K_0^-1 q_0|`` (times the adaptation).
    max_increments : int
        Accepted increments at most; without a target, the path ends there with success.
    target_load_factor : float, optional
        End where lambda reaches this value moving towards it (solved with lambda fixed).
    target_displacement : (c, value), optional
        End where ``c . u = value`` (c: (n_dof,) weights, value [m]).
    monitor : (n_dof,) weights, optional
        Displacement reported at critical points (default: ``c`` of the target displacement).
    options : NewtonOptions
        Corrector tolerances, iterations and cuts (a failed increment halves the arc length,
        at most ``max_cuts`` times below ``arc_length``).
    adapt : bool
        Double the arc length after increments converging in at most ``fast_iterations``
        corrections, halve it after those needing ``max(SLOW_ITERATIONS, 2 fast_iterations)``
        or more.
    max_arc_length : float, optional
        Cap of the adapted arc length (default ``4 arc_length``).
    step_norm : float, optional
        Displacement norm of the first predictor [m] instead of ``arc_length |K_0^-1 q_0|``
        (to restart near a limit point, where ``K_0^-1 q_0`` is huge); ``arc_length`` then only
        scales the adaptation.
    fast_iterations : int
        See ``adapt`` (models whose Newton needs more iterations anyway raise it).
    stability : bool
        Compute the inertia of the tangent at every accepted point.
    until_stable : bool
        End (with success, message "stable again past the limit point") at the first stable
        point after the load factor turned back, once it exceeds the load factor where it
        turned: the snap is passed and load control can take over.
    direction : (n_nodes, 3) array, optional
        Displacement direction the path comes from (e.g. the last load-controlled increment):
        the first predictor moves along it, whatever the sign of the load factor change (a
        restart at or just past a limit point); default: towards ``target_load_factor``, else
        increasing the load factor.
    prior : (u, lam), optional
        An equilibrium point before the start (e.g. an earlier load-controlled increment), so
        that a restart at a limit point finds the turn there.
    callback : callable, optional
        ``callback(lam, u)`` after every accepted point; True stops (status "stopped").
    resolution : float, optional
        Arc length (in the units of ``arc_length``) that resolves a limit point: at the first
        accepted point where the load factor turns back or the tangent has more negative
        eigenvalues than at the point before (with ``stability``), the increment is redone
        from the point before with at most this arc length, which from then on caps the
        adaptation wherever the load factor is within ``resolution`` of that point's (around
        the limit point, and where the path crosses its load factor again): at ``resolution``,
        or where the last increment changed the load factor by less than its arc length (a
        flat fold) at the arc length that changes it by ``resolution`` at that rate. So the
        limit point (and a snap's jump) is located at this resolution, whatever the arc length
        the path arrived with. Default: no cap.
    switch_branches : bool
        Follow the stable branch at a loss of stability without a load-factor turn (with
        ``stability``): where the tangent gains a negative eigenvalue while the load factor
        goes on, the loss is located by bisection of the arc length (to :data:`LOCATE`
        of ``resolution``, or of ``arc_length``), and the first unstable point, pushed along
        its critical mode, falls by energy descent to a stable equilibrium at its load
        factor (:func:`~simulator.solvers.descent.switch_branch`), where the path goes on
        (and, with ``until_stable``, ends: message "stable on another branch past the
        bifurcation ..."). The jump is in :attr:`ContinuationResult.jumps` and the
        critical point is a "bifurcation".
    locate_stability_loss : bool or "stop"
        Locate such a loss of stability by the same bisection, without the switch: the path
        goes on from the located point with the arc length of the bisection (True), or ends
        there ("stop": success, status "stability_lost", the last two accepted points the
        last stable and the first unstable one), for a restart from it
        with settings that do not depend on how the path got there. Implied by
        ``switch_branches``.
    lost_fold_jump : float, optional
        Where the run fails after passing a load-factor maximum above ``lam0`` (its arc
        length cut below ``arc_length / 2 ** max_cuts``, or its increments used up): land by
        energy descent (:func:`~simulator.solvers.descent.descend`) at this much above the
        highest point reached, and end there with success (message "jump from load factor
        ..."; from the highest point itself if the descent fails).
    handover : callable, optional
        With ``until_stable``: ``handover(u, lam, point, stability)`` (the accepted point's
        :class:`~simulator.solvers.load_path.PathPoint` and :class:`~simulator.solvers.stability.Stability`, or None
        without ``stability``) must also be True at the stable point where the run ends;
        until it is, the run goes on along the stable branch (e.g. a heating path, where
        load control cannot take over while its coupling diverges:
        :meth:`~simulator.steps.limit.HeatPath.coupling_gain`).
    """
    _check_arc_length_settings(arc_length, max_arc_length, step_norm, max_increments,
                               fast_iterations, target_load_factor)
    positive("resolution", resolution, allow_none=True)
    if not (isinstance(locate_stability_loss, bool) or locate_stability_loss == "stop"):
        one_of("locate_stability_loss", locate_stability_loss, (True, False, "stop"))
    run = _ArcLengthRun(path, u0, lam0, arc_length=arc_length, max_arc_length=max_arc_length,
                        target_load_factor=target_load_factor,
                        target_displacement=target_displacement, monitor=monitor,
                        options=options, adapt=adapt, step_norm=step_norm,
                        fast_iterations=fast_iterations, stability=stability,
                        until_stable=until_stable, direction=direction, prior=prior,
                        callback=callback, resolution=resolution,
                        switch_branches=switch_branches, lost_fold_jump=lost_fold_jump,
                        locate_stability_loss=locate_stability_loss, handover=handover)
    return run.trace_path(max_increments)


def _check_arc_length_settings(arc_length, max_arc_length, step_norm, max_increments,
                               fast_iterations, target_load_factor) -> None:
    """:class:`ParameterError` for a setting of :func:`mgdcm` out of range."""
    positive("arc_length", arc_length)
    positive("max_arc_length", max_arc_length, allow_none=True)
    positive("step_norm", step_norm, allow_none=True)
    integer("max_increments", max_increments)
    integer("fast_iterations", fast_iterations)
    finite("target_load_factor", target_load_factor, allow_none=True)


class _ArcLengthRun:
    """One :func:`mgdcm` run (settings as there): the last accepted point ``(u, lam)`` with its
    path evaluation, the arc length ``ds``, the sign of the load step, what is known about a
    limit point passed, and the :class:`PathTrace` of the accepted points."""

    def __init__(self, path, u0, lam0, *, arc_length, max_arc_length, target_load_factor,
                 target_displacement, monitor, options, adapt, step_norm, fast_iterations,
                 stability, until_stable, direction, prior, callback, resolution=None,
                 switch_branches=False, lost_fold_jump=None, locate_stability_loss=False,
                 handover=None):
        self.path, self.options, self.arc_length = path, options, arc_length
        self.handover = handover
        self.resolution, self.fine = resolution, False
        self.adapt, self.step_norm, self.until_stable = adapt, step_norm, until_stable
        self.direction, self.callback, self.lam_t = direction, callback, target_load_factor
        self.fast, self.slow = fast_iterations, max(SLOW_ITERATIONS, 2 * fast_iterations)
        self.max_ds = 4 * arc_length if max_arc_length is None else max(max_arc_length,
                                                                         arc_length)
        self.min_ds = arc_length / 2 ** options.max_cuts
        self.free, self.size = path.free, model_size(path.system)
        self.c_t, self.v_t = (None, None) if target_displacement is None else (  # c . u = v
            np.asarray(target_displacement[0], float).ravel(), float(target_displacement[1]))
        self.u, self.lam = np.array(u0, float).reshape(-1, 3), float(lam0)
        self.trace = PathTrace(path, self.c_t if monitor is None else
                               np.asarray(monitor, float).ravel(), stability, self.u, self.lam,
                               prior)
        self.pt = begin_point(path, self.u, self.lam)
        self.sig = 1.0 if target_load_factor is None or target_load_factor >= self.lam else -1.0
        self.ds, self.uhat_prev, self.norm1 = arc_length, None, None
        self.sig0, self.peak, self.turned = self.sig, self.lam, False
        self.lam_start, self.jump = self.lam, lost_fold_jump
        self.switch = switch_branches and stability
        self.bisect = (switch_branches or bool(locate_stability_loss)) and stability
        self.stop_at_loss = self.bisect and locate_stability_loss == "stop"
        self.locate = (resolution if resolution is not None else arc_length) * LOCATE
        self.locating, self.neg0 = 0, (tangent_stability(self.pt.K).negative
                                       if self.bisect else 0)

    def result(self, success: bool, status: str, message: str) -> ContinuationResult:
        return self.trace.result(success, status, message, self.u, self.lam)

    def trace_path(self, max_increments: int) -> ContinuationResult:
        """Increments until the path ends or ``max_increments`` are accepted."""
        while len(self.trace.history) < max_increments:
            done = self.increment()
            if done is not None:
                return done
        if self.lam_t is None and self.c_t is None:
            return self.result(True, "converged", f"{max_increments} increments")
        msg = f"target not reached in {max_increments} increments (load factor {self.lam:.6g})"
        res = self.result(False, "failed", msg)
        return res if self.jump is None else self.jump_lost_fold(res, msg)

    def increment(self) -> ContinuationResult | None:
        """Predict and correct one increment; accept it, or halve the arc length for a retry.
        The result if the path ends here, else None."""
        uhat, msg = path_tangent(self.pt, self.lam, self.options.linear_solver)
        if uhat is None:
            return self.result(False, "failed", msg)
        s, dlam = self.load_step(uhat)
        end, dl, con = _predict(self.u, self.lam, dlam, uhat, self.free, self.lam_t, self.c_t,
                                self.v_t)
        ok, u1, lam1, pt1, its, res, msg = correct_point(self.path, free_added(self.u, self.free,
                                                                     dl * uhat),
                                                    self.lam + dl, con, self.options, self.size)
        self.trace.iterations += its
        refused = self.refusal(dl, u1, lam1) if ok and not end else ""
        if ok and not refused:          # a node through the substrate (theory 6.11)
            refused = substrate_refusal(self.path.system, u1)
        if ok and not refused and hasattr(self.path, "rest"):     # a spring past its wrap
            refused = wrap_refusal(self.path.system, self.u, self.path.rest(self.lam), u1,
                                   self.path.rest(lam1))
        if refused:
            logger.debug("load factor %.6g refused: %s", lam1, refused)
        if refused:
            ok, msg = False, refused
        if not ok:
            return self.cut(msg)
        return self.accept(s, uhat, u1, lam1, pt1, its, res, end)

    def load_step(self, uhat: np.ndarray) -> tuple[float, float]:
        """(sign, load-factor step) of the predictor along ``uhat = K^-1 q``: the sign flips
        where successive tangents point into opposite half-spaces."""
        if self.norm1 is None:
            self.norm1 = float(np.linalg.norm(uhat)) if self.step_norm is None else \
                self.step_norm / self.arc_length
            if not np.any(uhat):
                raise ParameterError("mgdcm: the reference load does not act on any free DOF "
                                     "(K^-1 q = 0); load free nodes.")
        if self.uhat_prev is not None:
            s = self.sig * np.sign(self.uhat_prev @ uhat)
        elif self.direction is not None:
            s = np.sign(np.asarray(self.direction, float).ravel()[self.free] @ uhat) or self.sig
        else:
            s = self.sig
        return s, s * self.ds * self.norm1 / float(np.linalg.norm(uhat))

    def refusal(self, dl: float, u1: np.ndarray, lam1: float) -> str:
        """Why a converged increment to ``(u1, lam1)`` is refused ("" if it is not): the
        corrector jumped to another branch, or carried the point past the target."""
        lam = self.lam
        if (lam1 - lam) * dl < 0 and abs(lam1 - lam) > max(abs(dl), self.arc_length):
            return (f"corrector reversed the load step ({dl:.3g} predicted, {lam1 - lam:.3g} "
                    "found: a jump to another branch)")
        if _passed(self.u, lam, u1, lam1, self.lam_t, self.c_t, self.v_t):
            return "the corrector carried the point past the target"   # approach it
        return ""

    def cut(self, msg: str) -> ContinuationResult | None:
        """Halve the arc length after a failed increment; the failed result below ``min_ds``."""
        if self.ds / 2 < self.min_ds:
            msg = (f"gave up at load factor {self.lam:.6g} after {self.trace.cuts} cuts (arc "
                   f"length {self.ds:.3g}): {msg}")
            res = self.result(False, "failed", msg)
            return res if self.jump is None else self.jump_lost_fold(res, msg)
        self.ds, self.trace.cuts = self.ds / 2, self.trace.cuts + 1
        return None

    def accept(self, s, uhat, u1, lam1, pt1, its, res, end) -> ContinuationResult | None:
        """Take the converged point; the result if the path ends there (callback, target
        reached, stable again), else adapt the arc length and evaluate the path there."""
        back = (self.u, self.lam, self.sig, self.uhat_prev, self.pt)
        taken = self.ds                          # (the arc length of this increment)
        self.u, self.lam, self.sig, self.uhat_prev = u1, lam1, s, uhat
        self.trace.accept(u1, lam1, pt1, its, res)
        if self.refine(s, back[2], end):      # redo it shorter from the point before
            self.trace.pop()
            self.u, self.lam, self.sig, self.uhat_prev, self.pt = back
            return None
        if self.bisect and s == back[2] and (lam1 - back[1]) * self.sig0 > 0 and \
                self.lost_stability():
            done = self.at_bifurcation(back)
            if done is not False:
                return done
        if self.callback is not None and self.callback(lam1, u1):
            return self.result(False, "stopped", f"stopped by callback at load factor "
                               f"{lam1:.6g}")
        if end:
            return self.result(True, "converged", f"reached {end} in "
                               f"{len(self.trace.history)} increments")
        if self.stable_again(s):
            return self.result(True, "converged", f"stable again past the limit point at "
                               f"load factor {lam1:.6g}")
        if self.locating:          # bisecting a loss of stability: no doubling meanwhile
            self.locating = 0 if self.locating > 2 else self.locating + 1
        elif self.adapt:
            self.ds = min(2 * self.ds, self.max_ds) if its <= self.fast else (
                max(self.ds / 2, self.min_ds) if its >= self.slow else self.ds)
        if self.fine and abs(lam1 - self.lam_fine) <= self.resolution:
            self.ds = min(self.ds, self.resolved(taken, lam1 - back[1]))
        self.pt = begin_point(self.path, u1, lam1) if hasattr(self.path, "begin_increment") else pt1
        return None

    def refine(self, s, sig_before, end) -> bool:
        """True if the point just accepted is the first near a limit point (the load factor
        turned, or the tangent lost stability) and was reached with an arc length above
        ``resolution``: it is then redone from the point before with that arc length."""
        if self.resolution is None or self.fine or end:
            return False
        stab = self.trace.stab
        lost = bool(stab) and stab[-1].negative > (stab[-2].negative if len(stab) > 1 else 0)
        if s == sig_before and not lost:
            return False
        self.fine, self.lam_fine = True, self.trace.points[-2][0]
        if self.ds <= self.resolution:
            return False
        self.ds = self.resolution
        return True

    def resolved(self, ds: float, dlam: float) -> float:
        """Cap of the arc length near a located limit point, after an increment of arc
        length ``ds`` that changed the load factor by ``dlam``: ``resolution``, or the arc
        length that changes the load factor by ``resolution`` at that increment's rate where
        that is longer (a flat fold, whose load factor stays within ``resolution`` of the
        limit point's over many times ``resolution`` of arc length)."""
        if dlam == 0:
            return self.max_ds
        return min(self.max_ds, self.resolution * max(1.0, ds / abs(dlam)))

    def lost_stability(self) -> bool:
        """True if the tangent at the last accepted point has more negative eigenvalues than
        at the point before (the start's count for the first)."""
        stab = self.trace.stab
        before = stab[-2].negative if len(stab) > 1 else self.neg0
        return bool(stab) and stab[-1].negative > before

    def at_bifurcation(self, back):
        """A loss of stability while the load factor goes on (``back``: the point before):
        None to redo the increment at half the arc length (bisection), until it is located
        to ``locate``; then the result (``locate_stability_loss="stop"``), or the branch
        switch from the unstable point: False if the descent does not land (the path goes on
        along the unstable branch), else None or the result if the run ends there
        (``until_stable``)."""
        if self.ds > max(self.locate, self.min_ds):
            self.trace.pop()
            self.u, self.lam, self.sig, self.uhat_prev, self.pt = back
            self.ds, self.locating = self.ds / 2, 1
            return None
        self.locating = 0
        if self.stop_at_loss:
            return self.result(True, "stability_lost", f"stability lost at load factor "
                               f"{self.lam:.6g}")
        if not self.switch:
            return False
        from .descent import switch_branch          # (descent imports the corrector)
        landed = switch_branch(self.path, self.u, self.lam, self.trace.stab[-1].mode,
                               self.options)
        if landed is None:
            logger.debug("no stable branch found from load factor %.6g", self.lam)
            return False
        pt = self.path.at(landed, self.lam)
        self.trace.accept(landed, self.lam, pt, 0, [])
        self.trace.jumps.append((len(self.trace.history) - 3, len(self.trace.history) - 1,
                                 "bifurcation"))
        self.u, self.uhat_prev, self.direction, self.sig = landed, None, None, self.sig0
        self.pt = begin_point(self.path, landed, self.lam)
        if self.until_stable and (not self.trace.stab or self.trace.stab[-1].stable):
            return self.result(True, "converged", "stable on another branch past the "
                               f"bifurcation at load factor {self.lam:.6g}")
        return None

    def jump_lost_fold(self, failed: ContinuationResult, msg: str) -> ContinuationResult:
        """After a failure past a load-factor maximum above the start (:func:`lost_peak`):
        the result at the equilibrium ``lost_fold_jump`` above the highest point that energy
        descent lands on (the highest point itself if it does not), with success; else
        ``failed``."""
        k = lost_peak(failed, self.lam_start)
        if k is None:
            return failed
        from .descent import descend
        lam1, u1 = float(failed.history[k][0]), failed.history[k][1]
        landed = descend(self.path, u1, lam1 + self.jump, self.options, rounds=1)
        if landed is not None:
            lam1, u1 = lam1 + self.jump, landed
        self.path.at(u1, lam1)                     # (a heating path: temperatures there)
        return self.trace.result(True, "converged", f"{msg}; jump from load factor "
                                 f"{lam1:.6g}", u1, lam1)

    def stable_again(self, s) -> bool:
        """Note whether the load factor turned (sign ``s`` of the last step); True if
        ``until_stable`` and the last point is stable beyond the load factor where it turned
        (and ``handover`` accepts it)."""
        self.turned = self.turned or s != self.sig0
        self.peak = self.peak if self.turned else self.lam
        st = self.trace.stab[-1] if self.trace.stab else None
        return bool(self.until_stable and self.turned and (self.lam - self.peak) * self.sig0 > 0
                    and (st is None or st.stable)
                    and (self.handover is None or
                         self.handover(self.u, self.lam, self.trace.last, st)))


def _predict(u, lam, dlam, uhat, free, lam_t, c_t, v_t):
    """Predictor of one increment: (what it ends at or "", its load step, its constraint)."""
    if lam_t is not None and dlam * (lam_t - lam) > 0 and abs(dlam) >= abs(lam_t - lam):
        return f"load factor {lam_t:.6g}", lam_t - lam, PathConstraint(None, lam_t)
    if c_t is not None:
        m0, rate = float(c_t @ u.ravel()), float(c_t[free] @ uhat)
        if rate != 0 and (m0 - v_t) * (m0 + dlam * rate - v_t) <= 0:
            return f"displacement {v_t:.6g} m", (v_t - m0) / rate, PathConstraint(c_t[free], v_t)
    v = u.ravel()[free]
    return "", dlam, PathConstraint(uhat, float(uhat @ v) + dlam * float(uhat @ uhat))


def _passed(u, lam, u1, lam1, lam_t, c_t, v_t) -> bool:
    """True if the step from (u, lam) to (u1, lam1) crossed the target load factor or
    displacement (it is then retried shorter, so that a predictor lands on the target)."""
    if lam_t is not None and (lam - lam_t) * (lam1 - lam_t) < 0:
        return True
    return c_t is not None and (c_t @ u.ravel() - v_t) * (c_t @ u1.ravel() - v_t) < 0
