"""Parameters of the steady and transient heat-transfer models (theory 4): how the sheet loses
heat (:class:`~simulator.model.heat_loss.ChainLoss` or :class:`~simulator.model.heat_loss.IntegralLoss`),
the medium it loses it to (:class:`~simulator.geometry.materials.Fluid`), the
:class:`~simulator.model.heat_loss.Substrate`, room temperature and the nodes and panels held at
it. :class:`~simulator.thermal.steady.ThermalModel` builds the operators from them."""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .._deprecation import warn_deprecated
from .._validate import finite, non_negative, one_of
from ..errors import ParameterError
from ..geometry.materials import AIR, Fluid
from . import heat_loss
from .heat_loss import HEAT_LOSS_MODELS, ChainLoss, IntegralLoss, Substrate, heat_loss_from_dict
from .layers import SheetLayers

__all__ = ["ThermalParameters", "REFERENCE_BETA", "CONDUCTIONS", "CREASE_CONDUCTIONS",
           "AUTO_SHEET_REFINEMENT", "MAX_SHEET_REFINEMENT", "SHEET_EXTRAPOLATIONS"]

logger = logging.getLogger(__name__)

#: The reference's default dissipation angle: 20 degrees converted with pi ~ 3.14
#: (0.348888... rad instead of 0.349066 rad; tan differs by 0.06 %). Use it to reproduce
#: the reference's numbers; ``math.radians(20)`` is the physical value.
REFERENCE_BETA = 20 / 180 * 3.14

#: The sheet conduction settings (:attr:`ThermalParameters.conduction`): ``"t3"`` the mesh
#: triangles' T3 elements (the reference's), ``"monotone"`` the M-matrix of
#: :mod:`simulator.thermal.monotone`.
CONDUCTIONS = ("t3", "monotone")
#: How a crease conducts heat in-plane (:attr:`ThermalParameters.crease_conduction`).
CREASE_CONDUCTIONS = ("paper", "layers")
#: The values of :attr:`ThermalParameters.sheet_extrapolation` that extrapolate (theory 4.13):
#: True, from the sheets refined r and 2r; ``"r+1"``, from the sheets refined r and r + 1
#: (``(r + 1) T(r + 1) - r T(r)``).
SHEET_EXTRAPOLATIONS = (True, "r+1")
#: Largest sheet refinement accepted (``r^2`` fine triangles per mesh triangle).
MAX_SHEET_REFINEMENT = 16
#: The integral loss's sheet refinement where its dense operator allows
#: (:meth:`ThermalParameters.sheet_refinement_for`; theory 4.11).
AUTO_SHEET_REFINEMENT = 2

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
#: The old flat keywords (deprecated, issue 29) and what to write instead.
_OLD_KEYWORDS = {
    **{old: f"loss=ChainLoss({new}=...), or params.with_loss({new}=...) on existing "
            "parameters" for old, new in _CHAIN_NAMES.items()},
    "env_conductivity": "medium=AIR.with_properties(thermal_conductivity=...)",
    **{old: f"loss=IntegralLoss({new}=...), or params.with_loss({new}=...) on existing "
            "parameters" for old, new in _INTEGRAL_NAMES.items()},
    "env_density": "medium=AIR.with_properties(density=...)",
    "env_specific_heat": "medium=AIR.with_properties(specific_heat=...)",
    "loss_model": "loss=ChainLoss(thickness=...) or loss=IntegralLoss(), or "
                  "params.with_loss('chain' or 'integral') on existing parameters",
    "substrate_plane": "substrate=Substrate.plane(point, normal), or substrate=None for none",
}
#: The old properties (deprecated) and what to read instead.
_OLD_PROPERTIES = {
    **{old: f"loss.{new} (of the chain loss)" for old, new in _CHAIN_NAMES.items()},
    **{old: f"loss.{new} (of the integral loss)" for old, new in _INTEGRAL_NAMES.items()},
    "extrapolated": "loss.extrapolated (of the integral loss)",
    **{old: f"medium.{new}" for old, new in _MEDIUM_NAMES.items()},
    "loss_model": "loss.model",
    "substrate_plane": "substrate.as_tuple() (substrate None: no plane)",
    "plane": "substrate.point and substrate.normal (an explicit Substrate.plane), or "
             "simulator.thermal.boundary_panel_plane(model) (the boundary panels' plane)",
}


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
    """The medium from a :class:`Fluid` (or its dict) and the old ``env_*`` overrides
    (:meth:`Fluid.with_properties`)."""
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
    changed = {_MEDIUM_NAMES[k]: v for k, v in overrides.items() if v is not None}
    for k, v in changed.items():
        non_negative(f"ThermalParameters.{[o for o, n in _MEDIUM_NAMES.items() if n == k][0]}",
                     v, {"density": "kg/m^3", "specific_heat": "J/(kg K)",
                         "thermal_conductivity": "W/(m K)"}[k])
    return base.with_properties(**changed)


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
            _no_thickness()
        return _build(ChainLoss, fields, old_chain)
    base = given.to_dict() if isinstance(given, IntegralLoss) else {}
    return _build(IntegralLoss, {k: v for k, v in base.items() if k != "model"} | integral,
                  old_integral)


