"""Robustness to the residual fold that fabrication leaves in the actuated creases.

:func:`residual_fold_grid` (one value for all actuated creases, or a product over the crease
groups ``"base"`` = creases 2, 5 and ``"arm"`` = 3, 9), :func:`sweep_residual_fold` (designs x
residual folds with any executor, one table row per point, the same floats whatever the
executor) and :class:`RobustGripperProblem` (worst case over the residual folds, for the
optimisers).

A residual-fold *spec* is a dict ``{group: fold [rad]}``: ``{"all": r}`` for one value on all
actuated creases, or ``{"base": r1, "arm": r2}`` per group (a group left out takes the problem's
own ``residual_fold``). A plain number is ``{"all": number}``, in rad.

Per-group specs set :attr:`GripperProblem.residual_fold_groups`, which the gripper model
applies as residual folds of the base and arm hinges (with equal group values it reproduces
``GripperProblem(residual_fold=r)`` bit for bit; tested).
"""

from __future__ import annotations

import itertools
import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING

import numpy as np

from simulator import ParameterError

from ..devices import gripper as _gr
from ..core.points import design_list, evaluate_points
from ..core.problem import DesignProblem, EvaluationOutcome
from ..devices.gripper_problem import GripperProblem

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["CREASE_GROUPS", "residual_fold_grid", "with_residual_fold",
           "sweep_residual_fold", "RobustGripperProblem", "TIMING_COLUMNS"]

logger = logging.getLogger(__name__)

#: Actuated crease groups of the gripper (0-based crease ids), i.e. its two heater circuits.
CREASE_GROUPS = {"base": _gr.BASE_CREASES, "arm": _gr.ARM_CREASES}
#: Columns of the sweep table that differ from run to run (excluded from comparisons).
TIMING_COLUMNS = ("wall_time [s]",)
_MAX_RESIDUAL = math.pi / 2


def _deg(rad: float) -> float:
    """Degrees, rounded to 1e-10 deg so that -10 deg reads -10 (radians -> degrees is inexact)."""
    return round(math.degrees(rad), 10)


def residual_fold_grid(values_deg, creases=None) -> list:
    """Residual-fold specs on a grid.

    Parameters
    ----------
    values_deg : sequence of float or mapping {group: sequence of float}
        Residual folds [deg]. A mapping gives each group its own values (product grid).
    creases : None, "all" or sequence of group names
        With a sequence of values: ``None``/``"all"``: the same value on all actuated creases;
        group names (e.g. ``("base", "arm")``): the product of the values over these groups.

    Returns
    -------
    list of dict
        Specs ``{"all": rad}`` or ``{group: rad, ...}`` (radians); products vary the last
        group fastest.
    """
    if isinstance(values_deg, Mapping):
        if creases not in (None, "all"):
            raise ParameterError("residual_fold_grid: give either a mapping {group: values} or "
                                 "values with creases=groups, not both.")
        groups, lists = list(values_deg), [list(v) for v in values_deg.values()]
    else:
        vals = list(np.atleast_1d(np.asarray(values_deg, dtype=float)))
        if creases is None or creases == "all":
            return [_normalize_spec({"all": math.radians(v)}) for v in vals]
        groups = [creases] if isinstance(creases, str) else list(creases)
        lists = [vals] * len(groups)
    if not groups or any(not v for v in lists):
        raise ParameterError("residual_fold_grid: every group needs at least one value.")
    return [_normalize_spec({g: math.radians(float(v)) for g, v in zip(groups, combo)})
            for combo in itertools.product(*lists)]


def _normalize_spec(spec) -> dict:
    """Validated spec dict (rad), groups in :data:`CREASE_GROUPS` order."""
    if not isinstance(spec, Mapping):
        spec = {"all": spec}
    spec = {str(k): v for k, v in spec.items()}
    names = ("all",) if "all" in spec else tuple(g for g in CREASE_GROUPS if g in spec)
    if set(names) != set(spec) or not names:
        raise ParameterError(f"residual fold spec {spec!r}: use {{'all': rad}} or crease groups "
                             f"{', '.join(CREASE_GROUPS)} (not both).")
    out = {}
    for g in names:
        v = float(spec[g])
        if not (math.isfinite(v) and abs(v) <= _MAX_RESIDUAL):
            raise ParameterError(f"residual fold {g} = {spec[g]!r} rad must be finite and within "
                                 "+-pi/2 (give radians; residual_fold_grid takes degrees).")
        out[g] = v
    return out


def _label(spec: dict) -> str:
    if "all" in spec:
        return f"{_deg(spec['all']):g}deg"
    return ",".join(f"{g}={_deg(v):g}deg" for g, v in spec.items())


