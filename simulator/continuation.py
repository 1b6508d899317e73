"""Path following through limit points: arc-length (MGDCM) and displacement control.

Load control (:func:`~simulator.newton.follow_path`) prescribes the load factor and fails where
the path turns back (a limit point: the tangent becomes singular). Here the load factor lambda is
an unknown. A *path* gives the residual ``r(u, lambda) = f_ext - f_int`` on the free DOFs, the
tangent ``K = -dr/du`` and the load derivative ``q = dr/dlambda`` (:class:`LoadPath`: dead loads
``f0 + lambda P`` and spring rest angles ``rest0 + lambda R``; heating paths add temperatures).

:func:`mgdcm` is the modified generalized displacement control method (digest D1):

* predictor: ``u_hat = K^-1 q``; the load step ``dlambda = sig ds |u_hat_1| / |u_hat_i|`` keeps
  the predictor's displacement norm at ``ds |u_hat_1|`` (``ds`` = arc length, the first load
  factor increment); ``sig`` flips whenever two successive tangents point into opposite
  half-spaces (``u_hat_{i-1} . u_hat_i < 0``), which is how limit points are passed;
* corrector: Newton on (u, lambda) with the correction orthogonal to the predictor,
  ``dlambda = -(u_hat . K^-1 r) / (u_hat . K^-1 q)``;
* adaptive increments: the arc length doubles after an increment that converged in at most
  :data:`FAST_ITERATIONS` corrections (up to ``max_arc_length``) and halves after a slow one
  or a failure.

Unlike the reference (digest D9.11): convergence uses the residual test of
:class:`~simulator.newton.NewtonOptions`, a failed increment is retried with half the arc
length, the arc length has a maximum, and a path can end exactly at a target load factor or a
target displacement (the last increment is then solved with lambda, or the displacement, fixed).

:func:`displacement_control` prescribes ``c . u`` (a DOF or a node's displacement along a
direction) in equal increments with the load factor unknown (digest D2, but with the increment
prescribed rather than derived from ``lambdaBar``, D9.12). Every accepted point carries the
inertia of its tangent (:mod:`simulator.stability`).
"""

from __future__ import annotations

import logging
import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse.linalg as spla

from .errors import ParameterError
from .newton import DENSE_LIMIT, NewtonOptions
from .newton import _tangent as _assembled_tangent
from .small_solve import as_dense
from .path_trace import ContinuationResult, CriticalPoint, PathTrace

__all__ = ["LoadPath", "PathPoint", "CriticalPoint", "ContinuationResult", "mgdcm",
           "displacement_control"]

logger = logging.getLogger(__name__)

#: Arc-length adaptation: double after increments converging in at most this many corrections
#: (one more than the reference's 2: our residual test is tighter than its displacement test),
#: halve after those needing at least :data:`SLOW_ITERATIONS`.
FAST_ITERATIONS = 4
SLOW_ITERATIONS = 13


@dataclass(frozen=True, eq=False)
class PathPoint:
    """Residual, tangent and load derivative at (u, lambda).

    Attributes
    ----------
    r : (n_free,) residual f_ext - f_int [N]
    K : (n_free, n_free) tangent stiffness [N/m], CSR or (small models) dense
    q : (n_free,) dr/dlambda [N]
    evaluation : Evaluation
    temperature : (n_nodes,) node temperatures [deg C] or None
    """

    r: np.ndarray
    K: object
    q: np.ndarray
    evaluation: object
    temperature: np.ndarray | None = None


