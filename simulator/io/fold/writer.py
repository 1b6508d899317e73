"""FOLD writer: patterns back to FOLD, simulation histories to multi-frame FOLD.

:func:`pattern_to_fold` writes the pattern's vertices (metres, ``frame_unit: "m"``), panels,
edges in edge-id order with their assignments and fold angles, and the crease and panel data
under the ``etorigami:`` namespace; :func:`~simulator.io.fold.reader.fold_to_pattern` reads it
back exactly (JSON floats round-trip). :func:`result_to_fold_frames` writes the simulated
bar-and-hinge mesh as the key frame and one inheriting frame per record.
"""

from __future__ import annotations

import json
import pathlib

import numpy as np

from ..._version import __version__
from ..._validate import integer
from ...errors import ParameterError
from ...geometry.pattern import Pattern
from ._common import NS
from ._data import OWN_FIELDS

__all__ = ["pattern_to_fold", "write_fold", "result_to_fold_frames", "write_fold_frames",
           "dump_fold"]

#: FOLD spec version written.
FILE_SPEC = 1.2
_CREATOR = f"etorigami {__version__}"


def pattern_to_fold(pattern: Pattern) -> dict:
    """FOLD dict of a pattern (key frame only); see ``docs/fold-format.md``."""
    if not isinstance(pattern, Pattern):
        raise ParameterError(f"pattern_to_fold expects a Pattern, got {type(pattern).__name__}.")
    meta = {k: v for k, v in pattern.metadata.items()
            if k not in OWN_FIELDS and NS not in k}          # never overrides our own fields
    file_meta = {k: meta.pop(k) for k in list(meta) if k.startswith("file_")}
    crease = pattern.is_crease
    mats = _material_table(pattern)
    out = {"file_spec": FILE_SPEC, "file_creator": _CREATOR, **file_meta,
           "frame_unit": "m",
           "vertices_coords": pattern.vertices.tolist(),
           "faces_vertices": [list(p) for p in pattern.panels],
           "edges_vertices": pattern.edges.tolist(),
           "edges_assignment": pattern.edge_assignment.tolist(),
           "edges_foldAngle": np.degrees(pattern.edge_fold_angle).tolist(),
           f"edges_{NS}width": _on_creases(pattern.crease_width, crease),
           f"edges_{NS}thickness": _on_creases(pattern.crease_thickness, crease),
           f"faces_{NS}thickness": pattern.panel_thickness.tolist(),
           f"faces_{NS}material": [m.name for m in pattern.panel_material],
           f"{NS}crease_material": pattern.crease_material.name,
           f"{NS}materials": mats}
    out.update(meta)
    return out


def _on_creases(values, crease) -> list:
    return [float(v) if c else None for v, c in zip(values, crease)]


def _material_table(pattern: Pattern) -> dict:
    table = {}
    for m in (*pattern.panel_material, pattern.crease_material):
        props = m.to_dict()
        name = props.pop("name")
        if table.setdefault(name, props) != props:
            raise ParameterError(f"Two different materials are both named {name!r}; give them "
                                 "distinct names before writing FOLD.")
    return table


def dump_fold(data: dict, path) -> pathlib.Path:
    """Write a FOLD dict as JSON, one top-level field per line; returns the path."""
    path = pathlib.Path(path)
    try:
        lines = [f"  {json.dumps(k)}: {json.dumps(v, allow_nan=False)}" for k, v in data.items()]
    except ValueError as exc:
        raise ParameterError(f"cannot write FOLD: {exc} (NaN or inf values have no JSON form).") \
            from None
    path.write_text("{\n" + ",\n".join(lines) + "\n}\n", encoding="utf-8")
    return path


def write_fold(pattern: Pattern, path) -> pathlib.Path:
    """Write a pattern to a FOLD file (metres); returns the path."""
    return dump_fold(pattern_to_fold(pattern), path)


# ---------------------------------------------------------------------- frames
def result_to_fold_frames(result, every: int = 1) -> dict:
    """Multi-frame FOLD of a :class:`~simulator.results.SimulationResult`.

    The key frame is the bar-and-hinge mesh at the initial record (vertices = mesh nodes,
    faces = mesh triangles, ``B`` on the outline and ``F`` inside); ``file_frames`` hold every
    ``every``-th record (and the last) with ``frame_inherit: true``, ``frame_parent: 0``, the
    node positions, node temperatures [deg C] and per-crease fold angles [rad], rotations
    since the initial record [rad], temperatures [deg C] and powers [W] under ``etorigami:``.
    """
    integer("every", every, hint="the frame stride")
    mesh = result.model.mesh
    h = result.history
    m = len(h["stage"])
    records = sorted(set(range(0, m, every)) | {m - 1})
    x = mesh.nodes[None] + h["u"]
    tri = _oriented_triangles(mesh)
    edges, letters = _triangle_edges(tri)
    fold = result.fold_angle

    def frame_data(r):
        return {"vertices_coords": x[r].tolist(),
                f"vertices_{NS}temperature": h["temperature"][r].tolist(),
                f"{NS}fold_angle": fold[r].tolist(),
                f"{NS}crease_rotation": (fold[r] - fold[0]).tolist(),
                f"{NS}crease_temperature": result.crease_temperature[r].tolist(),
                f"{NS}crease_power": h["power"][r].tolist()}

    frames = [{"frame_title": _title(h, r), "frame_parent": 0, "frame_inherit": True,
               **frame_data(r)} for r in records[1:]]
    return {"file_spec": FILE_SPEC, "file_creator": _CREATOR, "file_classes": ["animation"],
            "frame_title": _title(h, 0), "frame_classes": ["foldedForm"], "frame_unit": "m",
            "faces_vertices": tri.tolist(), "edges_vertices": edges.tolist(),
            "edges_assignment": letters, f"{NS}crease_edges": mesh.crease_ids.tolist(),
            **frame_data(0), "file_frames": frames}


def write_fold_frames(result, path, every: int = 1) -> pathlib.Path:
    """Write a simulation history as multi-frame FOLD (:func:`result_to_fold_frames`)."""
    return dump_fold(result_to_fold_frames(result, every), path)


def _title(h, r) -> str:
    if r == 0:
        return "initial"
    return f"{h['stage_name'][r]} increment {int(h['increment'][r])}"


def _oriented_triangles(mesh) -> np.ndarray:
    """Mesh triangles ordered counterclockwise seen from +z in the reference geometry."""
    tri = mesh.triangles.copy()
    x = mesh.nodes
    nz = np.cross(x[tri[:, 1]] - x[tri[:, 0]], x[tri[:, 2]] - x[tri[:, 0]])[:, 2]
    flip = nz < 0
    tri[flip, 1], tri[flip, 2] = mesh.triangles[flip, 2], mesh.triangles[flip, 1]
    return tri


def _triangle_edges(tri: np.ndarray):
    """Unique triangle sides (E, 2) and their assignment: B (one triangle) or F."""
    sides = np.sort(np.stack([tri, np.roll(tri, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    edges, counts = np.unique(sides, axis=0, return_counts=True)
    return edges, ["B" if c == 1 else "F" for c in counts]
