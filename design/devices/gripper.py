"""Origami micro-gripper of the paper's section 6.3 (theory 10.6).

Four foldable panels on two heater circuits: the base creases fold the base panels up to
assemble the gripper (stage 1, "assembly": base fold past 90 deg), then, with the base heat
kept on, the arm creases close the arms (stage 2, "grip": arm tips closer than 100 um).
:func:`evaluate_gripper` finds the power each stage needs, per heated crease as in the paper:

* ``mode="staircase"`` (the reference's search): add ``step`` (0.1 mW) per heated crease, one
  thermal increment at a time, until the criterion holds;
* ``mode="bisect"`` (default): grow the power step geometrically (up to ``max_step``) from
  saved states, then bisect the crossing to ``tol`` (0.01 mW). Each trial restarts from the
  saved state below the crossing and heats in one increment, so nothing is recomputed from
  zero. (Iterated coupling gives the same powers on the reference design to 1e-3 mW at six
  times the cost, so the trials use the reference's staggered coupling.)

Both searches heat with ``on_limit_point="continue"`` (:class:`design.devices.power_search.HeatingStage`;
not the bisect mode's growth trials larger than ``step``, whose failures it retries with
smaller steps): where load control stalls at a limit point, arc length in the power carries
the trial through the snap, and a stage met after a snap says so in its message (``criterion
met after a snap (snap at P mW per crease: displacement jumps D um)``). Where load control
converges the numbers are those of plain load control. Of the ~4,900 trials of the paper's
coordinate descent (82 designs) one fails: a 0.4 mW growth trial, retried with 0.1 mW; the
start design with a residual fold of +45 deg snaps as its arm tips close (grip stage, 0.05 mW
per crease, a 0.23 um jump), where load control failed.
"""

from __future__ import annotations

import logging
import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from simulator import (AIR, Actuators, BarHingeParameters, Bimorph, ContactParameters, Load,
                       NewtonOptions, ParameterError, SelfFold, Supports, ThermalParameters,
                       example_patterns, make_mesh, make_model, simulate)
from simulator.materials import SPR
from simulator.model import REFERENCE_GRAVITY
from simulator.thermal import TemperatureLimit, TemperatureVerdict, crease_temperatures
from simulator._deprecation import warn_deprecated
from simulator._result import ResultFiles
from simulator._validate import finite, non_negative, one_of, positive

from ..core.contract import check_outcome, power_if
from .gripper_heat import GRIPPER_TRIANGLES, HEAT_FIELDS, LOSS_MODELS, GripperHeatModel
from .limits import SU8_LIMIT
from .power_search import HeatingStage, bisect_search, staircase_search

__all__ = ["GripperDesign", "StageResult", "GripperResult", "make_gripper_model", "evaluate_gripper",
           "BASE_CREASES", "ARM_CREASES", "REFERENCE_NEWTON", "STAGE_STATUSES", "LOSS_MODELS",
           "gripper_design_pattern", "GripperHeatModel", "split_heat", "gripper_settings",
           "GRIPPER_TRIANGLES"]

logger = logging.getLogger(__name__)

#: Heater circuits (0-based crease ids): base hinges (reference 3, 6), arm hinges (4, 10).
BASE_CREASES = (2, 5)
ARM_CREASES = (3, 9)
#: Self-weight increments. The reference uses 80 for its loose Newton loop; converged, the sag is
#: path-independent (4 and 80 increments end within 1e-12 m, measured on the start and G2
#: designs) and 4 cost a fifth of the time.
_GRAVITY_INCREMENTS = 4
_REFERENCE_GRAVITY_INCREMENTS = 80
#: The reference script's solver settings (theory 6.4, 10.6: tol 5e-7 N, iterMax 30, its loop),
#: for comparisons with its outputs; its equilibria are under-converged.
REFERENCE_NEWTON = NewtonOptions(atol=5e-7, max_iter=30, reference_loop=True)


def check_fold(name: str, value) -> float:
    """Check a fold angle given in rad: a finite number in (-pi, pi] (-180 to 180 deg)."""
    if not (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value) and -math.pi < value <= math.pi):
        deg = f" ({math.degrees(value):g} deg)" if isinstance(value, (int, float)) else ""
        raise ParameterError(f"{name} = {value!r} rad{deg} must be a fold angle in radians in "
                             "(-pi, pi], i.e. (-180, 180] deg; convert degrees with "
                             "math.radians.")
    return float(value)


