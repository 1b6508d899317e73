"""Mechanical model: mesh + element properties + supports + contact settings.

A :class:`Model` is immutable; build one with :func:`make_model` from a pattern
(or a mesh). Supports fix degrees of freedom (eliminated from the solve) and
may add elastic springs to ground.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from functools import cached_property

import numpy as np

from .bimorph import Actuators
from .._validate import integer, non_negative, one_of, positive
from ..errors import ParameterError
from .mesh import BarHingeMesh, make_mesh
from ..geometry.pattern import Pattern
from ..geometry.polygons import triangle_areas
from .properties import BarHingeParameters, MechanicalProperties, mechanical_properties
from .thermal_parameters import ThermalParameters

__all__ = ["Supports", "ContactParameters", "Model", "make_model", "gravity_loads", "CREASE_MODELS",
           "STANDARD_GRAVITY", "REFERENCE_GRAVITY", "AXES"]

#: Standard gravity [m/s^2] (the default of :func:`gravity_loads` and the ``Gravity`` step).
STANDARD_GRAVITY = 9.80665
#: Gravity of the reference scripts (Zhu & Filipov 2021: Example01, Example02 and the gripper)
#: [m/s^2]. Kept at 9.8 wherever results are compared with the reference's numbers.
REFERENCE_GRAVITY = 9.8
#: Index of each axis name in a node's (x, y, z) components (supports, drives).
AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True, eq=False)
class Supports:
    """Fixed and elastic supports.

    Parameters
    ----------
    fixed : mapping {node: "xyz"-subset}
        Fixed directions per node, e.g. ``{3: "xyz", 0: "z"}``.
    elastic : sequence of (node, direction, stiffness)
        Springs to ground: ``direction`` in "x", "y", "z", stiffness [N/m] > 0.
    """

    fixed: Mapping = field(default_factory=dict)
    elastic: tuple = ()

    def __post_init__(self):
        fixed = {}
        for node, dirs in dict(self.fixed).items():
            integer("Supports: node id", node, 0)
            if not isinstance(dirs, str) or not dirs or set(dirs) - set("xyz"):
                raise ParameterError(f"Supports: node {node} has directions {dirs!r}; use a "
                                     "non-empty subset of 'xyz'.")
            fixed[int(node)] = "".join(sorted(set(dirs)))
        object.__setattr__(self, "fixed", fixed)
        elastic = []
        for item in self.elastic:
            try:
                node, direction, k = item
            except (TypeError, ValueError):
                raise ParameterError(f"Supports: elastic support {item!r} must be (node, "
                                     "direction, stiffness).") from None
            where = f"Supports: elastic support {item!r}"
            integer(f"{where}: node", node, 0)
            one_of(f"{where}: direction", direction, tuple(AXES))
            elastic.append((int(node), direction, positive(f"{where}: stiffness", k, "N/m")))
        object.__setattr__(self, "elastic", tuple(elastic))

    @classmethod
    def nodes(cls, nodes, dirs: str = "xyz") -> "Supports":
        """Fix the same directions on several nodes."""
        return cls({int(n): dirs for n in np.atleast_1d(nodes)})

    def __or__(self, other: "Supports") -> "Supports":
        fixed = dict(self.fixed)
        for n, d in other.fixed.items():
            fixed[n] = fixed.get(n, "") + d
        return Supports(fixed, self.elastic + other.elastic)

    def fixed_mask(self, n_nodes: int) -> np.ndarray:
        """(n_nodes, 3) boolean mask of fixed DOFs, validating node ids."""
        mask = np.zeros((n_nodes, 3), bool)
        for node, dirs in self.fixed.items():
            _check_node(node, n_nodes)
            mask[node, [AXES[a] for a in dirs]] = True
        for node, _, _ in self.elastic:
            _check_node(node, n_nodes)
        return mask

    def to_dict(self) -> dict:
        return {"fixed": {str(k): v for k, v in self.fixed.items()},
                "elastic": [list(e) for e in self.elastic]}


def _check_node(node: int, n_nodes: int) -> None:
    if not 0 <= node < n_nodes:
        raise ParameterError(f"Supports: node {node} does not exist; node ids are 0..{n_nodes - 1}.")


@dataclass(frozen=True)
class ContactParameters:
    """Node-to-panel penalty contact (theory 3.5; Zhu & Filipov 2019).

    Parameters
    ----------
    stiffness : float
        Potential scale k_e [J] (reference examples: 1e-4).
    d0_corner : float
        Activation distance [m] for panel-corner nodes (reference ``d0edge``).
    d0_centre : float
        Activation distance [m] for panel-centre nodes (reference ``d0center``).
    max_step_fraction : float
        Newton steps are scaled so that no node moves more than this fraction of the smallest
        activation distance per iteration, so nodes cannot jump through a panel.
    """

    stiffness: float = 1e-4
    d0_corner: float = 40e-6
    d0_centre: float = 40e-6
    max_step_fraction: float = 0.5

    def __post_init__(self):
        for name, unit in (("stiffness", "J"), ("d0_corner", "m"), ("d0_centre", "m"),
                           ("max_step_fraction", "")):
            positive(f"ContactParameters.{name}", getattr(self, name), unit)

    @property
    def max_step(self) -> float:
        """Largest nodal displacement per Newton iteration [m]."""
        return self.max_step_fraction * min(self.d0_corner, self.d0_centre)

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True, eq=False)
class Model:
    """Everything the mechanics needs about a structure.

    Attributes
    ----------
    mesh : BarHingeMesh
    properties : MechanicalProperties
    params : BarHingeParameters
    supports : Supports
    contact : ContactParameters or None (contact off)
    thermal : ThermalParameters or None
        Heat-transfer parameters (needed by heating steps).
    actuators : Actuators or None
        Bimorph layers and signed expansion mismatch of the actuated creases.
    """

    mesh: BarHingeMesh
    properties: MechanicalProperties
    params: BarHingeParameters
    supports: Supports
    contact: ContactParameters | None = None
    thermal: object = None
    actuators: object = None

    def __post_init__(self):
        self.supports.fixed_mask(self.mesh.n_nodes)   # validates node ids

    @cached_property
    def fixed_mask(self) -> np.ndarray:
        """(n_nodes, 3) boolean mask of fixed DOFs."""
        return self.supports.fixed_mask(self.mesh.n_nodes)

    @cached_property
    def free_index(self) -> np.ndarray:
        """Reduced index of every DOF (node-major), -1 where fixed."""
        fixed = self.fixed_mask.ravel()
        idx = np.full(fixed.size, -1)
        idx[~fixed] = np.arange(int((~fixed).sum()))
        return idx

    def to_dict(self) -> dict:
        return {"pattern": self.mesh.pattern.to_dict(), "bar_hinge": self.params.to_dict(),
                "supports": self.supports.to_dict(),
                "contact": None if self.contact is None else self.contact.to_dict(),
                "thermal": None if self.thermal is None else self.thermal.to_dict(),
                "actuators": None if self.actuators is None else self.actuators.to_dict(),
                "n_nodes": self.mesh.n_nodes, "n_bars": len(self.mesh.bars),
                "n_springs": len(self.mesh.springs)}


def make_model(pattern_or_mesh: Pattern | BarHingeMesh, supports: Supports | Mapping = None,
               params: BarHingeParameters | None = None,
               contact: ContactParameters | bool | None = None,
               thermal: ThermalParameters | None = None,
               actuators: Actuators | None = None, crease_model: str = "compliant") -> Model:
    """Build a :class:`Model`: mesh (if given a pattern), element properties, supports.

    ``crease_model="sharp"`` gives the concentrated-hinge model of a pattern instead
    (:func:`~simulator.model.sharp.sharp_model`, theory 2.6; ``params`` then a
    :class:`~simulator.model.sharp.SharpHingeParameters` or None; no contact, thermal
    parameters or actuators, which need crease widths).

    ``supports`` is a :class:`Supports` or a mapping ``{node: "xyz"-subset}``;
    ``contact=True`` switches contact on with default :class:`ContactParameters`;
    ``thermal`` (:class:`~simulator.model.thermal_parameters.ThermalParameters`) and ``actuators``
    (:class:`~simulator.model.bimorph.Actuators`) are needed for heating steps. Every argument is
    type-checked; a wrong type raises :class:`~simulator.errors.ParameterError` naming the
    argument, the type given and what to pass instead.
    """
    one_of("make_model: crease_model", crease_model, CREASE_MODELS)
    if crease_model == "sharp":
        return _sharp(pattern_or_mesh, supports, params, contact, thermal, actuators)
    _check_arguments(pattern_or_mesh=pattern_or_mesh, supports=supports, params=params,
                     contact=contact, thermal=thermal, actuators=actuators)
    mesh = pattern_or_mesh if isinstance(pattern_or_mesh, BarHingeMesh) \
        else make_mesh(pattern_or_mesh)
    params = BarHingeParameters() if params is None else params
    if supports is None:
        supports = Supports()
    elif not isinstance(supports, Supports):
        supports = Supports(supports)
    if contact is True:
        contact = ContactParameters()
    elif contact is False:
        contact = None
    props: MechanicalProperties = mechanical_properties(mesh, params)
    if actuators is not None:
        actuators.delta_alpha_array(mesh)          # validates the crease ids
    return Model(mesh=mesh, properties=props, params=params, supports=supports, contact=contact,
                 thermal=thermal, actuators=actuators)


#: Crease models of :func:`make_model`: compliant creases with a width (theory 2.2) or
#: concentrated hinges (theory 2.6).
CREASE_MODELS = ("compliant", "sharp")


def _sharp(pattern, supports, params, contact, thermal, actuators) -> Model:
    """make_model(..., crease_model="sharp"): refuse what needs crease widths, then build."""
    from .sharp import sharp_model

    given = [n for n, v in (("contact", contact), ("thermal", thermal),
                            ("actuators", actuators)) if v not in (None, False)]
    if given:
        raise ParameterError(f"make_model: crease_model='sharp' takes no {', '.join(given)}: "
                             "concentrated hinges have no crease area to heat, actuate or "
                             "touch; use crease_model='compliant' (creases with a width).")
    if not isinstance(pattern, Pattern):
        raise ParameterError(f"make_model: crease_model='sharp' meshes a Pattern itself; got "
                             f"a {type(pattern).__name__}.")
    return sharp_model(pattern, supports, params)


#: make_model's arguments: accepted types and how to build a valid value.
_ARGUMENTS = {
    "pattern_or_mesh": ((Pattern, BarHingeMesh), False,
                        "pass a Pattern (e.g. simulator.geometry.example_patterns.single_fold_pattern()) "
                        "or a BarHingeMesh from make_mesh(pattern)"),
    "supports": ((Supports, Mapping), True,
                 "pass Supports(...), Supports.nodes([...]) or a mapping {node: 'xyz'}"),
    "params": ((BarHingeParameters,), True, "pass BarHingeParameters(...) or None for defaults"),
    "contact": ((ContactParameters, bool), True,
                "pass ContactParameters(...), True (defaults), False or None (no contact)"),
    "thermal": ((ThermalParameters,), True, "pass ThermalParameters(...) or None"),
    "actuators": ((Actuators,), True,
                  "pass Actuators(Bimorph(...), {crease: delta_alpha}) or None"),
}


def _check_arguments(**given) -> None:
    for name, value in given.items():
        types, optional, fix = _ARGUMENTS[name]
        if (value is None and optional) or isinstance(value, types):
            continue
        allowed = " or ".join(t.__name__ for t in types) + (" or None" if optional else "")
        raise ParameterError(f"make_model: {name} is a {type(value).__name__} ({value!r:.60}); "
                             f"it must be {allowed}; {fix}.")


def gravity_loads(mesh: BarHingeMesh, g: float = STANDARD_GRAVITY,
                  direction=(0.0, 0.0, -1.0), panels=None) -> np.ndarray:
    """Nodal weight of every panel, lumped by fan-triangle areas [N], shape (n_nodes, 3).

    Each fan triangle's weight rho t A g goes 1/3 to each of its three nodes; for a
    rectangular panel this is the reference's 1/6 of the panel weight per corner and 2/6
    at the centre. Crease mass is neglected, as in the reference. ``panels`` restricts the
    load to some panels (default: all).
    """
    d = np.asarray(direction, float)
    if d.shape != (3,) or not np.isfinite(d).all() or np.linalg.norm(d) == 0:
        raise ParameterError(f"gravity direction {direction!r} must be a non-zero 3-vector.")
    non_negative("gravity g", g, "m/s^2")
    pat = mesh.pattern
    fans = mesh.triangles[mesh.fan_triangles]
    panel = mesh.triangle_panel[mesh.fan_triangles]
    x = mesh.nodes
    area = triangle_areas(x[fans[:, 0]], x[fans[:, 1]], x[fans[:, 2]])
    rho = np.array([m.density for m in pat.panel_material])
    weight = rho[panel] * pat.panel_thickness[panel] * area * g
    if panels is not None:
        chosen = np.zeros(pat.n_panels, bool)
        chosen[[pat.check_panel(p) for p in np.atleast_1d(panels)]] = True
        weight = weight * chosen[panel]
    nodal = np.bincount(fans.ravel(), np.repeat(weight / 3, 3), minlength=mesh.n_nodes)
    return nodal[:, None] * (d / np.linalg.norm(d))[None, :]
