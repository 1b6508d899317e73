"""FOLD reader: a FOLD 1.0-1.2 file (key frame) to a :class:`~simulator.geometry.pattern.Pattern`.

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
from dataclasses import dataclass

import numpy as np

from ...errors import FoldFormatError, ParameterError, PatternError
from ...geometry.materials import Material
from ...geometry.pattern import Pattern
from ._common import NS, array_field as _array_field, fail as _fail, index_list as _index_list
from ._common import is_number as _is_number
from ._data import OWN_FIELDS, edge_fields, geometry_pattern, metadata_fields, panel_fields
from ._frames import select_frame
from ._merge import merge_flat_faces
from ._planar import faces_from_edges, lay_flat_sheet, merge_straight

__all__ = ["read_fold", "fold_to_pattern", "parse_fold", "load_fold_json", "FoldGeometry",
           "check_crease_model", "SHARP_PLACEHOLDER", "UNITS"]

logger = logging.getLogger(__name__)

#: Metres per FOLD ``frame_unit`` (``"unit"`` needs an explicit ``unit_scale``).
UNITS = {"in": 0.0254, "pt": 0.0254 / 72, "m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6,
         "nm": 1e-9}
_LETTERS = "BMVFUCJ"


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
        The parsed frame (all fields, for the model reader).
    notes : tuple of str
        What the reader repaired or recognised (derived faces, merged vertices, a sheet in
        another plane), for summaries.
    crease_model : {"compliant", "sharp"}
        The crease model the file or the reader's keywords ask for (:func:`check_crease_model`).
    sharp_missing : tuple of str
        Sharp creases only: the crease data neither the file nor the keywords give
        (``"crease_width"``, ``"crease_thickness"``). The pattern then carries the placeholder
        :data:`SHARP_PLACEHOLDER` there, and the model reader asks for the fold stiffness and
        the panel bending width instead of deriving them from it.
    """

    pattern: Pattern
    vertex: np.ndarray
    face: np.ndarray
    edge: np.ndarray
    data: dict
    notes: tuple = ()
    crease_model: str = "compliant"
    sharp_missing: tuple = ()


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
    """Read a FOLD file into a :class:`~simulator.geometry.pattern.Pattern` (keywords: see
    :func:`fold_to_pattern`)."""
    return fold_to_pattern(load_fold_json(path), **kwargs)


def fold_to_pattern(data: dict, **kwargs) -> Pattern:
    """Pattern of a parsed FOLD dict.

    Parameters
    ----------
    data : dict
        The FOLD key frame (top-level object).

    Other Parameters
    ----------------
    unit_scale : float, optional
        Metres per coordinate unit; required (and only allowed) when ``frame_unit`` is
        ``"unit"`` or absent.
    crease_width, crease_thickness, panel_thickness : float, optional
        Values [m] for files without ``edges_etorigami:width``, ``edges_etorigami:thickness``,
        ``faces_etorigami:thickness``.
    material : Material, optional
        Panel and crease material of files without ``faces_etorigami:material`` (default SU-8).
    frame : int or str, optional
        The frame to read: an index (0 = the key frame, k = ``file_frames[k - 1]``) or a class,
        ``"creasePattern"`` or ``"foldedForm"``; default the key frame.
    merge_collinear : bool
        Merge away vertices in the middle of a straight crease line (two alike creases,
        collinear), default True; T-junctions are meshed with straight corners.
    lay_flat : bool or None
        A flat sheet in another plane than x-y (e.g. x-z): None (default) lays it in x-y, its
        top side up (the side its faces run counter-clockwise around), unless the file gives
        data in its own axes (:data:`~simulator.io.fold._planar.FRAME_FIELDS`, or a thermal ``substrate`` plane); True
        always lays it in x-y, False never. Laid flat, a rotated copy of a sheet has the
        answer of the sheet drawn in x-y (up to a turn within the plane), and gravity acts
        towards its bottom side.
    crease_model : {"compliant", "sharp"}
        Compliant creases with a width (default), or ``"sharp"`` (concentrated hinges; also
        chosen by ``crease_width=0`` or width 0 on every crease in ``edges_etorigami:width``).
        A sharp pattern needs no crease width or thickness: what is missing is recorded in
        :attr:`FoldGeometry.sharp_missing` (the model reader then needs the fold stiffness).
    """
    return parse_fold(data, **kwargs).pattern


