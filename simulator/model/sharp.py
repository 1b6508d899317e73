"""Concentrated-hinge models: stiffness rules and the model builder (theory 2.6, 3.11).

:func:`sharp_model` builds a :class:`~simulator.model.model.Model` whose creases are sharp
hinges (:mod:`simulator.model.sharp_mesh`; the reference's ``compliantCreaseOpen = 0``,
Filipov et al. 2017). Its element properties (:func:`sharp_properties`):

* **fold springs**: ``k = L k_f`` with ``L`` the crease length and ``k_f`` the stiffness per
  unit length [N m/rad/m], by default ``E_c t_c^3 / (12 W)`` of the pattern's crease material,
  thickness and width (the bending stiffness of the crease strip it stands for, the
  reference's rule); or given by :attr:`SharpHingeParameters.fold_stiffness`;
* **panel bending springs** (on the spokes of N5B8 panels, the diagonal of N4B5 ones):
  ``k = L_bar E_p t_p^3 / (12 w_b)``, ``w_b`` = :attr:`SharpHingeParameters.panel_bending_width`
  (reference ``panelW``);
* **bars**: every panel gets ``a_P = 2 t_p A_P / ((1 - nu_p) L_sum)`` (``A_P`` its area,
  ``L_sum`` its perimeter plus its inner bars) on its inner bars; an edge bar gets twice the
  mean ``a_P`` of its panels (the reference's ``2 a_P`` on boundary edges; the sum of both
  panels' values on a crease), all with the panel moduli.

Masses: every panel triangle carries ``rho_p t_p A`` (2/3 to the centre node of a fan
triangle, 1/6 to each corner; 1/3 to each node of a triangle without centre); creases are
massless. Heating needs a crease with a width: a sharp model has no thermal parameters and
thermal steps refuse it (:func:`check_not_sharp`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .._validate import one_of, positive
from ..errors import ParameterError
from ..geometry.pattern import Pattern
from ..geometry.polygons import triangle_areas
from .model import Model, Supports
from .properties import MechanicalProperties
from .sharp_mesh import PANEL_MESHES, SharpHingeMesh, build_sharp_mesh

__all__ = ["SharpHingeParameters", "sharp_properties", "sharp_model", "check_not_sharp",
           "is_sharp"]


@dataclass(frozen=True)
class SharpHingeParameters:
    """Modelling parameters of the concentrated-hinge mechanics.

    Parameters
    ----------
    fold_stiffness : float, mapping or None
        Fold-spring stiffness per unit crease length [N m/rad/m]: one value for all creases,
        a mapping ``{crease id: value}`` (unlisted creases use the default), or None for the
        default ``E_c t_c^3 / (12 W)`` from the pattern's crease data.
    panel_bending_width : float or None
        Length ``w_b`` [m] of the panel bending stiffness ``E_p t_p^3 / (12 w_b)`` per unit
        bar length; None: the mean crease width (as the compliant model). Smaller is stiffer.
    panel_mesh : {"N5B8", "N4B5"}
        Meshing of quadrilateral panels (centre node and four spokes, or one diagonal).
    """

    fold_stiffness: object = None
    panel_bending_width: float | None = None
    panel_mesh: str = "N5B8"

    def __post_init__(self):
        positive("SharpHingeParameters.panel_bending_width", self.panel_bending_width, "m",
                 hint="or None for the mean crease width", allow_none=True)
        one_of("SharpHingeParameters.panel_mesh", self.panel_mesh, PANEL_MESHES)
        k = self.fold_stiffness
        if isinstance(k, Mapping):
            for c, v in k.items():
                positive(f"SharpHingeParameters.fold_stiffness[{c!r}]", v, "N m/rad/m")
            object.__setattr__(self, "fold_stiffness", {int(c): float(v) for c, v in k.items()})
        else:
            positive("SharpHingeParameters.fold_stiffness", k, "N m/rad/m",
                     hint="(per unit crease length), a mapping {crease: value} or None",
                     allow_none=True)

    def to_dict(self) -> dict:
        k = self.fold_stiffness
        return {"crease_model": "sharp", "panel_mesh": self.panel_mesh,
                "panel_bending_width [m]": self.panel_bending_width,
                "fold_stiffness [N m/rad/m]": ({str(c): v for c, v in k.items()}
                                               if isinstance(k, dict) else k)}


def is_sharp(mesh) -> bool:
    """Whether a mesh has concentrated hinges (a :class:`SharpHingeMesh`)."""
    return bool(getattr(mesh, "sharp", False))


def check_not_sharp(model, what: str) -> None:
    """Raise :class:`ParameterError` if ``model`` has concentrated hinges: ``what`` (a step or
    function) needs creases with a width."""
    if is_sharp(model.mesh):
        raise ParameterError(
            f"{what} needs compliant creases with a width and thermal parameters, but this model "
            "has concentrated hinges (sharp creases, built by sharp_model): its creases have no "
            "area to heat or to actuate. Build the model with make_model(pattern, thermal=..., "
            "actuators=...) for heating, or use mechanical steps only (Load, SelfFold, Gravity, "
            "ArcLengthLoad, DisplacementControl, Dynamics, natural_modes).")


def _fold_per_length(mesh: SharpHingeMesh, params: SharpHingeParameters) -> np.ndarray:
    """(C,) fold-spring stiffness per unit length [N m/rad/m]."""
    pat, ids = mesh.pattern, mesh.crease_ids
    k = params.fold_stiffness
    E = pat.crease_material.youngs_modulus
    default = E * pat.crease_thickness[ids] ** 3 / (12 * pat.crease_width[ids])
    if k is None:
        return default
    if not isinstance(k, dict):
        return np.full(len(ids), float(k))
    out = default.copy()
    for c, v in k.items():
        out[mesh.crease_row_of(c)] = v
    return out


def sharp_properties(mesh: SharpHingeMesh, params: SharpHingeParameters = SharpHingeParameters()
                     ) -> MechanicalProperties:
    """Bar areas, moduli and spring stiffnesses of a concentrated-hinge mesh (module docstring)."""
    pat = mesh.pattern
    E_p = np.array([m.youngs_modulus for m in pat.panel_material])
    nu_p = np.array([m.poisson_ratio for m in pat.panel_material])
    t_p = pat.panel_thickness
    L0 = mesh.bar_length
    x = mesh.nodes[mesh.triangles]
    area_p = np.bincount(mesh.triangle_panel, triangle_areas(x[:, 0], x[:, 1], x[:, 2]),
                         pat.n_panels)
    E = pat.n_edges
    inner = np.arange(E, len(mesh.bars))
    inner_panel = mesh.bar_panel[inner]
    ep = pat.edge_panels
    perimeter = np.bincount(ep[:, 0], L0[:E], pat.n_panels) + \
        np.bincount(ep[ep[:, 1] >= 0, 1], L0[:E][ep[:, 1] >= 0], pat.n_panels)
    l_sum = perimeter + np.bincount(inner_panel, L0[inner], pat.n_panels)
    a_panel = 2 * t_p * area_p / ((1 - nu_p) * l_sum)

    two = ep[:, 1] >= 0
    other = np.where(two, ep[:, 1], ep[:, 0])
    area = np.zeros(len(mesh.bars))
    modulus = np.zeros(len(mesh.bars))
    # edge bars: twice the mean of their panels' a_P; modulus the a_P-weighted mean
    area[:E] = np.where(two, a_panel[ep[:, 0]] + a_panel[other], 2 * a_panel[ep[:, 0]])
    modulus[:E] = (a_panel[ep[:, 0]] * E_p[ep[:, 0]] + a_panel[other] * E_p[other]) / \
        (a_panel[ep[:, 0]] + a_panel[other])
    area[inner], modulus[inner] = a_panel[inner_panel], E_p[inner_panel]

    stiff = np.zeros(len(mesh.springs))
    C = mesh.n_creases
    stiff[:C] = L0[mesh.spring_bar[:C]] * _fold_per_length(mesh, params)
    w_b = params.panel_bending_width
    if w_b is None:
        if C == 0:
            raise ParameterError("SharpHingeParameters.panel_bending_width must be given for a "
                                 "pattern without creases.")
        w_b = float(np.mean(pat.crease_width[mesh.crease_ids]))
    bar = mesh.spring_bar[C:]
    p = mesh.bar_panel[bar]
    stiff[C:] = L0[bar] * E_p[p] * t_p[p] ** 3 / (12 * w_b)
    return MechanicalProperties(bar_area=area, bar_modulus=modulus, spring_stiffness=stiff)


def sharp_model(pattern: Pattern, supports: Supports | Mapping = None,
                params: SharpHingeParameters | None = None) -> Model:
    """A :class:`~simulator.model.model.Model` of ``pattern`` with concentrated hinges.

    Parameters
    ----------
    pattern : Pattern
        Geometry, panel data and (for the default fold stiffness) crease data.
    supports : Supports or mapping {node: "xyz"-subset}, optional
        Node ids of :mod:`simulator.model.sharp_mesh`: vertex ``v`` is node ``v``.
    params : SharpHingeParameters, optional

    Returns
    -------
    Model
        ``model.mesh`` is a :class:`~simulator.model.sharp_mesh.SharpHingeMesh`; no contact, no
        thermal parameters (heating needs crease widths: :func:`check_not_sharp`). Works with
        the mechanical steps: Load, SelfFold, Gravity, ArcLengthLoad, DisplacementControl,
        Dynamics and :func:`~simulator.solvers.modes.natural_modes`.
    """
    if not isinstance(pattern, Pattern):
        raise ParameterError(f"sharp_model: pattern is a {type(pattern).__name__}; pass a "
                             "Pattern (e.g. simulator.example_patterns.miura_sheet_pattern()).")
    params = SharpHingeParameters() if params is None else params
    if not isinstance(params, SharpHingeParameters):
        raise ParameterError(f"sharp_model: params is a {type(params).__name__}; pass "
                             "SharpHingeParameters(...) or None.")
    if supports is None:
        supports = Supports()
    elif not isinstance(supports, Supports):
        supports = Supports(supports)
    mesh = build_sharp_mesh(pattern, params.panel_mesh)
    return Model(mesh=mesh, properties=sharp_properties(mesh, params), params=params,
                 supports=supports, contact=None)

