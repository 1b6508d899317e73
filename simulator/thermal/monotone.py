"""Monotone sheet conduction (theory 4.2): the P1 conduction of the sheet on a triangulation of
the mesh nodes whose couplings are all non-positive (an M-matrix), condensed back to the nodes.

The T3 matrix of a triangle couples its nodes ``j, k`` by ``-k t cot(theta_i) / 2``, with
``theta_i`` the angle at the third node. Summed over the triangles of an edge the coupling is
``-sum k t cot / 2``; where an edge's opposite angles are too obtuse it is positive, the
assembled conduction is not an M-matrix and heating can put a node below room temperature (the
discrete maximum principle fails). :func:`monotone_conduction` removes every positive
coupling:

1. *Flips.* Inside a region of one material and thickness (a panel's fan, a crease's six
   triangles) an edge whose two opposite angles add up to more than 180 degrees is flipped
   (Lawson's algorithm: the region's Delaunay triangulation of the same nodes, on which every
   inner edge has ``cot a + cot b >= 0``). Edges between regions and on the sheet's outline
   are never flipped: a flip would mix two materials.
2. *Steiner points.* A region-boundary edge whose coupling is still positive (an obtuse angle
   opposite it on one side, not made up for on the other) is split at the foot of the
   altitude from its most obtuse opposite corner (kept within the middle 60 % of the edge),
   which makes that corner's two new angles acute; the regions on both sides are flipped
   again. Repeated until no coupling is positive (:data:`MAX_ROUNDS` rounds at most).
3. *Condensation.* The Steiner points carry no heat capacity, loss or heat input; each group
   of them that shares triangles is eliminated (a Schur complement, which keeps an M-matrix an
   M-matrix) into one block on the mesh nodes of its triangles.

The result is the P1 (Galerkin) conduction on a finer triangulation of the same sheet, so it
converges to the same temperature field as the T3 one under mesh refinement and reproduces
linear fields exactly where the conductivity is uniform. The triangulation is chosen once, at
the mesh's own positions; at any shape its triangles are built from the current positions of
their corners (a Steiner point stays at its fraction of its mesh edge).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from .. import _jit
from ..linalg.small_solve import schur_complements

__all__ = ["MonotoneConduction", "corner_cotangents", "delaunay_flips",
           "monotone_conduction", "t3_matrices"]

logger = logging.getLogger(__name__)

#: Rounds of edge splitting before giving up (with a warning naming what is left).
MAX_ROUNDS = 30
#: A coupling counts as positive above this fraction of the largest ``|k t cot| / 2``.
WEIGHT_TOL = 1e-10
#: A Steiner point splits an edge no closer to its ends than this fraction of it.
_SPLIT_CLAMP = 0.2


def corner_cotangents(P) -> np.ndarray:
    """Cotangent of the angle at each corner of triangles ``P`` (..., 3, 3) [m]: (..., 3),
    negative at an obtuse corner."""
    P = np.asarray(P, float)
    u = np.roll(P, -1, axis=-2) - P
    v = np.roll(P, 1, axis=-2) - P
    return (np.einsum("...k,...k->...", u, v)
            / np.linalg.norm(np.cross(u, v), axis=-1))


def t3_matrices(P, kt) -> np.ndarray:
    """T3 conduction matrices [W/K] of triangles with corners ``P`` (m, 3, 3) [m] and ``k t``
    (m,) [W/K]: ``k t (e_i . e_j) / (4 A)``, ``e_i`` the edge opposite corner ``i``, (m, 3, 3)."""
    P = np.asarray(P, float)
    e = np.empty_like(P)
    e[:, 0] = P[:, 2] - P[:, 1]
    e[:, 1] = P[:, 0] - P[:, 2]
    e[:, 2] = P[:, 1] - P[:, 0]
    u, v = e[:, 2], -e[:, 1]                                      # P1 - P0, P2 - P0
    cross = np.stack([u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1], u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
                      u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]], axis=1)
    scale = np.asarray(kt, float) / (2 * np.sqrt(np.einsum("mk,mk->m", cross, cross)))
    return scale[:, None, None] * np.einsum("mik,mjk->mij", e, e)


class _Triangulation:
    """Triangles over points (the mesh nodes, then Steiner points on mesh edges), each with a
    region and ``k t``; Lawson flips inside regions, splits of region-boundary edges."""

    def __init__(self, x, tri, region, kt):
        x = np.asarray(x, float)
        n = len(x)
        #: per point: (a, b, s), its position x_a + s (x_b - x_a); a mesh node is (i, i, 0)
        self.where = [(i, i, 0.0) for i in range(n)]
        self.X = [tuple(map(float, p)) for p in x]
        self.tri = [list(map(int, t)) for t in tri]
        self.region = [int(r) for r in region]
        self.kt = [float(k) for k in kt]
        self.flips = 0
        #: per triangle its corners' cotangents, or None until asked for (and after a flip
        #: or split rewrote it): every edge check reads them, every round checks every edge
        self._cots = [None] * len(self.tri)
        self.tol = WEIGHT_TOL * float(np.abs(np.asarray(kt)[:, None] * corner_cotangents(
            x[np.asarray(tri)])).max(initial=0.0)) / 2

    def edges(self) -> dict:
        """Edge ``(i, j)``, i < j -> [(triangle, corner opposite it), ...]."""
        out = {}
        for t, (a, b, c) in enumerate(self.tri):
            for corner, key in enumerate(((b, c) if b < c else (c, b),
                                          (c, a) if c < a else (a, c),
                                          (a, b) if a < b else (b, a))):
                sides = out.get(key)
                if sides is None:
                    out[key] = [(t, corner)]
                else:
                    sides.append((t, corner))
        return out

    def cot(self, t, corner) -> float:
        """Cotangent of the angle of triangle ``t`` at ``corner`` (plain floats, kept per
        triangle until a flip or split rewrites it: this runs for every edge check)."""
        cots = self._cots[t]
        if cots is None:
            cots = self._cots[t] = tuple(self._cot(t, k) for k in range(3))
        return cots[corner]

    def _cot(self, t, corner) -> float:
        tri = self.tri[t]
        a, b, c = self.X[tri[corner]], self.X[tri[(corner + 1) % 3]], self.X[tri[(corner + 2) % 3]]
        ux, uy, uz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
        vx, vy, vz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
        cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        return (ux * vx + uy * vy + uz * vz) / math.sqrt(cx * cx + cy * cy + cz * cz)

    def weight(self, sides) -> float:
        """``sum k t cot / 2`` [W/K] of an edge's sides (its coupling is minus this)."""
        total = 0
        for t, c in sides:
            total += self.kt[t] * self.cot(t, c) / 2
        return total

    def constrained(self, sides) -> bool:
        """An edge of the outline or between two regions: never flipped."""
        return len(sides) == 1 or self.region[sides[0][0]] != self.region[sides[1][0]]

    def flip(self, sides) -> bool:
        """Flip the edge of two triangles ``sides`` if the quad they form is strictly convex
        (laid out flat along the edge); returns whether it did."""
        (t1, c1), (t2, c2) = sides
        k, m = self.tri[t1][c1], self.tri[t2][c2]
        a, b = self.tri[t1][(c1 + 1) % 3], self.tri[t1][(c1 + 2) % 3]    # t1 = (k, a, b)
        X = np.array([self.X[i] for i in (a, b, k, m)])
        ab = X[1] - X[0]
        length = float(np.linalg.norm(ab))
        rel = X[2:] - X[0]
        along = rel @ ab / length
        height = np.linalg.norm(np.cross(rel, ab), axis=1) / length
        # where the segment k m crosses the line a b, in the layout with k and m either side
        cross = along[0] + (along[1] - along[0]) * height[0] / (height[0] + height[1])
        if not 1e-9 * length < cross < (1 - 1e-9) * length:
            return False
        self.tri[t1], self.tri[t2] = [k, a, m], [k, m, b]
        self._cots[t1] = self._cots[t2] = None
        self.flips += 1
        return True

    def make_delaunay(self) -> None:
        """Lawson flips of every unconstrained edge with ``cot a + cot b < 0``: a stack of
        edges to check, starting with all; a flip puts the four outer edges of its quad back."""
        edges = self.edges()
        stack = list(edges)
        for _ in range(100 * len(self.tri) + 100 + len(stack)):
            if not stack:
                return
            e = stack.pop()
            sides = edges.get(e)
            if sides is None or len(sides) != 2 or self.constrained(sides) \
                    or self.weight(sides) >= -self.tol:
                continue
            (t1, _), (t2, _) = sides
            old = [self.tri[t1][:], self.tri[t2][:]]
            if not self.flip(sides):
                continue
            for t, corners in zip((t1, t2), old):
                for c in range(3):
                    i, j = corners[(c + 1) % 3], corners[(c + 2) % 3]
                    key = (min(i, j), max(i, j))
                    edges[key] = [(u, v) for u, v in edges[key] if u != t]
                    if not edges[key]:
                        del edges[key]
            for t in (t1, t2):
                corners = self.tri[t]
                for c in range(3):
                    i, j = corners[(c + 1) % 3], corners[(c + 2) % 3]
                    key = (min(i, j), max(i, j))
                    edges.setdefault(key, []).append((t, c))
                    if key != e:
                        stack.append(key)
        logger.warning("monotone conduction: the edge flips did not terminate")

    def split(self, edge, sides) -> None:
        """Add a Steiner point on the constrained ``edge`` at the foot of its most obtuse
        opposite corner (within the middle of the edge) and split its triangles there."""
        t, c = min(sides, key=lambda s: self.kt[s[0]] * self.cot(*s))
        p, q = edge
        X = np.array([self.X[i] for i in (p, q, self.tri[t][c])])
        d = X[1] - X[0]
        f = float(np.clip((X[2] - X[0]) @ d / (d @ d), _SPLIT_CLAMP, 1 - _SPLIT_CLAMP))
        (a, b), sp, sq = self._mesh_edge(p, q)
        s = sp + f * (sq - sp)
        self.where.append((a, b, s))
        xa, xb = np.array(self.X[a]), np.array(self.X[b])
        self.X.append(tuple(map(float, xa + s * (xb - xa))))
        new = len(self.X) - 1
        for t, c in sides:
            corners = self.tri[t]
            apex, u, v = corners[c], corners[(c + 1) % 3], corners[(c + 2) % 3]
            self.tri[t] = [apex, u, new]
            self.tri.append([apex, new, v])
            self._cots[t] = None
            self._cots.append(None)
            self.region.append(self.region[t])
            self.kt.append(self.kt[t])

    def _mesh_edge(self, p, q):
        """The mesh edge ``(a, b)`` that the segment between points ``p`` and ``q`` lies on,
        and their parameters along it."""
        wp, wq = self.where[p], self.where[q]
        if wp[0] != wp[1]:
            a, b = wp[0], wp[1]
        elif wq[0] != wq[1]:
            a, b = wq[0], wq[1]
        else:
            a, b = p, q
        return (a, b), self._param(wp, a), self._param(wq, a)

    @staticmethod
    def _param(w, a) -> float:
        """Parameter from ``a`` of a point with ``where`` entry ``w`` on an edge at ``a``."""
        if w[0] == w[1]:
            return 0.0 if w[0] == a else 1.0
        return w[2] if w[0] == a else 1.0 - w[2]

    def still_sides(self, edge, sides) -> bool:
        """Whether every ``(triangle, corner)`` of ``sides`` still has ``edge`` opposite that
        corner: then they are the edge's sides in :meth:`edges` (a split rewrites the
        triangles it touches, so entries made before it are checked, and :meth:`edges` is
        rebuilt only when one is stale, not for every edge: the rebuild for every edge made
        the build quadratic in the mesh size)."""
        for t, c in sides:
            corners = self.tri[t]
            i, j = corners[(c + 1) % 3], corners[(c + 2) % 3]
            if (min(i, j), max(i, j)) != edge:
                return False
        return True

    def bad_edges(self, edges=None) -> list:
        """Edges whose coupling is positive, with their sides (of ``edges``, default
        :meth:`edges`)."""
        edges = self.edges() if edges is None else edges
        return [(e, s) for e, s in edges.items() if self.weight(s) < -self.tol]