def with_residual_fold(problem, spec):
    """The problem evaluated at a residual-fold spec.

    ``{"all": r}`` (or a number) replaces the ``residual_fold`` field of any dataclass
    problem that has one (clearing per-group values of a :class:`GripperProblem`); per-group
    specs set :attr:`GripperProblem.residual_fold_groups`.
    """
    spec = _normalize_spec(spec)
    if "all" in spec:
        if not any(f.name == "residual_fold" for f in fields(problem)):
            raise ParameterError(f"{type(problem).__name__} has no residual_fold to vary.")
        extra = {"residual_fold_groups": ()} if isinstance(problem, GripperProblem) else {}
        return replace(problem, residual_fold=spec["all"], **extra)
    if not isinstance(problem, GripperProblem):
        raise ParameterError(f"per-group residual folds need a GripperProblem; got "
                             f"{type(problem).__name__}.")
    return replace(problem, residual_fold_groups=tuple(spec.items()))


def _stage_power(ev, key):
    """Stage power [mW] from the metrics; None when the stage was not met."""
    v = ev.metrics.get(key)
    return v if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def _nan(v) -> float:
    """A table cell: None (not met) becomes NaN, written as an empty CSV cell."""
    return math.nan if v is None else v


def _row(problem, x: dict, spec: dict, columns: list, ev) -> dict:
    space = problem.space
    row = {f"{n} [{space[n].display_unit}]": v * space[n].display_scale for n, v in x.items()}
    if columns == ["all"]:
        row["residual_fold [deg]"] = _deg(spec["all"])
    else:
        for g in columns:
            row[f"residual_fold {g} [deg]"] = _deg(spec.get(g, spec.get("all", getattr(
                problem, "residual_fold", 0.0))))
    m = ev.metrics
    row.update({"success": ev.success, "status": ev.status, "feasible": ev.feasible,
                "assembly_power [mW]": _nan(_stage_power(ev, "assembly_power [mW]")),
                "grip_power [mW]": _nan(_stage_power(ev, "grip_power [mW]")),
                "total_power [mW]": 1e3 * ev.objective if ev.success else math.nan,
                "temperature [degC]": m.get("temperature [degC]", math.nan),
                "temperature_limit [degC]": getattr(problem, "temperature_limit", math.nan),
                "assembly_temperature [degC]": m.get("assembly_temperature [degC]", math.nan),
                "grip_temperature [degC]": m.get("grip_temperature [degC]", math.nan),
                "max_crease_temperature [degC]": m.get("max_crease_temperature [degC]",
                                                       math.nan),
                "simulations": m.get("assembly_simulations", 0) + m.get("grip_simulations", 0)})
    for name in ["temperature"] + list(space.bound_margins(x)):
        row[f"margin {name} [-]"] = -ev.constraints.get(name, math.nan)
    row.update({"message": ev.message, "wall_time [s]": ev.wall_time})
    return row


def sweep_residual_fold(problem, designs, residual_folds, executor=None, log=None,
                        progress=None) -> pd.DataFrame:
    """Evaluate every design at every residual fold.

    Parameters
    ----------
    problem : GripperProblem (or a dataclass problem with ``residual_fold``)
        Its own ``residual_fold`` is replaced by the swept values.
    designs : mapping, vector, sequence of them, or None (the start design)
    residual_folds : sequence of specs
        From :func:`residual_fold_grid`, or numbers [rad].
    executor : Executor, optional
        Default serial; not closed here.
    log : str or os.PathLike, optional
        Evaluation log CSV (:class:`~design.core.evaluation_log.EvaluationLog`, one settings hash
        per residual fold): logged points are reused, each new one is appended as soon as it
        finishes (on every executor), so an interrupted sweep resumes where it stopped. A
        point whose worker died more often than the executor retries it is a failed row
        (message ``"not evaluated: ..."``), not logged, and the sweep goes on.
    progress : callable, optional
        ``progress(done, total)`` as points complete (points computed, not reused).

    Returns
    -------
    pandas.DataFrame
        One row per (design, residual fold), designs outer, residual folds inner: design
        variables in display units (``W [um]``), ``residual_fold [deg]`` (or
        ``residual_fold <group> [deg]`` per group), ``success`` (the point was evaluated),
        ``status`` (``feasible``, ``infeasible``, ``not_met``: a criterion not met below the
        power cap, ``failed``: a simulation failure), ``feasible``, stage and total powers
        [mW] (NaN, an empty CSV cell, when not met), temperatures [degC],
        ``margin <constraint> [-]``
        (``-g``, positive when satisfied), ``simulations``, ``message`` (of an infeasible point:
        the crease, its temperature and the limit, e.g. ``both stages met; not feasible: crease
        2: centre-line mean 281.02 degC > 1.2 T_g = 252 degC``), ``wall_time [s]``.
        Everything except :data:`TIMING_COLUMNS` is the same whatever the executor.
    """
    import pandas as pd

    specs = [_normalize_spec(s) for s in residual_folds]
    if not specs:
        raise ParameterError("sweep_residual_fold: no residual folds given.")
    xs = design_list(problem.space, designs)
    probs = [with_residual_fold(problem, s) for s in specs]
    points = [(x, j) for x in xs for j in range(len(specs))]        # designs outer
    logger.info("residual-fold sweep: %d designs x %d residual folds on %r", len(xs),
                len(specs), executor)
    evs = evaluate_points([(probs[j], x) for x, j in points], executor, progress, log)
    columns = ["all"] if all("all" in s for s in specs) else list(CREASE_GROUPS)
    return pd.DataFrame([_row(probs[j], x, specs[j], columns, ev)
                         for (x, j), ev in zip(points, evs)])


