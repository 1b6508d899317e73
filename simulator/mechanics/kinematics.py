"""Geometric measures of a deformed mesh: panel normals, crease fold angles and rotations.

Two measures of how far a crease has folded, both signed (> 0 towards +z) and 0 when flat:

* :func:`fold_angles`, the **fold angle**: the rotation of one panel relative to the other
  (panel-to-panel, from the panels' mean planes). It is what one sees and what the reference
  scripts measure between panel edges.
* :func:`crease_rotations`, the **crease rotation**: the rotation taken up by the crease itself,
  the sum over its fold lines (edge line 1, centre line, edge line 2) of their rotations from flat.
  It is the reference implementation's measure of a crease and what the bimorph drives (the
  rest angles of the fold lines add up to the crease's rest-angle change).

They agree when the panels stay flat; when panels bend (the crane, up to about 8 deg) the fold
angle also contains the panels' bending near the crease.
"""

from __future__ import annotations

import numpy as np

from .elements.springs import fold_angle
from ..model.mesh import BarHingeMesh
from ..geometry.polygons import rings, unit_normals

__all__ = ["panel_normals", "fold_angles", "crease_rotations"]

#: Columns of ``BarHingeMesh.crease_springs`` on the crease's fold lines: edge1, edge2 and the
#: two halves (A-Ctr, B-Ctr) of the centre line; the diagonals are not fold lines.
_EDGE_LINES, _CENTRE_LINE = [0, 1], [4, 5]


def panel_normals(mesh: BarHingeMesh, x: np.ndarray) -> np.ndarray:
    """Unit normals (P, 3) of the shrunk panels at positions x (n, 3), by Newell's method;
    (..., P, 3) for positions (..., n, 3) of several records at once.

    Orientation follows the panel's corner order; the fans run from the panel's centre node.
    """
    s = mesh.panel_corner_start
    return unit_normals(x[..., :s[-1], :], np.diff(s), x[..., mesh.panel_center, :])


def fold_angles(mesh: BarHingeMesh, x: np.ndarray) -> np.ndarray:
    """Signed fold angle [rad] of every crease (crease-row order) at positions x (n, 3).

    The fold angle is the relative rotation of the two panels of a crease about the
    crease line, 0 when they are coplanar as in the flat reference and positive when
    the panels fold towards the sheet's top side (+z for a flat pattern in the x-y plane; see
    :mod:`simulator.geometry.orientation`), the side a positive rest-angle change folds to. With
    concentrated hinges (theory 2.6) it is the angle of the crease's fold spring minus pi.

    Positions (..., n, 3) of several records give (..., C), the same numbers as one call per
    record (what :attr:`simulator.SimulationResult.fold_angle` uses).
    """
    if getattr(mesh, "sharp", False):
        return _hinge_rotations(mesh, x)
    cur = panel_normals(mesh, x)
    p1, p2 = mesh.crease_panels.T
    # the panels' top sides (Pattern.panel_orientation: consistent across every crease and
    # independent of where the sheet sits in space); the axis is the crease side as panel 2
    # runs it along its top side, so a fold towards panel 1's top side is positive
    top = mesh.pattern.panel_orientation
    n1, n2 = cur[..., p1, :] * top[p1, None], cur[..., p2, :] * top[p2, None]
    q1 = mesh.crease_edge_bars[:, 0]                 # edge bar q ends at corner node q
    prev = rings(np.diff(mesh.panel_corner_start)).prev[q1]
    axis = (x[..., prev, :] - x[..., q1, :]) * top[p1, None]
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    return np.arctan2(np.einsum("...j,...j->...", np.cross(n1, n2), axis),
                      np.einsum("...j,...j->...", n1, n2))


def crease_rotations(mesh: BarHingeMesh, x: np.ndarray) -> np.ndarray:
    """Signed rotation [rad] of every crease (crease-row order) at positions x (n, 3), or
    (..., C) at positions (..., n, 3).

    The sum over the crease's three fold lines of their rotations from flat, ``theta - pi`` of
    their springs (> 0 towards +z, as the rest-angle change); the centre line is two springs
    (A-Ctr, B-Ctr) and counts with their mean. Equals :func:`fold_angles` while the panels stay
    flat; see the module docstring. With concentrated hinges it is the fold angle.
    """
    if getattr(mesh, "sharp", False):
        return _hinge_rotations(mesh, x)
    springs = mesh.springs[mesh.crease_springs[:, _EDGE_LINES + _CENTRE_LINE]]     # (C, 4, 4)
    lead = x.shape[:-2]                              # records, for positions (..., n, 3)
    corners = x[..., springs.reshape(-1, 4), :].reshape(-1, 4, 3)
    rot = fold_angle(corners).reshape(*lead, -1, 4) - np.pi
    return rot[..., 0] + rot[..., 1] + 0.5 * (rot[..., 2] + rot[..., 3])


def _hinge_rotations(mesh, x: np.ndarray) -> np.ndarray:
    """theta - pi of the fold spring of every crease of a concentrated-hinge mesh, in [-pi, pi)."""
    lead = x.shape[:-2]
    corners = x[..., mesh.springs[mesh.crease_springs[:, 0]], :].reshape(-1, 4, 3)
    theta = fold_angle(corners).reshape(*lead, -1)
    return np.mod(theta, 2 * np.pi) - np.pi
