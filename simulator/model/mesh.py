"""Compliant-crease bar-and-hinge mesh (theory 2.2).

Every panel is shrunk away from its creases by half the crease width; each
interior crease gets three nodes (A, B, Ctr), six triangles and ten bars;
every panel gets a centre node, spokes and fan triangles. Numbering follows the
reference implementation exactly (0-based = reference id - 1):

* nodes: panel corners panel by panel (``S`` of them), then (A, B, Ctr) per
  crease in crease-id order, then one centre per panel;
* bars: ``S`` panel-edge bars (bar ``q`` ends at corner ``q``), ten bars per
  crease, then ``S`` spokes (spoke of corner ``q`` is bar ``S + 10 C + q``);
* triangles: six per crease, then the fan triangles of the panels;
* springs: one per bar that carries one, in ascending bar order.

All per-element data are arrays; crease and panel element maps are index
arrays (``crease_nodes``, ``crease_bars``, ``crease_springs``, ...).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from .._arrays import read_only
from .._validate import capped
from ..errors import PatternError
from ..geometry.pattern import Pattern
from ..geometry.pattern_checks import OPEN_START
from ..geometry.polygons import area_vectors, centroids, fan_normals, on_segment, rings

__all__ = ["BarHingeMesh", "make_mesh", "BarType", "SpringKind", "NodeKind", "crease_up",
           "polarity_fix"]

logger = logging.getLogger(__name__)


class BarType:
    """Bar types as in the reference: panel edge, crease 'vertical', diagonal, centre line, spoke."""
    PANEL_EDGE, CREASE_SIDE, CREASE_DIAGONAL, CREASE_CENTRE, SPOKE = 1, 2, 3, 4, 5


class SpringKind:
    """Rotational spring kinds: panel bending, crease edge line, crease centre line, diagonal."""
    PANEL, CREASE_EDGE, CREASE_CENTRE, CREASE_DIAGONAL = 0, 1, 2, 3


class NodeKind:
    CORNER, CREASE, CENTRE = 0, 1, 2


# Crease-local node slots: 0 N11, 1 N12, 2 N21, 3 N22, 4 A, 5 B, 6 Ctr.
_N11, _N12, _N21, _N22, _A, _B, _CTR = range(7)
#: The ten crease bars (node slots) and their types, the slot table of theory 2.2.
_CREASE_BARS = np.array([[_N11, _A], [_N11, _CTR], [_N12, _CTR], [_N12, _B], [_A, _CTR],
                         [_B, _CTR], [_N21, _A], [_N21, _CTR], [_N22, _CTR], [_N22, _B]])
_CREASE_BAR_TYPES = np.array([2, 3, 3, 2, 4, 4, 2, 3, 3, 2])
#: Springs on crease bars #2, #3, #5, #6, #8, #9 (bar slot, (i, j, k, l) node slots).
_CREASE_SPRING_BARS = np.array([1, 2, 4, 5, 7, 8])
_CREASE_SPRINGS = np.array([[_N12, _CTR, _N11, _A], [_B, _CTR, _N12, _N11], [_N11, _CTR, _A, _N21],
                            [_N12, _B, _CTR, _N22], [_A, _CTR, _N21, _N22], [_B, _N22, _CTR, _N21]])
_CREASE_SPRING_KIND = np.array([3, 3, 2, 2, 3, 3])
_CREASE_TRIANGLES = np.array([[_CTR, _A, _N11], [_N21, _A, _CTR], [_N21, _CTR, _N22],
                              [_N22, _B, _CTR], [_N12, _CTR, _B], [_N12, _CTR, _N11]])


@dataclass(frozen=True, eq=False)
class BarHingeMesh:
    """Bar-and-hinge mesh of a :class:`~simulator.geometry.pattern.Pattern` (all indices 0-based).

    Immutable: every array is read-only (variants: :meth:`with_nodes`, ``dataclasses.replace``).

    Attributes
    ----------
    pattern : Pattern
    nodes : (n, 3) reference node positions [m]
    node_kind : (n,) :class:`NodeKind`
    node_vertex : (n,) pattern vertex of a corner node, -1 otherwise
    node_panel : (n,) panel of corner and centre nodes, -1 for crease nodes
    bars : (nb, 2) node pairs, smaller index first
    bar_type : (nb,) :class:`BarType`
    bar_crease : (nb,) edge id of panel-edge bars and of crease bars with a spring, else -1
    bar_panel : (nb,) panel of panel-edge bars and spokes, -1 for crease bars
    bar_length : (nb,) stored reference lengths [m] (never recomputed, theory 2.2)
    springs : (ns, 4) nodes (i, j, k, l) of the rotational springs, axis j-k; crease springs after
        the polarity fix (a fold towards +z increases their angle above pi)
    spring_bar : (ns,) bar carrying each spring
    spring_kind : (ns,) :class:`SpringKind`
    triangles : (nt, 3) crease triangles (six per crease) then panel fan triangles
    triangle_panel, triangle_crease : (nt,) owner panel / crease row, -1 where not applicable
    crease_ids : (C,) edge ids of the interior creases
    crease_nodes : (C, 7) nodes N11, N12, N21, N22, A, B, Ctr
    crease_bars : (C, 10) the ten crease bars (slot order of theory 2.2)
    crease_edge_bars : (C, 2) the two shrunk panel edges (edge1 of the earlier panel, edge2)
    crease_springs : (C, 8) springs in the reference ``creaseRef`` order: edge1, edge2,
        N11-Ctr, N12-Ctr, A-Ctr, B-Ctr, N21-Ctr, N22-Ctr
    crease_triangles : (C, 6)
    crease_panels : (C, 2) panels of edge1 and edge2
    panel_center : (P,) centre node of each panel
    panel_corner_start : (P + 1,) corner nodes of panel p are ``panel_corner_start[p]:[p+1]``
    """

    pattern: Pattern
    nodes: np.ndarray
    node_kind: np.ndarray
    node_vertex: np.ndarray
    node_panel: np.ndarray
    bars: np.ndarray
    bar_type: np.ndarray
    bar_crease: np.ndarray
    bar_panel: np.ndarray
    bar_length: np.ndarray
    springs: np.ndarray
    spring_bar: np.ndarray
    spring_kind: np.ndarray
    triangles: np.ndarray
    triangle_panel: np.ndarray
    triangle_crease: np.ndarray
    crease_ids: np.ndarray
    crease_nodes: np.ndarray
    crease_bars: np.ndarray
    crease_edge_bars: np.ndarray
    crease_springs: np.ndarray
    crease_triangles: np.ndarray
    crease_panels: np.ndarray
    panel_center: np.ndarray
    panel_corner_start: np.ndarray

    def __post_init__(self):
        """Lock every array: a mesh is immutable, so no caller can edit it in place."""
        for name, value in vars(self).items():
            if isinstance(value, np.ndarray):
                object.__setattr__(self, name, read_only(value))

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def n_dof(self) -> int:
        return 3 * len(self.nodes)

    @property
    def n_creases(self) -> int:
        return len(self.crease_ids)

    @cached_property
    def crease_row(self) -> np.ndarray:
        """Row in the crease arrays of each edge id, -1 for boundary edges, shape (n_edges,)."""
        row = np.full(self.pattern.n_edges, -1)
        row[self.crease_ids] = np.arange(self.n_creases)
        return read_only(row)

    @cached_property
    def spring_crease(self) -> np.ndarray:
        """Crease row of each spring (-1 for panel springs), shape (ns,)."""
        out = np.full(len(self.springs), -1)
        out[self.crease_springs] = np.arange(self.n_creases)[:, None]
        return read_only(out)

    @cached_property
    def fan_triangles(self) -> np.ndarray:
        """Indices (into ``triangles``) of the panel fan triangles."""
        return read_only(np.flatnonzero(self.triangle_panel >= 0))

    @cached_property
    def corner_nodes(self) -> np.ndarray:
        """Panel corner nodes (the first S nodes)."""
        return read_only(np.arange(self.panel_corner_start[-1]))

    def panel_nodes(self, panel: int) -> np.ndarray:
        """Corner nodes and centre node of one panel."""
        p = self.pattern.check_panel(panel)
        s = self.panel_corner_start
        return np.r_[np.arange(s[p], s[p + 1]), self.panel_center[p]]

    def crease_row_of(self, crease: int) -> int:
        """Row of a crease (edge id) in the crease arrays, validating the id."""
        return int(self.crease_row[self.pattern.check_crease(crease)])

    def with_nodes(self, nodes) -> "BarHingeMesh":
        """A copy with moved reference nodes but the SAME stored bar lengths.

        Reproduces the reference's post-meshing node edits (gripper, theory 10.6):
        bars then carry the originally meshed reference lengths.
        """
        nodes = np.array(nodes, dtype=float)          # a copy: the caller's array stays theirs
        if nodes.shape != self.nodes.shape or not np.all(np.isfinite(nodes)):
            raise PatternError(f"nodes must be a finite array of shape {self.nodes.shape}.")
        return replace(self, nodes=nodes)


def make_mesh(pattern: Pattern) -> BarHingeMesh:
    """Mesh a pattern with compliant creases (theory 2.2, ``mesh2D3D = 2``)."""
    if not isinstance(pattern, Pattern):
        raise PatternError(f"make_mesh expects a Pattern, got {type(pattern).__name__}.")
    sizes = pattern.corner_sizes
    S, P = int(sizes.sum()), pattern.n_panels
    ring = rings(sizes)
    prev, nxt, corner_panel = ring.prev, ring.nxt, ring.owner

    corners = _shrink_corners(pattern, prev, nxt)
    _check_shrunk_panels(pattern, corners)
    crease_ids = pattern.creases
    C = len(crease_ids)

    # Pass A: panel edge bars, bar q = (prev corner, corner q)
    edge_bars = np.sort(np.column_stack([prev, np.arange(S)]), axis=1)

    # Pass B: crease nodes (N11, N12, N21, N22, A, B, Ctr) and their positions
    pair, cn, crease_pos = _crease_nodes(pattern, corners, edge_bars)

    # Pass C: centres, spokes, fans
    centre = S + 3 * C + np.arange(P)
    centre_pos = centroids(corners, sizes)
    nodes = np.vstack([corners, crease_pos, centre_pos])
    spokes = np.column_stack([np.arange(S), centre[corner_panel]])
    last = ring.local == sizes[corner_panel] - 1                   # fan (centre, C_1, C_N) last
    fans = np.column_stack([centre[corner_panel],
                            np.where(last, ring.first[corner_panel], np.arange(S)),
                            np.where(last, np.arange(S), nxt)])

    bars = np.vstack([edge_bars, np.sort(cn[:, _CREASE_BARS].reshape(-1, 2), axis=1), spokes])
    bar_type = np.r_[np.full(S, 1), np.tile(_CREASE_BAR_TYPES, C), np.full(S, 5)]
    crease_bar_crease = np.where(_CREASE_BAR_TYPES == 2, -1, crease_ids[:, None]).ravel()
    bar_crease = np.r_[pattern.corner_edges, crease_bar_crease, np.full(S, -1)]
    bar_panel = np.r_[corner_panel, np.full(10 * C, -1), corner_panel]
    crease_bars = S + 10 * np.arange(C)[:, None] + np.arange(10)

    springs, spring_bar, spring_kind, crease_springs = _springs(
        nodes, cn, pair, centre[corner_panel], prev, nxt, crease_bars, crease_up(pattern))

    triangles = np.vstack([cn[:, _CREASE_TRIANGLES].reshape(-1, 3), fans])
    node_kind = np.r_[np.full(S, NodeKind.CORNER), np.full(3 * C, NodeKind.CREASE),
                      np.full(P, NodeKind.CENTRE)]
    mesh = BarHingeMesh(
        pattern=pattern, nodes=nodes, node_kind=node_kind,
        node_vertex=np.r_[pattern.corner_vertices, np.full(3 * C + P, -1)],
        node_panel=np.r_[corner_panel, np.full(3 * C, -1), np.arange(P)],
        bars=bars, bar_type=bar_type, bar_crease=bar_crease, bar_panel=bar_panel,
        bar_length=np.linalg.norm(nodes[bars[:, 1]] - nodes[bars[:, 0]], axis=1),
        springs=springs, spring_bar=spring_bar, spring_kind=spring_kind,
        triangles=triangles,
        triangle_panel=np.r_[np.full(6 * C, -1), corner_panel],
        triangle_crease=np.r_[np.repeat(np.arange(C), 6), np.full(S, -1)],
        crease_ids=crease_ids, crease_nodes=cn, crease_bars=crease_bars,
        crease_edge_bars=pair, crease_springs=crease_springs,
        crease_triangles=np.arange(6 * C).reshape(C, 6),
        crease_panels=corner_panel[pair], panel_center=centre,
        panel_corner_start=np.r_[0, np.cumsum(sizes)])
    _check_quality(mesh)
    logger.debug("meshed %d panels, %d creases: %d nodes, %d bars, %d springs, %d triangles",
                 P, C, len(nodes), len(bars), len(springs), len(triangles))
    return mesh


def _crease_nodes(pattern: Pattern, corners: np.ndarray, edge_bars: np.ndarray):
    """Pass B: the two shrunk edges of every crease, its 7 nodes and the 3 new positions.

    Returns ``pair`` (C, 2) edge bars (edge1 of the earlier panel, edge2), ``cn`` (C, 7) nodes
    N11, N12, N21, N22, A, B, Ctr and the (3C, 3) positions of A, B, Ctr per crease.
    """
    S, C = len(corners), len(pattern.creases)
    order = np.argsort(pattern.corner_edges, kind="stable")
    on_crease = pattern.is_crease[pattern.corner_edges[order]]
    pair = order[on_crease].reshape(C, 2)           # (edge1, edge2) bar ids per crease, ascending
    n11, n12 = edge_bars[pair[:, 0]].T
    n21, n22 = edge_bars[pair[:, 1]].T
    swap = (np.linalg.norm(corners[n11] - corners[n21], axis=1)
            >= np.linalg.norm(corners[n11] - corners[n22], axis=1))
    n21, n22 = np.where(swap, n22, n21), np.where(swap, n21, n22)
    a = S + 3 * np.arange(C)
    cn = np.column_stack([n11, n12, n21, n22, a, a + 1, a + 2])
    pos_a = (corners[n11] + corners[n21]) / 2
    pos_b = (corners[n12] + corners[n22]) / 2
    pos_c = (corners[n11] + corners[n12] + corners[n21] + corners[n22]) / 4
    return pair, cn, np.stack([pos_a, pos_b, pos_c], axis=1).reshape(-1, 3)


def _springs(nodes, cn, pair, corner_centre, prev, nxt, crease_bars, up):
    """Pass D: every spring (i, j, k, l), its bar and kind, sorted by bar; crease maps.

    ``corner_centre`` (S,) is the centre node of each corner's panel, ``up`` (C, 3) the top
    side of every crease (:func:`crease_up`).
    """
    S, C = len(prev), len(cn)
    edge_spr = np.vstack([
        np.column_stack([cn[:, _CTR], cn[:, _N11], cn[:, _N12], corner_centre[pair[:, 0]]]),
        np.column_stack([cn[:, _CTR], cn[:, _N22], cn[:, _N21], corner_centre[pair[:, 1]]])])
    spr_nodes = np.vstack([edge_spr, cn[:, _CREASE_SPRINGS].reshape(-1, 4),
                           np.column_stack([nxt, np.arange(S), corner_centre, prev])])
    spr_bar = np.r_[pair[:, 0], pair[:, 1], (crease_bars[:, _CREASE_SPRING_BARS]).ravel(),
                    S + 10 * C + np.arange(S)]
    spr_kind = np.r_[np.full(2 * C, SpringKind.CREASE_EDGE), np.tile(_CREASE_SPRING_KIND, C),
                     np.full(S, SpringKind.PANEL)]
    # The polarity fix applies to crease springs only: the reference keeps panel springs as
    # (p_{j+1}, p_j, centre, p_{j-1}); their rest angle is the initial angle, so it is immaterial.
    is_crease_spr = spr_kind != SpringKind.PANEL
    spr_nodes[is_crease_spr] = polarity_fix(nodes, spr_nodes[is_crease_spr],
                                             np.vstack([up, up, np.repeat(up, 6, axis=0)]))
    o = np.argsort(spr_bar, kind="stable")
    slot = np.empty(len(o), int)
    slot[o] = np.arange(len(o))
    # creaseRef order: edge1, edge2, then crease-bar springs #2, #3, #5, #6, #8, #9
    crease_springs = np.column_stack([slot[:C], slot[C:2 * C], slot[2 * C:8 * C].reshape(C, 6)])
    return spr_nodes[o], spr_bar[o], spr_kind[o], crease_springs


def _shrink_corners(pattern: Pattern, prev: np.ndarray, nxt: np.ndarray) -> np.ndarray:
    """Pass A: move every panel corner W/2 away from its adjacent creases.

    A straight corner (its two sides collinear: a vertex in the middle of a crease line, a
    T-junction) moves W/2 straight into the panel, so that the crease side stays a line at W/2
    from the crease; the reference's rule (an offset along the other side) has no offset there.
    """
    X = pattern.vertices[pattern.corner_vertices]
    e_in = pattern.corner_edges
    e_out = e_in[nxt]
    crease_in, crease_out = pattern.is_crease[e_in], pattern.is_crease[e_out]
    w_in, w_out = pattern.crease_width[e_in], pattern.crease_width[e_out]
    u_out = X[nxt] - X
    u_in = X[prev] - X
    u_out /= np.linalg.norm(u_out, axis=1, keepdims=True)
    u_in /= np.linalg.norm(u_in, axis=1, keepdims=True)
    cross = np.cross(u_in, u_out)
    sin = np.linalg.norm(cross, axis=1)
    collinear = np.all(cross == 0, axis=1)
    safe_sin = np.where(collinear, 1.0, sin)
    shift_in = np.where(collinear, 0.0, w_in / (2 * safe_sin))[:, None] * u_out
    shift_out = np.where(collinear, 0.0, w_out / (2 * safe_sin))[:, None] * u_in
    both = crease_in & crease_out
    out = X.copy()
    out[crease_in & ~crease_out] += shift_in[crease_in & ~crease_out]
    out[crease_out & ~crease_in] += shift_out[crease_out & ~crease_in]
    out[both] += (w_out[:, None] / 2 * u_in + w_in[:, None] / 2 * u_out)[both]
    straight = ((sin < 1e-6) | on_segment(X, X[prev], X[nxt], pattern.size)) \
        & (np.einsum("ij,ij->i", u_in, u_out) < 0) & (crease_in | crease_out)
    if straight.any():
        normal = area_vectors(X, pattern.corner_sizes)[rings(pattern.corner_sizes).owner]
        inward = np.cross(normal, u_out)
        inward /= np.linalg.norm(inward, axis=1, keepdims=True)
        w = (np.where(crease_in, w_in, 0) + np.where(crease_out, w_out, 0)) \
            / np.maximum(crease_in.astype(int) + crease_out, 1)
        out[straight] = X[straight] + (w / 2)[straight, None] * inward[straight]
    return out


def crease_up(pattern: Pattern) -> np.ndarray:
    """Top side (C, 3) of every crease: the sum of its two panels' top-side unit normals.

    For a flat pattern in the x-y plane this is exactly (0, 0, 2), and the polarity fix is the
    reference's (the z component); for a folded start shape it follows the sheet, so a rigid
    rotation or a mirror image of the shape gives the same springs. A crease folded flat
    (+-180 deg, the two normals opposite) has no top side and is refused, named.
    """
    area = area_vectors(pattern.vertices[pattern.corner_vertices], pattern.corner_sizes)
    top = area / np.linalg.norm(area, axis=1, keepdims=True) * pattern.panel_orientation[:, None]
    p = pattern.edge_panels[pattern.creases]
    up = top[p[:, 0]] + top[p[:, 1]]
    flat = np.flatnonzero(np.linalg.norm(up, axis=1) < 2e-3)        # |fold| > ~179.9 deg
    if len(flat):
        ids = capped(pattern.creases[flat].tolist(), 5)
        raise PatternError(f"crease(s) {ids} are folded flat (+-180 deg) in the start shape; "
                           f"{OPEN_START}.")
    return up


def polarity_fix(nodes: np.ndarray, springs: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Swap i and l where (X_j - X_i) x (X_k - X_j) points to the top side ``up`` (n, 3)."""
    xi, xj, xk = nodes[springs[:, 0]], nodes[springs[:, 1]], nodes[springs[:, 2]]
    z = np.einsum("ij,ij->i", np.cross(xj - xi, xk - xj), up)
    out = springs.copy()
    flip = z > 0
    out[flip, 0], out[flip, 3] = springs[flip, 3], springs[flip, 0]
    return out