def delaunay_flips(x, tri, region) -> np.ndarray:
    """The triangles ``tri`` (m, 3) of nodes at ``x`` (n, 3) [m] after Lawson flips inside each
    region (``region`` (m,): edges between regions and on the outline are kept): every inner
    edge of a region then has ``cot a + cot b >= 0`` (step 1 of the module docstring), (m, 3)."""
    tr = _Triangulation(x, tri, region, np.ones(len(tri)))
    tr.make_delaunay()
    return np.array(tr.tri, dtype=np.int64)


def monotone_conduction(x, tri, region, kt) -> "MonotoneConduction":
    """The monotone conduction of the module docstring for the triangles ``tri`` (m, 3) of
    nodes at ``x`` (n, 3) [m] with their regions (m,) and ``k t`` (m,) [W/K]."""
    x = np.asarray(x, float)
    tr = _Triangulation(x, tri, region, kt)
    tr.make_delaunay()
    for _ in range(MAX_ROUNDS):
        edges = tr.edges()
        bad = tr.bad_edges(edges)
        if not bad:
            break
        for e, _sides in bad:
            sides = edges.get(e)
            if sides is not None and not tr.still_sides(e, sides):   # a split changed them
                edges = tr.edges()
                sides = edges.get(e)
            if sides is not None and tr.constrained(sides) and tr.weight(sides) < -tr.tol:
                tr.split(e, sides)
        tr.make_delaunay()
    bad = tr.bad_edges()
    if bad:
        logger.warning("monotone conduction: %d edges keep a positive coupling after %d rounds "
                       "(largest %.3g W/K)", len(bad), MAX_ROUNDS,
                       -min(tr.weight(s) for _, s in bad))
    return MonotoneConduction(len(x), tr)


