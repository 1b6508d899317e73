"""FOLD reader: a FOLD 1.0-1.2 file (key frame) to a :class:`~simulator.pattern.Pattern`.

Geometry comes from ``vertices_coords`` (2-D or 3-D, scaled to metres by ``frame_unit``) and
``faces_vertices``; ``edges_vertices`` / ``edges_assignment`` / ``edges_foldAngle`` (or the
legacy ``edges_foldAngles``) say which edges are creases. ``F`` and ``J`` edges are not
creases: the faces on their two sides are merged into one panel (they must be coplanar).
Crease and panel data come from the ``etorigami:`` namespace (see ``docs/fold-format.md``).
Every malformed file raises one :class:`~simulator.errors.FoldFormatError` whose message
names the field and the index.
"""

from __future__ import annotations

import json
import logging
import math
import pathlib
import re
from dataclasses import dataclass

import numpy as np

from ..errors import FoldFormatError, PatternError
from ..materials import SPR, SU8, SUBSTRATE, Material
from ..pattern import Pattern

__all__ = ["read_fold", "fold_to_pattern", "load_fold_json", "FoldGeometry", "UNITS", "NS"]

logger = logging.getLogger(__name__)

#: Our namespace prefix.
NS = "etorigami:"
#: Metres per FOLD ``frame_unit`` (``"unit"`` needs an explicit ``unit_scale``).
UNITS = {"in": 0.0254, "pt": 0.0254 / 72, "m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6,
         "nm": 1e-9}
_LETTERS = "BMVFUCJ"
#: Built-in materials a file may name without defining them in ``etorigami:materials``.
BUILTIN_MATERIALS = {m.name: m for m in (SU8, SPR, SUBSTRATE)}
#: FOLD fields the reader interprets or regenerates on writing (not kept as metadata).
_OWN_FIELDS = {"vertices_coords", "faces_vertices", "edges_vertices", "edges_assignment",
               "edges_foldAngle", "edges_foldAngles", "frame_unit", "file_spec", "file_creator",
               "file_frames", "edges_faces", "faces_edges", "vertices_vertices",
               "vertices_faces", "vertices_edges", "edges_lengths", "faceOrders", "edgeOrders",
               "faces_faces", "edges_edges"}


@dataclass(frozen=True, eq=False)
class FoldGeometry:
    """A pattern read from FOLD and the maps from file indices to pattern ids.

    Attributes
    ----------
    pattern : Pattern
    vertex : (n_file_vertices,) pattern vertex of each file vertex, -1 if dropped (merged away)
    face : (n_file_faces,) panel of each file face
    edge : (n_file_edges,) pattern edge of each file edge, -1 for edges merged away
    data : dict
        The parsed key frame (all fields, for the model reader).
    """

    pattern: Pattern
    vertex: np.ndarray
    face: np.ndarray
    edge: np.ndarray
    data: dict


def _fail(field: str, message: str):
    raise FoldFormatError(f"FOLD {field}: {message}")


def load_fold_json(path) -> dict:
    """Parse a FOLD file into a dict; invalid JSON raises FoldFormatError with the line."""
    path = pathlib.Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise FoldFormatError(f"cannot read FOLD file {str(path)!r}: {exc.strerror}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise FoldFormatError(f"FOLD file {path.name}: invalid JSON at line {exc.lineno}, column "
                              f"{exc.colno}: {exc.msg}") from None
    if not isinstance(data, dict):
        raise FoldFormatError(f"FOLD file {path.name}: the top level must be a JSON object "
                              f"{{...}}, got a {type(data).__name__}.")
    return data


def read_fold(path, **kwargs) -> Pattern:
    """Read a FOLD file into a :class:`~simulator.pattern.Pattern` (keywords: see
    :func:`fold_to_pattern`)."""
    return fold_to_pattern(load_fold_json(path), **kwargs)


