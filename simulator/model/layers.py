"""The sheet as layer stacks for the heat balance (theory 4.10, 7.2).

A thin sheet's layers (a gold heater film on a polymer, a metal film on a panel) share one
temperature through the thickness, so in-plane they conduct in parallel and store heat together:
a stack conducts with the sheet conductance ``sum_i k_i t_i`` [W/K] and holds the areal heat
capacity ``sum_i rho_i c_i t_i`` [J/(m^2 K)]. With ``ThermalParameters(crease_conduction=
"layers")`` the thermal model takes both from the stacks the model knows:

* the actuated creases, from their bimorph (:attr:`~simulator.model.bimorph.Bimorph.layers`);
* the panels and passive creases listed in :class:`SheetLayers` (given as
  ``ThermalParameters(sheet_layers=...)``): a panel with a metal film, a crease that carries a
  heater film but does not actuate.

Everything else conducts and stores heat as one layer of its material over its thickness, as in
the paper's setting. The mechanics (stiffness, mass) keeps the pattern's single layer.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .._validate import capped, integer, non_negative, positive
from ..errors import ParameterError
from ..geometry.materials import Material

__all__ = ["Layer", "SheetLayers", "stack_conductance", "stack_capacity"]


@dataclass(frozen=True)
class Layer:
    """One layer of a sheet (SI units).

    Parameters
    ----------
    thickness : float
        Layer thickness t [m], > 0.
    conductivity : float
        In-plane thermal conductivity k [W/(m K)], >= 0 (a thin metal film's, which is below
        the bulk value: :data:`~simulator.geometry.materials.GOLD_FILM_CONDUCTIVITY`).
    heat_capacity : float
        Volumetric heat capacity rho c [J/(m^3 K)], >= 0 (0: none given; the transient model
        then refuses a stack that holds no heat).
    name : str
        Label for reports (the material's name by :meth:`of`).
    """

    thickness: float
    conductivity: float
    heat_capacity: float = 0.0
    name: str = ""

    def __post_init__(self):
        owner = f"Layer {self.name!r}" if self.name else "Layer"
        object.__setattr__(self, "thickness", positive(f"{owner}.thickness", self.thickness,
                                                       "m", hint="e.g. 0.2e-6 for a gold film"))
        object.__setattr__(self, "conductivity", non_negative(
            f"{owner}.conductivity", self.conductivity, "W/(m K)",
            hint="the layer's in-plane thermal conductivity, e.g. 150 for a thin gold film"))
        object.__setattr__(self, "heat_capacity", non_negative(
            f"{owner}.heat_capacity", self.heat_capacity, "J/(m^3 K)",
            hint="density times specific heat, e.g. 2.49e6 for gold"))

    @classmethod
    def of(cls, material: Material, thickness: float) -> Layer:
        """A layer of ``material`` (its conductivity, density and specific heat) ``thickness``
        [m] thick, e.g. ``Layer.of(GOLD_FILM, 0.1e-6)``."""
        if not isinstance(material, Material):
            raise ParameterError(f"Layer.of: material is a {type(material).__name__}; give a "
                                 "Material, e.g. GOLD_FILM or SU8.")
        return cls(thickness, material.thermal_conductivity,
                   material.density * material.specific_heat, material.name)

    @property
    def sheet_conductance(self) -> float:
        """``k t`` [W/K]."""
        return self.conductivity * self.thickness

    @property
    def areal_capacity(self) -> float:
        """``rho c t`` [J/(m^2 K)]."""
        return self.heat_capacity * self.thickness

    def to_dict(self) -> dict:
        return {"thickness": self.thickness, "conductivity": self.conductivity,
                "heat_capacity": self.heat_capacity, "name": self.name}


def stack_conductance(layers) -> float:
    """Sheet conductance ``sum_i k_i t_i`` [W/K] of a sequence of :class:`Layer`."""
    return float(sum(layer.sheet_conductance for layer in layers))


def stack_capacity(layers) -> float:
    """Areal heat capacity ``sum_i rho_i c_i t_i`` [J/(m^2 K)] of a sequence of
    :class:`Layer`."""
    return float(sum(layer.areal_capacity for layer in layers))


def _stacks(owner: str, value) -> dict:
    """``{id: (Layer, ...)}`` from a mapping of ids to layer sequences (or their dicts)."""
    if not isinstance(value, Mapping):
        raise ParameterError(f"{owner} = {value!r:.80} must be a mapping {{id: (Layer, ...)}}.")
    out = {}
    for key, layers in value.items():
        i = int(integer(f"{owner}: id", int(key) if isinstance(key, str) and key.isdigit()
                        else key, 0))
        if isinstance(layers, (Layer, Mapping)) or not layers:
            raise ParameterError(f"{owner}[{i}] = {layers!r:.80} must be a non-empty sequence "
                                 "of Layer, e.g. (Layer.of(GOLD_FILM, 0.1e-6), "
                                 "Layer.of(SU8, 5e-6)).")
        stack = tuple(Layer(**layer) if isinstance(layer, Mapping) else layer
                      for layer in layers)
        bad = [layer for layer in stack if not isinstance(layer, Layer)]
        if bad:
            raise ParameterError(f"{owner}[{i}] holds {bad[0]!r:.60}, not a Layer; give "
                                 "Layer(thickness, conductivity, heat_capacity) or "
                                 "Layer.of(material, thickness).")
        out[i] = stack
    return out


@dataclass(frozen=True)
class SheetLayers:
    """The layer stacks of panels and passive creases (theory 4.10).

    Each stack is the whole thickness of its panel or crease for the heat balance: it replaces
    the pattern's single layer (material, thickness) in the conduction and the heat capacity,
    with ``ThermalParameters(crease_conduction="layers", sheet_layers=...)``. The actuated
    creases take their bimorph's layers and cannot be listed here.

    Parameters
    ----------
    panels : mapping {panel id: sequence of Layer}
        E.g. a 0.1 um gold film on a 5 um SPR panel: ``{0: (Layer.of(GOLD_FILM, 0.1e-6),
        Layer.of(SPR, 5e-6))}``.
    creases : mapping {crease id: sequence of Layer}
        Passive creases that carry a heater film, e.g. ``{7: bimorph.layers}``.
    """

    panels: Mapping = field(default_factory=dict)
    creases: Mapping = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "panels", _stacks("SheetLayers.panels", self.panels))
        object.__setattr__(self, "creases", _stacks("SheetLayers.creases", self.creases))

    def __bool__(self) -> bool:
        return bool(self.panels or self.creases)

    def __hash__(self) -> int:
        return hash((tuple(sorted(self.panels.items())), tuple(sorted(self.creases.items()))))

    def to_dict(self) -> dict:
        return {name: {str(i): [layer.to_dict() for layer in stack]
                       for i, stack in getattr(self, name).items()}
                for name in ("panels", "creases")}

    @classmethod
    def from_dict(cls, d) -> SheetLayers:
        """From :meth:`to_dict`'s form (ids may be strings, as in JSON)."""
        if isinstance(d, SheetLayers):
            return d
        if not isinstance(d, Mapping) or set(d) - {"panels", "creases"}:
            raise ParameterError(f"sheet_layers = {d!r:.80} must be a SheetLayers or a dict "
                                 "with 'panels' and 'creases' ({id: [layer dicts]}).")
        return cls(d.get("panels", {}), d.get("creases", {}))

    def per_triangle(self, mesh, pattern) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(listed, kt, rho_c_t)``, each (n_tri,): which triangles of ``mesh`` (a
        :class:`~simulator.model.mesh.BarHingeMesh` or the refined sheet's) lie on a listed
        panel or crease, and their stack's ``sum k t`` [W/K] and ``sum rho c t``
        [J/(m^2 K)] (0 elsewhere). Unknown ids raise."""
        for p in self.panels:
            if not 0 <= p < pattern.n_panels:
                raise ParameterError(f"SheetLayers.panels: panel {p} does not exist (the "
                                     f"pattern has panels 0..{pattern.n_panels - 1}).")
        ids = [int(c) for c in np.asarray(mesh.crease_ids)]
        for c in self.creases:
            if c not in ids:
                raise ParameterError(f"SheetLayers.creases: {c} is not a crease of the mesh; "
                                     f"its creases are {capped(ids)}.")
        panel, crease = np.asarray(mesh.triangle_panel), np.asarray(mesh.triangle_crease)
        pk, pc = _tables(self.panels, pattern.n_panels)
        ck, cc = _tables({ids.index(c): s for c, s in self.creases.items()}, len(ids))
        on_panel, on_crease = panel >= 0, crease >= 0
        kt = np.where(on_panel, pk[np.maximum(panel, 0)], np.where(
            on_crease, ck[np.maximum(crease, 0)], np.nan))
        cap = np.where(on_panel, pc[np.maximum(panel, 0)], np.where(
            on_crease, cc[np.maximum(crease, 0)], np.nan))
        listed = np.isfinite(kt)
        return listed, np.where(listed, kt, 0.0), np.where(listed, cap, 0.0)


def _tables(stacks: Mapping, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(n,) ``sum k t`` and ``sum rho c t`` of the rows listed in ``stacks``, NaN elsewhere."""
    kt, cap = np.full(n, np.nan), np.full(n, np.nan)
    for i, stack in stacks.items():
        kt[i], cap[i] = stack_conductance(stack), stack_capacity(stack)
    return kt, cap