def _no_thickness():
    raise ParameterError(
        "ThermalParameters: the chain heat loss needs the medium thickness t_env: give "
        "loss=ChainLoss(thickness=...) [m] (env_thickness=... in the old spelling; the "
        "paper suggests 1.5 x the panel length), or use the calibration-free "
        "loss=IntegralLoss(), which needs none.")


def _old_property(name: str, read):
    """A deprecated read-only property ``name``: warns, then ``read(params)``."""
    def get(self):
        warn_deprecated(f"ThermalParameters.{name} is deprecated; read "
                        f"{_OLD_PROPERTIES[name]}.")
        return read(self)

    get.__doc__ = f"Deprecated: read ``{_OLD_PROPERTIES[name]}``."
    return property(get)


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
    boundary_panels=(), room_temperature_nodes=(), conduction=None, crease_conduction="paper",
    sheet_layers=None, sheet_refinement=None, sheet_extrapolation=False)``;
    give them by keyword.

    Parameters
    ----------
    loss : ChainLoss or IntegralLoss
        How the sheet loses heat to the medium (:mod:`simulator.model.heat_loss`): the paper's
        fitted chains, ``ChainLoss(thickness=t_env)``, or the calibration-free
        ``IntegralLoss()`` (the default). Each carries only its own options
        (:meth:`with_loss` changes them). Transient and electro-thermal steps use the same
        loss (theory 8.1).
    medium : Fluid
        The medium: conductivity, and density and specific heat for the time domain
        (:data:`~simulator.geometry.materials.AIR` by default,
        :data:`~simulator.geometry.materials.WATER`; another conductivity:
        ``AIR.with_properties(thermal_conductivity=...)``).
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
    crease_conduction : {"paper", "layers"}
        The in-plane conduction of a crease (theory 4.10): ``"paper"`` (default) one layer of the
        crease material's conductivity over the crease thickness, as the reference;
        ``"layers"`` the actuated creases conduct as their two bimorph layers, sheet
        conductance ``k1 t1 + k2 t2`` (:class:`~simulator.model.bimorph.Bimorph`, taken from
        the model's actuators; about 100x the paper's on the paper's gold-on-SU-8 creases),
        and the panels and passive creases listed in ``sheet_layers`` as their stacks; the
        transient model's heat capacity of those is ``sum rho c t`` over the same layers
        (theory 7.2). Everything else stays as in ``"paper"``.
    sheet_layers : SheetLayers or None
        Layer stacks of panels and passive creases (:class:`~simulator.model.layers.
        SheetLayers`: a metal film on a panel, a heater film on a crease that does not
        actuate), used with ``crease_conduction="layers"`` (with ``"paper"`` an error: they
        would be ignored). None (default): none.
    sheet_refinement : int or None
        The sheet's temperature resolved within the mesh triangles (theory 4.11,
        :mod:`~simulator.thermal.refined`): every mesh triangle split uniformly into ``r^2``
        for the heat balance, the temperatures the mechanics reads taken at the mesh nodes;
        the integral loss only (the chains were fitted on the mesh triangles, and their loss
        area sums triangle perimeters, theory 4.3). None (default): the loss model's: 1 with
        the chains, :data:`AUTO_SHEET_REFINEMENT` with the integral loss where its dense
        operator allows (:meth:`sheet_refinement_for` says which).
    sheet_extrapolation : bool or str
        The steady temperatures extrapolated from the sheet refined ``r`` and ``2 r``, ``2
        T(2r) - T(r)`` (Richardson's estimate for an error of first order in the element size,
        theory 4.13: the crease metal layer's effect converges so, not on one sheet); the
        refinement in force (:meth:`sheet_refinement_for`) must be 2 to 8. True: each sheet
        its own integral loss operator; ``"r+1"``: from the sheets refined ``r`` and ``r +
        1``, ``(r + 1) T(r + 1) - r T(r)``, each its own operator (about 2.5 times cheaper than True at r = 2, within
        0.6 % of it on the grippers). Default False. Steady solves only: the time domain and
        the loss per node of a refined sheet refuse it.

    Notes
    -----
    Old spellings (deprecated; they warn with an
    :class:`~simulator.errors.EtorigamiDeprecationWarning` naming the new spelling, and go in
    the next release): the flat keywords, also positional in this order, ``env_thickness``,
    ``env_conductivity``, ``layers``, ``dissipation_angle`` (then ``room_temperature``,
    ``boundary_panels``, ``room_temperature_nodes``), ``env_density``, ``env_specific_heat``,
    ``loss_model`` ("chain" or "integral"), ``integral_refinement``, ``substrate_plane`` (6
    floats, a point and a normal; () for none), ``integral_shape_tol``,
    ``integral_extrapolation``, ``integral_correction_tol``; and the properties of those names
    and ``extrapolated``, ``plane``. ``env_*`` are the medium's fields, ``env_thickness``,
    ``layers``, ``dissipation_angle`` the chains' and ``integral_*`` the integral loss'.
    Without ``loss`` or ``loss_model``, a given ``env_thickness`` selects the chains. Those of
    the model not selected are checked, and not kept. :meth:`from_dict` reads the old flat
    form without a warning (older FOLD model files).
    """

    loss: ChainLoss | IntegralLoss
    medium: Fluid
    substrate: Substrate | None
    room_temperature: float
    boundary_panels: tuple
    room_temperature_nodes: tuple
    conduction: str | None
    crease_conduction: str
    sheet_layers: SheetLayers | None
    sheet_refinement: int | None
    sheet_extrapolation: bool | str

    def __init__(self, env_thickness=None, env_conductivity=None, layers=None,
                 dissipation_angle=None, room_temperature=21.0, boundary_panels=(),
                 room_temperature_nodes=(), env_density=None, env_specific_heat=None,
                 loss_model=None, integral_refinement=None, substrate_plane=None,
                 integral_shape_tol=None, integral_extrapolation=None,
                 integral_correction_tol=None, *, loss=None, medium=None, substrate=_PANELS,
                 conduction=None, crease_conduction="paper", sheet_layers=None,
                 sheet_refinement=None, sheet_extrapolation=False):
        old = {"env_thickness": env_thickness, "env_conductivity": env_conductivity,
               "layers": layers, "dissipation_angle": dissipation_angle,
               "env_density": env_density, "env_specific_heat": env_specific_heat,
               "loss_model": loss_model, "integral_refinement": integral_refinement,
               "substrate_plane": substrate_plane, "integral_shape_tol": integral_shape_tol,
               "integral_extrapolation": integral_extrapolation,
               "integral_correction_tol": integral_correction_tol}
        for name in (k for k, v in old.items() if v is not None):
            warn_deprecated(f"ThermalParameters({name}=...) is deprecated; use "
                            f"{_OLD_KEYWORDS[name]}.")
        self._set(old, loss, medium, substrate, room_temperature, boundary_panels,
                  room_temperature_nodes, conduction, crease_conduction, sheet_refinement,
                  sheet_layers, sheet_extrapolation)

    def _set(self, old: dict, loss=None, medium=None, substrate=_PANELS,
             room_temperature=21.0, boundary_panels=(), room_temperature_nodes=(),
             conduction=None, crease_conduction="paper", sheet_refinement=None,
             sheet_layers=None, sheet_extrapolation=False):
        """Set the fields from the new ones and the ``old`` flat ones (None: not given)."""
        old = {k: old.get(k) for k in _OLD_KEYWORDS}
        loss = _loss(loss, old["loss_model"], {k: old[k] for k in (*_CHAIN_NAMES,
                                                                   *_INTEGRAL_NAMES)})
        medium = _medium(medium, {k: old[k] for k in _MEDIUM_NAMES})
        set_ = object.__setattr__
        set_(self, "loss", loss)
        set_(self, "medium", medium)
        set_(self, "substrate", _substrate(substrate, old["substrate_plane"]))
        set_(self, "room_temperature", finite("ThermalParameters.room_temperature",
                                              room_temperature, "deg C"))
        for name, value in (("boundary_panels", boundary_panels),
                            ("room_temperature_nodes", room_temperature_nodes)):
            set_(self, name, _ids(value, name))
        set_(self, "conduction", None if conduction is None else one_of(
            "ThermalParameters.conduction", conduction, CONDUCTIONS,
            hint="or None: 't3' with the chains, 'monotone' with the integral loss"))
        set_(self, "crease_conduction", one_of(
            "ThermalParameters.crease_conduction", crease_conduction, CREASE_CONDUCTIONS,
            hint="'paper' for the reference's single crease layer, 'layers' for the sum of "
                 "k t over the actuators' bimorph layers"))
        set_(self, "sheet_layers", _sheet_layers(sheet_layers, self.crease_conduction))
        set_(self, "sheet_refinement", _sheet_refinement(sheet_refinement, loss))
        set_(self, "sheet_extrapolation", _sheet_extrapolation(sheet_extrapolation, loss,
                                                               self.sheet_refinement))
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

    def sheet_refinement_for(self, n_triangles: int) -> int:
        """The sheet refinement in force on a mesh of ``n_triangles`` triangles:
        :attr:`sheet_refinement`, or if None 1 with the chains and, with the integral loss,
        :data:`AUTO_SHEET_REFINEMENT` on meshes of at most ``MAX_SUB_TRIANGLES / (r m)^2``
        triangles (111 at the default m = 3: the gripper, the double and single folds, the
        Miura lifter; the refined sheet's dense operator has ``(r ceil(m / r))^2`` sub-triangles
        per mesh triangle, theory 4.11), else 1 (the crane, large sheets)."""
        if self.sheet_refinement is not None:
            return self.sheet_refinement
        if self.loss.model != "integral" or self.loss.operator == "fast":
            return 1
        r, m = AUTO_SHEET_REFINEMENT, self.loss.refinement
        return r if int(n_triangles) * (r * m) ** 2 <= heat_loss.MAX_SUB_TRIANGLES else 1

    def finer_refinement(self, r: int) -> int:
        """The finer sheet's refinement of :attr:`sheet_extrapolation` from the sheet refined
        ``r``: ``r + 1`` with ``"r+1"``, else ``2 r``."""
        return r + 1 if self.sheet_extrapolation == "r+1" else 2 * r

    def _describe_refinement(self, n_triangles) -> str:
        """The sheet refinement's part of :meth:`describe`."""
        if self.sheet_extrapolation:
            r = (AUTO_SHEET_REFINEMENT if self.sheet_refinement is None
                 else self.sheet_refinement) if n_triangles is None \
                else self.sheet_refinement_for(n_triangles)
            return f"; sheet refined r = {r} and {self.finer_refinement(r)}, extrapolated"
        if n_triangles is not None:
            r = self.sheet_refinement_for(n_triangles)
            return f"; sheet refined r = {r}" if r > 1 else ""
        if self.sheet_refinement is None:
            return (f"; sheet refined r = {AUTO_SHEET_REFINEMENT} where the dense operator "
                    "allows" if self.loss.model == "integral" else "")
        return f"; sheet refined r = {self.sheet_refinement}" if self.sheet_refinement > 1 else ""

    @classmethod
    def from_dict(cls, d: Mapping) -> ThermalParameters:
        """Parameters from :meth:`to_dict`'s form; also the old flat form of older FOLD model
        files and metadata (``env_thickness``, ``loss_model``, ...), read without a
        deprecation warning (logged at INFO)."""
        if not isinstance(d, Mapping):
            raise ParameterError(f"ThermalParameters.from_dict({d!r}): give a dict, e.g. "
                                 "ThermalParameters(...).to_dict().")
        new = {k: v for k, v in d.items() if k not in _OLD_KEYWORDS}
        fields = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(new) - set(fields))
        if unknown:
            raise ParameterError(f"ThermalParameters: unknown field(s) {', '.join(unknown)}; "
                                 f"the fields are {', '.join(fields)} (older files: "
                                 f"{', '.join(_OLD_KEYWORDS)}).")
        old = {k: v for k, v in d.items() if k in _OLD_KEYWORDS}
        if old:
            logger.info("ThermalParameters read in the old flat form (%s); written as loss, "
                        "medium and substrate from now on", ", ".join(old))
        self = cls.__new__(cls)
        self._set(old, **new)
        return self

    def with_loss(self, model: str | None = None, **changes) -> ThermalParameters:
        """These parameters with another heat loss: ``model`` ``"chain"`` or ``"integral"``
        (default: the current loss's), and ``changes`` to its fields (:class:`ChainLoss`:
        ``thickness``, ``layers``, ``dissipation_angle``; :class:`IntegralLoss`:
        ``refinement``, ``extrapolation``, ``shape_tol``, ``correction_tol``, ``lumped``). The
        current loss's fields are kept where the model stays, else the new model's defaults, e.g.
        ``params.with_loss(correction_tol=0.0)``, ``params.with_loss("integral")``."""
        model = self.loss.model if model is None else one_of(
            "ThermalParameters.with_loss: model", model, HEAT_LOSS_MODELS)
        cls = ChainLoss if model == "chain" else IntegralLoss
        unknown = sorted(set(changes) - set(cls.__dataclass_fields__))
        if unknown:
            raise ParameterError(f"ThermalParameters.with_loss: {', '.join(unknown)} is not a "
                                 f"field of {cls.__name__}; its fields are "
                                 f"{', '.join(cls.__dataclass_fields__)}.")
        if self.loss.model == model:
            return dataclasses.replace(self, loss=dataclasses.replace(self.loss, **changes))
        if model == "chain" and "thickness" not in changes:
            _no_thickness()
        fine = {} if model == "integral" or (self.sheet_refinement or 1) == 1 else {
            "sheet_refinement": None}        # the chains on the mesh triangles (theory 4.11)
        if model == "chain":
            fine["sheet_extrapolation"] = False
        return dataclasses.replace(self, loss=cls(**changes), **fine)

    # ------------------------------------------------------------------ old flat spellings
    def _chain(self) -> ChainLoss:
        """The chain loss, or with the integral loss the chains' defaults (old properties)."""
        return self.loss if isinstance(self.loss, ChainLoss) else _DEFAULT_CHAIN

    def _integral(self) -> IntegralLoss:
        """The integral loss, or with the chains its defaults (old properties)."""
        return self.loss if isinstance(self.loss, IntegralLoss) else _DEFAULT_INTEGRAL

    loss_model = _old_property("loss_model", lambda p: p.loss.model)
    env_thickness = _old_property("env_thickness", lambda p: p.loss.thickness
                                  if isinstance(p.loss, ChainLoss) else None)
    layers = _old_property("layers", lambda p: p._chain().layers)
    dissipation_angle = _old_property("dissipation_angle", lambda p: p._chain().dissipation_angle)
    integral_refinement = _old_property("integral_refinement",
                                        lambda p: p._integral().refinement)
    integral_extrapolation = _old_property("integral_extrapolation",
                                           lambda p: p._integral().extrapolation)
    integral_shape_tol = _old_property("integral_shape_tol", lambda p: p._integral().shape_tol)
    integral_correction_tol = _old_property("integral_correction_tol",
                                            lambda p: p._integral().correction_tol)
    extrapolated = _old_property("extrapolated", lambda p: p._integral().extrapolated)
    env_conductivity = _old_property("env_conductivity",
                                     lambda p: p.medium.thermal_conductivity)
    env_density = _old_property("env_density", lambda p: p.medium.density)
    env_specific_heat = _old_property("env_specific_heat", lambda p: p.medium.specific_heat)
    substrate_plane = _old_property("substrate_plane", lambda p: () if p.substrate is None
                                    else p.substrate.as_tuple())
    plane = _old_property("plane", lambda p: _plane(p.substrate))

    def to_dict(self) -> dict:
        """Plain-dict view (result metadata, FOLD model files; SI units): ``loss``,
        ``medium``, ``substrate`` (None, ``"boundary_panels"`` or a plane), room temperature,
        the held panels and nodes, the ``conduction`` (None: the loss model's), the
        ``crease_conduction`` and, where given, the ``sheet_layers``, the
        ``sheet_refinement`` and ``sheet_extrapolation`` (where on).
        :meth:`from_dict` (or ``ThermalParameters(**d)``) reads it back."""
        return {"loss": self.loss.to_dict(), "medium": self.medium.to_dict(),
                "substrate": None if self.substrate is None else self.substrate.to_dict(),
                "room_temperature": float(self.room_temperature),
                "boundary_panels": list(self.boundary_panels),
                "room_temperature_nodes": list(self.room_temperature_nodes),
                "conduction": self.conduction, "crease_conduction": self.crease_conduction,
                **({} if self.sheet_layers is None
                   else {"sheet_layers": self.sheet_layers.to_dict()}),
                **({} if self.sheet_refinement is None
                   else {"sheet_refinement": self.sheet_refinement}),
                **({"sheet_extrapolation": self.sheet_extrapolation}
                   if self.sheet_extrapolation else {})}

    def describe(self, n_triangles: int | None = None) -> str:
        """One line for figure footers and summaries: the loss, the medium, the substrate (and
        the crease conduction where it is not the paper's, and the sheet refinement where it
        is above 1: the one in force on a mesh of ``n_triangles`` triangles where given)."""
        panels = ", ".join(map(str, self.boundary_panels))
        if self.substrate is None or (self.substrate.from_panels and not panels):
            sub = "no substrate"
        elif self.loss.model == "chain":
            sub = f"t_env capped at the boundary panels ({panels})"
        elif self.substrate.from_panels:
            sub = f"substrate: the plane of the boundary panels ({panels})"
        else:
            sub = "substrate: a given plane"
        layers = ("; creases conduct as their bimorph layers (sum of k t)"
                  if self.crease_conduction == "layers" else "")
        if self.sheet_layers is not None:
            layers += (f", {len(self.sheet_layers.panels)} panel(s) and "
                       f"{len(self.sheet_layers.creases)} passive crease(s) as their stacks")
        fine = self._describe_refinement(n_triangles)
        return (f"heat loss: {self.loss.describe()}; medium: {self.medium.name}, k = "
                f"{self.medium.thermal_conductivity:g} W/(m K); {sub}{layers}{fine}")


