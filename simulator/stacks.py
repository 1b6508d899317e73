"""Named layer stacks: the physical parameters a plain crease pattern lacks.

A crease pattern drawn in an editor gives geometry and fold directions only. A
:class:`LayerStack` supplies the rest (crease width, the bimorph's two layers, panel thickness,
the air around it), so that :func:`stack_model` turns any pattern into a heatable model: every
chosen crease becomes an actuator that folds in its assigned direction (M / V, or the sign of
its start fold for U), one panel is clamped, and panel contact (:func:`plain_contact`) keeps
the panels from passing through each other.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from ._validate import capped, one_of
from .errors import ParameterError
from .geometry.pattern import Pattern
from .geometry.materials import AIR
from .model.heat_loss import ChainLoss, IntegralLoss
from .model.thermal_parameters import REFERENCE_BETA, ThermalParameters
from .model.bimorph import Actuators, Bimorph
from .model.mesh import make_mesh
from .model.model import ContactParameters, Model, Supports, make_model
from .mechanics.contact_search import closest_pair
from .model.properties import BarHingeParameters

__all__ = ["LayerStack", "STACKS", "get_stack", "stack_model", "actuation_signs",
           "central_panel", "plain_contact", "plain_contact_distance"]

#: Activation distance of :func:`plain_contact` over the gap between the two panels of the
#: widest crease folded to 180 deg.
CONTACT_GAP_MARGIN = 1.15


@dataclass(frozen=True)
class LayerStack:
    """Layers and surroundings of an electro-thermal origami sheet (SI units).

    Attributes
    ----------
    name, description : str
    crease_width : float
        Crease width W [m].
    t_active, E_active : float
        Thickness [m] and Young's modulus [Pa] of the active (metal) layer.
    t_passive, E_passive : float
        Thickness [m] and Young's modulus [Pa] of the passive (polymer) layer.
    delta_alpha : float
        Expansion mismatch |alpha_passive - alpha_active| [1/K].
    panel_thickness : float
        Panel thickness [m].
    env_thickness, env_conductivity : float
        Air conductivity [W/(m K)] of the heat loss, and the air layer thickness t_env [m]
        of the paper's chains (used only with ``stack_model(..., loss_model="chain")``).
    """

    name: str
    description: str
    crease_width: float
    t_active: float
    E_active: float
    t_passive: float
    E_passive: float
    delta_alpha: float
    panel_thickness: float
    env_thickness: float = 1e-3
    env_conductivity: float = 0.026

    def __post_init__(self):
        for key, value in asdict(self).items():
            if key not in ("name", "description") and not (np.isfinite(value) and value > 0):
                raise ParameterError(f"LayerStack {self.name!r}: {key} = {value!r} must be a "
                                     "positive number (SI units).")

    @property
    def crease_thickness(self) -> float:
        """Crease thickness [m]: both layers."""
        return self.t_active + self.t_passive

    def to_dict(self) -> dict:
        return asdict(self)

    def heat_loss(self, loss_model: str = "integral") -> ChainLoss | IntegralLoss:
        """The stack's heat loss to its air: ``"integral"`` (:class:`IntegralLoss`, nothing
        fitted) or ``"chain"`` (the paper's chains, t_env :attr:`env_thickness`)."""
        one_of("loss_model", loss_model, ("integral", "chain"))
        if loss_model == "chain":
            return ChainLoss(thickness=self.env_thickness, dissipation_angle=REFERENCE_BETA)
        return IntegralLoss()

    def summary(self) -> str:
        """One line in CLI units (um, GPa, 1/K, W/(m K))."""
        return (f"{self.name}: {self.description}; crease width {self.crease_width * 1e6:g} um, "
                f"active layer {self.t_active * 1e6:g} um at {self.E_active / 1e9:g} GPa, "
                f"passive layer {self.t_passive * 1e6:g} um at {self.E_passive / 1e9:g} GPa, "
                f"delta_alpha {self.delta_alpha:g} /K, panels {self.panel_thickness * 1e6:g} um, "
                f"air at {self.env_conductivity:g} W/(m K) (the chains' t_env "
                f"{self.env_thickness * 1e6:g} um)")


#: The paper's SU-8 / gold bimorph (Zhu & Filipov; the Miura lifter, Example03: gold 0.2 um at
#: 50 GPa on SU-8 0.8 um at 2 GPa, delta_alpha 50e-6 /K, 200 um creases, 10 um SU-8 panels).
STACKS = {"su8-au": LayerStack("su8-au", "SU-8/Au bimorph of the paper (Miura lifter, "
                               "Example03)", crease_width=200e-6, t_active=0.2e-6,
                               E_active=50e9, t_passive=0.8e-6, E_passive=2e9,
                               delta_alpha=50e-6, panel_thickness=10e-6)}


def get_stack(name: str) -> LayerStack:
    """The named stack of :data:`STACKS`; an unknown name lists the known ones."""
    if name not in STACKS:
        raise ParameterError(f"layer stack {name!r} is unknown; known: {', '.join(STACKS)}.")
    return STACKS[name]


def actuation_signs(pattern: Pattern) -> np.ndarray:
    """(n_edges,) +1 / -1: the direction each crease should fold (V / M, else the sign of its
    design or start fold angle, else valley); 0 on boundary edges."""
    from .geometry.orientation import start_fold_angles

    design = np.sign(pattern.edge_fold_angle)
    start = np.sign(start_fold_angles(pattern))
    sign = np.where(design != 0, design, np.where(start != 0, start, 1.0))
    return np.where(pattern.is_crease, sign, 0.0)


def central_panel(pattern: Pattern) -> int:
    """The panel whose vertex centroid is nearest the pattern's (the default clamped panel).

    Of panels equally near (within 1e-9 of the pattern size: the four of a Miura vertex, the
    eight of a waterbomb base), the lowest id: a round-off tie-break would clamp another
    panel, and give another answer, when the sheet lies elsewhere in space."""
    centres = np.array([pattern.vertices[list(p)].mean(axis=0) for p in pattern.panels])
    d = np.linalg.norm(centres - pattern.vertices.mean(axis=0), axis=1)
    return int(np.flatnonzero(d <= d.min() + 1e-9 * pattern.size)[0])


def unsupported_panels(pattern: Pattern, panel: int) -> list[int]:
    """Panels joined to ``panel`` by no chain of creases (a separate sheet, or one that touches
    the rest at a vertex only): clamping ``panel`` leaves them free to move as rigid bodies."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    pairs = pattern.edge_panels[pattern.creases]
    n = pattern.n_panels
    adj = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(adj, directed=False)
    return np.flatnonzero(label != label[panel]).tolist()


def check_supported(pattern: Pattern, panel: int, what: str = "fixed panel") -> None:
    """Raise :class:`ParameterError` naming the panels that clamping ``panel`` leaves free."""
    free = unsupported_panels(pattern, panel)
    if free:
        raise ParameterError(
            f"{what} {panel}: panels {capped(free)} are joined to it by no crease (a separate "
            "sheet, or one touching it at a vertex only), so they would float free (a mechanism): "
            "give one sheet joined by creases, or split the file into one file per sheet.")


def plain_contact(pattern: Pattern, params: BarHingeParameters | None = None, *,
                  required: bool = False) -> ContactParameters | None:
    """Panel contact that keeps every crease of a plain pattern within (-180, 180) deg, or None
    where the start shape does not allow it.

    A bar-and-hinge crease of width W folded to 180 deg holds its two panels parallel at the gap
    ``W cos(pi f / 2)`` (0.71 W for the centre-line share f = 0.5: its fold lines take 1/4, 1/2
    and 1/4 of the fold). Contact that starts :data:`CONTACT_GAP_MARGIN` times farther out than
    the widest crease's gap (0.81 W, :func:`plain_contact_distance`) stops the panels before
    they turn past parallel, and holds stacked panels about that far apart; stiffness and step
    limit as :class:`~simulator.model.model.ContactParameters`' defaults.

    None if a panel corner or centre node starts within that distance of another panel
    (touching or stacked paper in a folded start shape): contact would push them apart before
    any load. Such a model runs without contact, and a step reports panels passing through each
    other as an event (:func:`~simulator.events.crossing_event`). ``required=True`` raises
    :class:`~simulator.errors.ParameterError` naming that node and panel instead.
    """
    return _plain_contact(make_mesh(pattern), params or BarHingeParameters(), required)


def plain_contact_distance(pattern: Pattern, params: BarHingeParameters | None = None) -> float:
    """Activation distance [m] of :func:`plain_contact`: :data:`CONTACT_GAP_MARGIN` times the
    gap ``W cos(pi f / 2)`` of the widest crease folded to 180 deg."""
    width = float(np.max(pattern.crease_width[pattern.creases], initial=0.0))
    if not width > 0:
        raise ParameterError("plain_contact: the pattern has no crease with a width (sharp "
                             "creases have no panel contact).")
    f = (params or BarHingeParameters()).centre_line_share
    return CONTACT_GAP_MARGIN * width * math.cos(math.pi * f / 2)


def _plain_contact(mesh, params: BarHingeParameters,
                   required: bool = False) -> ContactParameters | None:
    """:func:`plain_contact` of the pattern of ``mesh``."""
    d0 = plain_contact_distance(mesh.pattern, params)
    near = closest_pair(mesh, mesh.nodes, d0)
    if near is None:
        return ContactParameters(d0_corner=d0, d0_centre=d0)
    if required:
        gap, node, panel = near
        raise ParameterError(
            f"node {node} (panel {int(mesh.node_panel[node])}) starts {gap * 1e6:.3g} um from "
            f"panel {panel}, within the {d0 * 1e6:.3g} um at which panel contact acts "
            "(touching or stacked paper): contact would push them apart before any load.")
    return None


def stack_model(pattern: Pattern, stack: LayerStack, heated: Sequence[int],
                fixed_panel: int | None = None,
                contact: bool | ContactParameters | None = True,
                scatter: float = 0.0, seed: int = 0, loss_model: str = "integral") -> Model:
    """A heatable model of a pattern with a layer stack.

    Parameters
    ----------
    pattern : Pattern
        With the stack's (or the user's) crease widths and thicknesses.
    stack : LayerStack
    heated : sequence of int
        Crease ids that are actuators (each folds in its :func:`actuation_signs` direction).
    fixed_panel : int, optional
        The clamped panel; default the panel whose centroid is nearest the pattern's centre.
    contact : bool, ContactParameters or None
        Panel contact: True (default) :func:`plain_contact` (off where the start shape holds
        panels closer than its activation distance), False or None off (a step then reports
        panels passing through each other as a ``"panel_crossing"`` event), or the parameters.
    scatter, seed : float, int
        Relative scatter of the heated creases' actuation and its seed
        (:attr:`~simulator.model.bimorph.Actuators.scatter`, default 0: identical creases):
        a fabricated sheet's imperfection; with it the branch a symmetric pattern takes can
        change with the seed and with the step count (theory 6.12), without it the critical
        mode's sign picks it, the same at any step count.
    loss_model : {"integral", "chain"}
        Heat loss to the stack's air (theory 4.3, 4.7): ``"integral"`` (default,
        :class:`~simulator.model.heat_loss.IntegralLoss`: the sheet's single-layer potential in
        the medium, nothing fitted, within 1 % of the 3-D FE; above its dense limit the fast
        path of theory 4.7, minutes per solve on sheets of thousands of triangles) or
        ``"chain"`` (the paper's chains, t_env the stack's ``env_thickness``: seconds, but
        20-40 % too cool at the heated crease and blind to heat passed between creases).
    """
    if not isinstance(stack, LayerStack):
        raise ParameterError(f"stack must be a LayerStack, got {type(stack).__name__}.")
    loss = stack.heat_loss(loss_model)
    heated = [pattern.check_crease(c, "heated crease") for c in heated]
    if not heated:
        raise ParameterError("no crease to heat: give at least one crease id.")
    mesh = make_mesh(pattern)
    fixed_panel = central_panel(pattern) if fixed_panel is None else fixed_panel
    fixed_panel = pattern.check_panel(fixed_panel, "fixed panel")
    check_supported(pattern, fixed_panel)
    sign = actuation_signs(pattern)
    actuators = Actuators(Bimorph(E1=stack.E_active, t1=stack.t_active, E2=stack.E_passive,
                                  t2=stack.t_passive),
                          {c: stack.delta_alpha * float(sign[c]) for c in heated},
                          scatter=scatter, seed=seed)
    thermal = ThermalParameters(
        loss=loss, medium=AIR.with_properties(thermal_conductivity=stack.env_conductivity))
    supports = Supports({int(i): "xyz" for i in mesh.panel_nodes(fixed_panel)})
    params = BarHingeParameters()
    if contact is True:
        contact = _plain_contact(mesh, params)
    return make_model(mesh, supports, params, thermal=thermal, actuators=actuators,
                      contact=contact)