@dataclass(frozen=True)
class GripperDesign:
    """Gripper geometry, actuator layers and fabrication (SI units).

    How the heat balance is modelled (the loss model, conduction, refinement, radiation) is
    the evaluation's choice, :class:`~design.devices.gripper_heat.GripperHeatModel`, given to
    :func:`make_gripper_model`, :func:`evaluate_gripper` or
    :class:`~design.devices.gripper_problem.GripperProblem` as ``heat``.

    Parameters
    ----------
    W : crease width [m] (paper bounds 100-300 um, start 200 um)
    L1 : base panel width [m] (500-1500 um, start 1000 um)
    L2 : base panel length [m] (500-1500 um, start 1000 um)
    La : arm length [m] (500-1500 um, start 700 um)
    t_gold, t_su8 : actuator layer thicknesses [m] (0.2 and 0.8 um)
    grip_range : width of the central panel [m] (fixed 1000 um)
    undercut : gap to the substrate [m] (150 um)
    panel_thickness : SPR panel thickness [m] (5 um)
    residual_fold : residual fold of the four actuated creases after fabrication [rad]
    residual_fold_base, residual_fold_arm : optional residual folds of the base hinges and of
        the arm hinges [rad] that override ``residual_fold`` for that crease group
    residual_fold_creases : ((crease id, rad), ...) residual folds of single actuated creases
        that override the group values (default none)
    delta_alpha : bimorph expansion mismatch alpha_SU8 - alpha_Au [1/K] (38e-6, the paper's)
    env_conductivity : thermal conductivity of the surrounding air [W/(m K)] (0.026; with
        ``GripperHeatModel(temperature_dependent_air=True)`` Incropera's table instead)
    loss_model, integral_refinement, conduction, sheet_refinement, crease_conduction, k_gold,
        temperature_dependent_air, emissivity_polymer, emissivity_gold : deprecated (they go in
        the next release): the fields of :class:`~design.devices.gripper_heat.GripperHeatModel`;
        given here (not None) they warn and are that heat model's values wherever this design
        is evaluated
    lead_fraction : resistance of each heater circuit's leads and traces as a fraction of its
        heaters' resistance at room temperature [-] (default 0); the electrical drive only
        (:func:`~design.devices.gripper_drive.gripper_drive`, theory 8.8), not the heat balance
    heater_tcr : temperature coefficient of resistance of the gold heaters [1/K], or None
        (default: :class:`~simulator.Heater`'s, 0.0034, the upper end for a thin film); the
        electrical drive only, like ``lead_fraction``
    crease_widths : ((crease id, m), ...) widths of single actuated creases that override
        ``W`` for that crease (default none): its strip in the mesh, its hinge stiffness and
        its bimorph's rotation, and the reference's node edits beside it (theory 10.6)
    """

    W: float = 200e-6
    L1: float = 1000e-6
    L2: float = 1000e-6
    La: float = 700e-6
    t_gold: float = 0.2e-6
    t_su8: float = 0.8e-6
    grip_range: float = 1000e-6
    undercut: float = 150e-6
    panel_thickness: float = 5e-6
    residual_fold: float = 0.0
    residual_fold_base: float | None = None
    residual_fold_arm: float | None = None
    residual_fold_creases: tuple = ()
    delta_alpha: float = 38e-6
    env_conductivity: float = 0.026
    loss_model: str | None = None
    integral_refinement: int | None = None
    conduction: str | None = None
    sheet_refinement: int | None = None
    crease_conduction: str | None = None
    k_gold: float | None = None
    temperature_dependent_air: bool | None = None
    emissivity_polymer: float | None = None
    emissivity_gold: float | None = None
    lead_fraction: float = 0.0
    heater_tcr: float | None = None
    crease_widths: tuple = ()

    def __post_init__(self):
        folds = tuple((int(c), check_fold(f"GripperDesign.residual_fold_creases[{c!r}]", v))
                      for c, v in dict(self.residual_fold_creases).items())
        if set(dict(folds)) - set(BASE_CREASES + ARM_CREASES):
            raise ParameterError(f"GripperDesign.residual_fold_creases = {folds!r}: crease ids "
                                 f"must be actuated creases {BASE_CREASES + ARM_CREASES}.")
        object.__setattr__(self, "residual_fold_creases", tuple(sorted(folds)))
        legacy = self.legacy_heat()
        if legacy:
            warn_deprecated(
                f"GripperDesign({', '.join(f'{k}={v!r}' for k, v in legacy.items())}) is "
                "deprecated (it goes in the next release): the heat model is the evaluation's "
                "choice; give heat=GripperHeatModel(...) with these fields to "
                "make_gripper_model, evaluate_gripper or GripperProblem (from design.devices "
                "import GripperHeatModel).")
            GripperHeatModel(**legacy)                       # checks them
        non_negative("GripperDesign.lead_fraction", self.lead_fraction, "",
                     "0 without leads, e.g. 0.1 for leads of a tenth of the heaters' resistance")
        finite("GripperDesign.heater_tcr", self.heater_tcr, "1/K",
               "0.0011-0.0034 for a thin gold film, or None for 0.0034", allow_none=True)
        self._check_crease_widths()
        for name, value in asdict(self).items():
            if name in ("residual_fold_creases", "lead_fraction", "heater_tcr",
                        "crease_widths") or name in HEAT_FIELDS:
                continue
            if name.startswith("residual_fold"):
                if value is not None:
                    check_fold(f"GripperDesign.{name}", value)
            else:
                positive(f"GripperDesign.{name}", value, "m")
        if max(self.widths().values()) >= min(self.L1, self.L2, self.La):
            raise ParameterError(f"GripperDesign: crease widths {self.widths()} m must be "
                                 "smaller than the panels they join (L1, L2, La).")

    def _check_crease_widths(self) -> None:
        try:
            widths = {int(c): float(w) for c, w in dict(self.crease_widths).items()}
        except (TypeError, ValueError):
            raise ParameterError(f"GripperDesign.crease_widths = {self.crease_widths!r}: give "
                                 "((crease id, width [m]), ...).") from None
        if set(widths) - set(BASE_CREASES + ARM_CREASES):
            raise ParameterError(f"GripperDesign.crease_widths = {self.crease_widths!r}: crease "
                                 f"ids must be actuated creases {BASE_CREASES + ARM_CREASES}.")
        for c, w in widths.items():
            positive(f"GripperDesign.crease_widths[{c}]", w, "m")
        object.__setattr__(self, "crease_widths", tuple(sorted(widths.items())))

    def widths(self) -> dict:
        """Width [m] of each actuated crease id: ``W`` unless ``crease_widths`` gives it."""
        return {c: self.W for c in BASE_CREASES + ARM_CREASES} | dict(self.crease_widths)

    def legacy_heat(self) -> dict:
        """The deprecated heat-model fields given to this design (those not None)."""
        return {k: getattr(self, k) for k in HEAT_FIELDS if getattr(self, k) is not None}

    def to_dict(self) -> dict:
        """The design's fields; the later optional ones (``residual_fold_creases``,
        ``delta_alpha``, ``env_conductivity``, ``lead_fraction``, ``heater_tcr``) only when
        they differ from the values they had before they existed. The heat model is not the
        design's: :func:`gripper_settings` gives both in one dict."""
        out = {k: v for k, v in asdict(self).items() if k not in HEAT_FIELDS}
        for name in _OPTIONAL:
            if name in out and out[name] == _OPTIONAL[name]:
                del out[name]
        return out

    @property
    def sheet_refinement_in_force(self) -> int:
        """Deprecated: :attr:`GripperHeatModel.sheet_refinement_in_force
        <design.devices.gripper_heat.GripperHeatModel.sheet_refinement_in_force>`."""
        warn_deprecated("GripperDesign.sheet_refinement_in_force is deprecated (it goes in the "
                        "next release): use GripperHeatModel.sheet_refinement_in_force.")
        return split_heat(self)[1].sheet_refinement_in_force

    @property
    def integral_levels_in_force(self) -> str:
        """Deprecated: :attr:`GripperHeatModel.integral_levels_in_force
        <design.devices.gripper_heat.GripperHeatModel.integral_levels_in_force>`."""
        warn_deprecated("GripperDesign.integral_levels_in_force is deprecated (it goes in the "
                        "next release): use GripperHeatModel.integral_levels_in_force.")
        return split_heat(self)[1].integral_levels_in_force

    def crease_residual_folds(self) -> dict:
        """Residual fold [rad] of each actuated crease id."""
        base = self.residual_fold if self.residual_fold_base is None else self.residual_fold_base
        arm = self.residual_fold if self.residual_fold_arm is None else self.residual_fold_arm
        return {**{c: base for c in BASE_CREASES}, **{c: arm for c in ARM_CREASES},
                **dict(self.residual_fold_creases)}


