"""Rest angles of the creases and springs (theory 3.4): those of the mesh's reference geometry
(:func:`initial_crease_rest`; a folded start shape keeps its dihedral angles) and a crease rest
angle spread over the springs of its fold lines (:func:`spring_rest_angles`)."""

from __future__ import annotations

import weakref

import numpy as np

from ..model.mesh import BarHingeMesh
from ..model.properties import BarHingeParameters
from .elements.springs import fold_angle
from .kinematics import fold_angles

__all__ = ["spring_rest_angles", "initial_crease_rest", "FLAT_FOLD_TOL"]

#: Creases whose fold angle in the mesh's reference geometry is at most this [rad] count as
#: flat (rest angle exactly pi); the reference's Miura generator leaves ~1e-8 rad of round-off.
FLAT_FOLD_TOL = 1e-6


def spring_rest_angles(mesh: BarHingeMesh, crease_rest: np.ndarray,
                       params: BarHingeParameters = BarHingeParameters()) -> np.ndarray:
    """Spring rest angles for given crease rest angles (theory 3.4).

    Parameters
    ----------
    crease_rest : (C,) array
        Rest angle of each crease [rad], pi = flat, in crease-row order.

    Returns
    -------
    (ns,) array: pi for panel and diagonal springs; edge lines get
    ``pi + (theta0 - pi)(1 - f)/2`` each, the centre line ``pi + f (theta0 - pi)``.
    A concentrated-hinge mesh (theory 2.6) has one fold spring per crease, which takes the
    whole change. A crease folded in the mesh's reference geometry (a 3-D start shape) starts instead from
    its springs' initial angles and from :func:`initial_crease_rest`, so that its initial
    rest angles give back the start shape.
    """
    rest0, base, lines = _initial_rest(mesh)
    rho = np.asarray(crease_rest, dtype=float) - rest0
    out = base.copy()
    if lines is None:                           # one fold spring per crease (theory 2.6)
        out[mesh.crease_springs[:, 0]] += rho
        return out
    f = params.centre_line_share
    out[lines] += rho[:, None] * np.array([(1 - f) / 2, (1 - f) / 2, f, f])
    return out


def initial_crease_rest(mesh: BarHingeMesh) -> np.ndarray:
    """Crease rest angles [rad] of the mesh's reference geometry, (C,) in crease-row order.

    pi (flat) plus the fold angle of each crease in ``mesh.nodes``; exactly pi where that
    angle is at most :data:`FLAT_FOLD_TOL`. A folded start shape (a 3-D FOLD file) thus
    keeps its initial dihedral angles as rest angles.
    """
    return _initial_rest(mesh)[0].copy()


_INITIAL: "weakref.WeakKeyDictionary[BarHingeMesh, tuple]" = weakref.WeakKeyDictionary()


def _initial_rest(mesh: BarHingeMesh) -> tuple:
    """(crease rest (C,), spring base angles (ns,)) of the reference geometry, and the springs
    of each crease's fold lines (C, 4) (edge line 1, edge line 2, the centre line's two
    halves; None for concentrated hinges), cached per mesh."""
    cached = _INITIAL.get(mesh)
    if cached is None:
        fold = fold_angles(mesh, mesh.nodes) if mesh.n_creases else np.zeros(0)
        folded = np.abs(fold) > FLAT_FOLD_TOL
        rest0 = np.where(folded, np.pi + fold, np.pi)
        base = np.full(len(mesh.springs), np.pi)
        springs = mesh.crease_springs[folded].ravel()
        base[springs] = fold_angle(mesh.nodes[mesh.springs[springs]])
        lines = None if getattr(mesh, "sharp", False) else (
            np.ascontiguousarray(mesh.crease_springs[:, [0, 1, 4, 5]]) if mesh.n_creases
            else np.zeros((0, 4), dtype=int))
        cached = _INITIAL[mesh] = (rest0, base, lines)
    return cached