class LoadPath:
    """Affine loading in the load factor: ``f_ext = f0 + lambda P``, ``rest = rest0 + lambda R``.

    Parameters
    ----------
    system : EquilibriumSystem or any object with ``free`` and ``evaluate(u, rest, hessian)``
    f0, P : (n_dof,) dead load at lambda = 0 and reference load [N]
    rest0 : (n_springs,) spring rest angles at lambda = 0 [rad]
    R : (n_springs,) rest-angle change per unit lambda [rad], or None
    """

    def __init__(self, system, f0, P, rest0, R=None):
        self.system = system
        self.free = system.free
        self.f0, self.P = np.asarray(f0, float), np.asarray(P, float)
        self.rest0 = np.asarray(rest0, float)
        self.R = None if R is None or not np.any(R) else np.asarray(R, float)

    def rest(self, lam: float) -> np.ndarray:
        return self.rest0 if self.R is None else self.rest0 + lam * self.R

    def f_ext(self, lam: float) -> np.ndarray:
        return self.f0 + lam * self.P

    def temperature(self, u, lam):
        return None

    def at(self, u: np.ndarray, lam: float) -> PathPoint:
        """Residual, tangent and load derivative at displacements ``u`` (n_nodes, 3)."""
        rest = self.rest(lam)
        ev = self.system.evaluate(u, rest)
        q = self.P[self.free]
        if self.R is not None:   # f_int is linear in the rest angles: the difference is exact
            f1 = self.system.evaluate(u, rest + self.R, hessian=False).f_int
            q = q - (f1 - ev.f_int)[self.free]
        return PathPoint((self.f_ext(lam) - ev.f_int)[self.free], _assembled_tangent(ev), q,
                         ev)


