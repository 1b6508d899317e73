"""Geometric checks of a :class:`~simulator.geometry.pattern.Pattern` made when it is built: unused and
coincident vertices, degenerate, non-planar and self-intersecting panels."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

import numpy as np

from .._validate import capped
from ..errors import PatternError
from .polygons import area_vectors, fan_normals

if TYPE_CHECKING:
    from .pattern import Pattern

__all__ = ["check_geometry", "OPEN_START"]

#: What a compliant crease at +-180 deg in the start shape needs (the refusals of a pattern
#: folded flat end with it).
OPEN_START = ("a compliant crease needs an open start: use the flat crease pattern "
              "(frame='creasePattern', or export it) or open them below 180 deg")

logger = logging.getLogger(__name__)

#: Up to this many vertices coincident ones are found by all pairwise distances (numpy), above
#: by a k-d tree (scipy.spatial, slow to import: 0.1 s, more than the check of a small pattern).
_PAIRWISE_VERTICES = 500


def _coincident_pair(v: np.ndarray, tol: float) -> tuple[int, int] | None:
    """A pair ``(i, j)``, ``i < j``, of vertices ``v`` (n, 3) at most ``tol`` apart, or None."""
    if len(v) <= _PAIRWISE_VERTICES:
        d2 = np.sum((v[:, None, :] - v[None, :, :]) ** 2, axis=-1)
        i, j = np.nonzero(np.triu(d2 <= tol * tol, 1))
        return (int(i[0]), int(j[0])) if len(i) else None
    from scipy.spatial import cKDTree          # imported here: scipy.spatial is slow to import

    pairs = cKDTree(v).query_pairs(tol, output_type="ndarray")
    return tuple(int(k) for k in sorted(pairs[0])) if len(pairs) else None


def _folded(v: np.ndarray, size: float) -> bool:
    """True if the vertices do not lie in one plane (a folded start shape)."""
    c = v - v.mean(axis=0)
    return bool(np.linalg.svd(c, compute_uv=False)[-1] > 1e-9 * size * np.sqrt(len(v)))


def check_geometry(pattern: Pattern) -> None:
    """Unused / duplicate vertices, degenerate, non-planar and self-intersecting panels."""
    v = pattern.vertices
    size = pattern.size
    if size <= 0:
        raise PatternError("All vertices coincide; the pattern has zero size.")
    used = np.zeros(len(v), bool)
    used[pattern.corner_vertices] = True
    if not used.all():
        raise PatternError(f"vertex {np.flatnonzero(~used)[0]} is not used by any panel; remove it "
                           "or add it to a panel.")
    pair = _coincident_pair(v, 1e-9 * size)
    if pair is not None and _folded(v, size):
        # a folded form: distinct paper points may touch in space (contact handles them); only
        # the vertices the panels share are one point of the paper
        logger.info("vertices %d and %d coincide in the folded start shape; kept distinct",
                    *pair)
    elif pair is not None:
        i, j = pair
        flat = _folded_flat_note(pattern)
        raise PatternError(f"vertices {i} and {j} coincide at {v[i].tolist()}" + (
            f": {flat}; if not folded flat, merge them into one vertex." if flat else
            "; merge them into one vertex and use it in both panels."))
    c, a, b, panel = pattern._fan_triangles()
    sizes = pattern.corner_sizes
    starts = np.cumsum(sizes) - sizes
    fan_normal = fan_normals(a, sizes)
    normal = 2 * area_vectors(a, sizes)                        # Newell vector area x 2
    area2 = np.linalg.norm(normal, axis=1)
    diam = np.maximum.reduceat(np.linalg.norm(a - c, axis=1), starts)
    bad = np.flatnonzero(area2 <= 1e-8 * diam**2)
    unsigned = np.add.reduceat(np.linalg.norm(fan_normal, axis=1), starts)
    if len(bad) and unsigned[bad[0]] > 1e-8 * diam[bad[0]] ** 2:
        _raise_self_intersecting(pattern, bad[0])
    if len(bad):
        raise PatternError(f"panel {bad[0]} = {list(pattern.panels[bad[0]])} is degenerate (zero "
                           "area: coincident or collinear corners); fix its vertices.")
    unit = normal / area2[:, None]
    offplane = np.abs(np.einsum("ij,ij->i", a - c, unit[panel]))
    worst = np.maximum.reduceat(offplane, starts)
    bad = np.flatnonzero(worst > 1e-6 * diam)
    if len(bad):
        raise PatternError(f"panel {bad[0]} is not planar (a corner lies {worst[bad[0]]:.3g} m off "
                           "its plane); split it into planar panels (e.g. triangles).")
    # walking around the centroid, every fan angle must be positive and they must sum to 2 pi
    sin = np.einsum("ij,ij->i", fan_normal, unit[panel])
    cos = np.einsum("ij,ij->i", a - c, b - c)
    angle = np.arctan2(sin, cos)
    total = np.add.reduceat(angle, starts)
    bad = np.flatnonzero((np.minimum.reduceat(angle, starts) <= 0) | (np.abs(total - 2 * np.pi) > 1e-6))
    if len(bad):
        _raise_self_intersecting(pattern, bad[0])


def _folded_flat_note(pattern: Pattern) -> str:
    """For a flat-folded start shape (creases at +-180 deg), the creases that cause it."""
    from .orientation import folded_flat_creases

    flat = folded_flat_creases(pattern)
    if not len(flat):
        return ""
    return f"crease(s) {capped(flat.tolist(), 5)} are at +-180 deg; {OPEN_START}"


def _raise_self_intersecting(pattern: Pattern, i: int) -> None:
    raise PatternError(f"panel {i} = {list(pattern.panels[i])} is self-intersecting or not "
                       "star-shaped about its centroid; reorder its corners cyclically or split it "
                       "into convex panels.")
