"""Bar areas, moduli and spring stiffnesses of a bar-and-hinge mesh (theory 3.4).

Crease bars and springs follow the compliant-crease model (Zhu & Filipov 2020): the three
fold lines of a crease (its two edges and its centre line) each carry a stiffness
``E t^3 L / (4 W)`` so that in series they give the plate value ``E t^3 L / (12 W)``;
diagonals are ``diagonal_rate`` times stiffer per length. Panels get bar areas that
preserve their in-plane stiffness and spoke springs for bending.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .._validate import in_range, positive
from ..errors import ParameterError
from .mesh import BarHingeMesh, BarType, SpringKind
from ..geometry.polygons import triangle_areas

__all__ = ["BarHingeParameters", "MechanicalProperties", "mechanical_properties"]



@dataclass(frozen=True)
class BarHingeParameters:
    """Modelling parameters of the bar-and-hinge mechanics.

    Parameters
    ----------
    diagonal_rate : float
        Bending stiffness of crease diagonals relative to fold lines [-] (reference default 4;
        the single and double fold use 1000, the gripper 100).
    panel_bending_width : float or None
        Length ``panelW`` [m] in the panel bending stiffness ``E t^3 / (12 panelW)`` per unit
        spoke length. ``None`` uses the mean crease width, as every reference example does.
    centre_line_share : float
        Share of a crease rotation given to its centre line, in [0, 1]; each edge line gets half
        of the rest (reference ``zeroStrianDistributionFactor`` = 0.5).
    """

    diagonal_rate: float = 4.0
    panel_bending_width: float | None = None
    centre_line_share: float = 0.5

    def __post_init__(self):
        positive("BarHingeParameters.diagonal_rate", self.diagonal_rate)
        positive("BarHingeParameters.panel_bending_width", self.panel_bending_width, "m",
                 hint="or None for the mean crease width", allow_none=True)
        in_range("BarHingeParameters.centre_line_share", self.centre_line_share, 0, 1)

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True, eq=False)
class MechanicalProperties:
    """Element properties.

    Attributes
    ----------
    bar_area : (nb,) cross-section areas [m^2]
    bar_modulus : (nb,) Young's moduli [Pa]
    spring_stiffness : (ns,) rotational stiffnesses [N m / rad]
    """

    bar_area: np.ndarray
    bar_modulus: np.ndarray
    spring_stiffness: np.ndarray

    @property
    def bar_axial_stiffness(self) -> np.ndarray:
        """E A [N] per bar."""
        return self.bar_area * self.bar_modulus


def mechanical_properties(mesh: BarHingeMesh,
                          params: BarHingeParameters = BarHingeParameters()) -> MechanicalProperties:
    """Compute bar areas, moduli and spring stiffnesses (theory 3.4), vectorised."""
    if getattr(mesh, "sharp", False):
        raise ParameterError("mechanical_properties: this mesh has concentrated hinges; build "
                             "its model with simulator.model.sharp.sharp_model(pattern, ...).")
    pat = mesh.pattern
    L0 = mesh.bar_length
    area = np.zeros(len(mesh.bars))
    stiff = np.zeros(len(mesh.springs))
    spring_len = L0[mesh.spring_bar]

    # creases
    c_ids = mesh.crease_ids
    W, t = pat.crease_width[c_ids], pat.crease_thickness[c_ids]
    Ec, nuc = pat.crease_material.youngs_modulus, pat.crease_material.poisson_ratio
    L = L0[mesh.crease_edge_bars[:, 0]]
    a1 = L * t / (2 * (1 - nuc**2))
    a2 = (L**2 + W**2) ** 1.5 * t / (4 * (1 + nuc) * L * W)
    area[mesh.crease_bars[:, [0, 3, 6, 9]]] = a1[:, None]
    area[mesh.crease_bars[:, [1, 2, 4, 5, 7, 8]]] = a2[:, None]
    k_line = Ec * t**3 / (4 * W)
    per_length = np.where(mesh.spring_kind[mesh.crease_springs] == SpringKind.CREASE_DIAGONAL,
                          params.diagonal_rate * k_line[:, None], k_line[:, None])
    stiff[mesh.crease_springs] = per_length * spring_len[mesh.crease_springs]

    # panels: fan areas, perimeter + spokes
    E_p = np.array([m.youngs_modulus for m in pat.panel_material])
    nu_p = np.array([m.poisson_ratio for m in pat.panel_material])
    fans = mesh.triangles[mesh.fan_triangles]
    x = mesh.nodes
    fan_area = triangle_areas(x[fans[:, 0]], x[fans[:, 1]], x[fans[:, 2]])
    panel_area = np.bincount(mesh.triangle_panel[mesh.fan_triangles], fan_area, pat.n_panels)
    in_panel = mesh.bar_panel >= 0
    l_sum = np.bincount(mesh.bar_panel[in_panel], L0[in_panel], pat.n_panels)
    a_panel = 2 * pat.panel_thickness * panel_area / ((1 - nu_p) * l_sum)
    area[in_panel] += a_panel[mesh.bar_panel[in_panel]]

    panel_w = params.panel_bending_width
    if panel_w is None:
        if mesh.n_creases == 0:
            raise ParameterError("panel_bending_width must be given for a pattern without creases.")
        panel_w = float(np.mean(W))
    spokes = mesh.spring_kind == SpringKind.PANEL
    p_of_spring = mesh.bar_panel[mesh.spring_bar[spokes]]
    stiff[spokes] = spring_len[spokes] * E_p[p_of_spring] * pat.panel_thickness[p_of_spring] ** 3 \
        / (12 * panel_w)

    modulus = np.full(len(mesh.bars), Ec, dtype=float)
    panel_bar = np.isin(mesh.bar_type, (BarType.PANEL_EDGE, BarType.SPOKE))
    modulus[panel_bar] = E_p[mesh.bar_panel[panel_bar]]
    return MechanicalProperties(bar_area=area, bar_modulus=modulus, spring_stiffness=stiff)
