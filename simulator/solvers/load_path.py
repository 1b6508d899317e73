"""Load paths and the corrector that the path-following methods of :mod:`simulator.solvers.continuation`
share.

A *path* gives, at a point ``(u, lambda)`` (:class:`PathPoint`), the residual ``r(u, lambda) =
f_ext - f_int`` on the free DOFs, the tangent ``K = -dr/du`` and the load derivative ``q =
dr/dlambda``. :class:`LoadPath` is affine in the load factor (dead loads ``f0 + lambda P``,
spring rest angles ``rest0 + lambda R``); heating paths (:mod:`simulator.steps.limit`) add
temperatures. The corrector (:func:`correct_point`) is Newton on ``(u, lambda)`` with one extra
equation (:class:`PathConstraint`): ``c . u = value`` or ``lambda = value``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from ..mechanics.equilibrium import assembled_tangent as _assembled_tangent
from .nonlinear import iterate, residual_at_round_off
from ..linalg.ladder import solve

logger = logging.getLogger(__name__)

__all__ = ["LoadPath", "PathPoint", "model_size"]
# PathConstraint, correct_point, solve_path_system, path_tangent, begin_point and free_added
# are the corrector's pieces shared by the path-following solvers of this package and
# simulator.steps.limit: public to them, not exported.

#: Largest rest-angle change [rad] of the difference that gives ``q`` (:meth:`LoadPath.at`):
#: small against the half turn between a spring's rest angle and its kink, large enough that
#: the difference keeps ~15 digits.
REST_PROBE = 0.1
#: Most halvings of the probe when the internal force is not linear over it (a spring within
#: the probe of its kink, theory 6.11): 0.1 rad / 2**24 = 6e-9 rad.
PROBE_HALVINGS = 24
#: Linearity test of a probe ``s``: the difference over ``s`` and twice that over ``s / 2``
#: agree to this fraction of the first's norm. The test costs one more force evaluation per
#: :meth:`LoadPath.at`: on the chain-loss Miura lifter of theory 6.11 (1655 calls, none
#: shrunk) 0.36 ms per call, 0.6 s of a 7 to 13 s run (measured 8 Dec 2026).
PROBE_LINEARITY = 1e-6


@dataclass(frozen=True, eq=False)
class PathPoint:
    """Residual, tangent and load derivative at (u, lambda).

    Attributes
    ----------
    r : (n_free,) residual f_ext - f_int [N]
    K : (n_free, n_free) tangent stiffness [N/m], CSR or (small models) dense
    q : (n_free,) dr/dlambda [N]
    evaluation : SystemValues
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
        if self.R is not None:
            q = q - _rest_difference(self.system, u, rest, self.R, ev.f_int)[self.free]
        return PathPoint((self.f_ext(lam) - ev.f_int)[self.free], _assembled_tangent(ev), q,
                         ev)


