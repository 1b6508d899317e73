"""Where a snap lands: descent on the potential energy at a fixed load factor.

Past a point where the path stops being stable (a bifurcation, a fold the arc length loses) a
physical structure leaves its equilibrium for a stable one at the same load. :func:`descend`
finds it without dynamics: damped Newton (Levenberg-Marquardt) on the potential energy with
the temperatures of a heating path held on the current shape, steps accepted where the energy
decreases, so indefinite tangents are passed downhill; the temperatures are then solved on the
shape reached and the descent repeated until the shape stops moving (the slow heat following
the fast mechanics), and the end is polished on the path with the load factor fixed.
:func:`switch_branch` starts it from an unstable equilibrium pushed along its critical mode,
in the direction where the energy falls further. The continuation driver
(:func:`~simulator.solvers.continuation.mgdcm`) uses both.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..linalg.ladder import factorize
from ..linalg.thresholds import EIGEN_DENSE_LIMIT
from ..linalg.small_solve import as_dense
from .load_path import PathConstraint, correct_point, model_size

__all__ = ["DESCENT_DOF_LIMIT", "BRANCHES", "BranchChoice", "descend", "switch_branch",
           "choose_branch"]

logger = logging.getLogger(__name__)

#: Free DOFs at most of the energy descent (dense up to EIGEN_DENSE_LIMIT, sparse above);
#: larger models are not landed.
DESCENT_DOF_LIMIT = 300_000
#: Rounds at most of (temperatures on the shape, descent) before the polish.
ROUNDS = 20
#: Push along the critical mode of :func:`switch_branch`, as a fraction of the model size.
PUSH = 1e-3
#: Which of the two pushes along a critical mode :func:`choose_branch` follows: "lower" (the
#: one whose descent ends at the lower potential energy; on a tie, the sign that makes the
#: mode's first sizeable entry positive) or "other" (the other one).
BRANCHES = ("lower", "other")
#: Energies closer than this, relative, are a tie (a symmetric structure's two branches).
TIE_RTOL = 1e-9


def _energy_of(path, lam):
    """``energy(v) -> (potential energy [J], evaluation)`` at ``lam``, temperatures held on the
    shape of the last ``path.at``."""
    system, rest, f = path.system, path.rest(lam), path.f_ext(lam)

    def energy(v):
        ev = system.evaluate(v.reshape(-1, 3), rest)
        return sum(ev.energies.values()) - float(f @ v), ev
    return energy, f


def _minimise(path, u, lam, max_iter):
    """(flat displacements, energy) of the energy minimum that damped Newton reaches from
    ``u`` at ``lam``, temperatures solved on the shape ``u`` first; None if it does not.

    Up to :data:`~simulator.linalg.thresholds.EIGEN_DENSE_LIMIT` free DOFs the damped tangent
    is factorised densely (Cholesky: it fails where the damping is not yet enough), above by
    the ladder's symmetric factorisation, whose inertia says the same."""
    free, size = path.free, model_size(path.system)
    path.at(u, lam)                             # a heating path: temperatures on this shape
    energy, f = _energy_of(path, lam)
    v = np.array(u, float).ravel()
    e, ev = energy(v)
    dense = len(free) <= EIGEN_DENSE_LIMIT
    mu, step = None, getattr(path.system, "max_step", None)
    for _ in range(max_iter):
        g = (ev.f_int - f)[free]
        K = as_dense(ev.K) if dense else sp.csr_matrix(ev.K)
        if mu is None:
            mu = 1e-6 * float(np.mean(np.abs(K.diagonal())))
        while mu < 1e30:
            dv = _damped_step(K, mu, g, dense)
            if dv is None:                                  # not positive definite yet
                mu *= 4
                continue
            if step is not None and np.max(np.abs(dv)) > step:
                dv *= step / np.max(np.abs(dv))
            if np.max(np.abs(dv)) <= 1e-9 * size:  # (undamped by then: Newton's steps)
                return v, e
            w = v.copy()
            w[free] += dv
            e1, ev1 = energy(w)
            if e1 < e:
                v, e, ev, mu = w, e1, ev1, mu / 3
                break
            mu *= 4
        else:
            return None
    return None


def _damped_step(K, mu, g, dense):
    """``-(K + mu I)^-1 g``, or None where ``K + mu I`` is not positive definite."""
    n = K.shape[0]
    if dense:
        try:
            return -factorize(K + mu * np.eye(n), kind="spd", backend="dense").solve(g)
        except np.linalg.LinAlgError:
            return None
    try:
        factor = factorize((K + mu * sp.identity(n, format="csr")).tocsr(), kind="symmetric")
    except RuntimeError:                                    # exactly singular
        return None
    inertia = factor.inertia
    if inertia is None or inertia[1] or inertia[2]:
        return None
    return -factor.solve(g)


