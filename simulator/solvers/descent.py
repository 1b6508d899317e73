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

import numpy as np

from ..linalg.ladder import factorize
from ..linalg.small_solve import as_dense
from .load_path import _Constraint, _correct, _size

__all__ = ["DESCENT_DOF_LIMIT", "descend", "switch_branch"]

logger = logging.getLogger(__name__)

#: Free DOFs at most of the (dense) energy descent; larger models are not landed.
DESCENT_DOF_LIMIT = 3000
#: Rounds at most of (temperatures on the shape, descent) before the polish.
ROUNDS = 20
#: Push along the critical mode of :func:`switch_branch`, as a fraction of the model size.
PUSH = 1e-3


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
    ``u`` at ``lam``, temperatures solved on the shape ``u`` first; None if it does not."""
    free, size = path.free, _size(path.system)
    path.at(u, lam)                             # a heating path: temperatures on this shape
    energy, f = _energy_of(path, lam)
    v = np.array(u, float).ravel()
    e, ev = energy(v)
    eye = np.eye(len(free))
    mu, step = None, getattr(path.system, "max_step", None)
    for _ in range(max_iter):
        g, K = (ev.f_int - f)[free], as_dense(ev.K)
        mu = 1e-6 * float(np.mean(np.abs(np.diag(K)))) if mu is None else mu
        while mu < 1e30:
            try:
                dv = -factorize(K + mu * eye, kind="spd", backend="dense").solve(g)
            except np.linalg.LinAlgError:                   # not positive definite yet
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
    size = _size(path.system)
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
    ok, u1, _, _, _, _, _ = _correct(path, v.reshape(-1, 3), lam, _Constraint(None, lam),
                                     options, size)
    logger.debug("descent at load factor %.6g: polish %s", lam, "converged" if ok else "failed")
    return u1 if ok else None


def switch_branch(path, u, lam, mode, options, max_iter=300):
    """The stable equilibrium at ``lam`` that the unstable one ``u`` (n_nodes, 3) falls to
    when pushed along its critical ``mode`` (n_free,): both pushes (:data:`PUSH` of the
    model size) descend on the energy with the temperatures of ``u``; the one ending lower
    goes on (:func:`descend`; a tie, as in a symmetric structure, takes the sign that makes
    the mode's first sizeable entry positive). None if neither lands."""
    if len(path.free) > DESCENT_DOF_LIMIT:
        return None
    mode = np.asarray(mode, float)
    big = np.flatnonzero(np.abs(mode) >= 0.5 * np.max(np.abs(mode)))
    mode = mode if mode[big[0]] > 0 else -mode
    push = PUSH * _size(path.system) / float(np.max(np.abs(mode)))
    ends = []
    for sign in (1.0, -1.0):
        v = np.array(u, float).ravel()
        v[path.free] += sign * push * mode
        ends.append((_minimise(path, v.reshape(-1, 3), lam, max_iter), v))
    found = [(out[1], k) for k, (out, _) in enumerate(ends) if out is not None]
    if not found:
        return None
    e = [x for x, _ in found]
    tie = len(found) == 2 and abs(e[0] - e[1]) <= 1e-9 * max(abs(e[0]), abs(e[1]), 1e-300)
    k = 0 if tie else min(found)[1]
    out, v = ends[k]
    logger.debug("branch switch at load factor %.6g: push %+d along the critical mode", lam,
                 1 if k == 0 else -1)
    return descend(path, v.reshape(-1, 3), lam, options, max_iter, start=out)
