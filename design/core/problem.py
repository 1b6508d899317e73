"""Design problems: ``evaluate(x) -> Evaluation`` with objective, constraints g <= 0, metrics.

A simulator failure or any exception inside a problem's evaluation becomes an unsuccessful
:class:`Evaluation` (``success=False``, status ``"failed"``) with a message; it never
propagates into an optimiser. Problems are plain picklable objects so that process pools and Dask workers can evaluate them.
"""

from __future__ import annotations

import logging
import math
import time
import traceback
from dataclasses import dataclass, field

from simulator.errors import ParameterError
from simulator.geometry.materials import SU8

from ._contract import check_outcome
from ..devices.gripper import GripperDesign, check_fold, evaluate_gripper
from .space import DesignSpace, Variable

__all__ = ["Evaluation", "DesignProblem", "GripperProblem", "GRIPPER_SPACE", "SU8_TG",
           "EVALUATION_STATUSES"]

logger = logging.getLogger(__name__)

#: Glass transition temperature [deg C] of SU-8, the crease polymer of the paper's devices, read
#: from the material (:data:`simulator.geometry.materials.SU8`, 210 deg C); problems take it as default.
SU8_TG = SU8.glass_transition

#: The paper's gripper design space (section 6.3 and theory 10.6): bounds, steps, start.
GRIPPER_SPACE = DesignSpace([
    Variable("W", 100e-6, 300e-6, 10e-6, 200e-6),
    Variable("La", 500e-6, 1500e-6, 50e-6, 700e-6),
    Variable("L1", 500e-6, 1500e-6, 50e-6, 1000e-6),
    Variable("L2", 500e-6, 1500e-6, 50e-6, 1000e-6),
])


#: Status words of an evaluation: success (objective and constraints computed) is
#: "feasible" or "infeasible"; a failure is "not_met" (the problem's criterion was never met,
#: e.g. below a power cap) or "failed" (a simulation failed, an exception, a bad design).
EVALUATION_STATUSES = ("feasible", "infeasible", "not_met", "failed")


@dataclass(frozen=True)
class Evaluation:
    """One evaluated design.

    ``success`` means the thing asked of an evaluation was done: the objective and the
    constraints were computed. It says nothing about the constraints; ``feasible`` does
    (success and every ``g <= 0``), so both are kept, and ``status`` combines them.

    Attributes
    ----------
    x : dict {variable: value} (SI)
    objective : float
        Value to minimise (SI); ``inf`` when the evaluation did not succeed, so that every
        optimiser ranks it last (the objective is an optimiser's number, not a reported
        power: the metrics give powers, None when not met).
    constraints : dict {name: g}
        Constraint values, feasible when ``g <= 0`` (normalised, dimensionless).
    metrics : dict
        Further results, keys ``name [unit]``.
    success : bool
        Objective and constraints were computed.
    status : str
        ``"feasible"`` or ``"infeasible"`` (success), ``"not_met"`` (the criterion was never
        met, e.g. below the power cap) or ``"failed"`` (simulation failure, exception, design
        outside the bounds). Default: from ``success`` and the constraints.
    message : str
    wall_time : float [s]
    """

    x: dict
    objective: float
    constraints: dict = field(default_factory=dict)
    metrics: dict = field(default_factory=dict)
    success: bool = True
    status: str = ""
    message: str = ""
    wall_time: float = 0.0

    def __post_init__(self):
        ok = all(g <= 0 for g in self.constraints.values())
        derived = ("feasible" if ok else "infeasible") if self.success else "failed"
        if not self.status:
            object.__setattr__(self, "status", derived)
        check_outcome(self, (derived,), EVALUATION_STATUSES[2:])

    @property
    def feasible(self) -> bool:
        """Evaluated and every constraint ``g <= 0``."""
        return self.success and all(g <= 0 for g in self.constraints.values())

    @property
    def max_violation(self) -> float:
        return max([0.0] + [g for g in self.constraints.values()])

    def to_row(self, space=None) -> dict:
        """Flat dict for tables and the evaluation log: ``x.<name> [unit]`` (unit from
        ``space``; ``x.<name>`` without it), ``objective``, ``g.<name>``, ``m.<metric>``,
        ``success``, ``status``, ``feasible``, ``message``, ``wall_time [s]``."""
        unit = {} if space is None else {v.name: f" [{v.unit}]" for v in space.variables}
        row = {f"x.{k}{unit.get(k, '')}": v for k, v in self.x.items()}
        row["objective"] = self.objective
        row.update({f"g.{k}": v for k, v in self.constraints.items()})
        row.update({f"m.{k}": v for k, v in self.metrics.items()})
        row.update({"success": self.success, "status": self.status, "feasible": self.feasible,
                    "message": self.message, "wall_time [s]": self.wall_time})
        return row


class DesignProblem:
    """Base class: subclasses set ``space`` and implement :meth:`_evaluate`.

    ``_evaluate(values: dict) -> (objective, constraints, metrics, failure, message)``:
    ``failure`` is None when the objective and constraints were computed, else the status
    word saying why not (``"not_met"``, ``"failed"``).
    """

    space: DesignSpace
    name = "problem"

    def evaluate(self, x) -> Evaluation:
        """Evaluate a design (mapping or vector); never raises for simulation failures."""
        values = self.space.to_dict(x)
        t0 = time.perf_counter()
        try:
            self.space.validate(values)
            objective, constraints, metrics, failure, message = self._evaluate(values)
        except ParameterError as exc:
            objective, constraints, metrics, failure, message = (math.inf, {}, {}, "failed",
                                                                 str(exc))
        except Exception as exc:  # noqa: BLE001 - a failed design must not crash an optimiser
            logger.warning("evaluation of %s failed: %s", values, exc)
            objective, constraints, metrics, failure = math.inf, {}, {}, "failed"
            message = f"{type(exc).__name__}: {exc} ({traceback.format_exc(limit=1).strip()})"
        ev = Evaluation(values, math.inf if failure else float(objective), constraints, metrics,
                        success=not failure, status=failure or "", message=message,
                        wall_time=time.perf_counter() - t0)
        logger.info("evaluated %s -> %.6g (%s)", values, ev.objective, ev.status)
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
        T_g of the crease polymer [deg C]; default ``SU8.glass_transition`` (210).
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
            else d["max_crease_temperature [degC]"]
        constraints = dict(self.space.bound_margins(values))
        constraints["temperature"] = (temp - self.temperature_limit) / self.temperature_limit
        metrics = {k: v for k, v in d.items()
                   if not k.endswith("[m]") and not k.startswith("residual_fold")
                   and k not in ("success", "status", "message", "mode")}
        metrics["temperature [degC]"] = temp
        return (res.total_power, constraints, metrics, None if res.success else res.status,
                res.message)

    def settings(self) -> dict:
        folds = self.group_folds()
        return {"problem": self.name, "mode": self.mode,
                "residual_fold [rad]": (folds["base"] if folds["base"] == folds["arm"]
                                        else folds),
                "T_limit [degC]": self.temperature_limit,
                "temperature_measure": self.temperature_measure,
                "power_cap [W]": self.power_cap, "base": self.base.to_dict(),
                "space": self.space.to_dicts()}