def fold_to_pattern(data: dict, **kwargs) -> Pattern:
    """Pattern of a parsed FOLD dict.

    Parameters
    ----------
    data : dict
        The FOLD key frame (top-level object).
    unit_scale : float, optional
        Metres per coordinate unit; required (and only allowed) when ``frame_unit`` is
        ``"unit"`` or absent.
    crease_width, crease_thickness, panel_thickness : float, optional
        Values [m] for files without ``edges_etorigami:width``, ``edges_etorigami:thickness``,
        ``faces_etorigami:thickness``.
    material : Material, optional
        Panel and crease material of files without ``faces_etorigami:material`` (default SU-8).
    """
    return parse_fold(data, **kwargs).pattern


def parse_fold(data: dict, *, unit_scale=None, crease_width=None, crease_thickness=None,
               panel_thickness=None, material: Material | None = None) -> FoldGeometry:
    """Validate a FOLD dict and build the pattern and the index maps (:class:`FoldGeometry`)."""
    if not isinstance(data, dict):
        raise FoldFormatError(f"FOLD data must be a dict (JSON object), got {type(data).__name__}.")
    coords = _coords(data) * _scale(data, unit_scale)
    faces = _faces(data, len(coords))
    edges, letters, angles = _edges(data, len(coords), faces)
    groups, panels = _merge_flat_faces(coords, faces, edges, letters)
    vertex = np.full(len(coords), -1)
    used = np.unique(np.concatenate([np.asarray(p) for p in panels]))
    vertex[used] = np.arange(len(used))
    panels = [tuple(int(vertex[v]) for v in p) for p in panels]
    face = np.empty(len(faces), int)
    for g, members in enumerate(groups):
        face[members] = g
    geo = _pattern(coords[used], panels, face)
    key = {tuple(e): i for i, e in enumerate(geo.edges.tolist())}
    edge = np.array([key.get(tuple(sorted((vertex[a], vertex[b]))), -1) if vertex[a] >= 0
                     and vertex[b] >= 0 else -1 for a, b in edges], int).reshape(-1)
    per_edge = _edge_data(data, geo, edge, letters, angles, crease_width, crease_thickness)
    per_panel = _panel_data(data, groups, panel_thickness, material)
    try:
        pattern = Pattern(geo.vertices, geo.panels, **per_edge, **per_panel,
                          metadata=_metadata(data, vertex, face, edge, groups))
    except PatternError as exc:
        _fail("etorigami data", str(exc))
    return FoldGeometry(pattern, vertex, face, edge, data)


# ---------------------------------------------------------------------- fields
def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _index_list(value, field: str, n: int, length=None) -> list:
    """A list of integer indices in 0..n-1 (``length`` = exact count, or a minimum if negative)."""
    if not isinstance(value, list) or not all(isinstance(i, int) and not isinstance(i, bool)
                                              for i in value):
        _fail(field, f"{value!r} is not a list of integer indices.")
    if length is not None and (len(value) != length if length > 0 else len(value) < -length):
        need = f"{length}" if length > 0 else f"at least {-length}"
        _fail(field, f"{value!r} has {len(value)} entries; it needs {need}.")
    bad = [i for i in value if not 0 <= i < n]
    if bad:
        _fail(field, f"index {bad[0]} is out of range: there are {n} vertices (0..{n - 1}).")
    return value


def _array_field(data: dict, name: str, n: int, what: str):
    """A per-element list of length n, or None when absent."""
    value = data.get(name)
    if value is None:
        return None
    if not isinstance(value, list) or len(value) != n:
        got = f"{len(value)} entries" if isinstance(value, list) else f"a {type(value).__name__}"
        _fail(name, f"has {got}; it needs one entry per {what} ({n}).")
    return value


