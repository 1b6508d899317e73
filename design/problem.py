"""Design problems: ``evaluate(x) -> Evaluation`` with objective, constraints g <= 0, metrics.

A simulator failure or any exception inside a problem's evaluation becomes a *failed*
:class:`Evaluation` with a message; it never propagates into an optimiser. Problems are
plain picklable objects so that process pools and Dask workers can evaluate them.
"""

from __future__ import annotations

import logging
import math
import time
import traceback
from dataclasses import dataclass, field

from simulator.errors import ParameterError

from .gripper import GripperDesign, check_fold, evaluate_gripper
from .space import DesignSpace, Variable

__all__ = ["Evaluation", "DesignProblem", "GripperProblem", "GRIPPER_SPACE", "SU8_TG"]

logger = logging.getLogger(__name__)

#: Glass transition temperature of SU-8 [deg C] (the paper's value).
SU8_TG = 210.0

#: The paper's gripper design space (section 6.3 and digest 8.7): bounds, steps, start.
GRIPPER_SPACE = DesignSpace([
    Variable("W", 100e-6, 300e-6, 10e-6, 200e-6),
    Variable("La", 500e-6, 1500e-6, 50e-6, 700e-6),
    Variable("L1", 500e-6, 1500e-6, 50e-6, 1000e-6),
    Variable("L2", 500e-6, 1500e-6, 50e-6, 1000e-6),
])


@dataclass(frozen=True)
class Evaluation:
    """One evaluated design.

    Attributes
    ----------
    x : dict {variable: value} (SI)
    objective : float
        Value to minimise (SI; ``inf`` when the evaluation failed).
    constraints : dict {name: g}
        Constraint values, feasible when ``g <= 0`` (normalised, dimensionless).
    metrics : dict
        Further results with units in their names.
    failed : bool
        The evaluation could not produce an objective (simulation failure, criterion never met).
    message : str
    wall_time : float [s]
    """

    x: dict
    objective: float
    constraints: dict = field(default_factory=dict)
    metrics: dict = field(default_factory=dict)
    failed: bool = False
    message: str = ""
    wall_time: float = 0.0

    @property
    def feasible(self) -> bool:
        return (not self.failed) and all(g <= 0 for g in self.constraints.values())

    @property
    def max_violation(self) -> float:
        return max([0.0] + [g for g in self.constraints.values()])

    def to_row(self) -> dict:
        """Flat dict for tables and the evaluation log."""
        row = {f"x.{k}": v for k, v in self.x.items()}
        row["objective"] = self.objective
        row.update({f"g.{k}": v for k, v in self.constraints.items()})
        row.update({f"m.{k}": v for k, v in self.metrics.items()})
        row.update(failed=self.failed, feasible=self.feasible, message=self.message,
                   wall_time=self.wall_time)
        return row


class DesignProblem:
    """Base class: subclasses set ``space`` and implement :meth:`_evaluate`.

    ``_evaluate(values: dict) -> (objective, constraints, metrics, failed, message)``.
    """

    space: DesignSpace
    name = "problem"

    def evaluate(self, x) -> Evaluation:
        """Evaluate a design (mapping or vector); never raises for simulation failures."""
        values = self.space.to_dict(x)
        t0 = time.perf_counter()
        try:
            self.space.validate(values)
            objective, constraints, metrics, failed, message = self._evaluate(values)
        except ParameterError as exc:
            objective, constraints, metrics, failed, message = math.inf, {}, {}, True, str(exc)
        except Exception as exc:  # noqa: BLE001 - a failed design must not crash an optimiser
            logger.warning("evaluation of %s failed: %s", values, exc)
            objective, constraints, metrics, failed = math.inf, {}, {}, True
            message = f"{type(exc).__name__}: {exc} ({traceback.format_exc(limit=1).strip()})"
        ev = Evaluation(values, float(objective), constraints, metrics, failed, message,
                        time.perf_counter() - t0)
        logger.info("evaluated %s -> %.6g (%s)", values, ev.objective,
                    "failed" if failed else "feasible" if ev.feasible else "infeasible")
        return ev

    def _evaluate(self, values: dict):  # pragma: no cover - abstract
        raise NotImplementedError

    def settings(self) -> dict:
        """Everything that defines the problem besides x (for logs and cache keys)."""
        return {"problem": self.name}