def _solve(K, B):
    """Solve K X = B (B (n,) or (n, k)); None if K is exactly singular or X not finite.

    No ill-conditioning check: near a limit point K is nearly singular by design, and the
    bordered corrector combines the two solutions into a well-conditioned update.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("error", scipy.linalg.LinAlgWarning)
        try:
            if K.shape[0] <= DENSE_LIMIT:
                lu = scipy.linalg.lu_factor(as_dense(K), check_finite=False)
                X = scipy.linalg.lu_solve(lu, B, check_finite=False)
            else:
                X = spla.splu(K.tocsc()).solve(B)
        except (np.linalg.LinAlgError, scipy.linalg.LinAlgError, RuntimeError,
                scipy.linalg.LinAlgWarning):
            return None
    return X if np.all(np.isfinite(X)) else None


@dataclass
class _Constraint:
    """The extra equation of the bordered system: ``c . u_free = value`` or (c None)
    ``lambda = value``."""

    c: np.ndarray | None
    value: float

    def dlam(self, v, lam, uq, ur):
        if self.c is None:
            return self.value - lam
        return (self.value - self.c @ v - self.c @ ur) / (self.c @ uq)


def _size(system) -> float:
    mesh = getattr(getattr(system, "model", None), "mesh", None)
    nodes = mesh.nodes if mesh is not None else getattr(system, "nodes")
    return float(np.max(np.ptp(nodes, axis=0)))


def _correct(path, u, lam, constraint, options, size):
    """Newton on (u, lambda) from a predicted point that satisfies ``constraint``.

    Returns (success, u, lam, point, iterations, residual_norms, message).
    """
    free = path.free
    u = u.copy().ravel()
    res, ref, max_step = [], None, getattr(path.system, "max_step", None)
    for it in range(options.max_iter + 1):
        pt = path.at(u.reshape(-1, 3), lam)
        rn = float(np.linalg.norm(pt.r))
        res.append(rn)
        if not math.isfinite(rn):
            return False, u, lam, pt, it, res, "residual is not finite"
        ref = rn if ref is None else ref
        if options.criterion == "residual" and rn <= max(options.atol, options.rtol * ref):
            return True, u.reshape(-1, 3), lam, pt, it, res, "converged"
        if it == options.max_iter:
            break
        X = _solve(pt.K, np.column_stack([pt.q, pt.r]))
        if X is None:
            return False, u, lam, pt, it, res, "tangent stiffness is exactly singular"
        dlam = constraint.dlam(u[free], lam, X[:, 0], X[:, 1])
        du = dlam * X[:, 0] + X[:, 1]
        if not math.isfinite(dlam):
            return False, u, lam, pt, it, res, "constraint is degenerate (K^-1 q orthogonal to it)"
        if max_step is not None and np.max(np.abs(du)) > max_step:
            scale = max_step / np.max(np.abs(du))
            du, dlam = du * scale, dlam * scale
        u[free] += du
        lam += dlam
        dn = float(np.linalg.norm(du))
        if options.criterion == "displacement" and dn <= max(options.atol, options.rtol * (
                dn if it == 0 else ref)) or np.max(np.abs(du)) <= 1e-13 * size:
            pt = path.at(u.reshape(-1, 3), lam)
            return True, u.reshape(-1, 3), lam, pt, it + 1, res, "converged"
    return False, u, lam, pt, options.max_iter, res, (
        f"no convergence in {options.max_iter} iterations (last residual {res[-1]:.3g} N)")


def _positive(name, value, allow_none=False):
    if value is None and allow_none:
        return
    if isinstance(value, bool) or not (isinstance(value, (int, float, np.integer, np.floating))
                                       and math.isfinite(value) and value > 0):
        raise ParameterError(f"{name} = {value!r} must be a positive finite number.")


def _monitor_vector(path, target_displacement):
    """(c, value) with c the (n_dof,) weights of the monitored displacement, or (None, None)."""
    if target_displacement is None:
        return None, None
    c, value = target_displacement
    c = np.asarray(c, float).ravel()
    return c, float(value)


# ---------------------------------------------------------------------------- the algorithms
def _check_count(name, value):
    if isinstance(value, bool) or not (isinstance(value, (int, np.integer)) and value >= 1):
        raise ParameterError(f"{name} = {value!r} must be a positive integer.")


def _flat(u, free, dv):
    """Displacements ``u`` (n_nodes, 3) plus ``dv`` on the free DOFs, as a new array."""
    out = np.array(u, float).ravel()
    out[free] += dv
    return out.reshape(-1, 3)


def _begin(path, u, lam):
    """Let a path update per-increment data (staggered heating), then evaluate it."""
    if hasattr(path, "begin_increment"):
        path.begin_increment(u)
    return path.at(u, lam)


def _tangent(pt, lam):
    """K^-1 q at a converged point, or a message if K is exactly singular."""
    uhat = _solve(pt.K, pt.q)
    if uhat is None:
        return None, f"tangent stiffness is exactly singular at load factor {lam:.6g}"
    return uhat, ""


def mgdcm(path, u0, lam0: float = 0.0, *, arc_length: float = 0.05, max_increments: int = 100,
          target_load_factor: float | None = None, target_displacement=None, monitor=None,
          options: NewtonOptions = NewtonOptions(), adapt: bool = True,
          max_arc_length: float | None = None, step_norm: float | None = None,
          fast_iterations: int = FAST_ITERATIONS, stability: bool = True,
          until_stable: bool = False, direction=None, prior=None,
          callback=None) -> ContinuationResult:
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
    """
    _positive("arc_length", arc_length)
    _positive("max_arc_length", max_arc_length, allow_none=True)
    _positive("step_norm", step_norm, allow_none=True)
    _check_count("max_increments", max_increments)
    _check_count("fast_iterations", fast_iterations)
    slow = max(SLOW_ITERATIONS, 2 * fast_iterations)
    if target_load_factor is not None and not math.isfinite(target_load_factor):
        raise ParameterError(f"target_load_factor = {target_load_factor!r} must be finite.")
    max_ds = 4 * arc_length if max_arc_length is None else max(max_arc_length, arc_length)
    min_ds = arc_length / 2 ** options.max_cuts
    free, size = path.free, _size(path.system)
    c_t, v_t = _monitor_vector(path, target_displacement)
    u, lam = np.array(u0, float).reshape(-1, 3), float(lam0)
    trace = PathTrace(path, c_t if monitor is None else np.asarray(monitor, float).ravel(),
                   stability, u, lam, prior)
    pt = _begin(path, u, lam)
    sig = 1.0 if target_load_factor is None or target_load_factor >= lam else -1.0
    ds, uhat_prev, norm1 = arc_length, None, None
    sig0, peak, turned = sig, lam, False
    while len(trace.history) < max_increments:
        uhat, msg = _tangent(pt, lam)
        if uhat is None:
            return trace.result(False, "failed", msg, u, lam)
        if norm1 is None:
            norm1 = float(np.linalg.norm(uhat)) if step_norm is None else step_norm / arc_length
            if not np.any(uhat):
                raise ParameterError("mgdcm: the reference load does not act on any free DOF "
                                     "(K^-1 q = 0); load free nodes.")
        if uhat_prev is not None:
            s = sig * np.sign(uhat_prev @ uhat)
        elif direction is not None:
            s = np.sign(np.asarray(direction, float).ravel()[free] @ uhat) or sig
        else:
            s = sig
        dlam = s * ds * norm1 / float(np.linalg.norm(uhat))
        end, dl, con = _predict(u, lam, dlam, uhat, free, target_load_factor, c_t, v_t)
        ok, u1, lam1, pt1, its, res, msg = _correct(path, _flat(u, free, dl * uhat), lam + dl,
                                                    con, options, size)
        trace.iterations += its
        if ok and not end and (lam1 - lam) * dl < 0 and abs(lam1 - lam) > max(abs(dl),
                                                                              arc_length):
            ok, msg = False, (f"corrector reversed the load step ({dl:.3g} predicted, "
                              f"{lam1 - lam:.3g} found: a jump to another branch)")
        if ok and not end and _passed(u, lam, u1, lam1, target_load_factor, c_t, v_t):
            ok, msg = False, "the corrector carried the point past the target"   # approach it
        if not ok:
            if ds / 2 < min_ds:
                return trace.result(False, "failed", f"gave up at load factor {lam:.6g} after "
                                    f"{trace.cuts} cuts (arc length {ds:.3g}): {msg}", u, lam)
            ds, trace.cuts = ds / 2, trace.cuts + 1
            continue
        u, lam, sig, uhat_prev = u1, lam1, s, uhat
        trace.accept(u, lam, pt1, its, res)
        if callback is not None and callback(lam, u):
            return trace.result(False, "stopped", f"stopped by callback at load factor "
                                f"{lam:.6g}", u, lam)
        if end:
            return trace.result(True, "converged", f"reached {end} in {len(trace.history)} "
                                "increments", u, lam)
        turned = turned or s != sig0
        peak = peak if turned else lam
        if until_stable and turned and (lam - peak) * sig0 > 0 and (
                not trace.stab or trace.stab[-1].stable):
            return trace.result(True, "converged", f"stable again past the limit point at load "
                                f"factor {lam:.6g}", u, lam)
        if adapt:
            ds = min(2 * ds, max_ds) if its <= fast_iterations else (
                max(ds / 2, min_ds) if its >= slow else ds)
        pt = _begin(path, u, lam) if hasattr(path, "begin_increment") else pt1
    if target_load_factor is None and c_t is None:
        return trace.result(True, "converged", f"{max_increments} increments", u, lam)
    return trace.result(False, "failed", f"target not reached in {max_increments} increments "
                        f"(load factor {lam:.6g})", u, lam)