def parse_fold(data: dict, *, unit_scale=None, crease_width=None, crease_thickness=None,
               panel_thickness=None, material: Material | None = None, frame=None,
               merge_collinear: bool = True, lay_flat: bool | None = None,
               crease_model: str = "compliant") -> FoldGeometry:
    """Validate a FOLD dict and build the pattern and the index maps (:class:`FoldGeometry`)."""
    if not isinstance(data, dict):
        raise FoldFormatError(f"FOLD data must be a dict (JSON object), got {type(data).__name__}.")
    check_crease_model(crease_model, crease_width)
    data = select_frame(data, frame)
    notes = []
    coords = _coords(data) * _scale(data, unit_scale)
    given = _faces(data, len(coords)) if data.get("faces_vertices") is not None else None
    coords = lay_flat_sheet(coords, given, lay_flat, data, notes)
    if data.get("faces_vertices") is None and data.get("edges_vertices") is not None:
        raw = _index_pairs(data, len(coords))
        data = {**data, "faces_vertices": faces_from_edges(coords, raw)}
        notes.append(f"faces derived from the planar graph ({len(data['faces_vertices'])} faces; "
                     "the file has no faces_vertices)")
    faces = _faces(data, len(coords))
    edges, letters, angles = _edges(data, len(coords), faces)
    groups, panels = merge_flat_faces(coords, faces, edges, letters)
    alias = [None] * len(edges)
    if merge_collinear:
        before = len(set(np.concatenate(panels).tolist()))
        panels, alias = merge_straight(coords, panels, edges, letters,
                                       lambda i, j: _alike(data, letters, angles, i, j))
        dropped = before - len(set(np.concatenate(panels).tolist()))
        if dropped:
            notes.append(f"{dropped} vertices in the middle of straight crease lines merged away")
    vertex, used = _compact(len(coords), faces, panels)
    panels = [tuple(int(vertex[v]) for v in p) for p in panels]
    face = np.empty(len(faces), int)
    for g, members in enumerate(groups):
        face[members] = g
    geo = geometry_pattern(coords[used], panels, face)
    key = {tuple(e): i for i, e in enumerate(geo.edges.tolist())}
    ends = [alias[i] or (a, b) for i, (a, b) in enumerate(edges.tolist())]
    edge = np.array([key.get(tuple(sorted((vertex[a], vertex[b]))), -1) if vertex[a] >= 0
                     and vertex[b] >= 0 else -1 for a, b in ends], int).reshape(-1)
    crease_model = check_crease_model(crease_model, crease_width, data, edge)
    missing = ()
    if crease_model == "sharp":
        data, crease_width, crease_thickness, missing = _sharp_defaults(
            data, edge, crease_width, crease_thickness)
    per_edge = edge_fields(data, geo, edge, letters, angles, crease_width, crease_thickness)
    per_panel = panel_fields(data, groups, panel_thickness, material)
    merged = any(a is not None for a in alias)
    try:
        pattern = Pattern(geo.vertices, geo.panels, **per_edge, **per_panel,
                          metadata=metadata_fields(data, vertex, face, edge, groups, merged))
    except PatternError as exc:
        _fail("etorigami data", str(exc))
    _note_sign_mismatch(pattern, notes)
    return FoldGeometry(pattern, vertex, face, edge, data, tuple(notes), crease_model, missing)


def _note_sign_mismatch(pattern: Pattern, notes: list) -> None:
    """Report folded creases whose start fold disagrees with their assignment / fold angle."""
    from ...geometry.orientation import start_fold_angles

    c = pattern.creases
    start, design = start_fold_angles(pattern)[c], pattern.edge_fold_angle[c]
    bad = c[(np.abs(start) > 1e-6) & (start * design < 0)]
    if len(bad):
        notes.append(f"creases {bad.tolist()} are folded against their assignment in the start "
                     "shape (the geometry decides the mechanics)")
        logger.warning("FOLD: %s", notes[-1])


