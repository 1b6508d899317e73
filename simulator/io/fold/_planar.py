"""Geometry repairs of FOLD input: faces of a flat crease pattern from its planar graph,
vertices in the middle of a straight crease line merged away, a flat sheet in another plane
recognised and laid in x-y, its top side up."""

from __future__ import annotations

import logging
import math

import numpy as np

from ...geometry.polygons import area_vectors, on_segment
from ._common import NS, fail

logger = logging.getLogger(__name__)

#: Fields whose values are given in the file's own axes (loading steps, with their forces and
#: gravity along -z; supports by direction; mesh node positions): a flat sheet in another
#: plane than x-y that has one of them stays where it is unless ``lay_flat=True``.
FRAME_FIELDS = (f"{NS}steps", f"{NS}supports", f"faces_{NS}support", f"vertices_{NS}support",
                f"{NS}mesh_nodes")


def plane_normal(coords: np.ndarray, tol: float = 1e-9):
    """Unit normal (3,) of the plane of all ``coords`` (n, 3), or None if they are not flat."""
    c = coords - coords.mean(axis=0)
    size = float(np.max(np.ptp(coords, axis=0)))
    _, s, vt = np.linalg.svd(c, full_matrices=False)
    if size <= 0 or s[-1] > tol * size * math.sqrt(len(coords)):
        return None
    return vt[-1]


def faces_from_edges(coords: np.ndarray, edges: np.ndarray) -> list:
    """Faces (counter-clockwise about the plane normal) of a flat planar graph.

    Every bounded face of the graph drawn in the plane of ``coords``; the outer face (the
    largest, clockwise) is left out. Refuses folded (non-flat) coordinates.
    """
    normal = plane_normal(coords)
    if normal is None:
        fail("faces_vertices", "missing, and the file is folded (not flat), so its faces cannot "
             "be derived from the edges; add faces_vertices (or read its crease-pattern frame).")
    normal = _upward(normal)
    u = np.cross(normal, [1.0, 0, 0] if abs(normal[0]) < 0.9 else [0, 1.0, 0])
    u /= np.linalg.norm(u)
    xy = np.column_stack([coords @ u, coords @ np.cross(normal, u)])
    nbr = {}
    for a, b in edges.tolist():
        nbr.setdefault(a, []).append(b)
        nbr.setdefault(b, []).append(a)
    order = {v: sorted(ns, key=lambda w: math.atan2(*(xy[w] - xy[v])[::-1])) for v, ns in nbr.items()}
    used, faces = set(), []
    for a, b in edges.tolist():
        for start in ((a, b), (b, a)):
            if start in used:
                continue
            face, (u0, v0) = [], start
            while (u0, v0) not in used:
                used.add((u0, v0))
                face.append(u0)
                ring = order[v0]                      # next half-edge: turn left as much as possible
                w = ring[(ring.index(u0) - 1) % len(ring)]
                u0, v0 = v0, w
            faces.append(face)
    area = [_signed_area(xy[f]) for f in faces]
    outer = int(np.argmin(area))
    out = [f for i, f in enumerate(faces) if i != outer and area[i] > 0 and len(f) >= 3]
    if not out:
        fail("faces_vertices", "missing, and the edges enclose no face; add faces_vertices.")
    logger.info("FOLD faces_vertices absent: %d faces derived from the planar graph", len(out))
    return out


def _signed_area(p: np.ndarray) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def merge_straight(coords, faces, edges, letters, same) -> tuple:
    """Drop vertices in the middle of a straight crease line (two creases, collinear, alike).

    Collinear is judged relative to the pattern's extent
    (:data:`~simulator.geometry.polygons.STRAIGHT_TOL`): a vertex that an editor's rounding put
    picometres off the line is merged too. ``faces`` are the panels (after F / J merging); a
    vertex is dropped when it is a corner of exactly two panels and has exactly two crease
    edges (F / J edges not counted).

    ``same(i, j)`` says whether file edges i and j carry the same data. Returns the new faces
    and, per file edge, the pair of kept vertices it now belongs to (or None when unchanged).
    """
    n = len(coords)
    incident = [[] for _ in range(n)]
    for i, (a, b) in enumerate(edges.tolist()):
        if letters[i] not in "FJ":                 # flat edges are inside merged panels
            incident[a].append(i)
            incident[b].append(i)
    in_faces = np.zeros(n, int)
    for f in faces:
        in_faces[f] += 1
    size = float(np.max(np.ptp(coords, axis=0))) or 1.0
    drop = {}
    for v in range(n):
        if len(incident[v]) != 2 or in_faces[v] != 2:
            continue
        i, j = incident[v]
        if letters[i] not in "MVU" or letters[j] not in "MVU" or not same(i, j):
            continue
        a = edges[i][0] if edges[i][1] == v else edges[i][1]
        b = edges[j][0] if edges[j][1] == v else edges[j][1]
        if on_segment(coords[v], coords[a], coords[b], size):
            drop[v] = (i, j)
    if not drop:
        return faces, [None] * len(edges)
    new_faces = [[v for v in f if v not in drop] for f in faces]
    alias = [None] * len(edges)
    chain = {i for pair in drop.values() for i in pair}
    for i, (a, b) in enumerate(edges.tolist()):
        if i in chain:
            alias[i] = tuple(sorted((_walk(a, b, drop, edges), _walk(b, a, drop, edges))))
    logger.info("FOLD: %d vertices in the middle of straight crease lines merged away",
                len(drop))
    return new_faces, alias