def split_heat(design: GripperDesign, heat: GripperHeatModel | None = None) -> tuple:
    """``(design, heat)``: the design without the deprecated heat-model fields, and ``heat``
    (default ``GripperHeatModel()``) with the values of those given to the design (they
    win, as they did), checked together (the air's law against the design's constant)."""
    heat = GripperHeatModel() if heat is None else heat
    if not isinstance(design, GripperDesign):
        raise ParameterError(f"design = {design!r} must be a GripperDesign (the heat model goes "
                             "to heat=...).")
    if not isinstance(heat, GripperHeatModel):
        raise ParameterError(f"heat = {heat!r} must be a GripperHeatModel (from design.devices "
                             "import GripperHeatModel).")
    legacy = design.legacy_heat()
    if legacy:
        heat = replace(heat, **legacy)
        design = replace(design, **dict.fromkeys(legacy))
    if heat.temperature_dependent_air and design.env_conductivity != _OPTIONAL[
            "env_conductivity"]:
        raise ParameterError(
            f"GripperDesign.env_conductivity = {design.env_conductivity!r} W/(m K) with "
            "GripperHeatModel.temperature_dependent_air=True: the air then follows "
            "Incropera's table whatever the constant is (theory 4.12); leave "
            "env_conductivity at 0.026 or set temperature_dependent_air=False.")
    return design, heat


