"""Contact candidate search (theory 3.5), vectorised.

Contact points are the panel corner nodes and panel centres; contact surfaces are
the panel fan triangles. A point never touches its own panel, and a corner node
is not tested against a triangle holding a copy of the same pattern vertex (the
neighbour panel across a crease). Candidates are pruned by a bounding-sphere
test on current positions: for small meshes against a precomputed list of all
admissible pairs, for large ones with a k-d tree, never with a Python loop.
"""

from __future__ import annotations

import numpy as np

from ..model.mesh import BarHingeMesh
from ..model.model import ContactParameters

__all__ = ["ContactSearch", "closest_pair"]

#: Above this many admissible (point, triangle) pairs the k-d tree search is used.
STATIC_PAIR_LIMIT = 50_000


class ContactSearch:
    """Find (point, fan triangle) pairs that may be within their activation distance.

    Parameters
    ----------
    mesh : BarHingeMesh
    params : ContactParameters
    """

    def __init__(self, mesh: BarHingeMesh, params: ContactParameters):
        S = mesh.panel_corner_start[-1]
        self.points = np.r_[np.arange(S), mesh.panel_center]
        self.point_panel = mesh.node_panel[self.points]
        self.point_vertex = mesh.node_vertex[self.points]
        self.point_d0 = np.r_[np.full(S, params.d0_corner), np.full(len(mesh.panel_center),
                                                                     params.d0_centre)]
        self.tri = mesh.triangles[mesh.fan_triangles]
        self.tri_panel = mesh.triangle_panel[mesh.fan_triangles]
        self.tri_vertex = mesh.node_vertex[self.tri]
        self.d0_max = max(params.d0_corner, params.d0_centre)
        n_pairs = len(self.points) * len(self.tri)
        self.static = None
        if n_pairs <= STATIC_PAIR_LIMIT:
            p, t = np.divmod(np.arange(n_pairs), len(self.tri))
            ok = self.admissible(p, t)
            self.static = (p[ok], t[ok])

    def admissible(self, p: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Whether point p and fan triangle t (index arrays into :attr:`points`, the fan
        triangles) may touch: the exclusion rules of the reference (other panel, no shared
        pattern vertex)."""
        v = self.point_vertex[p]
        shared = (v[:, None] == self.tri_vertex[t]).any(axis=1) & (v >= 0)
        return (self.point_panel[p] != self.tri_panel[t]) & ~shared

    def candidates(self, x: np.ndarray):
        """Admissible pairs whose bounding spheres overlap.

        Parameters
        ----------
        x : (n_nodes, 3) current node positions [m]

        Returns
        -------
        conn : (m, 4) int array of nodes (point, T1, T2, T3)
        d0 : (m,) activation distance of each pair [m]
        index : (m,) position of each pair in :attr:`static_conn`, or None (k-d tree mode)
        """
        xt = x[self.tri]
        centre = xt.mean(axis=1)
        radius = np.linalg.norm(xt - centre[:, None], axis=2).max(axis=1)
        xp = x[self.points]
        index = None
        if self.static is not None:
            p, t = self.static
            index = np.arange(len(p))
        else:
            from scipy.spatial import cKDTree  # large meshes only; slow to import

            tree_p, tree_t = cKDTree(xp), cKDTree(centre)
            found = tree_p.sparse_distance_matrix(tree_t, radius.max() + self.d0_max,
                                                  output_type="ndarray")
            p, t = found["i"].astype(int), found["j"].astype(int)
            ok = self.admissible(p, t)
            p, t = p[ok], t[ok]
        dist = np.linalg.norm(xp[p] - centre[t], axis=1)
        near = dist <= radius[t] + self.point_d0[p]
        p, t = p[near], t[near]
        conn = np.column_stack([self.points[p], self.tri[t]])
        return conn, self.point_d0[p], None if index is None else index[near]

    @property
    def static_conn(self) -> np.ndarray | None:
        """(m, 4) nodes of all admissible pairs in static mode (small meshes), else None."""
        if self.static is None:
            return None
        p, t = self.static
        return np.column_stack([self.points[p], self.tri[t]])


def closest_pair(mesh: BarHingeMesh, x: np.ndarray, distance: float) -> tuple | None:
    """The admissible (point, fan triangle) pair nearest at positions ``x`` (n_nodes, 3) [m]
    if it is within ``distance`` [m]: ``(gap [m], node, panel of the triangle)``, else None
    (e.g. a start shape in which contact of that activation distance would already push)."""
    from .elements.contact import point_triangle_distance

    search = ContactSearch(mesh, ContactParameters(d0_corner=distance, d0_centre=distance))
    conn, _, _ = search.candidates(x)
    if not len(conn):
        return None
    gap = point_triangle_distance(x[conn[:, 0]], x[conn[:, 1:]])[0]
    k = int(np.argmin(gap))
    if gap[k] > distance:
        return None
    return float(gap[k]), int(conn[k, 0]), int(mesh.node_panel[conn[k, 1]])