def _walk(v, came_from, drop, edges):
    """The kept vertex reached from ``v`` away from ``came_from`` along dropped vertices."""
    while v in drop:
        i, j = drop[v]
        a, b = edges[i].tolist(), edges[j].tolist()
        other = [w for w in a + b if w != v]
        nxt = other[1] if other[0] == came_from else other[0]
        v, came_from = nxt, v
    return v


def _upward(normal: np.ndarray) -> np.ndarray:
    """``normal`` or its opposite: the one with z > 0 (z = 0: y > 0, then x > 0)."""
    n = normal
    return -n if n[2] < 0 or (n[2] == 0 and (n[1] < 0 or (n[1] == 0 and n[0] < 0))) else n


def top_normal(coords: np.ndarray, faces, normal: np.ndarray) -> np.ndarray:
    """Unit normal (3,) of the top side of a flat sheet in the plane of ``normal``: the side
    its faces run counter-clockwise around (FOLD's winding; by the faces' total vector area,
    which a rigid rotation carries along). Without faces, or with faces wound half each way,
    the side :func:`_upward` picks."""
    if faces:
        sizes = np.array([len(f) for f in faces])
        along = area_vectors(coords[np.concatenate(faces)], sizes) @ normal
        if abs(along.sum()) > 1e-9 * np.abs(along).sum():
            return normal if along.sum() > 0 else -normal
    return _upward(normal)


def lay_in_xy(coords: np.ndarray, up: np.ndarray | None = None) -> np.ndarray:
    """Rotate flat ``coords`` (n, 3) into the x-y plane (z = 0), centred on their centroid:
    the least rotation that turns the unit normal ``up`` (default: :func:`_upward` of the
    plane's normal) to +z, so a sheet standing in x-z turns about x."""
    n = plane_normal(coords)
    if n is None:
        return coords
    n = _upward(n) if up is None else np.asarray(up, float)
    axis = np.cross(n, [0.0, 0.0, 1.0])
    s, c = np.linalg.norm(axis), n[2]
    if s < 1e-15 and c > 0:
        return coords
    k = axis / s if s >= 1e-15 else np.array([1.0, 0.0, 0.0])     # upside down: about x
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    R = np.eye(3) + s * K + (1 - c) * K @ K
    out = (coords - coords.mean(axis=0)) @ R.T
    out[:, 2] = 0.0
    return out


def lay_flat_sheet(coords, faces, lay_flat: bool | None, data: dict, notes: list):
    """``coords`` (n, 3) [m], or, for a flat sheet in another plane than x-y, laid in x-y top
    side up (:func:`lay_in_xy`, :func:`top_normal` of the given ``faces`` or None): where
    ``lay_flat`` is True, or None and the file ``data`` has no :func:`_frame_bound` field;
    else kept standing with a warning. One line in ``notes`` says which."""
    n = plane_normal(coords)
    if n is None or abs(abs(n[2]) - 1) < 1e-9:
        return coords
    bound = _frame_bound(data)
    normal = np.round(n, 6).tolist()
    if lay_flat or (lay_flat is None and not bound):
        notes.append(f"flat sheet in the plane with normal {normal} laid in x-y, top side up "
                     "(its faces counter-clockwise seen from +z), the frame of the results; "
                     "lay_flat=False keeps it standing")
        logger.info("FOLD: %s", notes[-1])
        return lay_in_xy(coords, top_normal(coords, faces, n))
    why = "as asked (lay_flat=False)" if lay_flat is False else \
        f"since its {', '.join(bound)} are given in the file's axes"
    notes.append(f"flat sheet standing in the plane with normal {normal} (not x-y): simulated "
                 f"standing, {why}; lay_flat=True lays it in x-y")
    logger.warning("FOLD: %s", notes[-1])
    return coords


def _frame_bound(data: dict) -> list:
    """The fields of ``data`` given in the file's own axes (:data:`FRAME_FIELDS`, a thermal
    ``substrate`` plane, or ``substrate_plane`` in the old spelling)."""
    out = [f for f in FRAME_FIELDS if data.get(f) not in (None, [], {})]
    thermal = data.get(f"{NS}thermal")
    if isinstance(thermal, dict) and thermal.get("substrate_plane"):
        out.append(f"{NS}thermal.substrate_plane")
    if isinstance(thermal, dict) and isinstance(thermal.get("substrate"), dict):
        out.append(f"{NS}thermal.substrate")
    return out