def gripper_settings(design: GripperDesign, heat: GripperHeatModel | None = None) -> dict:
    """The design and its heat model in one dict, as :meth:`GripperDesign.to_dict` gave them
    while the heat model was the design's (problem settings, evaluation-log keys, result
    tables): the optional fields only when they differ from the values they had before they
    existed (``loss_model`` only when not "chain", the default until 7 Dec 2026; the physics
    switches ``crease_conduction`` to ``heater_tcr`` only away from their defaults,
    ``sheet_extrapolation`` only when on); with the
    integral model always ``integral_refinement``, the conduction, the sheet refinement and the
    loss levels in force (their defaults changed, so an older log of the integral model never
    matches)."""
    design, heat = split_heat(design, heat)
    out = asdict(design)
    out.update({k: getattr(heat, k) for k in HEAT_FIELDS})       # in their former places
    for name in _OPTIONAL:
        if out[name] == _OPTIONAL[name]:
            del out[name]
    if heat.loss_model != "chain":   # the integral model's default m changed (2 -> 3,
        out["integral_refinement"] = heat.integral_refinement   # 6 Dec 2026): always named
        out["conduction"] = heat.conduction or "monotone"       # and its conduction, 7 Dec
        out["sheet_refinement"] = heat.sheet_refinement_in_force  # and the sheet's, 8 Dec
        out["integral_levels"] = heat.integral_levels_in_force    # and its levels, 8 Dec
    if heat.sheet_extrapolation:                  # named only when on (theory 4.13)
        out["sheet_extrapolation"] = heat.sheet_extrapolation
    return out


#: Status words of a stage: met (success), criterion not met below the power cap, a
#: simulation failed, not attempted (assembly not met).
STAGE_STATUSES = ("met", "not_met", "failed", "not_attempted")


@dataclass(frozen=True)
class StageResult(ResultFiles):
    """Outcome of one stage's power search.

    Attributes
    ----------
    success : bool
        The criterion holds at ``power_per_crease``.
    status : str
        ``"met"``, ``"not_met"`` (not below the power cap), ``"failed"`` (a simulation or the
        pre-loading failed) or ``"not_attempted"`` (grip: assembly not met).
    message : str
        Why not met; if met, ``"criterion met"``, followed by ``" after a snap (...)"`` (snap
        power per crease and jump) when a snap lay on the way to the stopping power.
    power_per_crease : float or None
        Smallest power per heated crease [W] found to meet the criterion; None if not met.
    measure : float
        Criterion measure at that power (fold [rad] or tip distance [m]); at the last trial
        if not met.
    temperature : float
        max of the centre-line mean temperatures of the stage's heated creases [deg C]
        (the measure of the 1.2 T_g limit, theory 5.4, on the reference's creases: those the
        stage heats, at its stopping power; theory 10.6).
    max_crease_temperature : float
        Hottest crease node of the whole gripper [deg C] (information beside ``temperature``).
    simulations : int
        Heating solves (calls) used by the search.
    increments : int
        Thermal increments solved in total.
    snaps : tuple of Event
        The ``"snap"`` events (:class:`~simulator.events.Event`) on the way to the stopping
        power of a met stage (the ``" after a snap (...)"`` of the message); empty if none.
    temperature_crease, hottest_node_crease : int or None
        Crease ids of ``temperature`` and of ``max_crease_temperature``.
    crease_temperatures : tuple of float
        Actuation temperature of every crease [deg C] (the 7-node measure that drives the
        bimorph and sets a heater's resistance, theory 5.1 and 8.8), in crease-row order, at
        the stage's last state (its stopping power if met); empty if not computed.
    """

    success: bool
    status: str
    message: str
    power_per_crease: float | None
    measure: float
    temperature: float
    max_crease_temperature: float
    simulations: int
    increments: int
    snaps: tuple = ()
    temperature_crease: int | None = None
    hottest_node_crease: int | None = None
    crease_temperatures: tuple = ()

    def __post_init__(self):
        check_outcome(self, ("met",), STAGE_STATUSES[1:])
        if (self.power_per_crease is None) == self.success:
            raise ParameterError(f"StageResult.power_per_crease = {self.power_per_crease!r} "
                                 f"with success = {self.success}: a met stage has a power, "
                                 "an unmet one None.")

    _csv_name = "stage.csv"

    def _row(self) -> dict:
        return {"success": self.success, "status": self.status, "message": self.message,
                "power_per_crease [mW]": power_if(self.success, self.power_per_crease, 1e3),
                "measure": self.measure, "temperature [degC]": self.temperature,
                "temperature_crease": self.temperature_crease,
                "max_crease_temperature [degC]": self.max_crease_temperature,
                "hottest_node_crease": self.hottest_node_crease,
                "simulations": self.simulations, "increments": self.increments}


