"""The paper's gripper design problem: minimise the assembly + grip power per crease subject to
the size bounds and the crease temperature limit (paper section 6.3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from simulator import ParameterError
from simulator.thermal import TG_FACTOR

from ..core.problem import DesignProblem, EvaluationOutcome
from ..core.space import DesignSpace, Variable
from .gripper import (GripperDesign, GripperHeatModel, check_fold, evaluate_gripper,
                      gripper_settings, split_heat)
from .limits import SU8_TG, TemperatureLimited

__all__ = ["GripperProblem", "GRIPPER_SPACE"]

#: The paper's gripper design space (section 6.3 and theory 10.6): bounds, steps, start.
GRIPPER_SPACE = DesignSpace([
    Variable("W", 100e-6, 300e-6, 10e-6, 200e-6),
    Variable("La", 500e-6, 1500e-6, 50e-6, 700e-6),
    Variable("L1", 500e-6, 1500e-6, 50e-6, 1000e-6),
    Variable("L2", 500e-6, 1500e-6, 50e-6, 1000e-6),
])


@dataclass(frozen=True)
class GripperProblem(TemperatureLimited, DesignProblem):
    """Minimise the gripper's assembly + grip power per crease (paper section 6.3).

    Objective: ``total_power`` [W]. Constraints (g <= 0): the normalised size bounds and the
    crease temperature limit ``(T - T_limit) / T_limit`` with ``T_limit = 1.2 T_g``, from
    :meth:`~design.devices.gripper.GripperResult.temperature_verdict`
    (the verdict ``gripper evaluate`` prints); ``T`` is the measure of the limit (theory 5.4:
    centre-line mean of the heated creases at the stopping power, larger of the two stages)
    or, with ``temperature_measure="crease_max"``, the hottest crease node. A design whose
    criterion is never met below the power cap is a failed evaluation; an evaluated design
    above the limit is infeasible, and its message names the crease, its temperature and the
    limit.

    Parameters
    ----------
    mode : {"bisect", "staircase"}
    residual_fold : float
        Residual fold of the actuated creases [rad].
    residual_fold_groups : tuple of (group, rad) pairs
        Residual folds of crease groups ``"base"`` / ``"arm"`` overriding ``residual_fold``.
    glass_transition : float
        T_g of the crease polymer [deg C]; default ``SU8.glass_transition`` (210).
    temperature_factor : float
        Allowed multiple of T_g (1.2).
    base : GripperDesign
        Values of everything that is not a design variable (its deprecated heat-model
        fields, if given, move into ``heat``).
    power_step, max_power_step : float
        First and largest growth step of the bisect power search [W per crease]
        (:func:`~design.devices.gripper.evaluate_gripper` ``step`` and ``max_step``); smaller
        steps retry a path that a large step lost (``sweep_uncertainty(retry=...)``).
    heat : GripperHeatModel
        How the heat balance is modelled (default: the integral loss; ``GripperHeatModel(
        loss_model="chain")`` the paper's optimisation).
    """

    mode: str = "bisect"
    residual_fold: float = 0.0
    residual_fold_groups: tuple = ()
    glass_transition: float = SU8_TG
    temperature_factor: float = TG_FACTOR
    temperature_measure: str = "centre_line"
    power_cap: float = 40e-3
    base: GripperDesign = GripperDesign()
    power_step: float = 0.1e-3
    max_power_step: float = 0.4e-3
    heat: GripperHeatModel = GripperHeatModel()
    space: DesignSpace = field(default=GRIPPER_SPACE, compare=False)
    name: str = "gripper"

    def __post_init__(self):
        _ = self.limit                               # checks temperature_measure
        if self.mode not in ("bisect", "staircase"):
            raise ParameterError(f"mode = {self.mode!r}; use 'bisect' or 'staircase'.")
        for name in ("power_step", "max_power_step"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ParameterError(f"GripperProblem.{name} = {value!r} W must be a positive "
                                     "number of watts per crease (e.g. 0.05e-3).")
        groups = dict(self.residual_fold_groups)
        if set(groups) - {"base", "arm"}:
            raise ParameterError(f"residual_fold_groups {groups!r}: groups are 'base' and 'arm'.")
        check_fold("GripperProblem.residual_fold", self.residual_fold)
        for group, value in groups.items():
            check_fold(f"GripperProblem.residual_fold_groups[{group!r}]", value)
        object.__setattr__(self, "residual_fold_groups", tuple(sorted(groups.items())))
        base, heat = split_heat(self.base, self.heat)
        object.__setattr__(self, "base", base)
        object.__setattr__(self, "heat", heat)

    def group_folds(self) -> dict:
        """Residual fold [rad] of each crease group."""
        given = dict(self.residual_fold_groups)
        return {g: float(given.get(g, self.residual_fold)) for g in ("base", "arm")}

    def design(self, values: dict) -> GripperDesign:
        folds = self.group_folds()
        return replace(self.base, residual_fold=self.residual_fold,
                       residual_fold_base=folds["base"], residual_fold_arm=folds["arm"], **values)

    def _evaluate(self, values):
        res = evaluate_gripper(self.design(values), mode=self.mode, power_cap=self.power_cap,
                               step=self.power_step, max_step=self.max_power_step,
                               heat=self.heat)
        d = res.to_dict()
        verdict, message = self._judge(res)
        constraints = dict(self.space.bound_margins(values))
        constraints["temperature"] = verdict.constraint
        metrics = {k: v for k, v in d.items()
                   if not k.endswith("[m]")
                   and not k.startswith(("residual_fold", "loss_model", "integral_refinement",
                                         "conduction", "sheet_refinement", "sheet_extrapolation",
                                         "crease_conduction",
                                         "k_gold", "temperature_dependent_air", "emissivity",
                                         "lead_fraction", "heater_tcr"))
                   and k not in ("success", "status", "message", "mode")}
        metrics["temperature [degC]"] = verdict.temperature
        return EvaluationOutcome(res.total_power, constraints, metrics,
                                 None if res.success else res.status, message)

    def settings(self) -> dict:
        folds = self.group_folds()
        return {"problem": self.name, "mode": self.mode,
                "residual_fold [rad]": (folds["base"] if folds["base"] == folds["arm"]
                                        else folds),
                "T_limit [degC]": self.temperature_limit,
                "temperature_measure": self.temperature_measure,
                "power_cap [W]": self.power_cap, "base": gripper_settings(self.base, self.heat),
                "space": self.space.to_dicts(), **self._step_settings()}

    def _step_settings(self) -> dict:
        """The power-search steps, recorded only when not the defaults (so logs and cache
        keys of default problems stay as they were)."""
        steps = (self.power_step, self.max_power_step)
        return {} if steps == (0.1e-3, 0.4e-3) else {"power_steps [W]": list(steps)}
