"""Displacement control: one displacement combination driven, the load factor unknown
(theory 6.9).

The controlled displacement ``c . u`` goes linearly to its target in equal increments; each
increment is corrected with the constraint row ``c`` (the corrector of :mod:`.load_path`, as
arc length's) and cut by the one cut-and-retry driver (:func:`~simulator.solvers.nonlinear.
march`). Arc length is :func:`~simulator.solvers.continuation.mgdcm`.
"""

from __future__ import annotations

import numpy as np

from .._validate import finite, integer
from ..errors import ParameterError
from .load_path import PathConstraint, correct_point, free_added, model_size, path_tangent
from .newton import NewtonOptions
from .nonlinear import march
from .path_trace import ContinuationResult, PathTrace

__all__ = ["displacement_control"]


def displacement_control(path, u0, lam0: float, c, target: float, *, increments: int = 50,
                         options: NewtonOptions = NewtonOptions(), stability: bool = True,
                         callback=None) -> ContinuationResult:
    """Drive ``c . u`` linearly to ``target`` [m] with the load factor unknown (theory 6.9).

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
    integer("increments", increments)
    free, size = path.free, model_size(path.system)
    c = np.asarray(c, float).ravel()
    mask = np.ones(len(c), bool)
    mask[free] = False
    if np.any(c[mask] != 0) or not np.any(c):
        raise ParameterError("displacement_control: the controlled displacement must combine "
                             "free DOFs only (it weighs a supported DOF, or nothing).")
    finite("displacement_control: target", target, "m")
    cf = c[free]
    u, lam = np.array(u0, float).reshape(-1, 3), float(lam0)
    pt = path.at(u, lam)
    uhat, msg = path_tangent(pt, lam, options.linear_solver)
    if uhat is not None and abs(cf @ uhat) <= 1e-12 * np.linalg.norm(cf) * np.linalg.norm(uhat):
        raise ParameterError("displacement_control: the reference load does not move the "
                             "controlled displacement (c . K^-1 P = 0); it cannot be controlled "
                             "by that load. Load the controlled node along its direction.")
    trace = PathTrace(path, c, stability, u, lam)
    start = float(c @ u.ravel())
    state = [u, lam, pt]

    def attempt(t_try):
        u, lam, pt = state
        uhat, msg = path_tangent(pt, lam, options.linear_solver)
        if uhat is None or cf @ uhat == 0:
            return False, msg
        value = start + t_try * (target - start)
        dl = (value - float(c @ u.ravel())) / float(cf @ uhat)
        ok, u1, lam1, pt1, its, res, msg = correct_point(
            path, free_added(u, free, dl * uhat), lam + dl, PathConstraint(cf, value), options,
            size)
        trace.iterations += its
        return ok, (u1, lam1, pt1, its, res) if ok else msg

    def accept(t, outcome):
        u1, lam1, pt1, its, res = outcome
        state[:] = u1, lam1, pt1
        trace.accept(u1, lam1, pt1, its, res)
        return callback is not None and callback(lam1, u1)
    run = march(attempt, accept, increments, options.max_cuts, options.max_total_cuts,
                "displacement increment")
    u, lam = state[0], state[1]
    trace.cuts = run.cuts
    if run.status == "failed":
        return trace.result(False, "failed", f"gave up at controlled displacement "
                            f"{float(c @ u.ravel()):.6g} m after {run.in_row} cuts in a row: "
                            f"{run.failure or 'turning point of the controlled DOF'}", u, lam)
    if run.status == "stopped":
        return trace.result(False, "stopped", "stopped by callback", u, lam)
    return trace.result(True, "converged", f"reached displacement {target:.6g} m", u, lam)