@dataclass(frozen=True)
class GripperResult(ResultFiles):
    """Both stages; powers per heated crease as in the paper.

    ``success``: both stages met; ``status``: ``"met"``, or the status of the first stage
    that was not met; ``total_power``: assembly + grip power per crease [W], None unless
    both were met; ``message``: ``"both stages met"`` (followed by the stage messages of a
    stage met after a snap, i.e. with :attr:`StageResult.snaps`), or why the first unmet stage
    was not met; ``heat``: the heat model it was evaluated with
    (:class:`~design.devices.gripper_heat.GripperHeatModel`; :meth:`to_dict` names both, as
    :func:`gripper_settings` does).
    """

    design: GripperDesign
    mode: str
    assembly: StageResult
    grip: StageResult
    heat: GripperHeatModel = GripperHeatModel()

    @property
    def success(self) -> bool:
        return self.assembly.success and self.grip.success

    @property
    def status(self) -> str:
        return self.grip.status if self.assembly.success else self.assembly.status

    @property
    def total_power(self) -> float | None:
        """Objective of the paper: assembly + grip power per crease [W] (None if not met)."""
        if not self.success:
            return None
        return self.assembly.power_per_crease + self.grip.power_per_crease

    @property
    def max_temperature(self) -> float:
        """Largest stopping temperature of the two stages [deg C] (centre-line mean of the
        stage's heated creases: the measure of the 1.2 T_g limit)."""
        return max(self.assembly.temperature, self.grip.temperature)

    def temperature_verdict(self, limit: TemperatureLimit = SU8_LIMIT) -> TemperatureVerdict:
        """The verdict on ``limit`` (default 1.2 T_g of SU-8 on the crease centre-line mean):
        the stage whose stopping temperature on the limit's measure is the larger counts
        (:attr:`StageResult.temperature`, or with ``"crease_max"`` its
        ``max_crease_temperature``); the hottest node of the gripper is information."""
        centre = max(self.assembly, self.grip, key=lambda s: s.temperature)
        node = max(self.assembly, self.grip, key=lambda s: s.max_crease_temperature)
        return TemperatureVerdict.of(limit, (centre.temperature, centre.temperature_crease),
                                     (node.max_crease_temperature, node.hottest_node_crease))

    @property
    def message(self) -> str:
        if self.success:
            snapped = [f"{name}: {stage.message}" for name, stage in
                       (("assembly", self.assembly), ("grip", self.grip)) if stage.snaps]
            return "; ".join(["both stages met"] + snapped)
        bad = self.assembly if not self.assembly.success else self.grip
        return ("assembly: " if bad is self.assembly else "grip: ") + bad.message

    _csv_name = "gripper.csv"

    def to_dict(self) -> dict:
        """Flat summary, keys ``name [unit]`` (the CLI's JSON); powers of stages whose
        criterion was not met are None (never a silent zero)."""
        return {
            "assembly_power [mW]": power_if(self.assembly.success,
                                            self.assembly.power_per_crease, 1e3),
            "grip_power [mW]": power_if(self.grip.success, self.grip.power_per_crease, 1e3),
            "total_power [mW]": power_if(self.success, self.total_power, 1e3),
            "assembly_temperature [degC]": self.assembly.temperature,
            "grip_temperature [degC]": self.grip.temperature,
            "max_crease_temperature [degC]": max(self.assembly.max_crease_temperature,
                                                 self.grip.max_crease_temperature),
            "assembly_simulations": self.assembly.simulations,
            "grip_simulations": self.grip.simulations,
            "success": self.success, "status": self.status, "message": self.message,
            "mode": self.mode,
            **{f"{k} [{_UNITS.get(k, 'rad' if k.startswith('residual_fold') else 'm')}]": v
               for k, v in gripper_settings(self.design, self.heat).items()},
        }