def _predict(u, lam, dlam, uhat, free, lam_t, c_t, v_t):
    """Predictor of one increment: (what it ends at or "", its load step, its constraint)."""
    if lam_t is not None and dlam * (lam_t - lam) > 0 and abs(dlam) >= abs(lam_t - lam):
        return f"load factor {lam_t:.6g}", lam_t - lam, _Constraint(None, lam_t)
    if c_t is not None:
        m0, rate = float(c_t @ u.ravel()), float(c_t[free] @ uhat)
        if rate != 0 and (m0 - v_t) * (m0 + dlam * rate - v_t) <= 0:
            return f"displacement {v_t:.6g} m", (v_t - m0) / rate, _Constraint(c_t[free], v_t)
    v = u.ravel()[free]
    return "", dlam, _Constraint(uhat, float(uhat @ v) + dlam * float(uhat @ uhat))


def _passed(u, lam, u1, lam1, lam_t, c_t, v_t) -> bool:
    """True if the step from (u, lam) to (u1, lam1) crossed the target load factor or
    displacement (it is then retried shorter, so that a predictor lands on the target)."""
    if lam_t is not None and (lam - lam_t) * (lam1 - lam_t) < 0:
        return True
    return c_t is not None and (c_t @ u.ravel() - v_t) * (c_t @ u1.ravel() - v_t) < 0


