"""Sharp creases from FOLD files: the concentrated-hinge parameters of a file read with
``crease_model="sharp"`` (or width 0 on its creases).

The fold stiffness per unit crease length [N m/rad/m] comes, crease by crease, from
``edges_etorigami:fold_stiffness``, else from the reader's ``fold_stiffness``, else from the
object ``etorigami:sharp_hinge`` (``{"fold_stiffness", "panel_bending_width", "panel_mesh"}``),
else from the default rule ``E t^3 / (12 W)`` of the crease, which needs the crease width and
thickness. The panel bending width [m] comes from the reader, the object, or the mean crease
width. What is missing is named in one error, in the reader's keywords (the CLI says its
options, :mod:`design.cli._terms`).
"""

from __future__ import annotations

import math

from ..._validate import capped
from ...errors import ParameterError
from ...model.sharp import SharpHingeParameters
from ._common import NS, fail, is_number

__all__ = ["sharp_hinge_parameters", "SHARP_FIELDS"]

#: Keys of ``etorigami:sharp_hinge``.
SHARP_FIELDS = ("fold_stiffness", "panel_bending_width", "panel_mesh")

_FLAGS = {"fold_stiffness": "fold_stiffness=<N m/rad/m>",
          "panel_bending_width": "panel_bending_width=<m>",
          "crease_width": "crease_width=<m>", "crease_thickness": "crease_thickness=<m>"}


def sharp_hinge_parameters(geo, fold_stiffness=None, panel_bending_width=None,
                           panel_mesh=None) -> SharpHingeParameters:
    """:class:`~simulator.model.sharp.SharpHingeParameters` of a sharp FOLD read.

    Parameters
    ----------
    geo : FoldGeometry
        A sharp read (``geo.crease_model == "sharp"``).
    fold_stiffness : float, optional
        [N m/rad/m] for the creases without a file value.
    panel_bending_width : float, optional
        [m].
    panel_mesh : {"N5B8", "N4B5"}, optional
    """
    raw = _object(geo.data)
    k = fold_stiffness if fold_stiffness is not None else raw.get("fold_stiffness")
    width = panel_bending_width if panel_bending_width is not None else \
        raw.get("panel_bending_width")
    mesh = panel_mesh if panel_mesh is not None else raw.get("panel_mesh") or "N5B8"
    per_crease = _per_crease(geo)
    creases = geo.pattern.creases.tolist()
    if k is not None:
        _check_number("fold_stiffness", k, "N m/rad/m")
        per_crease = {c: per_crease.get(c, float(k)) for c in creases}
    needs = []
    if geo.sharp_missing and len(per_crease) < len(creases):
        needs.append(("fold_stiffness", [c for c in creases if c not in per_crease]))
    if "crease_width" in geo.sharp_missing and width is None:
        needs.append(("panel_bending_width", None))
    if needs:
        _refuse(geo, needs)
    return SharpHingeParameters(fold_stiffness=per_crease or None, panel_bending_width=width,
                                panel_mesh=mesh)


def _refuse(geo, needs) -> None:
    """One ParameterError: what the default rules cannot give, and the keywords / flags."""
    missing = " and ".join(m.replace("_", " ") for m in geo.sharp_missing)
    what = {"fold_stiffness": "the fold stiffness per length (E t^3/(12 W)) of creases {}",
            "panel_bending_width": "the panel bending width (the mean crease width)"}
    cannot = " or ".join(what[n].format(capped(c or ())) for n, c in needs)
    give = " and ".join(_FLAGS[n] for n, _ in needs)
    data = ", ".join(_FLAGS[m] for m in geo.sharp_missing)
    raise ParameterError(f"sharp creases: the file gives no {missing}, so the default rules cannot "
                         f"give {cannot}; pass {give}, or the crease data: {data}.")


def _object(data) -> dict:
    raw = data.get(f"{NS}sharp_hinge") or {}
    if not isinstance(raw, dict):
        fail(f"{NS}sharp_hinge", f"must be a JSON object, got {raw!r}.")
    unknown = sorted(set(raw) - set(SHARP_FIELDS))
    if unknown:
        fail(f"{NS}sharp_hinge", f"unknown keys {unknown}; known: {', '.join(SHARP_FIELDS)}.")
    return raw


def _per_crease(geo) -> dict:
    """{pattern crease: value} of ``edges_etorigami:fold_stiffness``."""
    field = f"edges_{NS}fold_stiffness"
    raw = geo.data.get(field)
    if raw is None:
        return {}
    if not isinstance(raw, list) or len(raw) != len(geo.edge):
        fail(field, f"must be a list with one entry per edge ({len(geo.edge)}).")
    out = {}
    for i, v in enumerate(raw):
        if v is None:
            continue
        e = int(geo.edge[i])
        if e < 0 or not geo.pattern.is_crease[e]:
            fail(f"{field}[{i}]", f"{v!r} on an edge that is not a crease; use null there.")
        if not (is_number(v) and math.isfinite(v) and v > 0):
            fail(f"{field}[{i}]", f"{v!r} must be a positive stiffness per length [N m/rad/m].")
        out[e] = float(v)
    return out


def _check_number(name, value, unit) -> None:
    if not (is_number(value) and math.isfinite(value) and value > 0):
        raise ParameterError(f"{name} = {value!r} must be a positive number [{unit}].")