def _sheet_layers(value, crease_conduction: str) -> SheetLayers | None:
    """The checked :attr:`ThermalParameters.sheet_layers` (None: none; an empty one is None)."""
    if value is None:
        return None
    layers = SheetLayers.from_dict(value)
    if not layers:
        return None
    if crease_conduction != "layers":
        raise ParameterError(
            f"ThermalParameters.sheet_layers: {len(layers.panels)} panel and "
            f"{len(layers.creases)} crease stack(s) given with crease_conduction = "
            f"{crease_conduction!r}, which ignores them; give crease_conduction='layers' (or "
            "sheet_layers=None for the paper's single layers).")
    return layers


def _sheet_refinement(value, loss) -> int | None:
    """The checked :attr:`ThermalParameters.sheet_refinement` (None: the loss model's)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) \
            or not 1 <= value <= MAX_SHEET_REFINEMENT:
        raise ParameterError(f"ThermalParameters.sheet_refinement = {value!r} must be None or an "
                             f"integer from 1 (the mesh triangles) to {MAX_SHEET_REFINEMENT}.")
    if value > 1 and loss.model != "integral":
        raise ParameterError(f"ThermalParameters.sheet_refinement = {value} needs the integral "
                             "loss (loss=IntegralLoss()): the chains were fitted on the mesh "
                             "triangles and their loss area sums triangle perimeters (theory "
                             "4.3), so refining would change them; use sheet_refinement=1 or "
                             "None with ChainLoss.")
    return int(value)


def _sheet_extrapolation(value, loss, sheet_refinement) -> bool | str:
    """The checked :attr:`ThermalParameters.sheet_extrapolation`."""
    if not (isinstance(value, (bool, np.bool_)) or (isinstance(value, str)
                                                     and value in SHEET_EXTRAPOLATIONS)):
        raise ParameterError(f"ThermalParameters.sheet_extrapolation = {value!r} must be True or "
                             "False, or 'r+1' (the sheets r and r + 1).")
    if value and (loss.model != "integral" or sheet_refinement == 1
                  or (sheet_refinement or 2) > 8):
        raise ParameterError(
            f"ThermalParameters.sheet_extrapolation = {value!r} extrapolates from the sheet "
            f"refined r and a finer one, r from 2 to 8 (theory 4.13); given the {loss.model} "
            f"loss and sheet_refinement = {sheet_refinement!r}: use the integral loss with "
            "sheet_refinement None or 2-8, or sheet_extrapolation=False.")
    return value if isinstance(value, str) else bool(value)


def _plane(substrate: Substrate | None):
    """An explicit substrate plane as ``(point (3,), unit normal (3,))``, else None (the old
    ``plane`` property)."""
    if substrate is None or substrate.from_panels:
        return None
    v = np.array(substrate.as_tuple(), float)
    return v[:3], v[3:] / np.linalg.norm(v[3:])


_DEFAULT_CHAIN = ChainLoss(thickness=1.0)
_DEFAULT_INTEGRAL = IntegralLoss()