def check_crease_model(crease_model, crease_width, data=None, edge=None) -> str:
    """The crease model a read asks for: ``"compliant"`` (creases with a width) or ``"sharp"``
    (concentrated hinges, :func:`~simulator.model.sharp.sharp_model`).

    ``crease_model="sharp"``, ``crease_width=0``, width 0 on every crease of
    ``edges_etorigami:width`` or an ``etorigami:sharp_hinge`` object ask for sharp creases. A file whose creases mix width 0 and
    positive widths is refused (per-crease mixing of the two models is not implemented).

    Parameters
    ----------
    crease_model : str
    crease_width : float or None
        The reader's default crease width [m].
    data : dict, optional
        The FOLD frame; with ``edge`` (file edge -> pattern edge, -1 merged away) its widths
        are checked too.

    Returns
    -------
    str
        ``"compliant"`` or ``"sharp"``.
    """
    if crease_model not in ("compliant", "sharp"):
        raise ParameterError(f"crease_model = {crease_model!r}; use 'compliant' (creases with a "
                             "width) or 'sharp' (concentrated hinges).")
    sharp = crease_model == "sharp" or (crease_width is not None and _is_number(crease_width)
                                        and crease_width == 0)
    sharp = sharp or (data is not None and data.get(f"{NS}sharp_hinge") is not None)
    widths = None if data is None else data.get(f"edges_{NS}width")
    if isinstance(widths, list) and edge is not None:
        letters = data.get("edges_assignment")
        on = [i for i, (w, e) in enumerate(zip(widths, edge)) if e >= 0 and w is not None and
              not (isinstance(letters, list) and i < len(letters) and
                   str(letters[i]).upper() in "BFJC")]
        zero = [i for i in on if _is_number(widths[i]) and widths[i] == 0]
        if zero and len(zero) < len(on):
            raise ParameterError(
                f"edges_{NS}width: creases (file edges) {zero} have width 0 (sharp hinges) and "
                f"{len(on) - len(zero)} others a positive width; mixing sharp and compliant "
                "creases in one model is not implemented: give every crease width 0 or every "
                "crease a positive width.")
        sharp = sharp or bool(zero)
    return "sharp" if sharp else "compliant"


#: Crease width and thickness [m] a sharp pattern carries where neither the file nor the
#: reader gives them (a :class:`Pattern` needs positive values; the sharp model uses them only
#: for its default fold stiffness and panel bending width, which are then asked for).
SHARP_PLACEHOLDER = 1e-6


def _sharp_defaults(data, edge, crease_width, crease_thickness):
    """``(data, crease_width, crease_thickness, missing)`` of a sharp read: widths of 0 are
    dropped, and crease data that nobody gives become :data:`SHARP_PLACEHOLDER`."""
    missing = []
    width_field = f"edges_{NS}width"
    widths = data.get(width_field)
    if isinstance(widths, list) and all(not _is_number(w) or w == 0 or e < 0
                                        for w, e in zip(widths, edge)):
        data = {k: v for k, v in data.items() if k != width_field}
    if width_field not in data and not (_is_number(crease_width) and crease_width > 0):
        crease_width = SHARP_PLACEHOLDER
        missing.append("crease_width")
    if f"edges_{NS}thickness" not in data and crease_thickness is None:
        crease_thickness = SHARP_PLACEHOLDER
        missing.append("crease_thickness")
    return data, crease_width, crease_thickness, tuple(missing)


def _alike(data, letters, angles, i, j) -> bool:
    """True if file edges i and j carry the same assignment, fold angle and per-edge data."""
    if letters[i] != letters[j] or angles[i] != angles[j]:
        return False
    for key, value in data.items():
        if key.startswith("edges_") and key not in OWN_FIELDS and isinstance(value, list) \
                and len(value) > max(i, j) and value[i] != value[j]:
            return False
    return True


def _index_pairs(data, n_vertices) -> np.ndarray:
    value = data.get("edges_vertices")
    if not isinstance(value, list):
        _fail("edges_vertices", "must be a list of [u, v] vertex pairs.")
    return np.array([_index_list(e, f"edges_vertices[{i}]", n_vertices, 2)
                     for i, e in enumerate(value)], int).reshape(-1, 2)


def _compact(n_vertices: int, faces: list, panels: list):
    """Pattern id of every file vertex (-1 if in no panel) and the used file vertices."""
    loose = np.setdiff1d(np.arange(n_vertices), np.concatenate(faces))
    if len(loose):
        logger.warning("FOLD vertices_coords: vertices %s belong to no face; dropped",
                       loose.tolist())
    vertex = np.full(n_vertices, -1)
    used = np.unique(np.concatenate([np.asarray(p) for p in panels]))
    vertex[used] = np.arange(len(used))
    return vertex, used


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
            default = "" if "frame_unit" in data else " (the FOLD default)"
            _fail("frame_unit", f"is {unit!r}{default}; pass unit_scale=<metres per unit> or set "
                  f"frame_unit to one of {', '.join(UNITS)}.")
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
            _fail(f"edges_assignment[{i}]", "cut 'C' between two faces is not supported; give "
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