_UNITS = {"delta_alpha": "1/K", "env_conductivity": "W/(m K)", "loss_model": "-",
          "integral_refinement": "-", "conduction": "-", "sheet_refinement": "-",
          "integral_levels": "-",
          "crease_conduction": "-", "k_gold": "W/(m K)", "temperature_dependent_air": "-",
          "emissivity_polymer": "-", "emissivity_gold": "-", "lead_fraction": "-",
          "heater_tcr": "1/K", "sheet_extrapolation": "-"}
#: The heat-transfer and electrical switches of issue 30 and their defaults (the paper
#: setting), left out of ``GripperDesign.to_dict`` at these values.
_PHYSICS = {"crease_conduction": "paper", "k_gold": None, "temperature_dependent_air": False,
            "emissivity_polymer": 0.0, "emissivity_gold": 0.0, "lead_fraction": 0.0,
            "heater_tcr": None}
#: The optional fields' values before they existed (left out of ``GripperDesign.to_dict``);
#: ``loss_model`` "chain" was the default until 7 Dec 2026.
_OPTIONAL = {"residual_fold_creases": (), "delta_alpha": 38e-6, "env_conductivity": 0.026,
             "loss_model": "chain", "integral_refinement": 3, "conduction": None,
             "sheet_refinement": None, "crease_widths": (), **_PHYSICS}


def _node_edits(design: GripperDesign, nodes: np.ndarray) -> np.ndarray:
    """The reference's post-meshing node moves (theory 10.6), 0-based node ids, each by the
    width of the crease it belongs to (all ``W`` in the reference): the arms' inner edges to
    the base creases' strips (2 left, 5 right), the central panel's top corners to the arm
    creases' (3 left, 9 right), and the centre-line ends and panel centres beside them by
    their share."""
    w = design.widths()
    w2, w3, w5, w9 = w[2], w[3], w[5], w[9]
    x = nodes.copy()
    moves = {(13, 14): (-w2 / 2, 0), (19, 16): (w5 / 2, 0), (7,): (0, -w3 / 2),
             (6,): (0, -w9 / 2), (25,): (0, -w3 / 4), (31,): (0, -w9 / 4),
             (37,): (0, -(w3 + w9) / 8), (27,): (-w2 / 4, 0), (34,): (w5 / 4, 0),
             (39,): (-w2 / 8, 0), (40,): (w5 / 8, 0)}
    for ids, (dx, dy) in moves.items():
        x[list(ids), 0] += dx
        x[list(ids), 1] += dy
    return x


def self_weight(design: GripperDesign, n_nodes: int) -> np.ndarray:
    """The reference's hand-lumped self-weight [N] (theory 10.6): 1/6 per corner, 2/6 per centre."""
    rho, t = SPR.density, design.panel_thickness
    base = design.L1 * design.L2 * t * rho * REFERENCE_GRAVITY / 6
    arm = 0.75 * design.L1 * design.La * t * rho * REFERENCE_GRAVITY / 6
    f = np.zeros((n_nodes, 3))
    f[[0, 1, 2, 3, 8, 9, 10, 11], 2] = -base
    f[[36, 38], 2] = -2 * base
    f[12:20, 2] = -arm
    f[[39, 40], 2] = -2 * arm
    return f


