"""Vectorised measures of many polygons stored flat (the panels of a pattern or a mesh).

Polygons are given by the number of corners of each, ``sizes`` (P,), and their corner
coordinates concatenated polygon by polygon in cyclic order, ``corners`` (S, 3) with
``S = sizes.sum()``. Every function works on all polygons at once (no Python loop).
Fans are the triangles (o, c_j, c_{j+1}) from a polygon's centre o (by default its vertex
centroid) to its edges; their vector areas add up to the polygon's (Newell's method), which
is exact for any planar polygon and gives a robust normal for a slightly warped one.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["Rings", "rings", "centroids", "fan_normals", "area_vectors", "unit_normals",
           "triangle_areas", "STRAIGHT_TOL", "on_segment"]

#: Distance from a line, as a fraction of the pattern's extent, within which a point counts as
#: on it (a vertex in the middle of a straight crease line, a straight panel corner). Editors
#: that keep coordinates in single precision (Origami Simulator exports its three.js float32
#: buffers: 6e-8 of the coordinates) put computed intersections up to about 1e-7 of the extent
#: off their lines (15 pm in a 1 mm sheet); no drawn feature is this small.
STRAIGHT_TOL = 1e-6


class Rings(NamedTuple):
    """Cyclic corner addressing of flat-stored polygons, all (S,) except ``first`` (P,).

    ``first`` is the flat index of each polygon's first corner, ``owner`` the polygon of each
    corner, ``local`` its position in the polygon, ``prev`` / ``nxt`` the flat indices of the
    previous / next corner of the same polygon.
    """

    first: np.ndarray
    owner: np.ndarray
    local: np.ndarray
    prev: np.ndarray
    nxt: np.ndarray


def rings(sizes) -> Rings:
    """Cyclic addressing (:class:`Rings`) of polygons with ``sizes`` (P,) corners each."""
    sizes = np.asarray(sizes)
    first = np.cumsum(sizes) - sizes
    start = np.repeat(first, sizes)
    local = np.arange(len(start)) - start
    period = np.repeat(sizes, sizes)
    return Rings(first, np.repeat(np.arange(len(sizes)), sizes), local,
                 start + (local - 1) % period, start + (local + 1) % period)


def centroids(corners: np.ndarray, sizes) -> np.ndarray:
    """Vertex centroid (P, 3) of every polygon [m] (the mean of its corners)."""
    sizes = np.asarray(sizes)
    return np.add.reduceat(corners, np.cumsum(sizes) - sizes) / sizes[:, None]


def fan_normals(corners: np.ndarray, sizes, centre: np.ndarray | None = None) -> np.ndarray:
    """Cross products (S, 3) ``(c_j - o) x (c_{j+1} - o)`` of every fan triangle [m^2].

    Each is twice the vector area of the fan triangle (o, c_j, c_{j+1}); ``centre`` (P, 3)
    gives o per polygon, default :func:`centroids`. ``corners`` (..., S, 3) and ``centre``
    (..., P, 3) with leading axes (e.g. records) give (..., S, 3), each the same numbers as
    one call per record.
    """
    r = rings(sizes)
    o = (centroids(corners, sizes) if centre is None else centre)[..., r.owner, :]
    return np.cross(corners - o, corners[..., r.nxt, :] - o)


def area_vectors(corners: np.ndarray, sizes, centre: np.ndarray | None = None) -> np.ndarray:
    """Vector area (P, 3) of every polygon [m^2]: normal by the right-hand rule, length = area.

    Newell's method (half the sum of :func:`fan_normals`); independent of ``centre`` for a
    planar polygon. Leading axes as in :func:`fan_normals` (with ``centre`` given).
    """
    sizes = np.asarray(sizes)
    return 0.5 * np.add.reduceat(fan_normals(corners, sizes, centre), np.cumsum(sizes) - sizes,
                                 axis=-2)


def unit_normals(corners: np.ndarray, sizes, centre: np.ndarray | None = None,
                 upward: bool = False) -> np.ndarray:
    """Unit normals (P, 3) by Newell's method; orientation from the corner order, or with a
    non-negative z component if ``upward``. Leading axes as in :func:`area_vectors`."""
    n = area_vectors(corners, sizes, centre)
    if upward:
        n = n * np.where(n[..., 2] < 0, -1.0, 1.0)[..., None]
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def triangle_areas(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Areas (n,) [m^2] of the triangles with corners a, b, c (n, 3)."""
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def on_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray, size: float) -> np.ndarray:
    """(n,) True where point ``p`` lies on the straight segment from ``a`` to ``b``: within
    ``STRAIGHT_TOL * size`` of the line through them and between them (all (n, 3); ``size``
    the pattern's extent [m])."""
    da, db = a - p, b - p
    twice_area = np.linalg.norm(np.cross(da, db), axis=-1)
    base = np.linalg.norm(b - a, axis=-1)
    return (twice_area <= STRAIGHT_TOL * size * base) & (np.einsum("...i,...i->...", da, db) < 0)