def _shrunk_ok(pattern: Pattern, X: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(P,) True where the shrunk panel keeps its orientation and stays inside the panel."""
    sizes = pattern.corner_sizes
    ring = rings(sizes)
    fan = fan_normals(corners, sizes)
    normal0 = 2 * area_vectors(X, sizes)
    ok = (np.einsum("ij,ij->i", fan, normal0[ring.owner])
          > 1e-8 * np.einsum("ij,ij->i", normal0, normal0)[ring.owner])
    # every shrunk corner in one of the original panel's fan triangles (centre, C_j, C_j+1)
    o = centroids(X, sizes)
    point = np.repeat(np.arange(len(X)), sizes[ring.owner])             # corner of each pair
    start = np.repeat(ring.first[ring.owner], sizes[ring.owner])
    fan_of = start + (np.arange(len(point)) - np.repeat(np.cumsum(sizes[ring.owner])
                                                        - sizes[ring.owner], sizes[ring.owner]))
    c, a, b = o[ring.owner[fan_of]], X[fan_of], X[ring.nxt[fan_of]]
    n = np.cross(a - c, b - c)
    nn = np.maximum(np.einsum("ij,ij->i", n, n), 1e-300)
    y = corners[point] - c
    wa = np.einsum("ij,ij->i", np.cross(y, b - c), n) / nn
    wb = np.einsum("ij,ij->i", np.cross(a - c, y), n) / nn
    tol = 1e-9
    inside = np.zeros(len(X), bool)
    np.logical_or.at(inside, point, (wa >= -tol) & (wb >= -tol) & (wa + wb <= 1 + tol))
    return np.logical_and.reduceat(ok & inside, ring.first)


def _check_shrunk_panels(pattern: Pattern, corners: np.ndarray) -> None:
    """Crease widths must leave every shrunk panel with positive area, the same orientation,
    and its corners inside the panel; the message names every panel that fails (capped) and
    the widths that would fit."""
    X = pattern.vertices[pattern.corner_vertices]
    ok = _shrunk_ok(pattern, X, corners)
    if ok.all():
        return
    ring = rings(pattern.corner_sizes)
    lo, hi = np.zeros(len(ok)), np.ones(len(ok))   # the corner shifts are linear in the widths
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        fits = _shrunk_ok(pattern, X, X + mid[ring.owner, None] * (corners - X))
        lo, hi = np.where(fits, mid, lo), np.where(fits, hi, mid)
    bad = np.flatnonzero(~ok)
    creases = {int(p): [int(e) for e in np.unique(pattern.corner_edges[ring.owner == p])
                        if pattern.is_crease[e]] for p in bad}
    fit = {p: 0.99 * lo[p] * pattern.crease_width[ids].min() for p, ids in creases.items()}
    p = min(fit, key=fit.get)                      # the tightest panel, in detail
    w = pattern.crease_width[creases[p]]
    across = np.ptp(X[ring.owner == p], axis=0).max()
    raise PatternError(
        f"panel(s) {capped(bad.tolist())} vanish, turn inside out or have corners outside "
        f"themselves after shrinking by half the crease widths; the tightest, panel {p} "
        f"({_um(across)} um across): its creases {creases[p]} are {_um(w)} um wide, at most about "
        f"{_um(0.99 * lo[p] * w)} um fit; reduce the crease widths (crease_width) or "
        "enlarge the panels.")


def _um(x) -> str:
    x = np.atleast_1d(np.asarray(x, float)) * 1e6
    return "/".join(f"{v:.4g}" for v in np.unique(np.round(x, 6)))


def _check_quality(mesh: BarHingeMesh) -> None:
    """No zero-length bar and no zero-area triangle reaches a solver: name the faulty place."""
    x, size = mesh.nodes, mesh.pattern.size
    length = np.linalg.norm(x[mesh.bars[:, 1]] - x[mesh.bars[:, 0]], axis=1)
    t = mesh.triangles
    area2 = np.linalg.norm(np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]]), axis=1)
    side = np.max([np.linalg.norm(x[t[:, i]] - x[t[:, (i + 1) % 3]], axis=1) for i in range(3)],
                  axis=0)
    bad_bar = np.flatnonzero(length <= 1e-9 * size)
    bad_tri = np.flatnonzero(area2 <= 1e-9 * side**2)
    if not len(bad_bar) and not len(bad_tri):
        return
    if len(bad_tri):
        k, what = int(bad_tri[0]), "a zero-area triangle"
        crease, panel = int(mesh.triangle_crease[k]), int(mesh.triangle_panel[k])
    else:
        k, what = int(bad_bar[0]), "a zero-length bar"
        panel = int(mesh.bar_panel[k])
        rows = np.flatnonzero((mesh.crease_bars == k).any(axis=1))
        crease = int(rows[0]) if len(rows) else -1
    pat = mesh.pattern
    if crease >= 0:
        e = int(mesh.crease_ids[crease])
        where = f"crease {e} (vertices {pat.edges[e].tolist()})"
    else:
        where = f"panel {panel} (vertices {list(pat.panels[panel])})"
    raise PatternError(f"mesh quality: {where} has {what}; its corners coincide or lie on a "
                       "line (a vertex in the middle of a crease line meshed without room, or "
                       "creases meeting at a zero angle); fix these vertices.")