@dataclass(frozen=True)
class _Group:
    """Groups of Steiner points condensed in one batch, padded to common sizes: ``k_o`` mesh
    nodes (a padding slot repeats the group's first node, with zero entries) and ``k_s``
    Steiner points (a padding slot has a unit diagonal and nothing else)."""

    nodes: np.ndarray        # (p, k_o) mesh nodes of each group
    triangles: np.ndarray    # (t,) triangles (rows of MonotoneConduction.corners) of all
    flat: np.ndarray         # (t, 3, 3) their entries' positions in the (p, k, k) matrices
    pad: np.ndarray          # positions of the padding Steiner slots' unit diagonal
    k_o: int
    k_s: int


class MonotoneConduction:
    """The conduction of :func:`monotone_conduction`, condensed to the mesh nodes.

    Attributes
    ----------
    corners : (m', 3) int array
        Triangles of the triangulation: point ids, mesh nodes below ``n_nodes``, Steiner
        points above.
    kt : (m',) float array
        Their ``k t`` [W/K].
    steiner : (s, 3) array
        Mesh edge ``(a, b)`` and parameter of every Steiner point (at ``x_a + s (x_b - x_a)``).
    families : list of (p, k) int arrays
        Mesh nodes of the elements that sum to the conduction: the triangles without Steiner
        points (k = 3), then the condensed groups, one array per size
        (:meth:`element_values`).
    flips : int
        Edge flips made.
    """

    def __init__(self, n_nodes: int, tr: _Triangulation):
        self.n_nodes = n = int(n_nodes)
        self.corners = np.array(tr.tri, dtype=np.int64)
        self.kt = np.array(tr.kt)
        where = tr.where[n:]
        self.steiner = np.array(where, float).reshape(-1, 3)
        self._ends = np.ascontiguousarray(self.steiner[:, :2].astype(np.int64).T)
        self._fraction = np.ascontiguousarray(self.steiner[:, 2:3])
        self.flips = tr.flips
        plain = np.all(self.corners < n, axis=1)
        self._plain = np.flatnonzero(plain)
        self.groups = _groups(self.corners, n, np.flatnonzero(~plain))
        self.families = [self.corners[self._plain]] + [g.nodes for g in self.groups]

    @property
    def n_steiner(self) -> int:
        """Number of Steiner points."""
        return len(self.steiner)

    def positions(self, x) -> np.ndarray:
        """Positions of all points [m], (n + s, 3), at node positions ``x`` (n, 3) [m]."""
        x = np.asarray(x, float)
        if not self.n_steiner:
            return x
        xa = x[self._ends[0]]
        return np.concatenate([x, xa + self._fraction * (x[self._ends[1]] - xa)])

    def triangle_matrices(self, x, compiled=None) -> np.ndarray:
        """T3 matrices [W/K] of every triangle of the triangulation at node positions ``x``
        (n, 3) [m], (m', 3, 3): by a compiled kernel when ``compiled`` (default: when the
        numba backend is selected), else by numpy (:func:`t3_matrices` of :meth:`positions`,
        the checked twin: the same formulas, its sums in another order)."""
        if compiled is None:
            compiled = _jit.numba_selected()
        kernel = _t3_kernel_compiled() if compiled else None
        if kernel is None:
            return t3_matrices(self.positions(x)[self.corners], self.kt)
        x = np.require(x, np.float64, ("C", "W"))
        out = np.empty((len(self.corners), 3, 3))
        kernel(x, self._ends[0], self._ends[1], self._fraction[:, 0], self.corners, self.kt,
               np.empty((len(x) + self.n_steiner, 3)), out)
        return out

    def element_values(self, x) -> list:
        """The element matrices [W/K] of :attr:`families` at node positions ``x`` (n, 3) [m]:
        the T3 matrices of the triangles without Steiner points, then one (p, k_o, k_o)
        Schur complement per group."""
        K = self.triangle_matrices(x)
        out = [K[self._plain]]
        for g in self.groups:
            k = g.k_o + g.k_s
            F = np.bincount(g.flat.ravel(), K[g.triangles].ravel(), minlength=len(g.nodes) * k * k)
            F[g.pad] = 1.0
            out.append(schur_complements(F.reshape(len(g.nodes), k, k), g.k_o))
        return out


