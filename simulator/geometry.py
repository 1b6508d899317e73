"""Geometric measures of a deformed mesh: panel normals and crease fold angles."""

from __future__ import annotations

import numpy as np

from .mesh import BarHingeMesh

__all__ = ["panel_normals", "fold_angles"]


def panel_normals(mesh: BarHingeMesh, x: np.ndarray) -> np.ndarray:
    """Unit normals (P, 3) of the shrunk panels at positions x (n, 3), by Newell's method.

    Orientation follows the panel's corner order.
    """
    s = mesh.panel_corner_start
    sizes = np.diff(s)
    S = s[-1]
    start = np.repeat(s[:-1], sizes)
    nxt = start + (np.arange(S) - start + 1) % np.repeat(sizes, sizes)
    c = x[mesh.panel_center]
    panel = np.repeat(np.arange(len(sizes)), sizes)
    n = np.add.reduceat(np.cross(x[:S] - c[panel], x[nxt] - c[panel]), s[:-1])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def fold_angles(mesh: BarHingeMesh, x: np.ndarray) -> np.ndarray:
    """Signed fold angle [rad] of every crease (crease-row order) at positions x (n, 3).

    The fold angle is the relative rotation of the two panels of a crease about the
    crease line, 0 when they are coplanar as in the flat reference and positive when
    the panels fold towards +z (the side a positive rest-angle change folds to).
    """
    ref = panel_normals(mesh, mesh.nodes)
    cur = panel_normals(mesh, x)
    p1, p2 = mesh.crease_panels.T
    # orient the first panel's normal to +z in the reference and the second one consistently
    # with it across the crease (the shared edge run in opposite directions); for a flat
    # reference both then point to +z, and a start shape folded past 90 deg keeps its sign
    end = mesh.pattern.corner_vertices[mesh.crease_edge_bars]
    s1 = np.where(ref[p1, 2] < 0, -1.0, 1.0)
    s2 = s1 * np.where(end[:, 0] != end[:, 1], 1.0, -1.0)
    n1, n2 = cur[p1] * s1[:, None], cur[p2] * s2[:, None]
    n1_ref = ref[p1] * s1[:, None]
    n11, n12 = mesh.crease_nodes[:, 0], mesh.crease_nodes[:, 1]
    X = mesh.nodes
    d = X[mesh.panel_center[p2]] - X[mesh.panel_center[p1]]
    e_ref = np.cross(d, n1_ref)
    sign = np.sign(np.einsum("ij,ij->i", X[n12] - X[n11], e_ref))
    axis = (x[n12] - x[n11]) * sign[:, None]
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    return np.arctan2(np.einsum("ij,ij->i", np.cross(n1, n2), axis), np.einsum("ij,ij->i", n1, n2))