@dataclass(frozen=True)
class GripperProblem(DesignProblem):
    """Minimise the gripper's assembly + grip power per crease (paper section 6.3).

    Objective: ``total_power`` [W]. Constraints (g <= 0): the normalised size bounds and the
    crease temperature limit ``(T - T_limit) / T_limit`` with ``T_limit = 1.2 T_g``; ``T`` is
    the reference's measure (centre-line mean of the heated creases at the stopping power,
    larger of the two stages) or, with ``temperature_measure="crease_max"``, the hottest crease
    node. A design whose criterion is never met below the power cap is a failed evaluation.

    Parameters
    ----------
    mode : {"bisect", "staircase"}
    residual_fold : float
        Residual fold of the actuated creases [rad].
    residual_fold_groups : tuple of (group, rad) pairs
        Residual folds of crease groups ``"base"`` / ``"arm"`` overriding ``residual_fold``.
    glass_transition : float
        T_g of the crease polymer [deg C] (SU-8: 210).
    temperature_factor : float
        Allowed multiple of T_g (1.2).
    base : GripperDesign
        Values of everything that is not a design variable.
    """

    mode: str = "bisect"
    residual_fold: float = 0.0
    residual_fold_groups: tuple = ()
    glass_transition: float = SU8_TG
    temperature_factor: float = 1.2
    temperature_measure: str = "centre_line"
    power_cap: float = 40e-3
    base: GripperDesign = GripperDesign()
    space: DesignSpace = field(default=GRIPPER_SPACE, compare=False)
    name: str = "gripper"

    def __post_init__(self):
        if self.temperature_measure not in ("centre_line", "crease_max"):
            raise ParameterError(f"temperature_measure = {self.temperature_measure!r}; use "
                                 "'centre_line' or 'crease_max'.")
        if self.mode not in ("bisect", "staircase"):
            raise ParameterError(f"mode = {self.mode!r}; use 'bisect' or 'staircase'.")
        groups = dict(self.residual_fold_groups)
        if set(groups) - {"base", "arm"}:
            raise ParameterError(f"residual_fold_groups {groups!r}: groups are 'base' and 'arm'.")
        check_fold("GripperProblem.residual_fold", self.residual_fold)
        for group, value in groups.items():
            check_fold(f"GripperProblem.residual_fold_groups[{group!r}]", value)
        object.__setattr__(self, "residual_fold_groups", tuple(sorted(groups.items())))

    def group_folds(self) -> dict:
        """Residual fold [rad] of each crease group."""
        given = dict(self.residual_fold_groups)
        return {g: float(given.get(g, self.residual_fold)) for g in ("base", "arm")}

    @property
    def temperature_limit(self) -> float:
        return self.temperature_factor * self.glass_transition

    def design(self, values: dict) -> GripperDesign:
        from dataclasses import replace
        folds = self.group_folds()
        return replace(self.base, residual_fold=self.residual_fold,
                       residual_fold_base=folds["base"], residual_fold_arm=folds["arm"], **values)

    def _evaluate(self, values):
        res = evaluate_gripper(self.design(values), mode=self.mode, power_cap=self.power_cap)
        d = res.to_dict()
        temp = res.max_temperature if self.temperature_measure == "centre_line" \
            else d["max_crease_temperature_C"]
        constraints = dict(self.space.bound_margins(values))
        constraints["temperature"] = (temp - self.temperature_limit) / self.temperature_limit
        metrics = {k: (math.nan if v is None else v) for k, v in d.items()
                   if not k.endswith("[m]") and not k.startswith("residual_fold")
                   and k not in ("feasible", "message", "mode")}
        metrics["temperature_C"] = temp
        return res.total_power, constraints, metrics, not res.feasible, res.message

    def settings(self) -> dict:
        folds = self.group_folds()
        return {"problem": self.name, "mode": self.mode,
                "residual_fold [rad]": (folds["base"] if folds["base"] == folds["arm"]
                                        else folds),
                "T_limit [degC]": self.temperature_limit,
                "temperature_measure": self.temperature_measure,
                "power_cap [W]": self.power_cap, "base": self.base.to_dict(),
                "space": self.space.to_dicts()}