def _t3_kernel(x, ends_a, ends_b, fraction, corners, kt, points, out):
    """Compiled :meth:`MonotoneConduction.triangle_matrices`: the points (mesh nodes ``x``,
    then the Steiner points at ``x_a + s (x_b - x_a)``) into ``points``, and into ``out`` the
    T3 matrix ``k t (e_i . e_j) / (4 A)`` of every triangle ``corners`` (:func:`t3_matrices`,
    the same formulas)."""
    n = x.shape[0]
    for i in range(n):
        for k in range(3):
            points[i, k] = x[i, k]
    for p in range(ends_a.shape[0]):
        for k in range(3):
            xa = x[ends_a[p], k]
            points[n + p, k] = xa + fraction[p] * (x[ends_b[p], k] - xa)
    e = np.empty((3, 3))
    for t in range(corners.shape[0]):
        c0, c1, c2 = corners[t, 0], corners[t, 1], corners[t, 2]
        for k in range(3):
            e[0, k] = points[c2, k] - points[c1, k]
            e[1, k] = points[c0, k] - points[c2, k]
            e[2, k] = points[c1, k] - points[c0, k]
        ux, uy, uz = e[2, 0], e[2, 1], e[2, 2]                 # P1 - P0
        vx, vy, vz = -e[1, 0], -e[1, 1], -e[1, 2]              # P2 - P0
        cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        scale = kt[t] / (2 * math.sqrt(cx * cx + cy * cy + cz * cz))
        for i in range(3):
            for j in range(3):
                out[t, i, j] = scale * (e[i, 0] * e[j, 0] + e[i, 1] * e[j, 1]
                                        + e[i, 2] * e[j, 2])


