"""Crease, panel and metadata fields of a FOLD file turned into :class:`Pattern` inputs."""

from __future__ import annotations

import logging
import math
import re

import numpy as np

from ...errors import PatternError
from ...geometry.materials import SPR, SU8, SUBSTRATE, Material
from ...geometry.pattern import Pattern
from ._common import NS, array_field as _array_field, fail as _fail, is_number as _is_number

logger = logging.getLogger(__name__)

#: Built-in materials a file may name without defining them in ``etorigami:materials``.
BUILTIN_MATERIALS = {m.name: m for m in (SPR, SU8, SUBSTRATE)}
#: FOLD fields the reader interprets or regenerates on writing (not kept as metadata).
OWN_FIELDS = {"vertices_coords", "faces_vertices", "edges_vertices", "edges_assignment",
              "edges_foldAngle", "edges_foldAngles", "frame_unit", "file_spec", "file_creator",
              "file_frames", "edges_faces", "faces_edges", "vertices_vertices",
              "vertices_faces", "vertices_edges", "edges_lengths", "faceOrders", "edgeOrders",
              "faces_faces", "edges_edges", "file_frames", "frame_inherit", "frame_parent"}


_PATTERN_MESSAGE = [(re.compile(r"^vertices (\d+) and (\d+)"), "vertices_coords", 2),
                    (re.compile(r"^vertex (\d+)"), "vertices_coords", 1),
                    (re.compile(r"^panel (\d+)"), "faces_vertices", 1)]


def geometry_pattern(vertices, panels, face) -> Pattern:
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


def edge_fields(data, geo, edge, letters, angles, crease_width, crease_thickness) -> dict:
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
                  f"file or pass {key}=<m>.")
        return np.full(geo.n_edges, float(default))
    out = np.zeros(geo.n_edges)
    for i, e in enumerate(edge):
        if e >= 0 and geo.is_crease[e]:
            x = raw[i]
            if not (_is_number(x) and math.isfinite(x) and x > 0):
                _fail(f"{field}[{i}]", f"{x!r}; every crease needs a positive length in metres.")
            out[e] = x
    return out


def panel_fields(data, groups, panel_thickness, material) -> dict:
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
                  "or pass panel_thickness=<m>.")
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
def metadata_fields(data, vertex, face, edge, groups, merged_edges: bool = False) -> dict:
    """Fields of other namespaces and FOLD metadata, re-indexed to the pattern."""
    out = {}
    merged = any(len(g) > 1 for g in groups) or merged_edges
    for key, value in data.items():
        if key in OWN_FIELDS or key.startswith(NS) or f"_{NS}" in key:
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
