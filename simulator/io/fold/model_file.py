"""Model files: a whole model and its loading steps in one FOLD file.

On top of the pattern fields (:mod:`simulator.io.fold.writer`), a model file carries the
bar-and-hinge parameters, supports, contact, thermal parameters, actuators, heater circuits
and the ordered loading steps under the ``etorigami:`` namespace (``docs/fold-format.md``).
:func:`write_model` then :func:`read_model` rebuilds the same model and steps, so a run of
the file reproduces the run of the original.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np

from ...model.bimorph import Actuators, Bimorph
from ...errors import ParameterError
from ...model.mesh import make_mesh
from ...model.model import ContactParameters, Model, Supports, make_model
from ...model.properties import BarHingeParameters
from ...steps import Step
from ...model.thermal_parameters import ThermalParameters
from ._common import NS, array_field, fail, is_number
from .reader import load_fold_json, parse_fold
from .writer import dump_fold, pattern_to_fold

__all__ = ["model_to_fold", "write_model", "fold_to_model", "read_model"]

#: Step fields whose keys are crease (edge) ids; a key may also be "a+b" (a circuit of
#: creases a and b) or a heater circuit name from ``edges_etorigami:heater``.
_EDGE_KEYED = {"SelfFold": "folds", "Heat": "power"}


# ---------------------------------------------------------------------- writing
def model_to_fold(model: Model, steps=(), title: str | None = None,
                  description: str | None = None) -> dict:
    """FOLD dict of a model and its loading steps."""
    if not isinstance(model, Model):
        raise ParameterError(f"model_to_fold expects a Model, got {type(model).__name__}.")
    mesh = model.mesh
    pattern = mesh.pattern
    out = pattern_to_fold(pattern)
    if title is not None:
        out["frame_title"] = title
    if description:
        out["frame_description"] = description
    if getattr(mesh, "sharp", False):
        _sharp_fields(model, out)
    else:
        if not np.array_equal(mesh.nodes, make_mesh(pattern).nodes):
            out[f"{NS}mesh_nodes"] = mesh.nodes.tolist()
        out[f"{NS}bar_hinge"] = model.params.to_dict()
    out[f"{NS}supports"] = {"fixed": {str(k): v for k, v in model.supports.fixed.items()},
                            "elastic": [list(e) for e in model.supports.elastic]}
    if model.contact is not None:
        out[f"{NS}contact"] = model.contact.to_dict()
    if model.thermal is not None:
        thermal = model.thermal.to_dict()
        boundary = set(thermal.pop("boundary_panels"))
        thermal["room_temperature_nodes"] = list(thermal["room_temperature_nodes"])
        out[f"{NS}thermal"] = thermal
        out[f"faces_{NS}substrate"] = [p in boundary for p in range(pattern.n_panels)]
    if model.actuators is not None:
        out[f"{NS}bimorph"] = dataclasses.asdict(model.actuators.bimorph)
        da = {int(k): float(v) for k, v in dict(model.actuators.delta_alpha).items()}
        out[f"edges_{NS}delta_alpha"] = [da.get(e) for e in range(pattern.n_edges)]
        if model.actuators.scatter:
            out[f"{NS}actuation_scatter"] = {"scatter": float(model.actuators.scatter),
                                             "seed": int(model.actuators.seed)}
    steps = tuple(steps)
    circuits = _circuits(steps, pattern.n_edges)
    if circuits:
        heater = [None] * pattern.n_edges
        for name, members in circuits.items():
            for e in members:
                heater[e] = name
        out[f"edges_{NS}heater"] = heater
    out[f"{NS}steps"] = [_encode_step(s, i, circuits) for i, s in enumerate(steps)]
    return out


def _sharp_fields(model: Model, out: dict) -> None:
    """``etorigami:sharp_hinge`` (and per-crease fold stiffnesses) of a concentrated-hinge
    model; its mesh follows from the pattern and the panel mesh."""
    from ...model.sharp_mesh import build_sharp_mesh

    p, mesh = model.params, model.mesh
    if not np.array_equal(mesh.nodes, build_sharp_mesh(mesh.pattern, p.panel_mesh).nodes):
        raise ParameterError("model_to_fold: the sharp model's nodes were edited after meshing; "
                             "FOLD model files keep node edits of compliant models only.")
    k = p.fold_stiffness
    out[f"{NS}sharp_hinge"] = {"panel_bending_width": p.panel_bending_width,
                               "panel_mesh": p.panel_mesh,
                               "fold_stiffness": None if isinstance(k, dict) else k}
    if isinstance(k, dict):
        out[f"edges_{NS}fold_stiffness"] = [k.get(e) for e in range(mesh.pattern.n_edges)]


def write_model(model: Model, steps, path, title: str | None = None,
                description: str | None = None):
    """Write a model and its loading steps to a FOLD model file; returns the path."""
    return dump_fold(model_to_fold(model, steps, title, description), path)


def _circuits(steps, n_edges) -> dict:
    """Name heater circuits (tuple keys of Heat powers) when they do not overlap."""
    keys = []
    for s in steps:
        if type(s).__name__ == "Heat":
            keys += [tuple(int(c) for c in k) for k in dict(s.power) if isinstance(k, tuple)]
    keys = list(dict.fromkeys(keys))
    used = [c for k in keys for c in k]
    if len(set(used)) != len(used):
        return {}
    return {f"circuit{i + 1}": k for i, k in enumerate(keys)}


def _encode_step(step, index: int, circuits: dict) -> dict:
    if not (isinstance(step, Step) and dataclasses.is_dataclass(step)):
        raise ParameterError(f"steps[{index}] = {step!r} is not a Step dataclass; only loading "
                             "steps can be written to FOLD.")
    names = {v: k for k, v in circuits.items()}
    out = {"type": type(step).__name__}
    for f in dataclasses.fields(step):
        if not f.init:
            continue
        value = getattr(step, f.name)
        if f.name == "circuits":                  # heater circuits (theory 8.8)
            if value:
                raise ParameterError(f"steps[{index}].circuits: heater circuits have no FOLD "
                                     "form yet; write the steps without them (powers per "
                                     "crease) and give the circuits in Python.")
            continue
        if _EDGE_KEYED.get(out["type"]) == f.name:
            value = {names.get(_key_tuple(k), k): v for k, v in dict(value).items()}
        out[f.name] = _encode(value, f"steps[{index}].{f.name}")
    return out


def _key_tuple(k):
    return tuple(int(c) for c in k) if isinstance(k, tuple) else None


def _encode(value, where: str):
    if isinstance(value, Mapping):
        return {_encode_key(k, where): _encode(v, where) for k, v in value.items()}
    if isinstance(value, (tuple, list)):
        return [_encode(v, where) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.integer, np.floating, np.bool_)):
        return value.item()
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise ParameterError(f"{where} = {value!r} ({type(value).__name__}) has no FOLD form.")


def _encode_key(k, where: str) -> str:
    if isinstance(k, tuple):
        return "+".join(str(int(c)) for c in k)
    if isinstance(k, (int, np.integer, str)) and not isinstance(k, bool):
        return str(k)
    raise ParameterError(f"{where}: key {k!r} has no FOLD form (use ids or tuples of ids).")


# ---------------------------------------------------------------------- reading
def read_model(path, **kwargs):
    """Read a FOLD model file: returns ``(model, steps)`` (keywords: see
    :func:`fold_to_model` and :func:`~simulator.io.fold.reader.fold_to_pattern`)."""
    return fold_to_model(load_fold_json(path), **kwargs)


def fold_to_model(data: dict, *, fold_stiffness=None, panel_bending_width=None,
                  panel_mesh=None, **kwargs):
    """``(model, steps)`` of a parsed FOLD dict; missing model fields take defaults (no
    supports, no contact, no thermal parameters, no actuators, no steps).

    Parameters
    ----------
    data : dict
    fold_stiffness : float, optional
        Sharp creases: fold-spring stiffness per unit crease length [N m/rad/m] of the creases
        without ``edges_etorigami:fold_stiffness``; default ``E t^3 / (12 W)`` of the crease.
    panel_bending_width : float, optional
        Sharp creases: the length [m] of the panel bending rule; default the mean crease width.
    panel_mesh : {"N5B8", "N4B5"}, optional
        Sharp creases: the meshing of quadrilateral panels (default N5B8).
    **kwargs
        Reader keywords (:func:`~simulator.io.fold.reader.fold_to_pattern`), among them
        ``crease_model="sharp"``.
    """
    geo = parse_fold(data, **kwargs)
    sharp = {"fold_stiffness": fold_stiffness, "panel_bending_width": panel_bending_width,
             "panel_mesh": panel_mesh}
    if geo.crease_model == "sharp":
        return _sharp_file_model(geo, sharp)
    given = [k for k, v in sharp.items() if v is not None]
    if given:
        raise ParameterError(f"{', '.join(given)} apply to sharp creases only; pass "
                             "crease_model='sharp' or drop them.")
    data = geo.data                                   # the chosen frame
    mesh = make_mesh(geo.pattern)
    nodes = data.get(f"{NS}mesh_nodes")
    if nodes is not None:
        mesh = _guard(f"{NS}mesh_nodes", lambda: mesh.with_nodes(np.array(nodes, float)))
    params = _guard(f"{NS}bar_hinge", lambda: BarHingeParameters(
        **_obj(data, f"{NS}bar_hinge")))
    supports = _guard(f"{NS}supports", lambda: _supports(data, geo, mesh))
    contact = data.get(f"{NS}contact")
    if contact is not None:
        contact = _guard(f"{NS}contact", lambda: ContactParameters(**_obj(data, f"{NS}contact")))
    thermal = _thermal(data, geo)
    actuators = _actuators(data, geo)
    model = _guard("model", lambda: make_model(mesh, supports, params, contact, thermal,
                                               actuators))
    steps = _steps(data, geo)
    return model, steps


def _sharp_file_model(geo, given: dict):
    """``(model, steps)`` of a file read with concentrated hinges (:mod:`.sharp_file`)."""
    from .sharp_file import sharp_hinge_parameters

    from ...model.sharp import sharp_model
    from ...model.sharp_mesh import build_sharp_mesh

    data = geo.data
    params = sharp_hinge_parameters(geo, **given)
    for field in (f"{NS}contact", f"{NS}thermal", f"{NS}bimorph", f"{NS}actuation_scatter"):
        if data.get(field) is not None:
            fail(field, "is given, but the file is read with sharp creases (concentrated "
                 "hinges), which have no crease area to heat, actuate or touch; give the "
                 "creases a positive width (compliant creases) or drop the field.")
    mesh = _guard(f"{NS}sharp_hinge", lambda: build_sharp_mesh(geo.pattern, params.panel_mesh))
    supports = _guard(f"{NS}supports", lambda: _supports(data, geo, mesh))
    model = _guard("model", lambda: sharp_model(geo.pattern, supports, params))
    return model, _steps(data, geo)


def _guard(field: str, build):
    """Run ``build``; parameter errors become one FoldFormatError naming ``field``."""
    try:
        return build()
    except (TypeError, ValueError) as exc:
        fail(field, str(exc))


def _obj(data, field) -> dict:
    value = data.get(field) or {}
    if not isinstance(value, dict):
        fail(field, f"must be a JSON object, got {value!r}.")
    return value


def _supports(data, geo, mesh) -> Supports:
    raw = _obj(data, f"{NS}supports")
    fixed = {int(k): v for k, v in (raw.get("fixed") or {}).items()}
    supports = Supports(fixed, tuple(tuple(e) for e in raw.get("elastic") or ()))
    faces = array_field(data, f"faces_{NS}support", len(geo.face), "face")
    for f, dirs in enumerate(faces or ()):
        if dirs:
            supports = supports | Supports.nodes(mesh.panel_nodes(int(geo.face[f])), dirs)
    verts = array_field(data, f"vertices_{NS}support", len(geo.vertex), "vertex")
    for v, dirs in enumerate(verts or ()):
        if dirs:
            if geo.vertex[v] < 0:
                fail(f"vertices_{NS}support[{v}]", f"vertex {v} was merged "
                     "away (inside an F/J region); support a panel instead.")
            supports = supports | Supports.nodes(
                np.flatnonzero(mesh.node_vertex == geo.vertex[v]), dirs)
    return supports


def _thermal(data, geo):
    raw = data.get(f"{NS}thermal")
    if raw is None:
        return None
    raw = dict(_obj(data, f"{NS}thermal"))
    flags = array_field(data, f"faces_{NS}substrate", len(geo.face), "face") or ()
    raw["boundary_panels"] = tuple(sorted({int(geo.face[f]) for f, s in enumerate(flags) if s}))
    raw["room_temperature_nodes"] = tuple(raw.get("room_temperature_nodes", ()))
    return _guard(f"{NS}thermal", lambda: ThermalParameters.from_dict(raw))


def _actuators(data, geo):
    raw = data.get(f"{NS}bimorph")
    if raw is None:
        return None
    bimorph = _guard(f"{NS}bimorph", lambda: Bimorph(**_obj(data, f"{NS}bimorph")))
    da = _crease_values(data, f"edges_{NS}delta_alpha", geo, "a number in 1/K",
                        lambda v: is_number(v) and math.isfinite(v))
    scatter = dict(_obj(data, f"{NS}actuation_scatter")) if f"{NS}actuation_scatter" in data \
        else {}
    return _guard(f"{NS}actuation_scatter", lambda: Actuators(
        bimorph, {e: float(v) for e, v in da.items()}, **scatter))


def _crease_values(data, field, geo, allowed: str, ok) -> dict:
    """{pattern crease id: value} of a per-edge field; non-null entries must be on creases and
    pass ``ok``."""
    out = {}
    for i, v in enumerate(array_field(data, field, len(geo.edge), "edge") or ()):
        if v is None:
            continue
        e = int(geo.edge[i])
        if not ok(v) or e < 0 or not geo.pattern.is_crease[e]:
            fail(f"{field}[{i}]", f"{v!r}; give {allowed} on creases only, null elsewhere.")
        out[e] = v
    return out


def _steps(data, geo) -> tuple:
    raw = data.get(f"{NS}steps", [])
    if not isinstance(raw, list):
        fail(f"{NS}steps", "must be a list of step objects.")
    known = _step_classes()
    circuits = _heater_circuits(data, geo)
    steps = []
    for i, item in enumerate(raw):
        where = f"{NS}steps[{i}]"
        if not isinstance(item, dict) or item.get("type") not in known:
            got = item.get("type") if isinstance(item, dict) else item
            fail(where, f"type {got!r} is not a step; known: "
                 f"{', '.join(sorted(known))}.")
        kind = item["type"]
        kwargs = {k: _decode(v) for k, v in item.items() if k != "type"}
        field = _EDGE_KEYED.get(kind)
        if field in kwargs:
            kwargs[field] = _edge_keys(kwargs[field], geo, circuits, f"{where}.{field}")
        steps.append(_guard(where, lambda: known[kind](**kwargs)))
    return tuple(steps)


def _step_classes() -> dict:
    out, todo = {}, list(Step.__subclasses__())
    while todo:
        cls = todo.pop()
        todo += cls.__subclasses__()
        if dataclasses.is_dataclass(cls):
            out[cls.__name__] = cls
    return out


def _decode(value):
    """JSON to step values: lists to tuples, object keys of digits to int ids."""
    if isinstance(value, list):
        return tuple(_decode(v) for v in value)
    if isinstance(value, dict):
        return {_decode_key(k): _decode(v) for k, v in value.items()}
    return value


def _decode_key(k: str):
    parts = k.split("+")
    if all(p.isdigit() for p in parts):
        return int(k) if len(parts) == 1 else tuple(int(p) for p in parts)
    return k


def _heater_circuits(data, geo) -> dict:
    names = _crease_values(data, f"edges_{NS}heater", geo, "a circuit name (string)",
                           lambda v: isinstance(v, str))
    out = {}
    for e, name in names.items():
        out.setdefault(name, []).append(e)
    return {k: tuple(sorted(v)) for k, v in out.items()}


def _edge_keys(mapping, geo, circuits, where) -> dict:
    """Map file edge ids / circuit names to pattern crease ids."""
    if not isinstance(mapping, dict):
        fail(where, "must be an object keyed by edge id or circuit.")
    n = len(geo.edge)

    def edge(i):
        if not 0 <= i < n or geo.edge[i] < 0:
            fail(where, f"edge {i} is not an edge of the file "
                 f"(0..{n - 1}, F/J edges excluded).")
        return int(geo.edge[i])

    out = {}
    for k, v in mapping.items():
        if isinstance(k, str):
            if k not in circuits:
                fail(where, f"{k!r} is neither an edge id nor a circuit "
                     f"of edges_{NS}heater (circuits: {sorted(circuits)}).")
            out[circuits[k]] = v
        else:
            out[tuple(edge(i) for i in k) if isinstance(k, tuple) else edge(k)] = v
    return out
