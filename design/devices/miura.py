"""Miura-ori lifter design problem (paper section 6.2, the ``miura_lifter`` case).

A Miura sheet clamped along its first column of panels; all creases are heated with the same
power and the free end (largest x) lifts. *Lift*: mean z displacement of the sheet's corner
nodes at the largest x. :func:`lift_power` finds the power per crease for a target lift with
the gripper's searches (:mod:`design.devices.gripper`); :class:`MiuraProblem` minimises its total power.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from simulator import (IntegralLoss, Model, ParameterError, PatternError, make_mesh,
                       example_patterns, simulate)
from simulator.cases import miura_fold_signs, miura_sheet_model
from simulator.thermal import TG_FACTOR, TemperatureLimit, TemperatureVerdict
from simulator._result import ResultFiles
from simulator._validate import in_range, integer, one_of, positive

from ..core.contract import check_outcome, power_if
from .power_search import HeatingStage, bisect_search, staircase_search
from ..core.problem import DesignProblem, EvaluationOutcome
from .limits import SU8_LIMIT, SU8_TG, TemperatureLimited
from ..core.space import DesignSpace, Variable

__all__ = ["MIURA_SPACE", "LiftPowerResult", "MiuraDesign", "MiuraProblem", "heated_creases",
           "lift_per_power_table", "lift_power", "make_miura_model", "design_columns"]

_DEG = math.pi / 180


@dataclass(frozen=True)
class MiuraDesign:
    """Miura lifter geometry and layers (SI units); defaults: the ``miura_lifter`` case with
    4 x 2 cells over a substrate.

    Parameters
    ----------
    a, b : panel sides [m] (``a`` along y, ``b`` the zig-zag side), 1 mm
    gamma : sector angle [rad], in (0, pi/2); 60 deg
    cells_x, cells_y : cells along x (>= 2: the first column is clamped) and y (>= 1)
    W : crease width [m], 200 um; the flat sheet must mesh without collapsed creases
        (e.g. W < 207 um for a = b = 0.5 mm, gamma = 45 deg)
    t_gold, t_su8 : actuator layers [m] (0.2 and 0.8 um); the crease is ``t_gold + t_su8`` thick
    panel_thickness : SU-8 panel thickness [m], 10 um
    substrate : bool
        Sheet over a substrate (a thermal boundary and a contact surface), True.
    undercut : gap between the sheet and the substrate [m], 100 um
    loss_model : heat loss to the air, ``"integral"`` (default since 7 Dec 2026, theory 4.7:
        nothing fitted, over the substrate's plane) or ``"chain"`` (the ``miura_lifter``
        case's chains, the paper setting)
    """

    a: float = 1e-3
    b: float = 1e-3
    gamma: float = 60 * _DEG
    cells_x: int = 4
    cells_y: int = 2
    W: float = 200e-6
    t_gold: float = 0.2e-6
    t_su8: float = 0.8e-6
    panel_thickness: float = 10e-6
    substrate: bool = True
    undercut: float = 100e-6
    loss_model: str = "integral"

    def __post_init__(self):
        for name in ("a", "b", "W", "t_gold", "t_su8", "panel_thickness", "undercut"):
            positive(f"MiuraDesign.{name}", getattr(self, name), "m")
        in_range("MiuraDesign.gamma", self.gamma, 0, math.pi / 2, "rad", hint="(0, pi/2), i.e. "
                 "0 to 90 deg; convert degrees with math.radians", open_low=True, open_high=True)
        integer("MiuraDesign.cells_x", self.cells_x, 2)
        integer("MiuraDesign.cells_y", self.cells_y, 1)
        one_of("MiuraDesign.loss_model", self.loss_model, ("integral", "chain"))
        if not isinstance(self.substrate, (bool, np.bool_)):
            raise ParameterError(f"MiuraDesign.substrate = {self.substrate!r} must be a bool.")
        if not _meshable(self, self.W):
            lo, hi = 0.0, min(self.a, self.b)                 # largest W that meshes
            for _ in range(30):
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if _meshable(self, mid) else (lo, mid)
            raise ParameterError(
                f"MiuraDesign.W = {self.W * 1e6:g} um collapses a crease or panel of the mesh for "
                f"a = {self.a * 1e6:g} um, b = {self.b * 1e6:g} um, gamma = {self.gamma / _DEG:g} "
                f"deg; allowed: W < {lo * 1e6:.4g} um.")

    def to_dict(self) -> dict:
        """The fields; ``loss_model`` only when not "chain" (the heat loss before the field
        existed), so that the logs of chain designs keep their hashes."""
        out = asdict(self)
        if out["loss_model"] == "chain":
            del out["loss_model"]
        return out


def _meshable(d: MiuraDesign, W: float) -> bool:
    """The flat sheet meshes with crease width ``W`` without collapsed creases or panels."""
    try:
        mesh = make_mesh(example_patterns.miura_sheet_pattern(d.a, d.b, d.gamma, d.cells_x, d.cells_y, W=W))
    except PatternError:
        return False
    cn, x = mesh.crease_nodes, mesh.nodes
    return bool(np.linalg.norm(x[cn[:, 4]] - x[cn[:, 5]], axis=1).min() > 1e-3 * min(d.a, d.b))


def heated_creases(design: MiuraDesign) -> dict:
    """{crease id: fold sign} of the sheet: every crease is heated (as in the case)."""
    return miura_fold_signs(design.a, design.b, design.gamma, design.cells_x, design.cells_y)


def design_columns(values) -> dict:
    """``a [um]``, ``b [um]``, ``gamma [deg]``, ``W [um]`` of a :class:`MiuraDesign` or of a
    mapping with these keys (SI)."""
    v = values if isinstance(values, Mapping) else asdict(values)
    return {"a [um]": 1e6 * v["a"], "b [um]": 1e6 * v["b"], "gamma [deg]": v["gamma"] / _DEG,
            "W [um]": 1e6 * v["W"]}


def make_miura_model(design: MiuraDesign = MiuraDesign()) -> Model:
    """The ``miura_lifter`` case's model for ``design`` (one builder for both:
    :func:`simulator.cases.miura_sheet_model`), with the design's heat loss (the integral one
    over the substrate's plane, or the case's chains)."""
    d = design
    model = miura_sheet_model(d.a, d.b, d.gamma, d.cells_x, d.cells_y, d.W, t_gold=d.t_gold,
                              t_su8=d.t_su8, panel_thickness=d.panel_thickness,
                              substrate=d.substrate, undercut=d.undercut)
    if d.loss_model == "chain":
        return model
    return replace(model, thermal=replace(model.thermal, loss=IntegralLoss()))


def _lift_nodes(model: Model, design: MiuraDesign) -> np.ndarray:
    """Corner nodes of the sheet at its largest x (the free end)."""
    mesh = model.mesh
    sheet = (mesh.node_vertex >= 0) & (mesh.node_panel >= 0) & \
        (mesh.node_panel < design.cells_x * design.cells_y)
    return np.flatnonzero(sheet & np.isclose(mesh.nodes[:, 0], mesh.nodes[sheet, 0].max()))


@dataclass(frozen=True)
class LiftPowerResult(ResultFiles):
    """Outcome of :func:`lift_power`.

    Attributes
    ----------
    success : bool (the target lift is reached at ``power_per_crease``)
    status : ``"met"``, ``"not_met"`` (not below the power cap) or ``"failed"`` (a heating
        simulation failed)
    message : str (why not met: power cap or simulation failure)
    power_per_crease : smallest power per heated crease found to reach it [W] (None if not)
    total_power : ``power_per_crease`` x ``n_creases`` [W] (None if not met)
    lift : lift of the free end there (at the last trial if not met) [m]
    max_crease_temperature : hottest crease node there [deg C]
    simulations : heating solves used by the search
    n_creases : heated creases
    snaps : ``"snap"`` events (:class:`~simulator.events.Event`) on the way to the power found
        (the ``" after a snap (...)"`` of the message); empty if none or not met
    temperature : centre-line mean of the hottest crease there [deg C] (the measure of the
        1.2 T_g limit; theory 5.4)
    temperature_crease, hottest_node_crease : crease ids of ``temperature`` and of
        ``max_crease_temperature`` (None if unknown)
    """

    success: bool
    status: str
    message: str
    power_per_crease: float | None
    total_power: float | None
    lift: float
    max_crease_temperature: float
    simulations: int
    n_creases: int
    snaps: tuple = ()
    temperature: float = math.nan
    temperature_crease: int | None = None
    hottest_node_crease: int | None = None

    def __post_init__(self):
        check_outcome(self, ("met",), ("not_met", "failed"))
        if (self.power_per_crease is None) == self.success:
            raise ParameterError(f"LiftPowerResult.power_per_crease = {self.power_per_crease!r}"
                                 f" with success = {self.success}: a reached target has a "
                                 "power, an unreached one None.")

    _csv_name = "lift_power.csv"

    def temperature_verdict(self, limit: TemperatureLimit = SU8_LIMIT) -> TemperatureVerdict:
        """The verdict on ``limit`` (default 1.2 T_g of SU-8 on the crease centre-line mean)
        at the power found (at the last trial if not met)."""
        return TemperatureVerdict.of(limit, (self.temperature, self.temperature_crease),
                                     (self.max_crease_temperature, self.hottest_node_crease))

    def to_dict(self) -> dict:
        """Flat summary, keys ``name [unit]`` (powers None when not met)."""
        return {"power_per_crease [mW]": power_if(self.success, self.power_per_crease, 1e3),
                "total_power [mW]": power_if(self.success, self.total_power, 1e3),
                "lift [um]": 1e6 * self.lift,
                "temperature [degC]": self.temperature,
                "max_crease_temperature [degC]": self.max_crease_temperature,
                "simulations": self.simulations, "n_creases": self.n_creases,
                "success": self.success, "status": self.status, "message": self.message}


class _LiftStage(HeatingStage):
    """Heating trials from saved states, with the interface the gripper searches use; a snap
    (limit point) is followed by arc length in the power and noted for the result's message."""

    def __init__(self, model, creases, nodes, target):
        super().__init__(model, creases)
        self.nodes, self.target = nodes, target

    def met(self, state) -> bool:
        """Whether the target lift is reached (without the temperatures :meth:`look` judges)."""
        return float(state.u[self.nodes, 2].mean()) >= self.target

    def look(self, state):
        """(lift [m], target met, hottest crease's centre-line mean [deg C], hottest crease
        node [deg C])."""
        lift = float(state.u[self.nodes, 2].mean())
        v = SU8_LIMIT.judge(state.temperature, self.model.mesh)
        return lift, lift >= self.target, v.temperature, v.hottest_node

    def result(self, status, power, state, message):
        lift = float(state.u[self.nodes, 2].mean())
        v = SU8_LIMIT.judge(state.temperature, self.model.mesh)
        met = status == "met"
        p = power if met else None
        if not met:
            message = (f"target lift {self.target * 1e6:g} um not reached (lift "
                       f"{lift * 1e6:.4g} um): {message}")
        if met:
            message = self.after_snaps(message, state)
        return LiftPowerResult(met, status, message, p, power_if(met, p, len(self.creases)),
                               lift, v.hottest_node, self.simulations, len(self.creases),
                               self.snap_events(state) if met else (), v.temperature, v.crease,
                               v.hottest_node_crease)


