"""Bar areas, moduli and spring stiffnesses of a bar-and-hinge mesh (theory 3.4).

Crease bars and springs follow the compliant-crease model (Zhu & Filipov 2020): the three
fold lines of a crease (its two edges and its centre line) each carry a stiffness
``E t^3 L / (4 W)`` so that in series they give the plate value ``E t^3 L / (12 W)``;
diagonals are ``diagonal_rate`` times stiffer per length. Panels get bar areas that
preserve their in-plane stiffness and spoke springs for bending.
"""

from __future__ import annotations

import weakref
from dataclasses import asdict, dataclass

import numpy as np

from ..mechanics.elements.springs import fold_angle
from .._validate import in_range, positive
from ..errors import ParameterError
from ..mechanics.kinematics import fold_angles
from .mesh import BarHingeMesh, BarType, SpringKind
from ..geometry.polygons import triangle_areas

__all__ = ["BarHingeParameters", "MechanicalProperties", "mechanical_properties",
           "spring_rest_angles", "initial_crease_rest", "FLAT_FOLD_TOL"]

#: Creases whose fold angle in the mesh's reference geometry is at most this [rad] count as
#: flat (rest angle exactly pi); the reference's Miura generator leaves ~1e-8 rad of round-off.
FLAT_FOLD_TOL = 1e-6


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


def spring_rest_angles(mesh: BarHingeMesh, crease_rest: np.ndarray,
                       params: BarHingeParameters = BarHingeParameters()) -> np.ndarray:
    """Spring rest angles for given crease rest angles (theory 3.4).

    Parameters
    ----------
    crease_rest : (C,) array
        Rest angle of each crease [rad], pi = flat, in crease-row order.

    Returns
    -------
    (ns,) array: pi for panel and diagonal springs; edge lines get
    ``pi + (theta0 - pi)(1 - f)/2`` each, the centre line ``pi + f (theta0 - pi)``.
    A concentrated-hinge mesh (theory 2.6) has one fold spring per crease, which takes the
    whole change. A crease folded in the mesh's reference geometry (a 3-D start shape) starts instead from
    its springs' initial angles and from :func:`initial_crease_rest`, so that its initial
    rest angles give back the start shape.
    """
    rest0, base, lines = _initial_rest(mesh)
    rho = np.asarray(crease_rest, dtype=float) - rest0
    out = base.copy()
    if lines is None:                           # one fold spring per crease (theory 2.6)
        out[mesh.crease_springs[:, 0]] += rho
        return out
    f = params.centre_line_share
    out[lines] += rho[:, None] * np.array([(1 - f) / 2, (1 - f) / 2, f, f])
    return out


def initial_crease_rest(mesh: BarHingeMesh) -> np.ndarray:
    """Crease rest angles [rad] of the mesh's reference geometry, (C,) in crease-row order.

    pi (flat) plus the fold angle of each crease in ``mesh.nodes``; exactly pi where that
    angle is at most :data:`FLAT_FOLD_TOL`. A folded start shape (a 3-D FOLD file) thus
    keeps its initial dihedral angles as rest angles.
    """
    return _initial_rest(mesh)[0].copy()


_INITIAL: "weakref.WeakKeyDictionary[BarHingeMesh, tuple]" = weakref.WeakKeyDictionary()


def _initial_rest(mesh: BarHingeMesh) -> tuple:
    """(crease rest (C,), spring base angles (ns,)) of the reference geometry, and the springs
    of each crease's fold lines (C, 4) (edge line 1, edge line 2, the centre line's two
    halves; None for concentrated hinges), cached per mesh."""
    cached = _INITIAL.get(mesh)
    if cached is None:
        fold = fold_angles(mesh, mesh.nodes) if mesh.n_creases else np.zeros(0)
        folded = np.abs(fold) > FLAT_FOLD_TOL
        rest0 = np.where(folded, np.pi + fold, np.pi)
        base = np.full(len(mesh.springs), np.pi)
        springs = mesh.crease_springs[folded].ravel()
        base[springs] = fold_angle(mesh.nodes[mesh.springs[springs]])
        lines = None if getattr(mesh, "sharp", False) else (
            np.ascontiguousarray(mesh.crease_springs[:, [0, 1, 4, 5]]) if mesh.n_creases
            else np.zeros((0, 4), dtype=int))
        cached = _INITIAL[mesh] = (rest0, base, lines)
    return cached
