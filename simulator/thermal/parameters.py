"""Parameters of the steady heat-transfer model (theory 4): the structure's environment
(chain layers or the integral loss model of theory 4.7), room temperature and the medium.
:class:`~simulator.thermal.steady.ThermalModel` builds the operators from them."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from .._validate import finite, in_range, integer, non_negative, one_of, positive
from ..errors import ParameterError
from ..geometry.materials import AIR

__all__ = ["ThermalParameters", "REFERENCE_BETA"]

#: The reference's default dissipation angle: 20 degrees converted with pi ~ 3.14
#: (0.348888... rad instead of 0.349066 rad; tan differs by 0.06 %). Use it to reproduce
#: the reference's numbers; ``math.radians(20)`` is the physical value.
REFERENCE_BETA = 20 / 180 * 3.14


def _ids(value, name):
    try:
        ids = tuple(int(v) for v in value)
    except (TypeError, ValueError):
        ids = None
    if ids is None or any(i != v or isinstance(v, bool) for i, v in zip(ids, value)):
        raise ParameterError(f"ThermalParameters.{name} = {value!r} is invalid; it must be a "
                             "sequence of integer (0-based) ids.")
    return ids


def _plane(value):
    """``substrate_plane`` as a tuple of 6 floats (a point and a non-zero normal) or ()."""
    try:
        v = tuple(float(c) for c in value)
    except (TypeError, ValueError):
        v = None
    if v is None or len(v) not in (0, 6) or not all(map(math.isfinite, v)) \
            or (v and not any(v[3:])):
        raise ParameterError(f"ThermalParameters.substrate_plane = {value!r} is invalid; give "
                             "() or 6 finite numbers: a point (x, y, z) [m] and a non-zero "
                             "normal (nx, ny, nz) pointing into the medium.")
    return v


@dataclass(frozen=True)
class ThermalParameters:
    """Heat-transfer parameters (theory 4; SI units, temperatures in deg C).

    Parameters
    ----------
    env_thickness : float
        Environment thickness t_env [m] between the structure and room temperature, > 0
        (the paper suggests 1.5 x the panel length).
    env_conductivity : float
        Environment conductivity k_env [W/(m K)], >= 0 (air 0.026, water ~0.6).
    layers : int
        Number N of environment layers per node, >= 1.
    dissipation_angle : float
        Heat-spreading angle beta [rad] in [0, pi/2); :data:`REFERENCE_BETA` matches the reference.
    room_temperature : float
        Room temperature [deg C] of the far layer and of ``room_temperature_nodes``.
    boundary_panels : tuple of int
        Panel ids of thermal boundaries (substrate); their distance caps t_env.
    room_temperature_nodes : tuple of int
        Mesh node ids whose structure temperature is held at room temperature.
    env_density : float
        Environment density rho_env [kg/m^3], >= 0 (transient heat only; default air as in the
        reference transient example, :data:`~simulator.geometry.materials.AIR`).
    env_specific_heat : float
        Environment specific heat c_env [J/(kg K)], >= 0 (transient heat only; default air).
    loss_model : {"chain", "integral"}
        Heat loss of the steady model: "chain" (the paper's fitted chains, using
        ``env_thickness``, ``layers``, ``dissipation_angle``) or "integral" (the single-layer
        potential of the sheet in the medium, :mod:`simulator.thermal.integral`: nothing to fit;
        boundary panels, and nodes on the ``substrate_plane``, lie on the substrate at room
        temperature). Transient and
        electro-thermal steps always use the chains (they carry the medium's heat capacity).
    integral_refinement : int
        Sub-triangles per triangle edge m of the "integral" model (m^2 per mesh triangle),
        1..16 (default 3).
    integral_extrapolation : bool or None
        "integral" model only: Richardson extrapolation of the loss conductance from the
        refinements ``c = max(m // 2, 2)`` and ``m``, ``(m L_m - c L_c) / (m - c)``, which
        removes the error of first order in ``1 / m`` (the flux density's edge singularity;
        theory 4.7). Needs m >= 3 (the coarse level must be in the first-order regime: from
        m = 1 it is not). False: the plain operator at ``m``. None (default): True from
        m = 3 on, else False. On the strips and folded shapes of docs/heat_fe.md the default
        (m = 3 extrapolated) is within 2.8 % of the converged 3-D FE (m = 4: 2.3 %) where the
        plain m = 2 is up to 15 % hot.
    integral_correction_tol : float
        "integral" model only, >= 0 (default 0.1): the operator at ``integral_refinement``
        (extrapolated or not) is rebuilt only when the cheap m = 1 operator, rebuilt at
        ``integral_shape_tol``, has changed by more than this fraction of itself since the
        last such build (largest absolute row sum), and follows the shape in between through
        the change of the m = 1 operator: ``L(x) = L_m(x0) + L_1(x) - L_1(x0)`` (theory 4.7;
        the default keeps the node temperatures within 2 % of a rebuild at every shape along
        the gripper's power search, 0.44 % along the double fold's heating). 0: the operator
        at ``integral_refinement`` itself is rebuilt at ``integral_shape_tol``. No effect with
        m = 1 without extrapolation.
    substrate_plane : tuple of 6 floats, or ()
        "integral" model only: an isothermal substrate plane, a point (3,) [m] and a normal
        (3,) pointing into the medium, in the global frame; () for an unbounded medium. A
        model with ``boundary_panels`` (the substrate) wants their plane,
        :func:`~simulator.thermal.fixed_shape.boundary_panel_plane`; without one the steady
        model warns (once).
    integral_shape_tol : float
        "integral" model only: the dense operator is rebuilt when the distance between two
        sheet nodes has changed since the last build by more than this fraction of the larger
        of that distance and the mean sub-triangle diameter (or, with a substrate plane, a
        node's height over it by more than this fraction of the height, at least 1 % of the
        diameter), >= 0 (a rigid motion of the sheet changes none; 0: rebuilt on every change
        of position). With ``integral_correction_tol`` > 0 (the default) this schedules the
        m = 1 operator, and the accurate one follows ``integral_correction_tol``: for the
        accurate operator at every shape set both to 0.
    """

    env_thickness: float
    env_conductivity: float = 0.026
    layers: int = 10
    dissipation_angle: float = math.radians(20)
    room_temperature: float = 21.0
    boundary_panels: tuple = ()
    room_temperature_nodes: tuple = ()
    env_density: float = AIR.density
    env_specific_heat: float = AIR.specific_heat
    loss_model: str = "chain"
    integral_refinement: int = 3
    substrate_plane: tuple = ()
    integral_shape_tol: float = 0.02
    integral_extrapolation: bool | None = None
    integral_correction_tol: float = 0.1

    def __post_init__(self):
        owner = "ThermalParameters"
        for name, unit in (("env_density", "kg/m^3"), ("env_specific_heat", "J/(kg K)"),
                           ("env_conductivity", "W/(m K)")):
            non_negative(f"{owner}.{name}", getattr(self, name), unit)
        positive(f"{owner}.env_thickness", self.env_thickness, "m")
        in_range(f"{owner}.dissipation_angle", self.dissipation_angle, 0, math.pi / 2, "rad",
                 hint="the range is [0, pi/2)", open_high=True)
        finite(f"{owner}.room_temperature", self.room_temperature, "deg C")
        integer(f"{owner}.layers", self.layers)
        for name in ("boundary_panels", "room_temperature_nodes"):
            object.__setattr__(self, name, _ids(getattr(self, name), name))
        one_of(f"{owner}.loss_model", self.loss_model, ("chain", "integral"))
        integer(f"{owner}.integral_refinement", self.integral_refinement, 1, 16)
        non_negative(f"{owner}.integral_shape_tol", self.integral_shape_tol)
        if self.integral_extrapolation is not None and not isinstance(
                self.integral_extrapolation, (bool, np.bool_)):
            raise ParameterError(f"{owner}.integral_extrapolation = "
                                 f"{self.integral_extrapolation!r} must be True, False or None "
                                 "(True from integral_refinement = 3 on).")
        if self.integral_extrapolation is not None:
            object.__setattr__(self, "integral_extrapolation", bool(self.integral_extrapolation))
        if self.integral_extrapolation and self.integral_refinement < 3:
            raise ParameterError(f"{owner}.integral_extrapolation = True needs "
                                 f"integral_refinement >= 3, got {self.integral_refinement}: "
                                 "the coarse level max(m // 2, 2) must be below m; use "
                                 "integral_refinement=3 (or integral_extrapolation=False).")
        non_negative(f"{owner}.integral_correction_tol", self.integral_correction_tol)
        object.__setattr__(self, "substrate_plane", _plane(self.substrate_plane))
        if self.loss_model == "integral" and not self.env_conductivity > 0:
            raise ParameterError(f"{owner}.env_conductivity = {self.env_conductivity!r} W/(m K): "
                                 "loss_model 'integral' needs a medium conductivity > 0.")

    @property
    def extrapolated(self) -> bool:
        """Whether the integral model extrapolates (``integral_extrapolation``, None: from
        ``integral_refinement`` = 3 on)."""
        if self.integral_extrapolation is None:
            return self.integral_refinement >= 3
        return self.integral_extrapolation

    @property
    def plane(self):
        """The substrate plane as ``(point (3,), unit normal (3,))``, or None."""
        if not self.substrate_plane:
            return None
        v = np.array(self.substrate_plane, float)
        return v[:3], v[3:] / np.linalg.norm(v[3:])

    def to_dict(self) -> dict:
        """Plain-dict view for result metadata."""
        return asdict(self)