def lift_power(design: MiuraDesign = MiuraDesign(), target_lift: float = 100e-6,
               mode: str = "bisect", step: float = 0.1e-3, tol: float = 0.01e-3,
               power_cap: float = 30e-3, max_step: float = 1e-3) -> LiftPowerResult:
    """Power per crease that lifts the free end by ``target_lift``.

    Parameters
    ----------
    design : MiuraDesign
    target_lift : required lift of the free end [m] (> 0)
    mode : {"bisect", "staircase"}
        ``staircase``: add ``step`` per crease per simulation (one increment) until the lift is
        reached; ``bisect``: grow the step geometrically (to ``max_step``) from saved states,
        then bisect the crossing to ``tol``.
    step, tol, power_cap, max_step : powers per crease [W]; the target is not reachable if
        it needs more than ``power_cap``

    Returns
    -------
    LiftPowerResult
        ``success=False`` with the reason (power cap, simulation failure) if not reached.
    """
    one_of("mode", mode, ("bisect", "staircase"))
    positive("target_lift", target_lift, "m")
    for name, v in (("step", step), ("tol", tol), ("power_cap", power_cap), ("max_step", max_step)):
        positive(name, v, "W per crease")
    model = make_miura_model(design)
    stage = _LiftStage(model, tuple(heated_creases(design)), _lift_nodes(model, design),
                       target_lift)
    state = simulate(model, []).state
    if mode == "staircase":
        return staircase_search(stage, state, step, power_cap)[0]
    return bisect_search(stage, state, step, tol, power_cap, max_step)[0]