def descend(path, u, lam, options, max_iter=300, start=None, rounds=ROUNDS):
    """The equilibrium at ``lam`` that energy descent reaches from ``u`` (n_nodes, 3): rounds
    of damped Newton with the temperatures on the shape reached, polished on ``path`` with
    the load factor fixed. None if it does not get there (or the model has more than
    :data:`DESCENT_DOF_LIMIT` free DOFs).

    ``start`` : (flat displacements, energy) of a first round already made from ``u``;
    ``rounds`` : descents at most (1: the temperatures stay on the shape ``u``).
    """
    if len(path.free) > DESCENT_DOF_LIMIT:
        return None
    size = model_size(path.system)
    v = np.array(u, float).ravel()
    for _ in range(rounds):
        out = start if start is not None else _minimise(path, v.reshape(-1, 3), lam, max_iter)
        start = None
        if out is None:
            logger.debug("descent at load factor %.6g: no minimum reached", lam)
            return None
        moved = float(np.max(np.abs(out[0] - v)))
        logger.debug("descent at load factor %.6g: moved %.3g m", lam, moved)
        v = out[0]
        if moved <= 1e-9 * size:
            break
    ok, u1, _, _, _, _, _ = correct_point(path, v.reshape(-1, 3), lam, PathConstraint(None, lam),
                                     options, size)
    logger.debug("descent at load factor %.6g: polish %s", lam, "converged" if ok else "failed")
    return u1 if ok else None


@dataclass(frozen=True, eq=False)
class BranchChoice:
    """Where an unstable equilibrium went (:func:`choose_branch`).

    Attributes
    ----------
    u : (n_nodes, 3) displacements of the stable equilibrium reached [m], or None
    sign : int
        +1 or -1: the push along the critical mode (its sign made deterministic: the first
        entry of at least half the largest magnitude is positive).
    energies : tuple of (float or None, float or None)
        Potential energy [J] where the descents of the pushes +1 and -1 ended (None: no
        minimum reached).
    tie : bool
        The two energies agree within :data:`TIE_RTOL` (then ``sign`` is +1 for "lower").
    """

    u: np.ndarray | None
    sign: int
    energies: tuple
    tie: bool

    @property
    def gap(self) -> float | None:
        """Energy of the branch not taken minus that of the one taken [J] (None if only one
        was reached)."""
        e = self.energies
        if e[0] is None or e[1] is None:
            return None
        taken = e[0] if self.sign > 0 else e[1]
        return (e[1] if self.sign > 0 else e[0]) - taken


def choose_branch(path, u, lam, mode, options, prefer: str = "lower",
                  max_iter=300) -> BranchChoice | None:
    """The stable equilibrium at ``lam`` that the unstable one ``u`` (n_nodes, 3) falls to
    when pushed along its critical ``mode`` (n_free,): both pushes (:data:`PUSH` of the
    model size) descend on the energy with the temperatures of ``u``; ``prefer`` "lower" goes
    on from the one ending lower (a tie, as in a symmetric structure, takes the sign that makes
    the mode's first sizeable entry positive), "other" from the other one (:func:`descend`).
    None if the model is too large for the descent (:data:`DESCENT_DOF_LIMIT`) or neither
    push lands."""
    if len(path.free) > DESCENT_DOF_LIMIT:
        return None
    mode = np.asarray(mode, float)
    big = np.flatnonzero(np.abs(mode) >= 0.5 * np.max(np.abs(mode)))
    mode = mode if mode[big[0]] > 0 else -mode
    push = PUSH * model_size(path.system) / float(np.max(np.abs(mode)))
    ends = []
    for sign in (1.0, -1.0):
        v = np.array(u, float).ravel()
        v[path.free] += sign * push * mode
        ends.append((_minimise(path, v.reshape(-1, 3), lam, max_iter), v))
    energies = tuple(None if out is None else float(out[1]) for out, _ in ends)
    found = [(e, k) for k, e in enumerate(energies) if e is not None]
    if not found:
        return None
    tie = len(found) == 2 and abs(energies[0] - energies[1]) <= TIE_RTOL * max(
        abs(energies[0]), abs(energies[1]), 1e-300)
    k = 0 if tie else min(found)[1]
    if prefer == "other" and len(found) == 2:
        k = 1 - k
    out, v = ends[k]
    logger.debug("branch switch at load factor %.6g: push %+d along the critical mode", lam,
                 1 if k == 0 else -1)
    u1 = descend(path, v.reshape(-1, 3), lam, options, max_iter, start=out)
    return BranchChoice(u1, 1 if k == 0 else -1, energies, tie)


def switch_branch(path, u, lam, mode, options, max_iter=300):
    """The stable equilibrium at ``lam`` that the unstable one ``u`` (n_nodes, 3) falls to
    when pushed along its critical ``mode`` (n_free,) (:func:`choose_branch` with "lower"):
    displacements (n_nodes, 3), or None if neither push lands."""
    choice = choose_branch(path, u, lam, mode, options, "lower", max_iter)
    return None if choice is None else choice.u