def _rest_difference(system, u, rest, R, f):
    """(n_dof,) d f_int / d lambda at ``u`` for rest angles ``rest + lambda R``, by a difference
    over a rest change ``s R`` of at most :data:`REST_PROBE` rad (``f`` the internal force at
    ``rest`` [N]).

    f_int is linear in the rest angles only between the kinks of the spring law at theta0 +- pi
    (the deviation is taken modulo 2 pi, theory 3.3): a difference over the whole R (a unit load
    factor, e.g. a whole heating step) can cross one, and so can the probe where a spring is
    within it of its kink (theory 6.11), which gives a wrong q (the corrector then converges
    linearly, or not at all). The difference over ``s`` is used where it is twice that over
    ``s / 2`` (so bit-identical to the plain difference where no kink is near); otherwise the
    probe is tried with the other sign, then halved, at most :data:`PROBE_HALVINGS` times (the
    smallest is used if none is linear, and logged)."""
    h = min(1.0, REST_PROBE / float(np.max(np.abs(R))))
    for k in range(2 * PROBE_HALVINGS + 2):
        s = h * 0.5 ** (k // 2) * (1.0 if k % 2 == 0 else -1.0)
        d = system.evaluate(u, rest + s * R, hessian=False).f_int - f
        d_half = system.evaluate(u, rest + 0.5 * s * R, hessian=False).f_int - f
        if np.linalg.norm(d - 2.0 * d_half) <= PROBE_LINEARITY * np.linalg.norm(d):
            if k:
                logger.debug("load derivative: rest-angle probe shrunk from %.3g to %.3g rad "
                             "(a spring near its kink)", h * np.max(np.abs(R)),
                             s * np.max(np.abs(R)))
            return d / s
    logger.debug("load derivative: the internal force is not linear over any rest-angle probe "
                 "down to %.3g rad; the smallest is used", abs(s) * np.max(np.abs(R)))
    return d / s


def solve_path_system(K, B, backend: str = "auto"):
    """Solve K X = B (B (n,) or (n, k)) by the factorisation ladder, the same backend as
    Newton's (:func:`~simulator.linalg.ladder.solve`); None if K is exactly singular or X
    is not finite.

    No ill-conditioning check: near a limit point K is nearly singular by design, and the
    bordered corrector combines the two solutions into a well-conditioned update.
    """
    return solve(K, B, backend=backend, reject_ill_conditioned=False)


@dataclass
class PathConstraint:
    """The extra equation of the bordered system: ``c . u_free = value`` or (c None)
    ``lambda = value``."""

    c: np.ndarray | None
    value: float

    def dlam(self, v, lam, uq, ur):
        if self.c is None:
            return self.value - lam
        return (self.value - self.c @ v - self.c @ ur) / (self.c @ uq)


def model_size(system) -> float:
    """Largest extent [m] of a system's reference nodes (the scale of its steps and pushes)."""
    mesh = getattr(getattr(system, "model", None), "mesh", None)
    nodes = mesh.nodes if mesh is not None else getattr(system, "nodes")
    return float(np.max(np.ptp(nodes, axis=0)))


def correct_point(path, u, lam, constraint, options, size):
    """Newton on (u, lambda) from a predicted point that satisfies ``constraint``
    (:func:`~simulator.solvers.nonlinear.iterate` on the bordered system).

    Returns (success, u, lam, point, iterations, residual_norms, message).
    """
    problem = _Bordered(path, u, lam, constraint, options.linear_solver)
    out = iterate(problem, max_iter=options.max_iter, atol=options.atol, rtol=options.rtol,
                  size=size, criterion=options.criterion,
                  max_step=getattr(path.system, "max_step", None),
                  keep_best=lambda: (problem.u.copy(), problem.lam),
                  at_round_off=residual_at_round_off(path.system, path.free))
    if out.reason == "round-off":                  # the best iterate, at round-off level
        problem.u, problem.lam = out.best[2]
    u = problem.u.reshape(-1, 3) if out.success else problem.u
    message = "converged" if out.success else out.message
    return out.success, u, problem.lam, out.point, out.iterations, out.residual_norms, message


class _Bordered:
    """The corrector's problem for :func:`~simulator.solvers.nonlinear.iterate`: residual of
    the path at (u, lambda); correction from the tangent bordered by the constraint row,
    ``du = dlam K^-1 q + K^-1 r`` with ``dlam`` from the constraint."""

    def __init__(self, path, u, lam, constraint, backend):
        self.path, self.constraint, self.backend = path, constraint, backend
        self.u, self.lam, self.dlam = u.copy().ravel(), lam, 0.0

    def evaluate(self):
        pt = self.path.at(self.u.reshape(-1, 3), self.lam)
        return pt.r, pt

    def correct(self, pt, r):
        X = solve_path_system(pt.K, np.column_stack([pt.q, r]), self.backend)
        if X is None:
            return "tangent stiffness is exactly singular"
        free = self.path.free
        dlam = self.constraint.dlam(self.u[free], self.lam, X[:, 0], X[:, 1])
        if not math.isfinite(dlam):
            return "constraint is degenerate (K^-1 q orthogonal to it)"
        self.dlam = dlam
        return dlam * X[:, 0] + X[:, 1]

    def apply(self, du, scale):
        self.u[self.path.free] += du
        self.lam += self.dlam * scale if scale != 1.0 else self.dlam


def free_added(u, free, dv):
    """Displacements ``u`` (n_nodes, 3) plus ``dv`` on the free DOFs, as a new array."""
    out = np.array(u, float).ravel()
    out[free] += dv
    return out.reshape(-1, 3)


def begin_point(path, u, lam):
    """Let a path update per-increment data (staggered heating), then evaluate it."""
    if hasattr(path, "begin_increment"):
        path.begin_increment(u)
    return path.at(u, lam)


def path_tangent(pt, lam, backend: str = "auto"):
    """K^-1 q at a converged point, or a message if K is exactly singular."""
    uhat = solve_path_system(pt.K, pt.q, backend)
    if uhat is None:
        return None, f"tangent stiffness is exactly singular at load factor {lam:.6g}"
    return uhat, ""