#: Design variables: panel sides, sector angle (rad, shown in deg), crease width.
MIURA_SPACE = DesignSpace([
    Variable("a", 0.5e-3, 1.5e-3, 50e-6, 1e-3),
    Variable("b", 0.5e-3, 1.5e-3, 50e-6, 1e-3),
    Variable("gamma", 45 * _DEG, 75 * _DEG, 5 * _DEG, 60 * _DEG, unit="rad",
             display_scale=180 / math.pi, display_unit="deg"),
    Variable("W", 100e-6, 300e-6, 10e-6, 200e-6),
])


@dataclass(frozen=True)
class MiuraProblem(TemperatureLimited, DesignProblem):
    """Minimise the total power that lifts the Miura lifter's free end by ``target_lift``.

    Objective: total power of all heated creases [W]. Constraints (g <= 0): the normalised
    size bounds and ``(T - T_limit) / T_limit`` with ``T`` the centre-line mean of the hottest
    crease (the measure of every design problem; ``temperature_measure="crease_max"``: the
    hottest crease node) and ``T_limit = temperature_factor x glass_transition``. A target not reached below
    ``power_cap`` (per crease) is an unsuccessful evaluation (status ``"not_met"``, or
    ``"failed"`` if a simulation failed).

    Parameters
    ----------
    target_lift : required lift [m] (200 um)
    mode, power_cap, step, tol : search settings of :func:`lift_power` (powers per crease [W])
    glass_transition : T_g of the crease polymer [deg C]; default ``SU8.glass_transition`` (210)
    temperature_factor : allowed multiple of T_g (1.2)
    base : MiuraDesign (values of everything that is not a design variable)
    """

    target_lift: float = 200e-6
    mode: str = "bisect"
    power_cap: float = 30e-3
    step: float = 0.1e-3
    tol: float = 0.01e-3
    glass_transition: float = SU8_TG
    temperature_factor: float = TG_FACTOR
    base: MiuraDesign = MiuraDesign()
    space: DesignSpace = field(default=MIURA_SPACE, compare=False)
    name: str = "miura"
    temperature_measure: str = "centre_line"

    def __post_init__(self):
        if self.mode not in ("bisect", "staircase"):
            raise ParameterError(f"mode = {self.mode!r}; use 'bisect' or 'staircase'.")
        _ = self.limit                               # checks temperature_measure

    def design(self, values: dict) -> MiuraDesign:
        return replace(self.base, **values)

    def _evaluate(self, values):
        res = lift_power(self.design(values), self.target_lift, mode=self.mode, step=self.step,
                         tol=self.tol, power_cap=self.power_cap)
        constraints = dict(self.space.bound_margins(values))
        verdict, message = self._judge(res)
        constraints["temperature"] = verdict.constraint
        metrics = {k: v for k, v in res.to_dict().items()
                   if k not in ("success", "status", "message")}
        return EvaluationOutcome(res.total_power, constraints, metrics,
                                 None if res.success else res.status, message)

    def settings(self) -> dict:
        return {"problem": self.name, "mode": self.mode, "target_lift [m]": self.target_lift,
                "T_limit [degC]": self.temperature_limit,
                "temperature_measure": self.temperature_measure, "power_cap [W]": self.power_cap,
                "step [W]": self.step, "tol [W]": self.tol, "base": self.base.to_dict(),
                "space": self.space.to_dicts()}


