"""Origami pattern input: vertices, polygonal panels and crease / panel data.

A :class:`Pattern` is the user-facing description of an origami sheet before
meshing. Creases are the edges shared by two panels. Edges are numbered in the
reference implementation's first-seen order (theory 2.1): for every
panel ``C_1..C_N`` in order, visit ``(C_1, C_N)``, then ``(C_1, C_2)``, ...,
``(C_{N-1}, C_N)``; an edge gets the next id when first seen. Edge ids are
0-based (reference id - 1); the ids of interior edges are the crease ids.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .._arrays import read_only
from ..errors import PatternError
from .materials import SU8, Material
from .pattern_checks import check_geometry
from .polygons import centroids, fan_normals, rings

__all__ = ["Pattern"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class Pattern:
    """Flat (or gently non-flat) origami pattern with compliant creases (immutable; its arrays
    are read-only).

    Parameters
    ----------
    vertices : array_like, shape (n, 3) or (n, 2)
        Vertex coordinates [m]; 2-D input is placed at z = 0.
    panels : sequence of sequence of int
        Each panel is a polygon given by >= 3 vertex indices (0-based) in cyclic order.
    crease_width : float, mapping or array_like
        Crease width W [m] of every interior crease: a scalar for all creases, a mapping
        ``{crease_id: width}`` covering every crease, or an array indexed by edge id
        (entries of boundary edges are ignored).
    crease_thickness : float, mapping or array_like
        Crease (actuator) thickness t_c [m], given like ``crease_width``.
    panel_thickness : float or array_like, shape (n_panels,)
        Panel thickness t_p [m].
    panel_material : Material or sequence of Material
        Panel material, one for all panels or one per panel.
    crease_material : Material
        Material used for the crease bars and springs (its modulus and Poisson ratio).
    edge_assignment : sequence of str, optional
        FOLD assignment letter of every edge, in edge-id order: ``"M"``, ``"V"`` or ``"U"``
        for interior creases, ``"B"`` or ``"C"`` for boundary edges. Default ``"U"`` / ``"B"``.
        Design data only: the mechanics does not read it.
    edge_fold_angle : array_like, shape (n_edges,), optional
        Design (target) fold angle of every edge [rad], in [-pi, pi], <= 0 for ``"M"``, >= 0
        for ``"V"``, 0 on boundary edges; default -pi for ``"M"``, pi for ``"V"``, else 0 (the
        FOLD convention). Design data only: the start shape's fold angles are those of the
        vertex coordinates.
    metadata : mapping, optional
        Extra FOLD fields (other namespaces, ``file_*`` / ``frame_*`` data) kept so that a file
        read with :func:`~simulator.io.fold.read_fold` is written back with them.

    Attributes
    ----------
    edges : ndarray, shape (n_edges, 2)
        Vertex pair of every edge, smaller index first, in edge-id order.
    edge_panels : ndarray, shape (n_edges, 2)
        The panels sharing each edge, in panel order; -1 in column 1 for boundary edges.
    creases : ndarray
        Edge ids of the interior creases, ascending.
    """

    vertices: np.ndarray
    panels: tuple
    crease_width: object
    crease_thickness: object
    panel_thickness: object
    panel_material: object = SU8
    crease_material: Material = SU8
    edge_assignment: object = None
    edge_fold_angle: object = None
    metadata: Mapping = field(default_factory=dict)
    _edge_of_corner: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        verts = _as_vertices(self.vertices)
        panels = _as_panels(self.panels, len(verts))
        object.__setattr__(self, "vertices", verts)
        object.__setattr__(self, "panels", panels)
        self._enumerate_edges()
        check_geometry(self)
        object.__setattr__(self, "panel_thickness", self._per_panel_positive(
            self.panel_thickness, "panel_thickness"))
        object.__setattr__(self, "panel_material", self._per_panel_material(self.panel_material))
        if not isinstance(self.crease_material, Material):
            raise PatternError(f"crease_material must be a Material, got {self.crease_material!r}.")
        for name in ("crease_width", "crease_thickness"):
            object.__setattr__(self, name, self._per_crease_positive(getattr(self, name), name))
        _set_fold_data(self)
        for name in ("edges", "edge_panels", "_edge_of_corner", "panel_thickness", "crease_width",
                     "crease_thickness"):
            object.__setattr__(self, name, read_only(getattr(self, name)))

    # ------------------------------------------------------------------ topology
    def _enumerate_edges(self):
        """Number edges in first-seen order (theory 2.1), vectorised over all corners."""
        n_v = len(self.vertices)
        sizes = np.array([len(p) for p in self.panels])
        flat = np.concatenate(self.panels)
        ring = rings(sizes)
        prev = flat[ring.prev]
        # visiting order per panel: (C1, CN) first, then (C_{j-1}, C_j) for j = 2..N; that is the
        # edge *ending* at corner j in corner order, which is exactly (prev, flat).
        key = np.minimum(prev, flat) * n_v + np.maximum(prev, flat)
        uniq, first, inverse, counts = np.unique(key, return_index=True, return_inverse=True,
                                                 return_counts=True)
        order = np.argsort(first, kind="stable")
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        edge_of_corner = rank[inverse]
        edges = np.column_stack([uniq[order] // n_v, uniq[order] % n_v])
        panel_of_corner = ring.owner
        if np.any(counts > 2):
            bad = order[np.flatnonzero(counts[order] > 2)[0]]
            e = rank[bad]
            users = np.unique(panel_of_corner[edge_of_corner == e])
            raise PatternError(
                f"Edge between vertices {edges[e, 0]} and {edges[e, 1]} is shared by panels "
                f"{users.tolist()}; an edge may belong to at most two panels. Split the pattern so "
                "that each crease joins exactly two panels.")
        edge_panels = np.full((len(edges), 2), -1)
        o = np.lexsort((panel_of_corner, edge_of_corner))
        e_sorted, p_sorted = edge_of_corner[o], panel_of_corner[o]
        is_first = np.r_[True, e_sorted[1:] != e_sorted[:-1]]
        edge_panels[e_sorted[is_first], 0] = p_sorted[is_first]
        edge_panels[e_sorted[~is_first], 1] = p_sorted[~is_first]
        object.__setattr__(self, "_edge_of_corner", edge_of_corner)
        object.__setattr__(self, "edges", edges)
        object.__setattr__(self, "edge_panels", edge_panels)

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_panels(self) -> int:
        return len(self.panels)

    @property
    def n_edges(self) -> int:
        return len(self.edges)

    @cached_property
    def is_crease(self) -> np.ndarray:
        """Boolean mask over edges: True for interior creases (edge shared by two panels)."""
        return read_only(self.edge_panels[:, 1] >= 0)

    @cached_property
    def creases(self) -> np.ndarray:
        """Edge ids of the interior creases, ascending."""
        return read_only(np.flatnonzero(self.is_crease))

    @cached_property
    def panel_orientation(self) -> np.ndarray:
        """+1 / -1 per panel: the factor turning its winding normal into the sheet's top side
        (:func:`~simulator.geometry.orientation.panel_orientation`); fold angles are positive
        towards the top (valley)."""
        from .orientation import panel_orientation

        return read_only(panel_orientation(self))

    @cached_property
    def corner_sizes(self) -> np.ndarray:
        """Number of corners of each panel, shape (n_panels,)."""
        return read_only([len(p) for p in self.panels])

    @cached_property
    def corner_vertices(self) -> np.ndarray:
        """Vertex id of every panel corner, panels concatenated in order, shape (S,)."""
        return read_only(np.concatenate(self.panels))

    @cached_property
    def corner_edges(self) -> np.ndarray:
        """Edge id of the edge ending at each corner, (C_{j-1}, C_j), shape (S,)."""
        return self._edge_of_corner

    # ------------------------------------------------------------------ addressing
    def check_panel(self, panel, what: str = "panel") -> int:
        """Return ``panel`` as int if it is a valid panel id, else raise PatternError."""
        if not _is_int(panel) or not 0 <= int(panel) < self.n_panels:
            raise PatternError(f"Unknown {what} id {panel!r}: panel ids are 0..{self.n_panels - 1}.")
        return int(panel)

    def check_crease(self, crease, what: str = "crease") -> int:
        """Return ``crease`` as int if it is an interior crease id, else raise PatternError."""
        if not _is_int(crease) or not 0 <= int(crease) < self.n_edges:
            raise PatternError(
                f"Unknown {what} id {crease!r}: edge ids are 0..{self.n_edges - 1}, interior "
                f"creases are {self.creases.tolist()}.")
        if not self.is_crease[int(crease)]:
            v = self.edges[int(crease)]
            raise PatternError(
                f"Edge {crease} (vertices {v[0]}-{v[1]}) is a boundary edge, not a crease; interior "
                f"creases are {self.creases.tolist()}.")
        return int(crease)

    def crease_between(self, panel_a: int, panel_b: int) -> int:
        """Id of the crease shared by two panels."""
        a, b = self.check_panel(panel_a), self.check_panel(panel_b)
        hit = np.flatnonzero(np.all(np.sort(self.edge_panels, axis=1) == sorted((a, b)), axis=1))
        if len(hit) == 0:
            nb = sorted({int(q) for e in np.flatnonzero((self.edge_panels == a).any(axis=1))
                         for q in self.edge_panels[e] if q not in (a, -1)})
            raise PatternError(f"Panels {a} and {b} do not share a crease; panel {a} borders "
                               f"panels {nb}.")
        return int(hit[0])

    def crease_nearest(self, point) -> int:
        """Id of the interior crease whose centre line passes closest to ``point`` [m]."""
        p = _as_point(point)
        if len(self.creases) == 0:
            raise PatternError("The pattern has no interior crease (no edge is shared by two "
                               "panels); there is no crease to pick.")
        a = self.vertices[self.edges[self.creases, 0]]
        b = self.vertices[self.edges[self.creases, 1]]
        t = np.clip(np.einsum("ij,ij->i", p - a, b - a) / np.einsum("ij,ij->i", b - a, b - a), 0, 1)
        dist = np.linalg.norm(a + t[:, None] * (b - a) - p, axis=1)
        return int(self.creases[np.argmin(dist)])

    def panel_containing(self, point, tol: float | None = None) -> int:
        """Id of the (first) panel containing ``point`` [m] within distance ``tol``.

        ``tol`` defaults to 1e-9 times the pattern size.
        """
        p = _as_point(point)
        tol = 1e-9 * self.size if tol is None else tol
        c, a, b, panel = self._fan_triangles()
        n = fan_normals(a, self.corner_sizes)
        nn = np.einsum("ij,ij->i", n, n)
        dist = np.einsum("ij,ij->i", p - c, n) / np.sqrt(nn)
        q = p - dist[:, None] * n / np.sqrt(nn)[:, None]
        # barycentric coordinates of the projection q in triangle (c, a, b)
        w_a = np.einsum("ij,ij->i", np.cross(q - c, b - c), n) / nn
        w_b = np.einsum("ij,ij->i", np.cross(a - c, q - c), n) / nn
        scale = np.sqrt(np.sqrt(nn))
        inside = (w_a >= -tol / scale) & (w_b >= -tol / scale) & (w_a + w_b <= 1 + tol / scale)
        hit = panel[inside & (np.abs(dist) <= tol)]
        if len(hit) == 0:
            raise PatternError(f"No panel contains the point {p.tolist()} (tolerance {tol:.3g} m); "
                               "give a point on a panel (in metres) or a larger tol.")
        return int(hit.min())

    @cached_property
    def size(self) -> float:
        """Largest extent of the pattern along x, y or z [m]."""
        return float(np.max(np.ptp(self.vertices, axis=0)))

    def _fan_triangles(self):
        """Fan triangles (centroid, C_j, C_{j+1}) of the original panels, flat over panels."""
        ring = rings(self.corner_sizes)
        xc = self.vertices[self.corner_vertices]
        return centroids(xc, self.corner_sizes)[ring.owner], xc, xc[ring.nxt], ring.owner

    # ------------------------------------------------------------------ data normalisation
    def _per_panel_positive(self, value, name):
        arr = _as_float_array(value, name)
        if arr.ndim == 0:
            arr = np.full(self.n_panels, float(arr))
        if arr.shape != (self.n_panels,):
            raise PatternError(
                f"{name} must be a scalar or have one entry per panel ({self.n_panels}); got shape "
                f"{arr.shape}.")
        bad = np.flatnonzero(~(np.isfinite(arr) & (arr > 0)))
        if len(bad):
            raise PatternError(f"{name} of panel {bad[0]} is {float(arr[bad[0]])!r}; it must be "
                               "a positive finite length in metres.")
        return arr

    def _per_panel_material(self, value):
        hint = f"give a Material or a sequence of {self.n_panels} Materials (one per panel)"
        if isinstance(value, Material):
            return (value,) * self.n_panels
        try:
            mats = tuple(value) if not isinstance(value, (str, bytes)) else None
        except TypeError:
            mats = None
        if mats is None:
            raise PatternError(f"panel_material is {value!r}; {hint}.")
        if len(mats) != self.n_panels:
            raise PatternError(f"panel_material has {len(mats)} entries for {self.n_panels} "
                               f"panels; {hint}.")
        bad = [i for i, m in enumerate(mats) if not isinstance(m, Material)]
        if bad:
            raise PatternError(f"panel_material of panel {bad[0]} is {mats[bad[0]]!r}, not a "
                               f"Material; {hint}.")
        return mats

    def _per_crease_positive(self, value, name):
        out = np.zeros(self.n_edges)
        if isinstance(value, Mapping):
            for key in value:
                self.check_crease(key, what=f"{name} crease")
            missing = [c for c in self.creases.tolist() if c not in {int(k) for k in value}]
            if missing:
                raise PatternError(f"{name} has no value for crease(s) {missing}; give every "
                                   "interior crease a value or pass a scalar.")
            for key, v in value.items():
                v = _as_float_array(v, f"{name} of crease {key}")
                if v.ndim:
                    raise PatternError(f"{name} of crease {key} is {value[key]!r}; give one "
                                       "number per crease.")
                out[int(key)] = v
        elif (arr := _as_float_array(value, name)).ndim == 0:
            out[self.creases] = float(arr)
        else:
            if arr.shape != (self.n_edges,):
                raise PatternError(
                    f"{name} array must have one entry per edge ({self.n_edges}, indexed by edge id); "
                    f"got shape {arr.shape}. Use a mapping {{crease_id: value}} instead.")
            out[self.creases] = arr[self.creases]
        vals = out[self.creases]
        bad = np.flatnonzero(~(np.isfinite(vals) & (vals > 0)))
        if len(bad):
            c = int(self.creases[bad[0]])
            raise PatternError(
                f"{name} of crease {c} (between panels {self.edge_panels[c, 0]} and "
                f"{self.edge_panels[c, 1]}) is {float(vals[bad[0]])!r}; every interior crease "
                "needs a positive finite value in metres.")
        return out

    def to_dict(self) -> dict:
        """Plain-dict summary for result metadata."""
        return {
            "n_vertices": self.n_vertices, "n_panels": self.n_panels,
            "creases": self.creases.tolist(),
            "crease_width [m]": self.crease_width[self.creases].tolist(),
            "crease_thickness [m]": self.crease_thickness[self.creases].tolist(),
            "panel_thickness [m]": self.panel_thickness.tolist(),
            "panel_material": [m.name for m in self.panel_material],
            "crease_material": self.crease_material.name,
        }


# ---------------------------------------------------------------------- validation helpers
def _is_int(x) -> bool:
    return isinstance(x, (int, np.integer)) and not isinstance(x, bool)


def _as_float_array(value, name) -> np.ndarray:
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise PatternError(f"{name} = {value!r} is not a number or an array of numbers; give "
                           "lengths in metres.") from None


def _as_point(point) -> np.ndarray:
    p = np.asarray(point, dtype=float).ravel()
    if p.shape == (2,):
        p = np.r_[p, 0.0]
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise PatternError(f"A point must be 2 or 3 finite coordinates, got {point!r}.")
    return p


def _as_vertices(vertices) -> np.ndarray:
    try:
        v = np.array(vertices, dtype=float)
    except (TypeError, ValueError) as exc:
        raise PatternError(f"vertices must be an (n, 3) array of numbers: {exc}") from None
    if v.ndim != 2 or v.shape[1] not in (2, 3) or len(v) < 3:
        raise PatternError(f"vertices must have shape (n, 3) or (n, 2) with n >= 3; got {v.shape}.")
    if v.shape[1] == 2:
        v = np.column_stack([v, np.zeros(len(v))])
    bad = np.flatnonzero(~np.all(np.isfinite(v), axis=1))
    if len(bad):
        raise PatternError(f"vertex {bad[0]} has a non-finite coordinate {v[bad[0]].tolist()}; "
                           "replace NaN/inf by real coordinates in metres.")
    v.setflags(write=False)
    return v


def _as_panels(panels, n_vertices) -> tuple:
    if isinstance(panels, np.ndarray) and panels.ndim == 2:
        panels = panels.tolist()
    if not isinstance(panels, Sequence) or len(panels) == 0:
        raise PatternError("panels must be a non-empty sequence of vertex-index lists.")
    out = []
    for i, poly in enumerate(panels):
        try:
            ids = [int(c) for c in poly]
            integral = all(c == k for c, k in zip(poly, ids))
        except (TypeError, ValueError):
            integral = False
        if not integral:
            raise PatternError(f"panel {i} = {poly!r} is not a list of integer vertex indices; "
                               "give each corner as a 0-based vertex id.")
        if len(ids) < 3:
            raise PatternError(f"panel {i} has {len(ids)} corners {ids}; a panel needs at least 3.")
        bad = [c for c in ids if not 0 <= c < n_vertices]
        if bad:
            raise PatternError(f"panel {i} refers to vertex {bad[0]}, but vertex ids are "
                               f"0..{n_vertices - 1}.")
        if len(set(ids)) != len(ids):
            raise PatternError(f"panel {i} = {ids} repeats a vertex; list each corner once.")
        out.append(tuple(ids))
    return tuple(out)


_CREASE_LETTERS, _BOUNDARY_LETTERS = "MVU", "BC"


def _set_fold_data(pattern: Pattern) -> None:
    """Normalise ``edge_assignment``, ``edge_fold_angle`` and ``metadata`` (design data)."""
    n, crease = pattern.n_edges, pattern.is_crease
    given = pattern.edge_assignment
    letters = np.where(crease, "U", "B") if given is None else np.array(list(given), dtype="<U1")
    if letters.shape != (n,):
        raise PatternError(f"edge_assignment has {letters.size} letters for {n} edges; give one "
                           "letter per edge in edge-id order.")
    ok = np.where(crease, np.char.find(_CREASE_LETTERS, letters) >= 0,
                  np.char.find(_BOUNDARY_LETTERS, letters) >= 0) & (np.char.str_len(letters) == 1)
    if not ok.all():
        e = int(np.flatnonzero(~ok)[0])
        kind, allowed = ("an interior crease", "M, V or U") if crease[e] else \
            ("a boundary edge", "B or C")
        raise PatternError(f"edge_assignment of edge {e} is {str(letters[e])!r}, but the edge is "
                           f"{kind}; use {allowed}.")
    default = np.select([letters == "M", letters == "V"], [-np.pi, np.pi], 0.0)
    angle = default if pattern.edge_fold_angle is None else \
        _as_float_array(pattern.edge_fold_angle, "edge_fold_angle")
    if angle.shape != (n,):
        raise PatternError(f"edge_fold_angle must have one entry per edge ({n}); got shape "
                           f"{angle.shape}.")
    bad = ~np.isfinite(angle) | (np.abs(angle) > np.pi) | ((letters == "M") & (angle > 0)) \
        | ((letters == "V") & (angle < 0)) | (~crease & (angle != 0))
    if bad.any():
        e = int(np.flatnonzero(bad)[0])
        raise PatternError(f"edge_fold_angle of edge {e} ({str(letters[e])}) is "
                           f"{float(angle[e])!r} rad; fold angles lie in [-pi, pi], <= 0 for M, "
                           ">= 0 for V and 0 on boundary edges.")
    letters.setflags(write=False)
    angle = angle.copy()
    angle.setflags(write=False)
    if not isinstance(pattern.metadata, Mapping):
        raise PatternError(f"metadata must be a mapping of FOLD fields, got "
                           f"{type(pattern.metadata).__name__}.")
    object.__setattr__(pattern, "edge_assignment", letters)
    object.__setattr__(pattern, "edge_fold_angle", angle)
    object.__setattr__(pattern, "metadata", dict(pattern.metadata))