def gripper_design_pattern(design: GripperDesign, heat: GripperHeatModel | None = None):
    """The design's pattern (before the node edits): SPR panels, the creases of the panel
    material, both radiating at the heat model's emissivities (a crease the mean of its
    polymer and gold faces', theory 4.12; no radiation at the defaults)."""
    design, heat = split_heat(design, heat)
    panel = SPR
    if heat.emissivity_polymer:
        panel = replace(SPR, emissivity=heat.emissivity_polymer)
    pattern = example_patterns.gripper_pattern(w=design.W, la=design.La, l1=design.L1, l2=design.L2,
                              crease_thickness=design.t_gold + design.t_su8,
                              grip_range=design.grip_range, undercut=design.undercut,
                              panel_thickness=design.panel_thickness, panel_material=panel)
    if design.crease_widths:
        pattern = replace(pattern, crease_width=design.widths())
    crease = (heat.emissivity_polymer + heat.emissivity_gold) / 2
    if crease != pattern.crease_material.emissivity:
        pattern = replace(pattern, crease_material=replace(pattern.crease_material,
                                                           emissivity=crease))
    return pattern


def _medium(design: GripperDesign, heat: GripperHeatModel):
    """The air: Incropera's k(T) (theory 4.12) or the design's constant ``env_conductivity``."""
    if heat.temperature_dependent_air:
        return AIR.with_temperature_dependence()
    return AIR.with_properties(thermal_conductivity=design.env_conductivity)


def make_gripper_model(design: GripperDesign, gravity_increments: int = _GRAVITY_INCREMENTS,
                       heat: GripperHeatModel | None = None):
    """The gripper model and the loading steps before heating (residual fold, gravity).

    ``heat``: how the heat balance is modelled (default ``GripperHeatModel()``: the
    integral loss)."""
    design, heat = split_heat(design, heat)
    mesh = make_mesh(gripper_design_pattern(design, heat))
    mesh = mesh.with_nodes(_node_edits(design, mesh.nodes))
    supports = Supports.nodes([4, 5, 6, 7, 37, 20, 21, 22, 23, 41])
    thermal = ThermalParameters(
        medium=_medium(design, heat), boundary_panels=(5,), room_temperature_nodes=(37,),
        conduction=heat.conduction, crease_conduction=heat.crease_conduction,
        sheet_refinement=heat.sheet_refinement, sheet_extrapolation=heat.sheet_extrapolation,
        **heat.loss_parameters(design))
    gold = {} if heat.k_gold is None else {"k1": heat.k_gold}
    actuators = Actuators(Bimorph(E1=0.5 * 79e9, t1=design.t_gold, E2=2e9, t2=design.t_su8,
                                  **gold),
                          {c: design.delta_alpha for c in BASE_CREASES + ARM_CREASES})
    model = make_model(mesh, supports, BarHingeParameters(diagonal_rate=100),
                       contact=ContactParameters(1e-4, 40e-6, 40e-6), thermal=thermal,
                       actuators=actuators)
    pre = []
    folds = design.crease_residual_folds()
    if any(v != 0 for v in folds.values()):
        pre.append(SelfFold(folds, increments=40, name="residual_fold"))
    pre.append(Load(self_weight(design, mesh.n_nodes), increments=gravity_increments,
                    name="gravity"))
    return model, pre


def _base_fold(x) -> float:
    """Reference measure: sign(z_1 - z_6) * angle(x_2 - x_1, x_6 - x_5) (1-based nodes)."""
    a, b = x[1] - x[0], x[5] - x[4]
    ang = math.acos(float(np.clip(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)), -1, 1)))
    return float(np.sign(x[0, 2] - x[5, 2])) * ang


def _tip_distance(x) -> float:
    """Distance between the outer arm tips (reference nodes 16 and 19)."""
    return float(np.linalg.norm(x[15] - x[18]))


#: The stages' criteria: the base fold (:func:`_base_fold`) past ASSEMBLY_FOLD [rad], then the
#: arm tips (:func:`_tip_distance`) closer than GRIP_DISTANCE [m].
ASSEMBLY_FOLD = math.pi / 2
GRIP_DISTANCE = 100e-6
_STAGES = {
    "assembly": (BASE_CREASES, _base_fold, lambda v: v > ASSEMBLY_FOLD),
    "grip": (ARM_CREASES, _tip_distance, lambda v: v < GRIP_DISTANCE),
}


