"""Parameters of the steady and transient heat-transfer models (theory 4): how the sheet loses
heat (:class:`~simulator.thermal.loss.ChainLoss` or :class:`~simulator.thermal.loss.IntegralLoss`),
the medium it loses it to (:class:`~simulator.geometry.materials.Fluid`), the
:class:`~simulator.thermal.loss.Substrate`, room temperature and the nodes and panels held at
it. :class:`~simulator.thermal.steady.ThermalModel` builds the operators from them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import finite, non_negative, one_of
from ..errors import ParameterError
from ..geometry.materials import AIR, WATER, Fluid
from .loss import HEAT_LOSS_MODELS, ChainLoss, IntegralLoss, Substrate, heat_loss_from_dict
from .monotone import CONDUCTIONS

__all__ = ["ThermalParameters", "REFERENCE_BETA"]

#: The reference's default dissipation angle: 20 degrees converted with pi ~ 3.14
#: (0.348888... rad instead of 0.349066 rad; tan differs by 0.06 %). Use it to reproduce
#: the reference's numbers; ``math.radians(20)`` is the physical value.
REFERENCE_BETA = 20 / 180 * 3.14

#: ``substrate`` not given: the plane of the model's thermal-boundary panels, if any.
_PANELS = object()
#: The fields of the chain and of the integral loss under their old names.
_CHAIN_NAMES = {"env_thickness": "thickness", "layers": "layers",
                "dissipation_angle": "dissipation_angle"}
_INTEGRAL_NAMES = {"integral_refinement": "refinement",
                   "integral_extrapolation": "extrapolation",
                   "integral_shape_tol": "shape_tol", "integral_correction_tol": "correction_tol"}
_MEDIUM_NAMES = {"env_conductivity": "thermal_conductivity", "env_density": "density",
                 "env_specific_heat": "specific_heat"}


def _ids(value, name):
    try:
        ids = tuple(int(v) for v in value)
    except (TypeError, ValueError):
        ids = None
    if ids is None or any(i != v or isinstance(v, bool) for i, v in zip(ids, value)):
        raise ParameterError(f"ThermalParameters.{name} = {value!r} is invalid; it must be a "
                             "sequence of integer (0-based) ids.")
    return ids


def _medium(value, overrides: dict) -> Fluid:
    """The medium from a :class:`Fluid` (or its dict) and the old ``env_*`` overrides; named
    after a known fluid it equals, else ``"custom"``."""
    if value is None:
        base = AIR
    elif isinstance(value, Fluid):
        base = value
    elif isinstance(value, dict):
        try:
            base = Fluid(**value)
        except TypeError:
            raise ParameterError(f"ThermalParameters.medium = {value!r}: give a Fluid (AIR, "
                                 "WATER) or a dict with name, density, specific_heat, "
                                 "thermal_conductivity.") from None
    else:
        raise ParameterError(f"ThermalParameters.medium = {value!r}: give a Fluid, e.g. "
                             "simulator.AIR or simulator.WATER.")
    values = {f: getattr(base, f) for f in ("density", "specific_heat", "thermal_conductivity")}
    changed = {_MEDIUM_NAMES[k]: v for k, v in overrides.items() if v is not None}
    for k, v in changed.items():
        non_negative(f"ThermalParameters.{[o for o, n in _MEDIUM_NAMES.items() if n == k][0]}",
                     v, {"density": "kg/m^3", "specific_heat": "J/(kg K)",
                         "thermal_conductivity": "W/(m K)"}[k])
    if all(float(values[k]) == float(v) for k, v in changed.items()):
        return base
    values.update({k: float(v) for k, v in changed.items()})
    name = next((f.name for f in (AIR, WATER) if all(
        getattr(f, k) == v for k, v in values.items())), "custom")
    return Fluid(name, **values)


def _build(cls, fields: dict, legacy: dict):
    """``cls(**fields)``; an error about a field given under its old name (``legacy``: new ->
    old name) names it as given: ``ThermalParameters.env_thickness = ...``."""
    try:
        return cls(**fields)
    except ParameterError as error:
        text = str(error)
        for new, old in legacy.items():
            text = text.replace(f"{cls.__name__}.{new} ", f"ThermalParameters.{old} ")
            text = text.replace(f"needs {new} ", f"needs {old} ")
        raise ParameterError(text) from None


def _loss(loss, loss_model, legacy: dict) -> ChainLoss | IntegralLoss:
    """The heat loss from ``loss`` (object or dict), the old ``loss_model`` switch and the old
    flat fields of either model (``legacy``, None where not given)."""
    given = None if loss is None else heat_loss_from_dict(loss)
    chain = {new: legacy[old] for old, new in _CHAIN_NAMES.items() if legacy[old] is not None}
    integral = {new: legacy[old] for old, new in _INTEGRAL_NAMES.items()
                if legacy[old] is not None}
    old_chain = {new: old for old, new in _CHAIN_NAMES.items() if new in chain}
    old_integral = {new: old for old, new in _INTEGRAL_NAMES.items() if new in integral}
    if loss_model is not None:
        model = one_of("ThermalParameters.loss_model", loss_model, HEAT_LOSS_MODELS,
                       hint="or give loss=ChainLoss(thickness=...) / IntegralLoss()")
    elif given is not None:
        model = given.model
    else:              # the old default: chains where their thickness is given
        model = "chain" if "thickness" in chain else "integral"
    if integral and model == "chain":      # checked all the same, as before
        _build(IntegralLoss, integral, old_integral)
    if chain and model == "integral":
        _build(ChainLoss, {"thickness": 1.0} | chain, old_chain)
    if model == "chain":
        base = given.to_dict() if isinstance(given, ChainLoss) else {}
        fields = {k: v for k, v in base.items() if k != "model"} | chain
        if "thickness" not in fields:
            raise ParameterError(
                "ThermalParameters: the chain heat loss needs the medium thickness t_env: give "
                "loss=ChainLoss(thickness=...) [m] (env_thickness=... in the old spelling; the "
                "paper suggests 1.5 x the panel length), or use the calibration-free "
                "loss=IntegralLoss(), which needs none.")
        return _build(ChainLoss, fields, old_chain)
    base = given.to_dict() if isinstance(given, IntegralLoss) else {}
    return _build(IntegralLoss, {k: v for k, v in base.items() if k != "model"} | integral,
                  old_integral)


def _substrate(substrate, substrate_plane) -> Substrate | None:
    """The substrate: the old ``substrate_plane`` (6 floats; () for none) where given, else
    ``substrate`` (not given: the boundary panels' plane)."""
    if substrate_plane is not None:
        try:
            v = tuple(float(c) for c in substrate_plane)
        except (TypeError, ValueError):
            v = None
        if v is None or len(v) not in (0, 6):
            raise ParameterError(f"ThermalParameters.substrate_plane = {substrate_plane!r} is "
                                 "invalid; give () or 6 finite numbers: a point (x, y, z) [m] "
                                 "and a non-zero normal (nx, ny, nz) pointing into the medium "
                                 "(or substrate=Substrate.plane(point, normal)).")
        return Substrate.from_value(v)
    if substrate is _PANELS:
        return Substrate()
    return Substrate.from_value(substrate)


@dataclass(frozen=True, init=False)
class ThermalParameters:
    """Heat-transfer parameters (theory 4; SI units, temperatures in deg C).

    ``ThermalParameters(loss=..., medium=AIR, substrate=Substrate(), room_temperature=21.0,
    boundary_panels=(), room_temperature_nodes=(), conduction=None)``.

    Parameters
    ----------
    loss : ChainLoss or IntegralLoss
        How the sheet loses heat to the medium (:mod:`simulator.thermal.loss`): the paper's
        fitted chains, ``ChainLoss(thickness=t_env)``, or the calibration-free
        ``IntegralLoss()`` (default when no chain thickness is given). Each carries only its
        own options. Transient and electro-thermal steps use the same loss (theory 8.1).
    medium : Fluid
        The medium: conductivity, and density and specific heat for the time domain
        (:data:`~simulator.geometry.materials.AIR` by default,
        :data:`~simulator.geometry.materials.WATER`).
    substrate : Substrate or None
        The isothermal substrate plane of the integral loss: ``Substrate()`` (default) the
        plane of the thermal-boundary panels (none without such panels),
        ``Substrate.plane(point, normal)`` an explicit one, None an unbounded medium. (The
        chains cap their t_env at the distance to the boundary panels whatever it is.)
    room_temperature : float
        Room temperature [deg C] of the medium far away, the substrate and
        ``room_temperature_nodes``.
    boundary_panels : tuple of int
        Panel ids of thermal boundaries (on the substrate, at room temperature in the integral
        model; their distance caps t_env in the chain model).
    room_temperature_nodes : tuple of int
        Mesh node ids whose temperature is held at room temperature.
    conduction : {None, "t3", "monotone"}
        The sheet's conduction (theory 4.2, 4.9): ``"t3"`` the mesh triangles' T3 elements (the
        reference's), ``"monotone"`` the same P1 conduction on a finer triangulation of the
        mesh nodes without positive couplings, condensed back to them (an M-matrix: under
        heating no node below room temperature with the chains;
        :mod:`~simulator.thermal.monotone`). None (default): ``"t3"`` with the chains (the
        paper's model, on which they were fitted), ``"monotone"`` with the integral loss;
        :attr:`conduction_method` says which.

    Notes
    -----
    The old flat spellings are still accepted as keywords, and read as properties (deprecated):
    ``env_thickness``, ``layers``, ``dissipation_angle`` (the chains'), ``loss_model``
    ("chain" or "integral"), ``integral_refinement``, ``integral_extrapolation``,
    ``integral_shape_tol``, ``integral_correction_tol`` (the integral loss'),
    ``env_conductivity``, ``env_density``, ``env_specific_heat`` (the medium's) and
    ``substrate_plane`` (6 floats, a point and a normal; () for none). Without ``loss`` or
    ``loss_model``, a given ``env_thickness`` selects the chains (their old default). Those
    of the model not selected are checked, and not kept.
    """

    loss: ChainLoss | IntegralLoss
    medium: Fluid
    substrate: Substrate | None
    room_temperature: float
    boundary_panels: tuple
    room_temperature_nodes: tuple
    conduction: str | None

    def __init__(self, env_thickness=None, env_conductivity=None, layers=None,
                 dissipation_angle=None, room_temperature=21.0, boundary_panels=(),
                 room_temperature_nodes=(), env_density=None, env_specific_heat=None,
                 loss_model=None, integral_refinement=None, substrate_plane=None,
                 integral_shape_tol=None, integral_extrapolation=None,
                 integral_correction_tol=None, *, loss=None, medium=None, substrate=_PANELS,
                 conduction=None):
        legacy = {"env_thickness": env_thickness, "layers": layers,
                  "dissipation_angle": dissipation_angle,
                  "integral_refinement": integral_refinement,
                  "integral_extrapolation": integral_extrapolation,
                  "integral_shape_tol": integral_shape_tol,
                  "integral_correction_tol": integral_correction_tol}
        loss = _loss(loss, loss_model, legacy)
        medium = _medium(medium, {"env_conductivity": env_conductivity,
                                  "env_density": env_density,
                                  "env_specific_heat": env_specific_heat})
        set_ = object.__setattr__
        set_(self, "loss", loss)
        set_(self, "medium", medium)
        set_(self, "substrate", _substrate(substrate, substrate_plane))
        set_(self, "room_temperature", finite("ThermalParameters.room_temperature",
                                              room_temperature, "deg C"))
        for name, value in (("boundary_panels", boundary_panels),
                            ("room_temperature_nodes", room_temperature_nodes)):
            set_(self, name, _ids(value, name))
        set_(self, "conduction", None if conduction is None else one_of(
            "ThermalParameters.conduction", conduction, CONDUCTIONS,
            hint="or None: 't3' with the chains, 'monotone' with the integral loss"))
        if loss.model == "integral" and not medium.thermal_conductivity > 0:
            raise ParameterError(f"ThermalParameters: the medium's conductivity "
                                 f"{medium.thermal_conductivity!r} W/(m K): the integral loss "
                                 "needs a medium conductivity > 0.")

    @property
    def conduction_method(self) -> str:
        """The sheet conduction in force: :attr:`conduction`, or if None ``"t3"`` with the
        chains and ``"monotone"`` with the integral loss (theory 4.9)."""
        if self.conduction is not None:
            return self.conduction
        return "t3" if self.loss.model == "chain" else "monotone"

    # ------------------------------------------------------------------ old flat spellings
    @property
    def loss_model(self) -> str:
        """``"chain"`` or ``"integral"`` (``loss.model``)."""
        return self.loss.model

    def _chain(self) -> ChainLoss | None:
        return self.loss if isinstance(self.loss, ChainLoss) else None

    def _integral(self) -> IntegralLoss:
        return self.loss if isinstance(self.loss, IntegralLoss) else _DEFAULT_INTEGRAL

    @property
    def env_thickness(self) -> float | None:
        """The chains' t_env [m] (None with the integral loss)."""
        chain = self._chain()
        return None if chain is None else chain.thickness

    @property
    def layers(self) -> int:
        """The chains' medium layers N (their default with the integral loss)."""
        return (self._chain() or _DEFAULT_CHAIN).layers

    @property
    def dissipation_angle(self) -> float:
        """The chains' dissipation angle beta [rad] (their default with the integral loss)."""
        return (self._chain() or _DEFAULT_CHAIN).dissipation_angle

    @property
    def integral_refinement(self) -> int:
        return self._integral().refinement

    @property
    def integral_extrapolation(self) -> bool | None:
        return self._integral().extrapolation

    @property
    def integral_shape_tol(self) -> float:
        return self._integral().shape_tol

    @property
    def integral_correction_tol(self) -> float:
        return self._integral().correction_tol

    @property
    def extrapolated(self) -> bool:
        """Whether the integral loss extrapolates (:attr:`IntegralLoss.extrapolated`)."""
        return self._integral().extrapolated

    @property
    def env_conductivity(self) -> float:
        """The medium's conductivity k_env [W/(m K)]."""
        return self.medium.thermal_conductivity

    @property
    def env_density(self) -> float:
        """The medium's density [kg/m^3]."""
        return self.medium.density

    @property
    def env_specific_heat(self) -> float:
        """The medium's specific heat [J/(kg K)]."""
        return self.medium.specific_heat

    @property
    def substrate_plane(self) -> tuple:
        """An explicit substrate plane as 6 floats (point, normal); () for none or for the
        boundary panels' plane (:attr:`substrate`)."""
        return () if self.substrate is None else self.substrate.as_tuple()

    @property
    def plane(self):
        """The explicit substrate plane as ``(point (3,), unit normal (3,))``, or None."""
        if not self.substrate_plane:
            return None
        v = np.array(self.substrate_plane, float)
        return v[:3], v[3:] / np.linalg.norm(v[3:])

    def to_dict(self) -> dict:
        """Plain-dict view (result metadata, FOLD model files; SI units): ``loss``,
        ``medium``, ``substrate`` (None, ``"boundary_panels"`` or a plane), room temperature,
        the held panels and nodes and the ``conduction`` (None: the loss model's).
        ``ThermalParameters(**d)`` reads it back."""
        return {"loss": self.loss.to_dict(), "medium": self.medium.to_dict(),
                "substrate": None if self.substrate is None else self.substrate.to_dict(),
                "room_temperature": float(self.room_temperature),
                "boundary_panels": list(self.boundary_panels),
                "room_temperature_nodes": list(self.room_temperature_nodes),
                "conduction": self.conduction}

    def describe(self) -> str:
        """One line for figure footers and summaries: the loss, the medium, the substrate."""
        sub = ("no substrate" if self.substrate is None else "substrate: the boundary panels' "
               "plane" if self.substrate.from_panels else "substrate: a given plane")
        return (f"heat loss: {self.loss.describe()}; medium: {self.medium.name}, k = "
                f"{self.env_conductivity:g} W/(m K); {sub}")


_DEFAULT_CHAIN = ChainLoss(thickness=1.0)
_DEFAULT_INTEGRAL = IntegralLoss()