def lift_per_power_table(designs, power_mW, increments: int = 20):
    """Lift and crease temperature of designs heated to given powers per crease.

    Parameters
    ----------
    designs : sequence of MiuraDesign, or mapping {label: MiuraDesign}
    power_mW : float or sequence of float
        Power per crease [mW]; several powers are reached in turn from saved states.
    increments : int
        Heating increments per power segment.

    Returns
    -------
    pandas.DataFrame
        One row per design and power: ``label``, ``a [um]``, ``b [um]``, ``gamma [deg]``,
        ``W [um]``, ``cells_x``, ``cells_y``, ``substrate``, ``power [mW]`` (per crease),
        ``total_power [mW]``, ``lift [um]``, ``temperature [degC]`` (hottest crease,
        centre line), ``max_crease_temperature [degC]`` (hottest node), ``success``
        (the heating simulation converged), ``status`` (``converged`` or ``failed``),
        ``message``; lift and temperature NaN (empty in CSV) when it failed.
    """
    import pandas as pd
    items = designs.items() if isinstance(designs, Mapping) else enumerate(designs)
    powers = sorted(np.atleast_1d(np.asarray(power_mW, float)).tolist())
    if not powers or any(not (math.isfinite(p) and p >= 0) for p in powers):
        raise ParameterError(f"power_mW = {power_mW!r} must be finite powers >= 0 mW.")
    rows = []
    for label, d in items:
        if not isinstance(d, MiuraDesign):
            raise ParameterError(f"design {label!r} is a {type(d).__name__}, not a MiuraDesign.")
        model = make_miura_model(d)
        stage = _LiftStage(model, tuple(heated_creases(d)), _lift_nodes(model, d), math.inf)
        state, done, ok, msg = simulate(model, []).state, 0.0, True, "converged"
        for p in powers:
            if ok and p > done:
                state, ok, msg = stage.heat(state, 1e-3 * (p - done), increments=increments)
                done = p
            lift, _, temp, tmax = stage.look(state) if ok else (math.nan,) * 4
            rows.append({"label": label, **design_columns(d), "cells_x": d.cells_x,
                         "cells_y": d.cells_y, "substrate": d.substrate, "power [mW]": p,
                         "total_power [mW]": p * len(stage.creases), "lift [um]": 1e6 * lift,
                         "temperature [degC]": temp,
                         "max_crease_temperature [degC]": tmax, "success": ok,
                         "status": "converged" if ok else "failed", "message": msg})
    return pd.DataFrame(rows)
