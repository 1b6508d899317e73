"""Design problems: ``evaluate(x) -> Evaluation`` with objective, constraints g <= 0, metrics.

Generic: the devices' problems (:class:`~design.devices.gripper_problem.GripperProblem`,
:class:`~design.devices.miura.MiuraProblem`) subclass :class:`DesignProblem`.

A simulator failure or any exception inside a problem's evaluation becomes an unsuccessful
:class:`Evaluation` (``success=False``, status ``"failed"``) with a message; it never
propagates into an optimiser. Problems are plain picklable objects so that process pools and Dask workers can evaluate them.
"""

from __future__ import annotations

import logging
import math
import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from simulator import ParameterError
from simulator._result import ResultFiles

from .contract import check_outcome
from .space import DesignSpace

__all__ = ["Evaluation", "EvaluationOutcome", "DesignProblem", "EVALUATION_STATUSES"]

logger = logging.getLogger(__name__)

#: Status words of an evaluation: success (objective and constraints computed) is
#: "feasible" or "infeasible"; a failure is "not_met" (the problem's criterion was never met,
#: e.g. below a power cap) or "failed" (a simulation failed, an exception, a bad design).
EVALUATION_STATUSES = ("feasible", "infeasible", "not_met", "failed")


@dataclass(frozen=True)
class Evaluation(ResultFiles):
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
    objective_gradient : dict {variable: d objective / d variable} or None
        The objective's gradient with respect to the design variables (SI: objective unit
        over the variable's), from :meth:`DesignProblem.evaluate_with_gradient`; None when
        the problem supplied none (or the evaluation failed).
    constraint_gradients : dict {name: {variable: d g / d variable}} or None
        Each constraint's gradient, likewise.
    """

    x: dict
    objective: float
    constraints: dict = field(default_factory=dict)
    metrics: dict = field(default_factory=dict)
    success: bool = True
    status: str = ""
    message: str = ""
    wall_time: float = 0.0
    objective_gradient: dict | None = None
    constraint_gradients: dict | None = None

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

    _csv_name = "evaluation.csv"

    def _row(self) -> dict:
        return self.to_row()


class EvaluationOutcome(NamedTuple):
    """What a problem's ``_evaluate(values)`` returns (:class:`DesignProblem`).

    Attributes
    ----------
    objective : float
        Value to minimise (SI).
    constraints : dict {name: g}
        Feasible when ``g <= 0``.
    metrics : dict
        Further results, keys ``name [unit]``.
    failure : str or None
        None when the objective and constraints were computed, else the status word saying
        why not (``"not_met"``, ``"failed"``).
    message : str
    objective_gradient : mapping {variable: value} or sequence (space order), optional
        The objective's gradient with respect to the design variables (SI); given by
        ``_evaluate_with_gradient`` only.
    constraint_gradients : dict {name: mapping or sequence}, optional
        Each constraint's gradient, likewise.
    """

    objective: float
    constraints: dict
    metrics: dict
    failure: str | None = None
    message: str = ""
    objective_gradient: object = None
    constraint_gradients: dict | None = None


class DesignProblem:
    """Base class: subclasses set ``space`` and implement ``_evaluate(values: dict) ->``
    :class:`EvaluationOutcome` (a plain 5-tuple in its order is accepted as well).
    """

    space: DesignSpace
    name = "problem"
    #: The metric the coordinate descent reports per cycle (``cycles`` columns
    #: ``last_candidate.<metric>`` and ``current.<metric>``), or None for none.
    report_metric: str | None = None

    @property
    def supplies_gradients(self) -> bool:
        """The problem implements ``_evaluate_with_gradient`` (gradient methods need it)."""
        return type(self)._evaluate_with_gradient is not DesignProblem._evaluate_with_gradient

    def evaluate(self, x) -> Evaluation:
        """Evaluate a design (mapping or vector); never raises for simulation failures."""
        return self._run(x, self._evaluate)

    def evaluate_with_gradient(self, x) -> Evaluation:
        """Evaluate a design with the gradients of the objective and of every constraint
        (:attr:`Evaluation.objective_gradient`, :attr:`Evaluation.constraint_gradients`);
        never raises for simulation failures. A successful outcome without a gradient
        becomes a failed evaluation naming what is missing."""
        if not self.supplies_gradients:
            raise ParameterError(f"{type(self).__name__} supplies no gradients; implement "
                                 "_evaluate_with_gradient(values) or call evaluate(x).")
        return self._run(x, self._evaluate_with_gradient)

    def _run(self, x, fn) -> Evaluation:
        values = self.space.to_mapping(x)
        t0 = time.perf_counter()
        try:
            self.space.validate(values)
            out = EvaluationOutcome(*fn(values))
            grads = (_gradients(self.space, out) if fn != self._evaluate and not out.failure
                     else (None, None))
        except ParameterError as exc:
            out, grads = EvaluationOutcome(math.inf, {}, {}, "failed", str(exc)), (None, None)
        except Exception as exc:  # noqa: BLE001 - a failed design must not crash an optimiser
            logger.warning("evaluation of %s failed: %s", values, exc)
            out = EvaluationOutcome(math.inf, {}, {}, "failed", f"{type(exc).__name__}: {exc} "
                                    f"({traceback.format_exc(limit=1).strip()})")
            grads = (None, None)
        ev = Evaluation(values, math.inf if out.failure else float(out.objective),
                        out.constraints, out.metrics, success=not out.failure,
                        status=out.failure or "", message=out.message,
                        wall_time=time.perf_counter() - t0, objective_gradient=grads[0],
                        constraint_gradients=grads[1])
        logger.info("evaluated %s -> %.6g (%s)", values, ev.objective, ev.status)
        return ev

    def _evaluate(self, values: dict):  # pragma: no cover - abstract
        raise NotImplementedError

    def _evaluate_with_gradient(self, values: dict):  # pragma: no cover - optional
        """Like ``_evaluate``, with the outcome's ``objective_gradient`` and
        ``constraint_gradients`` (with respect to the design variables, SI) set."""
        raise NotImplementedError

    def settings(self) -> dict:
        """Everything that defines the problem besides x (for logs and cache keys)."""
        return {"problem": self.name}


def _gradient_dict(space: DesignSpace, grad, what: str) -> dict:
    """A gradient (mapping by variable, or sequence in the space's order) as a dict of
    finite floats by variable name; a ParameterError naming ``what`` otherwise."""
    if grad is None:
        raise ParameterError(f"the problem supplied no gradient of {what}; "
                             "_evaluate_with_gradient must set it.")
    names = space.names
    if isinstance(grad, Mapping):
        missing = [n for n in names if n not in grad]
        if missing:
            raise ParameterError(f"the gradient of {what} lacks the variable(s) {missing}.")
        vec = [grad[n] for n in names]
    else:
        vec = list(np.asarray(grad, float).ravel())
        if len(vec) != len(names):
            raise ParameterError(f"the gradient of {what} has {len(vec)} entries; the design "
                                 f"space has {len(names)} variables ({', '.join(names)}).")
    if not all(math.isfinite(float(v)) for v in vec):
        raise ParameterError(f"the gradient of {what} = {vec} is not finite.")
    return {n: float(v) for n, v in zip(names, vec)}


def _gradients(space: DesignSpace, out: EvaluationOutcome):
    """The outcome's gradients checked and keyed by variable: ``(objective, {name: ...})``;
    the bound margins' (:meth:`DesignSpace.bound_margins`) are known and may be left out."""
    given = {**space.bound_margin_gradients(), **(out.constraint_gradients or {})}
    return (_gradient_dict(space, out.objective_gradient, "the objective"),
            {k: _gradient_dict(space, given.get(k), f"constraint {k!r}")
             for k in out.constraints})