def displacement_control(path, u0, lam0: float, c, target: float, *, increments: int = 50,
                         options: NewtonOptions = NewtonOptions(), stability: bool = True,
                         callback=None) -> ContinuationResult:
    """Drive ``c . u`` linearly to ``target`` [m] with the load factor unknown (digest D2).

    Parameters
    ----------
    path : LoadPath
        Its reference load ``P`` is scaled by the unknown load factor (for a unit force along
        the controlled direction the load factor is the reaction [N]).
    u0 : (n_nodes, 3) start displacements [m], in equilibrium at ``lam0``
    c : (n_dof,) weights of the controlled displacement (zero on supported DOFs)
    target : float
        Final value of ``c . u`` [m].
    increments : int
        Equal increments of the controlled displacement; a failed one is halved (at most
        ``options.max_cuts`` times in a row).

    Raises
    ------
    ParameterError
        If ``c`` weighs supported DOFs or the reference load does not move ``c . u``.
    """
    _check_count("increments", increments)
    free, size = path.free, _size(path.system)
    c = np.asarray(c, float).ravel()
    mask = np.ones(len(c), bool)
    mask[free] = False
    if np.any(c[mask] != 0) or not np.any(c):
        raise ParameterError("displacement_control: the controlled displacement must combine "
                             "free DOFs only (it weighs a supported DOF, or nothing).")
    if not math.isfinite(target):
        raise ParameterError(f"displacement_control: target = {target!r} must be finite [m].")
    cf = c[free]
    u, lam = np.array(u0, float).reshape(-1, 3), float(lam0)
    pt = path.at(u, lam)
    uhat, msg = _tangent(pt, lam)
    if uhat is not None and abs(cf @ uhat) <= 1e-12 * np.linalg.norm(cf) * np.linalg.norm(uhat):
        raise ParameterError("displacement_control: the reference load does not move the "
                             "controlled displacement (c . K^-1 P = 0); it cannot be controlled "
                             "by that load. Load the controlled node along its direction.")
    trace = PathTrace(path, c, stability, u, lam)
    start = float(c @ u.ravel())
    t, dt, in_row = 0.0, 1.0 / increments, 0
    while t < 1.0 - 1e-12:
        t_try = min(1.0, t + dt)
        uhat, msg = _tangent(pt, lam)
        ok = uhat is not None and cf @ uhat != 0
        if ok:
            value = start + t_try * (target - start)
            dl = (value - float(c @ u.ravel())) / float(cf @ uhat)
            ok, u1, lam1, pt1, its, res, msg = _correct(
                path, _flat(u, free, dl * uhat), lam + dl, _Constraint(cf, value), options, size)
            trace.iterations += its
        if not ok:
            if in_row >= options.max_cuts or trace.cuts >= options.max_total_cuts:
                return trace.result(False, "failed", f"gave up at controlled displacement "
                                    f"{float(c @ u.ravel()):.6g} m after {in_row} cuts in a "
                                    f"row: {msg or 'turning point of the controlled DOF'}",
                                    u, lam)
            dt, in_row, trace.cuts = dt / 2, in_row + 1, trace.cuts + 1
            continue
        t, u, lam, pt = t_try, u1, lam1, pt1
        trace.accept(u, lam, pt, its, res)
        dt = min(1.0 / increments, 2 * dt) if in_row == 0 else dt
        in_row = 0
        if callback is not None and callback(lam, u):
            return trace.result(False, "stopped", "stopped by callback", u, lam)
    return trace.result(True, "converged", f"reached displacement {target:.6g} m", u, lam)