class _Stage(HeatingStage):
    """Run one stage's heating trials from saved states (snaps followed by arc length)."""

    def __init__(self, model, name, callback=None, options=NewtonOptions()):
        self.creases, self.measure_fn, self.met_fn = _STAGES[name]
        super().__init__(model, self.creases, options)
        self.name, self.callback = name, callback

    def heat(self, state, dp, increments=1, coupling="staggered", follow_snaps=True):
        """Add ``dp`` per crease in ``increments`` increments; returns (state, ok, message)."""
        state, ok, msg = super().heat(state, dp, increments, coupling, follow_snaps)
        if self.callback is not None and ok:
            value, met, temp, tmax = self.look(state)
            self.callback({"stage": self.name, "power_per_crease [W]": float(
                state.crease_power[self.model.mesh.crease_row[self.creases[0]]]),
                "measure": value, "met": met, "temperature [degC]": temp,
                "max_crease_temperature [degC]": tmax})
        return state, ok, msg

    def temperatures(self, state) -> tuple:
        """``(heated, gripper)``: :class:`~simulator.thermal.TemperatureVerdict` of the stage's
        heated creases (their centre-line mean: the limit's measure) and of all creases (the
        gripper's hottest node)."""
        mesh, t = self.model.mesh, state.temperature
        return SU8_LIMIT.judge(t, mesh, self.creases), SU8_LIMIT.judge(t, mesh)

    def met(self, state) -> bool:
        """The stage's criterion alone (the searches' question after every trial; the
        temperatures are judged where they are reported: :meth:`look`, :meth:`result`)."""
        return bool(self.met_fn(self.measure_fn(self.model.mesh.nodes + state.u)))

    def look(self, state):
        value = self.measure_fn(self.model.mesh.nodes + state.u)
        heated, gripper = self.temperatures(state)
        return value, self.met_fn(value), heated.temperature, gripper.hottest_node

    def result(self, status, power, state, message):
        value = self.measure_fn(self.model.mesh.nodes + state.u)
        heated, gripper = self.temperatures(state)
        met = status == "met"
        if met:
            message = self.after_snaps(message, state)
        return StageResult(met, status, message, power if met else None, value,
                           heated.temperature, gripper.hottest_node, self.simulations,
                           self.increments, self.snap_events(state) if met else (),
                           heated.crease, gripper.hottest_node_crease,
                           tuple(float(t) for t in crease_temperatures(state.temperature,
                                                                       self.model.mesh)))


def evaluate_gripper(design: GripperDesign = GripperDesign(), mode: str = "bisect",
                     step: float = 0.1e-3, tol: float = 0.01e-3, power_cap: float = 40e-3,
                     max_step: float = 0.4e-3, callback=None,
                     options: NewtonOptions = NewtonOptions(),
                     heat: GripperHeatModel | None = None) -> GripperResult:
    """Power per heated crease needed to assemble, then grip (theory 10.6).

    Parameters
    ----------
    design : GripperDesign
    mode : {"bisect", "staircase"}
    step : float
        Staircase step, and first step of the bisect growth [W per crease].
    tol : float
        Bisection tolerance [W per crease].
    power_cap : float
        Give up (status ``"not_met"``) above this power per crease [W] (the reference:
        400 x 0.1 mW).
    callback : callable, optional
        Called after every heating simulation with a dict (stage, power per crease [W],
        measure, met, temperature [deg C], max crease temperature [deg C]).
    max_step : float
        Largest growth step of the bisect mode [W per crease]; larger jumps cost more Newton
        iterations than they save (contact limits the step per iteration).
    options : NewtonOptions
        Equilibrium solver settings; :data:`REFERENCE_NEWTON` emulates the reference's loose
        loop (for comparisons with its outputs only).
    heat : GripperHeatModel, optional
        How the heat balance is modelled (default ``GripperHeatModel()``: the integral
        loss); the result records it (:attr:`GripperResult.heat`).
    """
    one_of("mode", mode, ("bisect", "staircase"))
    design, heat = split_heat(design, heat)
    for name, v in (("step", step), ("tol", tol), ("power_cap", power_cap), ("max_step", max_step)):
        positive(name, v, "W")
    model, pre = make_gripper_model(design, _REFERENCE_GRAVITY_INCREMENTS
                                    if options.reference_loop else _GRAVITY_INCREMENTS, heat)
    start = simulate(model, pre, options=options)
    results = {}
    state = start.state
    for name in ("assembly", "grip"):
        stage = _Stage(model, name, callback, options)
        if not start.success:
            results[name] = stage.result("failed", None, state,
                                         f"pre-loading failed: {start.message}")
            continue
        if name == "grip" and not results["assembly"].success:
            results[name] = stage.result("not_attempted", None, state,
                                         "not attempted: assembly not met")
            continue
        if mode == "staircase":
            results[name], state = staircase_search(stage, state, step, power_cap)
        else:
            results[name], state = bisect_search(stage, state, step, tol, power_cap, max_step)
        logger.info("gripper %s: %s", name, results[name])
    return GripperResult(design, mode, results["assembly"], results["grip"], heat)