def _coords(data: dict) -> np.ndarray:
    value = data.get("vertices_coords")
    if value is None:
        _fail("vertices_coords", "missing required field (vertex coordinates).")
    if not isinstance(value, list) or len(value) < 3:
        _fail("vertices_coords", "must be a list of at least 3 coordinate lists [x, y(, z)].")
    out = np.zeros((len(value), 3))
    for i, c in enumerate(value):
        if not isinstance(c, list) or len(c) not in (2, 3):
            _fail(f"vertices_coords[{i}]", f"{c!r} must be [x, y] or [x, y, z].")
        if not all(_is_number(x) and math.isfinite(x) for x in c):
            _fail(f"vertices_coords[{i}]", f"{c!r} has a non-numeric or non-finite coordinate.")
        out[i, :len(c)] = c
    return out


def _scale(data: dict, unit_scale) -> float:
    unit = data.get("frame_unit", "unit")
    if unit == "unit":
        if unit_scale is None:
            _fail("frame_unit", f"is {unit!r}{' (the FOLD default)' if 'frame_unit' not in data else ''}"
                  "; pass unit_scale=<metres per unit> or set frame_unit to one of "
                  f"{', '.join(UNITS)}.")
        if not (_is_number(unit_scale) and math.isfinite(unit_scale) and unit_scale > 0):
            raise FoldFormatError(f"unit_scale = {unit_scale!r} must be a positive number of "
                                  "metres per unit.")
        return float(unit_scale)
    if unit not in UNITS:
        _fail("frame_unit", f"{unit!r} is not a FOLD unit; use unit, {', '.join(UNITS)}.")
    if unit_scale is not None:
        _fail("frame_unit", f"is {unit!r}, so unit_scale is not used; drop it (it applies to "
              "frame_unit 'unit' only).")
    return UNITS[unit]


def _faces(data: dict, n_vertices: int) -> list:
    value = data.get("faces_vertices")
    if value is None:
        _fail("faces_vertices", "missing required field (the panels).")
    if not isinstance(value, list) or not value:
        _fail("faces_vertices", "must be a non-empty list of vertex-index lists.")
    faces = []
    for i, f in enumerate(value):
        f = _index_list(f, f"faces_vertices[{i}]", n_vertices, -3)
        if len(set(f)) != len(f):
            _fail(f"faces_vertices[{i}]", f"{f} repeats a vertex (slits are not supported); "
                  "duplicate the vertex instead.")
        faces.append(f)
    return faces


def _edges(data: dict, n_vertices: int, faces: list):
    """(edges (E, 2) file edges, letters (E,), fold angles [deg] (E,)); checks edges vs faces."""
    sides = {}
    for f, poly in enumerate(faces):
        for a, b in zip(poly, poly[1:] + poly[:1]):
            sides.setdefault((min(a, b), max(a, b)), []).append(f)
    for (a, b), users in sides.items():
        if len(users) > 2:
            _fail(f"faces_vertices[{users[2]}]", f"side {a}-{b} is shared by faces {users}; an "
                  "edge may border at most two faces.")
    value = data.get("edges_vertices")
    if value is None:
        for name in ("edges_assignment", "edges_foldAngle", "edges_foldAngles"):
            if name in data:
                _fail("edges_vertices", f"missing, but {name} is given; edge data needs the "
                      "edges.")
        edges = np.array(list(sides), int).reshape(-1, 2)
        letters = ["U" if len(sides[tuple(e)]) == 2 else "B" for e in edges.tolist()]
        return edges, letters, [None] * len(edges)
    if not isinstance(value, list):
        _fail("edges_vertices", "must be a list of [u, v] vertex pairs.")
    edges = np.array([_index_list(e, f"edges_vertices[{i}]", n_vertices, 2)
                      for i, e in enumerate(value)], int).reshape(-1, 2)
    seen = {}
    for i, (a, b) in enumerate(edges.tolist()):
        key = (min(a, b), max(a, b))
        if a == b:
            _fail(f"edges_vertices[{i}]", f"[{a}, {b}] joins a vertex to itself.")
        if key in seen:
            _fail(f"edges_vertices[{i}]", f"[{a}, {b}] repeats edge {seen[key]}.")
        if key not in sides:
            _fail(f"edges_vertices[{i}]", f"[{a}, {b}] is not a side of any face "
                  "(faces_vertices and edges_vertices disagree).")
        seen[key] = i
    missing = [k for k in sides if k not in seen]
    if missing:
        f = sides[missing[0]][0]
        _fail(f"faces_vertices[{f}]", f"side {missing[0][0]}-{missing[0][1]} is not in "
              "edges_vertices (faces_vertices and edges_vertices disagree).")
    letters = _assignments(data, edges, sides)
    angles = _fold_angles(data, letters)
    return edges, letters, angles


