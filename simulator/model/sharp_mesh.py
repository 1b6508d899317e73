"""Concentrated-hinge (sharp-crease) bar-and-hinge mesh (theory 2.6; Filipov et al. 2017).

Creases have no width: the two panels of a crease share the crease's two vertices, and the
crease is one rotational spring (the *fold spring*) about the shared edge. Panels are meshed as

* **N5B8** (default, every panel with four or more corners): a centre node at the vertex
  centroid, one spoke bar from every corner to it and one *panel bending spring* on every spoke
  (wings: the two neighbouring corners); the fan triangles (centre, c_j, c_j+1) carry the mass;
* **N4B5** (``panel_mesh="N4B5"``, quadrilaterals only): the shorter diagonal as a bar with one
  bending spring (wings: the two other corners), two triangles; panels with five or more
  corners still get a centre node;
* triangles: their three edge bars only (a rigid triangle, no bending spring).

Numbering (0-based): nodes are the pattern vertices (node ``v`` = vertex ``v``), then the
panel centres in panel order; bars are the pattern edges in edge-id order, then the spokes
(panel by panel, corner by corner) or diagonals; springs are the fold springs in crease-row
order, then the panel springs. A fold spring is (wing 1, a, b, wing 2) with axis a-b the
crease's vertices and the wings the nodes of the panels' triangles on the crease (the centre
of an N5B8 panel, the opposite corner of a triangle); the polarity fix of the compliant mesh
makes its angle exceed pi when the crease folds towards +z.

:class:`SharpHingeMesh` is a :class:`~simulator.model.mesh.BarHingeMesh` with the same
attributes where they make sense (``crease_nodes`` are the two hinge nodes of every crease,
``crease_springs`` its one fold spring) and ``sharp = True``; the functions that depend on
the crease model (fold angles, spring rest angles, properties, masses) dispatch on it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .._arrays import read_only
from .._validate import one_of
from ..errors import PatternError
from ..geometry.pattern import Pattern
from ..geometry.polygons import centroids
from .mesh import BarHingeMesh, BarType, NodeKind, SpringKind, crease_up, polarity_fix

__all__ = ["SharpHingeMesh", "build_sharp_mesh", "PANEL_MESHES"]

logger = logging.getLogger(__name__)

#: Panel meshings of the concentrated-hinge model (Filipov et al. 2017).
PANEL_MESHES = ("N5B8", "N4B5")
#: Mass share of a fan triangle's centre node (as the compliant mesh, theory 7.1).
_CENTRE_SHARE = 2.0 / 3.0


@dataclass(frozen=True, eq=False)
class SharpHingeMesh(BarHingeMesh):
    """Concentrated-hinge mesh of a pattern (see the module docstring; all indices 0-based).

    Attributes beyond :class:`~simulator.model.mesh.BarHingeMesh`, or with another meaning:

    crease_nodes : (C, 2) the two hinge nodes (crease vertices) of every crease
    crease_bars, crease_edge_bars : (C, 1) the bar on every crease line
    crease_springs : (C, 1) the fold spring of every crease
    crease_triangles : (C, 2) the triangles of the two panels on every crease
    panel_center : (P,) centre node of each panel, -1 where the panel has none
    panel_corner_start : (P + 1,) the corners of panel p are
        ``pattern.corner_vertices[panel_corner_start[p]:panel_corner_start[p + 1]]``
    mass_shares : (nt, 3) share of every triangle's mass given to each of its nodes
    panel_mesh : "N5B8" or "N4B5"
    """

    mass_shares: np.ndarray = None
    panel_mesh: str = "N5B8"
    sharp: ClassVar[bool] = True

    @property
    def corner_nodes(self) -> np.ndarray:
        """The vertex nodes (shared by the panels)."""
        return read_only(np.arange(self.pattern.n_vertices))

    def panel_nodes(self, panel: int) -> np.ndarray:
        """Corner nodes and (if any) centre node of one panel."""
        p = self.pattern.check_panel(panel)
        s = self.panel_corner_start
        corners = self.pattern.corner_vertices[s[p]:s[p + 1]]
        c = self.panel_center[p]
        return np.r_[corners, c] if c >= 0 else np.array(corners)


def build_sharp_mesh(pattern: Pattern, panel_mesh: str = "N5B8") -> SharpHingeMesh:
    """Mesh a pattern with concentrated hinges (see the module docstring).

    Parameters
    ----------
    pattern : Pattern
        Its crease widths are not used by the mesh (only by the default fold stiffness).
    panel_mesh : {"N5B8", "N4B5"}
        Meshing of the quadrilateral panels.
    """
    if not isinstance(pattern, Pattern):
        raise PatternError(f"build_sharp_mesh expects a Pattern, got {type(pattern).__name__}.")
    one_of("build_sharp_mesh: panel_mesh", panel_mesh, PANEL_MESHES)
    V, P = pattern.n_vertices, pattern.n_panels
    sizes = pattern.corner_sizes
    start = np.r_[0, np.cumsum(sizes)]
    cv = pattern.corner_vertices
    has_centre = (sizes > 4) | ((sizes == 4) & (panel_mesh == "N5B8"))
    centre = np.full(P, -1)
    centre[has_centre] = V + np.arange(int(has_centre.sum()))
    corner_pos = pattern.vertices[cv]
    nodes = np.vstack([pattern.vertices, centroids(corner_pos, sizes)[has_centre]])

    inner, tris, shares, tri_panel, psprings = [], [], [], [], []
    wing = np.empty(len(cv), int)             # wing node of the edge ending at each corner
    for p in range(P):
        c = cv[start[p]:start[p + 1]]
        q = np.arange(start[p], start[p + 1])
        s = len(c)
        nxt, prv = np.roll(c, -1), np.roll(c, 1)
        if centre[p] >= 0:
            o = centre[p]
            inner += [(v, o) for v in c]
            tris += [(o, a, b) for a, b in zip(c, nxt)]
            shares += [(_CENTRE_SHARE, (1 - _CENTRE_SHARE) / 2, (1 - _CENTRE_SHARE) / 2)] * s
            psprings += list(zip(nxt, c, np.full(s, o), prv))
            wing[q] = o
        elif s == 3:
            tris.append(tuple(c))
            shares.append((1 / 3,) * 3)
            wing[q] = np.roll(c, -1)          # edge (c_j-1, c_j): the corner after c_j
        else:                                  # N4B5 quadrilateral
            X = pattern.vertices[c]
            k = 0 if np.linalg.norm(X[2] - X[0]) <= np.linalg.norm(X[3] - X[1]) else 1
            a, b, l, r = c[k], c[k + 2], c[k + 1], c[(k + 3) % 4]
            inner.append((a, b))
            tris += [(a, l, b), (a, b, r)]
            shares += [(1 / 3,) * 3] * 2
            psprings.append((l, a, b, r))
            wing[q] = [_third((a, l, b), (a, b, r), c[j - 1], c[j]) for j in range(4)]
        tri_panel += [p] * (len(tris) - len(tri_panel))
    return _assemble(pattern, nodes, centre, start, np.array(inner, int).reshape(-1, 2),
                     np.array(tris, int), np.array(shares), np.array(tri_panel, int),
                     np.array(psprings, int).reshape(-1, 4), wing, panel_mesh)


def _third(t1, t2, u, v) -> int:
    """The node of triangle t1 (or else t2) that is not on the edge (u, v)."""
    t = t1 if {u, v} <= set(t1) else t2
    return next(n for n in t if n != u and n != v)


def _assemble(pattern, nodes, centre, start, inner, tris, shares, tri_panel, psprings, wing,
              panel_mesh) -> SharpHingeMesh:
    V, E, P = pattern.n_vertices, pattern.n_edges, pattern.n_panels
    crease_ids = pattern.creases
    C = len(crease_ids)
    # the two corners (one per panel) whose incoming edge is each crease
    order = np.argsort(pattern.corner_edges, kind="stable")
    on_crease = pattern.is_crease[pattern.corner_edges[order]]
    pair = order[on_crease].reshape(C, 2)
    ab = pattern.edges[crease_ids]
    fold = np.column_stack([wing[pair[:, 0]], ab[:, 0], ab[:, 1], wing[pair[:, 1]]])
    fold = polarity_fix(nodes, fold, crease_up(pattern))
    springs = np.vstack([fold, psprings])
    bars = np.sort(np.vstack([pattern.edges, inner]), axis=1)
    nb_inner = len(inner)
    inner_panel = _inner_panels(centre, pattern.corner_sizes)
    crease_bars = crease_ids[:, None]
    ct = _crease_triangles(tris, ab)
    mesh = SharpHingeMesh(
        pattern=pattern, nodes=nodes,
        node_kind=np.r_[np.full(V, NodeKind.CORNER), np.full(len(nodes) - V, NodeKind.CENTRE)],
        node_vertex=np.r_[np.arange(V), np.full(len(nodes) - V, -1)],
        node_panel=np.r_[np.full(V, -1), np.flatnonzero(centre >= 0)],
        bars=bars, bar_type=np.r_[np.full(E, BarType.PANEL_EDGE), np.full(nb_inner, BarType.SPOKE)],
        bar_crease=np.r_[np.arange(E), np.full(nb_inner, -1)],
        bar_panel=np.r_[pattern.edge_panels[:, 0], inner_panel],
        bar_length=np.linalg.norm(nodes[bars[:, 1]] - nodes[bars[:, 0]], axis=1),
        springs=springs,
        spring_bar=np.r_[crease_ids, E + np.arange(len(psprings))],   # one per inner bar
        spring_kind=np.r_[np.full(C, SpringKind.CREASE_CENTRE), np.full(len(psprings),
                                                                        SpringKind.PANEL)],
        triangles=tris, triangle_panel=tri_panel, triangle_crease=np.full(len(tris), -1),
        crease_ids=crease_ids, crease_nodes=ab, crease_bars=crease_bars,
        crease_edge_bars=crease_bars, crease_springs=np.arange(C)[:, None],
        crease_triangles=ct, crease_panels=pattern.edge_panels[crease_ids],
        panel_center=centre, panel_corner_start=start, mass_shares=shares,
        panel_mesh=panel_mesh)
    logger.debug("sharp mesh (%s) of %d panels, %d creases: %d nodes, %d bars, %d springs",
                 panel_mesh, P, C, len(nodes), len(bars), len(springs))
    return mesh


def _inner_panels(centre, sizes):
    """Panel of every spoke / diagonal bar, in the order they were made."""
    counts = np.where(centre >= 0, sizes, np.where(sizes == 4, 1, 0))
    return np.repeat(np.arange(len(sizes)), counts)


def _crease_triangles(tris, ab):
    """(C, 2) the triangles containing each crease edge (a, b)."""
    key = lambda u, v: np.minimum(u, v) * (tris.max() + 1) + np.maximum(u, v)  # noqa: E731
    edges = np.concatenate([key(tris[:, 0], tris[:, 1]), key(tris[:, 1], tris[:, 2]),
                            key(tris[:, 2], tris[:, 0])])
    owner = np.tile(np.arange(len(tris)), 3)
    o = np.argsort(edges, kind="stable")
    k = key(ab[:, 0], ab[:, 1])
    lo = np.searchsorted(edges[o], k)
    return owner[o][np.stack([lo, lo + 1], axis=1)] if len(k) else np.zeros((0, 2), int)