@dataclass(frozen=True)
class RobustGripperProblem(DesignProblem):
    """Worst case over a residual-fold range.

    Objective: the largest total power [W] over the residual folds. Constraints: the size
    bounds and ``temperature`` = the largest temperature constraint over the residual folds
    (the limit must hold at every one; the message of an infeasible design names, per residual
    fold above the limit, the crease, its temperature and the limit). Not successful if any
    residual fold is not (message names them; status ``"failed"`` if a simulation failed at
    one, else ``"not_met"``).
    Metrics per residual fold: ``total_power@-10deg [mW]``, ``assembly_power@... [mW]``,
    ``grip_power@... [mW]``, ``temperature@... [degC]`` (``@base=-10deg,arm=0deg`` per
    group; powers None when not met), plus the worst ``total_power [mW]`` and
    ``temperature [degC]``. The residual folds are evaluated
    one after the other in the calling process; parallelise over designs (e.g.
    ``executor.map(robust.evaluate, designs)``).

    Parameters
    ----------
    base_problem : GripperProblem
    residual_folds : sequence of specs
        From :func:`residual_fold_grid`, or numbers [rad].
    """

    base_problem: GripperProblem
    residual_folds: tuple
    name: str = "robust_gripper"
    report_metric = "temperature [degC]"      # the worst case, per cycle of cd
    _problems: tuple = field(init=False, repr=False, compare=False, default=())

    def __post_init__(self):
        specs = tuple(tuple(_normalize_spec(s).items()) for s in self.residual_folds)
        if not specs:
            raise ParameterError("RobustGripperProblem needs at least one residual fold.")
        object.__setattr__(self, "residual_folds", specs)
        object.__setattr__(self, "_problems", tuple(
            (_label(dict(s)), with_residual_fold(self.base_problem, dict(s))) for s in specs))

    @property
    def space(self):
        return self.base_problem.space

    def _evaluate(self, values):
        evs = [(label, p.evaluate(values)) for label, p in self._problems]
        metrics, temps = {}, []
        for label, ev in evs:
            metrics[f"total_power@{label} [mW]"] = 1e3 * ev.objective if ev.success else None
            for key in ("assembly_power", "grip_power"):
                metrics[f"{key}@{label} [mW]"] = _stage_power(ev, f"{key} [mW]")
            metrics[f"temperature@{label} [degC]"] = ev.metrics.get("temperature [degC]",
                                                                    math.nan)
            if "temperature" in ev.constraints:
                temps.append(ev.constraints["temperature"])
        bad = [(label, ev) for label, ev in evs if not ev.success]
        objective = max(ev.objective for _, ev in evs)
        metrics["total_power [mW]"] = None if bad else 1e3 * objective
        metrics["temperature [degC]"] = max([ev.metrics["temperature [degC]"] for _, ev in evs
                                             if "temperature [degC]" in ev.metrics],
                                            default=math.nan)
        constraints = dict(self.space.bound_margins(values))
        if temps:
            constraints["temperature"] = max(temps)
        hot = [f"residual fold {label}: {ev.message}" for label, ev in evs
               if ev.success and not ev.feasible]          # names crease, temperature, limit
        message = ("; ".join(f"residual fold {label}: {ev.message}" for label, ev in bad)
                   if bad else "; ".join([f"all {len(evs)} residual folds met"] + hot))
        failure = None if not bad else ("failed" if any(ev.status == "failed" for _, ev in bad)
                                        else "not_met")
        return EvaluationOutcome(math.inf if bad else objective, constraints, metrics, failure,
                                 message)

    def settings(self) -> dict:
        return {"problem": self.name, "aggregate": "max over residual folds",
                "residual_folds": [_label(dict(s)) for s in self.residual_folds],
                "base": self.base_problem.settings()}