def _assignments(data, edges, sides) -> list:
    raw = _array_field(data, "edges_assignment", len(edges), "edge")
    out = []
    for i, (a, b) in enumerate(edges.tolist()):
        n_faces = len(sides[(min(a, b), max(a, b))])
        if raw is None:
            out.append("U" if n_faces == 2 else "B")
            continue
        x = raw[i]
        if not isinstance(x, str) or x.upper() not in _LETTERS or len(x) != 1:
            _fail(f"edges_assignment[{i}]", f"{x!r} is not a FOLD assignment; use one of "
                  f"{', '.join(_LETTERS)}.")
        x = x.upper()
        if n_faces == 1 and x not in "BC":
            _fail(f"edges_assignment[{i}]", f"{x!r} is a crease on the boundary (edge {a}-{b} "
                  "borders one face); use B, or add the face on its other side.")
        if n_faces == 2 and x == "B":
            _fail(f"edges_assignment[{i}]", f"'B' but edge {a}-{b} borders two faces "
                  f"{sides[(min(a, b), max(a, b))]}; use M, V, U or F.")
        if n_faces == 2 and x == "C":
            _fail(f"edges_assignment[{i}]", f"cut 'C' between two faces is not supported; give "
                  "the two faces separate vertices along the cut.")
        out.append(x)
    return out


def _fold_angles(data, letters) -> list:
    name = "edges_foldAngle" if "edges_foldAngle" in data else "edges_foldAngles"
    raw = _array_field(data, name, len(letters), "edge")
    if raw is None:
        return [None] * len(letters)
    for i, (x, letter) in enumerate(zip(raw, letters)):
        if x is None:
            continue
        if not (_is_number(x) and math.isfinite(x) and abs(x) <= 180):
            _fail(f"{name}[{i}]", f"{x!r} must be a number of degrees in [-180, 180].")
        if (letter == "M" and x > 0) or (letter == "V" and x < 0) or \
                (letter in "BC" and x != 0):
            _fail(f"{name}[{i}]", f"{x!r} deg does not match assignment {letter!r} (M <= 0, "
                  "V >= 0, B and C 0).")
    return raw


# ---------------------------------------------------------------------- flat-face merging
def _merge_flat_faces(coords, faces, edges, letters):
    """Merge faces joined by F / J edges into panels; returns (groups, panel polygons)."""
    parent = list(range(len(faces)))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    owners = {}
    for f, poly in enumerate(faces):
        for a, b in zip(poly, poly[1:] + poly[:1]):
            owners.setdefault((min(a, b), max(a, b)), []).append(f)
    flat = set()
    for i, ((a, b), letter) in enumerate(zip(edges.tolist(), letters)):
        if letter in "FJ":
            f, g = owners[(min(a, b), max(a, b))]
            _check_coplanar(coords, faces, f, g, i, letter)
            parent[root(f)] = root(g)
            flat.add((min(a, b), max(a, b)))
    roots = [root(f) for f in range(len(faces))]
    order = list(dict.fromkeys(roots))
    groups = [[f for f in range(len(faces)) if roots[f] == r] for r in order]
    panels = [faces[g[0]] if len(g) == 1 else _boundary(faces, g, flat) for g in groups]
    return groups, panels


