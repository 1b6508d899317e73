"""Orientation of a pattern's sheet: which side of every panel is the paper's top.

Fold signs must not depend on where a pattern sits in space. The top side of every panel
comes from its winding (right-hand rule), made consistent across every crease (the two panels
of a crease run their shared edge in opposite directions). One sign per connected sheet is
then left; it is chosen, in this order,

1. by the design fold signs (``Pattern.edge_fold_angle``: M < 0, V > 0) of the creases that
   are folded in the start shape, so that a rigid rotation or a mirror image of a folded file
   gives the same fold angles (a mirror image reverses the winding, the assignments do not);
2. for a flat or unassigned sheet, so that the top faces +z (the reference convention for
   flat patterns in the x-y plane, whatever their winding);
3. for a sheet standing on edge (normal in the x-y plane), by the winding.

:func:`panel_orientation` gives the signs, :func:`start_fold_angles` the signed fold angle of
every crease of the start shape (positive = valley = towards the top side, FOLD's sign).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import PatternError
from .polygons import area_vectors, rings

if TYPE_CHECKING:
    from .pattern import Pattern

__all__ = ["panel_orientation", "start_fold_angles", "crease_corners", "folded_flat_creases"]


def crease_corners(pattern: Pattern) -> np.ndarray:
    """(n_creases, 2) corner ids whose incoming side is the crease, in panel order.

    Corner ``q`` of a panel ends the side ``(C_{q-1}, C_q)``: that side is run from
    ``corner_vertices[prev[q]]`` to ``corner_vertices[q]`` in the panel's corner order.
    """
    order = np.argsort(pattern.corner_edges, kind="stable")
    keep = pattern.is_crease[pattern.corner_edges[order]]
    return order[keep].reshape(-1, 2)


def _relations(pattern: Pattern):
    """Corners (C, 2) of every crease and +1 where its panels run it oppositely (consistent)."""
    pair = crease_corners(pattern)
    ends = pattern.corner_vertices[pair]
    return pair, np.where(ends[:, 0] != ends[:, 1], 1, -1)


def _consistent(pattern: Pattern, panels, relation):
    """Winding-consistent signs (P,) and the connected-sheet label (P,) of every panel."""
    P = pattern.n_panels
    sign, label = np.zeros(P, int), np.full(P, -1)
    nbr = [[] for _ in range(P)]
    for (p, q), r in zip(panels.tolist(), relation.tolist()):
        nbr[p].append((q, r))
        nbr[q].append((p, r))
    for start in range(P):
        if label[start] >= 0:
            continue
        label[start], sign[start], todo = start, 1, [start]
        while todo:
            p = todo.pop()
            for q, r in nbr[p]:
                if label[q] < 0:
                    label[q], sign[q] = start, sign[p] * r
                    todo.append(q)
    bad = np.flatnonzero(sign[panels[:, 0]] * sign[panels[:, 1]] != relation)
    if len(bad):
        e = int(pattern.creases[bad[0]])
        raise PatternError(f"the panels cannot be oriented consistently (the sheet is not "
                           f"orientable, e.g. a Moebius strip): crease {e} between panels "
                           f"{panels[bad[0]].tolist()} closes an orientation-reversing loop.")
    return sign, label


def _fold_angles(pattern: Pattern, sign, pair, panels) -> np.ndarray:
    """Signed fold angle [rad] of every crease with panel top sides ``sign`` (P,)."""
    area = area_vectors(pattern.vertices[pattern.corner_vertices], pattern.corner_sizes)
    normal = area / np.linalg.norm(area, axis=1, keepdims=True)
    n1 = normal[panels[:, 0]] * sign[panels[:, 0], None]
    n2 = normal[panels[:, 1]] * sign[panels[:, 1], None]
    prev = rings(pattern.corner_sizes).prev
    v = pattern.vertices[pattern.corner_vertices]
    axis = -(v[pair[:, 0]] - v[prev[pair[:, 0]]]) * sign[panels[:, 0], None]
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    return np.arctan2(np.einsum("ij,ij->i", np.cross(n1, n2), axis),
                      np.einsum("ij,ij->i", n1, n2))


def panel_orientation(pattern: Pattern) -> np.ndarray:
    """+1 / -1 per panel (P,): the factor turning the panel's winding normal into its top side.

    See the module docstring for the rule; raises PatternError for a non-orientable sheet.
    """
    pair, relation = _relations(pattern)
    panels = pattern.edge_panels[pattern.creases]
    sign, label = _consistent(pattern, panels, relation)
    theta = _fold_angles(pattern, sign, pair, panels)
    target = np.sign(pattern.edge_fold_angle[pattern.creases])
    folded = np.abs(theta) > 1e-6
    area = area_vectors(pattern.vertices[pattern.corner_vertices], pattern.corner_sizes)
    for root in np.unique(label):
        mine = label == root
        rows = mine[panels[:, 0]] & folded
        vote = float(np.sum(target[rows] * theta[rows]))
        if abs(vote) > 1e-6:
            flip = vote < 0
        else:
            up = float(np.sum(sign[mine] * area[mine, 2]))
            flip = up < -1e-9 * float(np.sum(np.linalg.norm(area[mine], axis=1)))
        if flip:
            sign[mine] = -sign[mine]
    return sign


def start_fold_angles(pattern: Pattern) -> np.ndarray:
    """Signed fold angle [rad] of every edge of the start shape (0 on boundary edges).

    Positive folds towards the top side (:func:`panel_orientation`), FOLD's valley sign.
    """
    pair, _ = _relations(pattern)
    panels = pattern.edge_panels[pattern.creases]
    out = np.zeros(pattern.n_edges)
    out[pattern.creases] = _fold_angles(pattern, pattern.panel_orientation, pair, panels)
    return out


def folded_flat_creases(pattern: Pattern, limit: float = np.radians(179.9)) -> np.ndarray:
    """Edge ids of the creases folded flat (|fold angle| >= ``limit``) in the start shape.

    Needs only the topology and the coordinates (usable while the pattern is being checked).
    """
    pair, relation = _relations(pattern)
    panels = pattern.edge_panels[pattern.creases]
    sign, _ = _consistent(pattern, panels, relation)
    theta = _fold_angles(pattern, sign, pair, panels)
    return pattern.creases[np.abs(theta) >= limit]