_t3_compiled = None


def _t3_kernel_compiled():
    """The compiled :func:`_t3_kernel` (compiled or loaded on the first call), None if numba
    cannot compile it (numpy's path then)."""
    global _t3_compiled
    if _t3_compiled is None:
        def build():
            from numba import njit
            return njit("void(f8[:, ::1], i8[::1], i8[::1], f8[::1], i8[:, ::1], f8[::1], "
                        "f8[:, ::1], f8[:, :, ::1])", cache=True, fastmath=False)(_t3_kernel)
        _t3_compiled = _jit.compile_kernel("monotone conduction kernel", build, "using numpy") \
            or False
    return _t3_compiled or None


def _groups(corners, n, triangles) -> list:
    """Condensation groups of the triangles with Steiner points: Steiner points sharing a
    triangle are eliminated together, into a block on the mesh nodes of their triangles."""
    parent = {}

    def find(p):
        parent.setdefault(p, p)
        while parent[p] != p:
            parent[p] = parent[parent[p]]
            p = parent[p]
        return p

    for t in triangles:
        s = [int(p) for p in corners[t] if p >= n]
        for p in s[1:]:
            parent[find(p)] = find(s[0])
    members = {}
    for t in triangles:
        root = find(int(next(p for p in corners[t] if p >= n)))
        members.setdefault(root, []).append(int(t))
    specs = {}
    for ts in members.values():
        pts = np.unique(corners[ts])
        nodes, steiner = pts[pts < n], pts[pts >= n]
        key = (_bucket(len(nodes)), _bucket(len(steiner)))     # a few batches, padded
        specs.setdefault(key, []).append((nodes, steiner, np.array(ts)))
    return [_group(group, k_o, k_s, corners) for (k_o, k_s), group in sorted(specs.items())]


def _bucket(k: int) -> int:
    """The padded size of ``k``: the next power of two up to 8, else the next multiple of 8
    (a few batches of small groups, little padding of large ones)."""
    k = int(k)
    return 1 << max(k - 1, 0).bit_length() if k <= 8 else -(-k // 8) * 8


def _group(specs, k_o, k_s, corners) -> _Group:
    """One :class:`_Group` of ``specs`` (mesh nodes, Steiner points, triangles), padded."""
    k = k_o + k_s
    nodes, tris, flat, pad = [], [], [], []
    for p, (own, steiner, ts) in enumerate(specs):
        nodes.append(np.r_[own, np.full(k_o - len(own), own[0])])
        index = dict(zip(own.tolist(), range(len(own))))
        index.update(zip(steiner.tolist(), range(k_o, k_o + len(steiner))))
        local = np.vectorize(index.__getitem__)(corners[ts])             # (t, 3)
        tris.append(ts)
        flat.append(p * k * k + local[:, :, None] * k + local[:, None, :])
        pad += [p * k * k + i * (k + 1) for i in range(k_o + len(steiner), k)]
    return _Group(np.array(nodes), np.concatenate(tris), np.concatenate(flat),
                  np.array(pad, dtype=np.int64), k_o, k_s)