def _check_coplanar(coords, faces, f, g, i, letter):
    n = [_normal(coords[faces[k]]) for k in (f, g)]
    angle = math.degrees(math.atan2(np.linalg.norm(np.cross(n[0], n[1])), n[0] @ n[1]))
    if abs(angle) > 1e-4:
        _fail(f"edges_assignment[{i}]", f"{letter!r} (flat) but faces {f} and {g} meet at a fold "
              f"angle of {angle:.4g} deg; assign M, V or U, or make the faces coplanar.")


def _normal(x) -> np.ndarray:
    c = x.mean(axis=0)
    n = np.cross(x - c, np.roll(x, -1, axis=0) - c).sum(axis=0)
    return n / max(np.linalg.norm(n), 1e-300)


def _boundary(faces, group, flat) -> list:
    """Outer polygon of faces merged along flat edges (directed sides chained into one cycle)."""
    nxt = {}
    for f in group:
        poly = faces[f]
        for a, b in zip(poly, poly[1:] + poly[:1]):
            if (min(a, b), max(a, b)) in flat:
                continue
            if a in nxt:
                _fail(f"faces_vertices[{f}]", f"merging faces {group} along their F/J edges "
                      f"does not give a simple polygon (vertex {a} is pinched or the faces are "
                      "not consistently oriented).")
            nxt[a] = b
    start = next(iter(nxt))
    cycle, v = [start], nxt[start]
    while v != start and len(cycle) <= len(nxt):
        cycle.append(v)
        v = nxt.get(v, start)
    if len(cycle) != len(nxt) or nxt.get(cycle[-1]) != start:
        _fail(f"faces_vertices[{group[0]}]", f"merging faces {group} along their F/J edges "
              "gives a panel with a hole or several outlines; mark some edges U instead.")
    return cycle


# ---------------------------------------------------------------------- pattern data
_PATTERN_MESSAGE = [(re.compile(r"^vertices (\d+) and (\d+)"), "vertices_coords", 2),
                    (re.compile(r"^vertex (\d+)"), "vertices_coords", 1),
                    (re.compile(r"^panel (\d+)"), "faces_vertices", 1)]


def _pattern(vertices, panels, face) -> Pattern:
    """Geometry-only pattern; PatternErrors re-raised naming the FOLD field and index."""
    try:
        return Pattern(vertices, panels, crease_width=1.0, crease_thickness=1.0,
                       panel_thickness=1.0)
    except PatternError as exc:
        msg = str(exc)
        for rx, field, group in _PATTERN_MESSAGE:
            m = rx.match(msg)
            if m:
                i = int(m.group(group))
                if field == "faces_vertices":
                    i = int(np.flatnonzero(face == i)[0])
                _fail(f"{field}[{i}]", msg)
        _fail("faces_vertices", msg)


def _edge_data(data, geo, edge, letters, angles, crease_width, crease_thickness) -> dict:
    n = geo.n_edges
    letter = np.where(geo.is_crease, "U", "B").astype("<U1")
    angle = np.zeros(n)
    explicit = np.zeros(n, bool)
    for i, e in enumerate(edge):
        if e >= 0:
            letter[e] = letters[i]
            if angles[i] is not None:
                angle[e], explicit[e] = math.radians(angles[i]), True
    angle[~explicit] = np.select([letter == "M", letter == "V"], [-np.pi, np.pi], 0.0)[~explicit]
    out = {"edge_assignment": letter, "edge_fold_angle": angle}
    for key, name, default in (("crease_width", "width", crease_width),
                               ("crease_thickness", "thickness", crease_thickness)):
        out[key] = _crease_values(data, f"edges_{NS}{name}", geo, edge, default, key)
    return out


def _crease_values(data, field, geo, edge, default, key) -> np.ndarray:
    raw = _array_field(data, field, len(edge), "edge")
    if raw is None:
        if default is None:
            _fail(field, f"missing: give the {key.replace('_', ' ')} of every crease [m] in the "
                  f"file or pass {key}=... to the reader.")
        return np.full(geo.n_edges, float(default))
    out = np.zeros(geo.n_edges)
    for i, e in enumerate(edge):
        if e >= 0 and geo.is_crease[e]:
            x = raw[i]
            if not (_is_number(x) and math.isfinite(x) and x > 0):
                _fail(f"{field}[{i}]", f"{x!r}; every crease needs a positive length in metres.")
            out[e] = x
    return out


def _panel_data(data, groups, panel_thickness, material) -> dict:
    thick = _per_group(data, f"faces_{NS}thickness", groups, panel_thickness)
    mats = _materials(data)
    names = _per_group(data, f"faces_{NS}material", groups, None)
    default = material or SU8
    panel_mat = []
    for g, name in enumerate(names):
        if name is None:
            panel_mat.append(default)
        elif name not in mats:
            _fail(f"faces_{NS}material[{groups[g][0]}]", f"{name!r} is not defined in "
                  f"{NS}materials (known: {', '.join(mats)}).")
        else:
            panel_mat.append(mats[name])
    crease = data.get(f"{NS}crease_material")
    if crease is not None and crease not in mats:
        _fail(f"{NS}crease_material", f"{crease!r} is not defined in {NS}materials (known: "
              f"{', '.join(mats)}).")
    for g, t in enumerate(thick):
        if t is None:
            _fail(f"faces_{NS}thickness", "missing: give every face a thickness [m] in the file "
                  "or pass panel_thickness=... to the reader.")
        if not (_is_number(t) and math.isfinite(t) and t > 0):
            _fail(f"faces_{NS}thickness[{groups[g][0]}]", f"{t!r} must be a positive length in "
                  "metres.")
    return {"panel_thickness": np.array(thick, float), "panel_material": panel_mat,
            "crease_material": mats[crease] if crease is not None else default}


def _per_group(data, field, groups, default) -> list:
    """One value per panel from a per-face field; merged faces must agree."""
    raw = _array_field(data, field, sum(len(g) for g in groups), "face")
    if raw is None:
        return [default] * len(groups)
    out = []
    for g in groups:
        values = [raw[f] for f in g]
        if any(v != values[0] for v in values):
            _fail(f"{field}[{g[1]}]", f"faces {g} are merged into one panel (F/J edges) but "
                  f"have different values {values}.")
        out.append(values[0])
    return out


def _materials(data) -> dict:
    out = dict(BUILTIN_MATERIALS)
    raw = data.get(f"{NS}materials", {})
    if not isinstance(raw, dict):
        _fail(f"{NS}materials", "must be an object {name: {youngs_modulus: ..., ...}}.")
    for name, props in raw.items():
        if not isinstance(props, dict):
            _fail(f"{NS}materials[{name!r}]", "must be an object of material properties.")
        try:
            out[name] = Material(name, **props)
        except (TypeError, ValueError) as exc:
            _fail(f"{NS}materials[{name!r}]", str(exc))
    return out


# ---------------------------------------------------------------------- metadata
def _metadata(data, vertex, face, edge, groups) -> dict:
    """Fields of other namespaces and FOLD metadata, re-indexed to the pattern."""
    out = {}
    merged = any(len(g) > 1 for g in groups)
    for key, value in data.items():
        if key in _OWN_FIELDS or key.startswith(NS) or f"_{NS}" in key:
            continue
        prefix = key.split("_", 1)[0]
        if prefix in ("vertices", "edges", "faces") and isinstance(value, list):
            index = {"vertices": vertex, "edges": edge, "faces": face}[prefix]
            if len(value) != len(index) or (merged and prefix != "vertices"):
                logger.warning("FOLD field %s dropped: it cannot be re-indexed to the pattern", key)
                continue
            keep = index >= 0
            order = np.argsort(index[keep], kind="stable")
            value = [value[i] for i in np.flatnonzero(keep)[order]]
        out[key] = value
    return out
