"""Gripper yield under fabrication uncertainty: sample sweeps and a robust design problem.

:class:`GripperSampleProblem` evaluates one gripper design at one sample of the uncertain
parameters (the design variables and the sampled parameters form one design vector, so one
:class:`~design.core.evaluation_log.EvaluationLog` serves every design and sample).
:func:`sweep_uncertainty` evaluates designs x samples with any executor, logging each point as
it finishes; :func:`summarize_yield` gives per design the yield (both stages met with
``T <= 1.2 T_g``; Wilson interval), power quantiles and the inputs' rank correlations.
:class:`RobustYieldProblem` minimises a power quantile subject to a yield target over a fixed
sample table (common random numbers: every design sees the same samples, so the objective does
not jump from design to design with the sampling noise).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from simulator import ParameterError

from ..core.points import design_list, evaluate_points
from ..core.problem import DesignProblem, EvaluationOutcome
from ..devices.gripper_problem import GripperProblem
from ..core.space import DesignSpace, Variable
from .uncertainty import PARAMETERS, FabricationScenario, quantile, rank_correlations, \
    wilson_interval

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["GripperSampleProblem", "sweep_uncertainty", "summarize_yield", "input_columns",
           "RobustYieldProblem", "sample_category", "CATEGORIES"]

logger = logging.getLogger(__name__)

_DESIGN_FIELDS = ("t_gold", "t_su8", "delta_alpha", "env_conductivity")


def _variable(name: str, base: GripperProblem) -> Variable:
    unit, shown, scale, lo, hi = PARAMETERS[name]
    return Variable(name, lo, hi, (hi - lo) / 100, _nominal(base, name), unit, scale, shown)


def _nominal(problem: GripperProblem, name: str) -> float:
    """The problem's own value of an uncertain parameter [SI]."""
    design = problem.design({})
    if name in _DESIGN_FIELDS:
        return float(getattr(design, name))
    if name.startswith("residual_fold_c"):
        return float(design.crease_residual_folds()[int(name[len("residual_fold_c"):])])
    return float(problem.group_folds()["arm" if name.endswith("arm") else "base"]
                 if name != "residual_fold" else problem.residual_fold)


def with_parameters(problem: GripperProblem, values: dict) -> GripperProblem:
    """The gripper problem with uncertain parameters set (SI values by name)."""
    base, groups, creases = problem.base, dict(problem.residual_fold_groups), {}
    fold = problem.residual_fold
    for name, v in values.items():
        if name in _DESIGN_FIELDS:
            base = replace(base, **{name: float(v)})
        elif name.startswith("residual_fold_c"):
            creases[int(name[len("residual_fold_c"):])] = float(v)
        elif name == "residual_fold":
            fold = float(v)
        else:
            groups[name[len("residual_fold_"):]] = float(v)
    if creases:
        base = replace(base, residual_fold_creases=tuple(
            {**dict(base.residual_fold_creases), **creases}.items()))
    return replace(problem, base=base, residual_fold=fold,
                   residual_fold_groups=tuple(groups.items()))


@dataclass(frozen=True)
class GripperSampleProblem(DesignProblem):
    """The gripper problem over the design variables and the uncertain parameters.

    ``evaluate(x)`` with ``x`` = design variables (W, La, L1, L2) then ``parameters`` (SI) is
    ``with_parameters(base, ...).evaluate(design)``: the same objective, constraints (size
    bounds of the design variables and the temperature limit) and metrics.
    """

    base: GripperProblem
    parameters: tuple
    name: str = "gripper_sample"
    report_metric = "temperature [degC]"
    _space: DesignSpace = field(init=False, repr=False, compare=False, default=None)

    def __post_init__(self):
        unknown = [p for p in self.parameters if p not in PARAMETERS]
        if unknown:
            raise ParameterError(f"GripperSampleProblem: parameters {unknown} unknown; use "
                                 f"{', '.join(PARAMETERS)}.")
        object.__setattr__(self, "parameters", tuple(self.parameters))
        object.__setattr__(self, "_space", DesignSpace(
            list(self.base.space.variables) + [_variable(p, self.base) for p in self.parameters]))

    @property
    def space(self):
        return self._space

    def _evaluate(self, values):
        design = {n: values[n] for n in self.base.space.names}
        params = {p: values[p] for p in self.parameters}
        return with_parameters(self.base, params)._evaluate(design)

    def settings(self) -> dict:
        return {"problem": self.name, "parameters": list(self.parameters),
                "base": self.base.settings()}


def input_columns(scenario: FabricationScenario) -> list:
    """Table columns of the sampled inputs (display units)."""
    return [i.column for i in scenario.inputs]


#: What became of one sample (column ``category``): it works, or why not. "solver failed" is
#: no verdict on the device (the simulation lost its path), so the yield leaves it out.
CATEGORIES = ("works", "too hot", "target not met", "solver failed", "outside bounds")


def sample_category(ev) -> str:
    """The :data:`CATEGORIES` entry of one sample's evaluation: ``works`` (feasible),
    ``too hot`` (both stages met above the temperature limit), ``target not met`` (a stage
    not met below the power cap), ``solver failed`` (a simulation failed), ``outside
    bounds`` (met, cool enough, but a size bound violated)."""
    if ev.feasible:
        return "works"
    if ev.status == "not_met":
        return "target not met"
    if not ev.success:
        return "solver failed"
    return "too hot" if ev.constraints.get("temperature", 0.0) > 0 else "outside bounds"


def _row(problem: GripperSampleProblem, scenario, design: dict, k: int, ev) -> dict:
    space = problem.space
    row = {f"{n} [{space[n].display_unit}]": design[n] * space[n].display_scale
           for n in problem.base.space.names}
    row["sample"] = k
    for inp in scenario.inputs:
        row[inp.column] = ev.x[inp.parameter] * PARAMETERS[inp.parameter][2]
    m = ev.metrics
    row.update({"success": ev.success, "status": ev.status, "works": ev.feasible,
                "category": sample_category(ev),
                "total_power [mW]": 1e3 * ev.objective if ev.success else math.nan,
                "assembly_power [mW]": _power(m, "assembly_power [mW]"),
                "grip_power [mW]": _power(m, "grip_power [mW]"),
                "temperature [degC]": m.get("temperature [degC]", math.nan),
                "message": ev.message, "wall_time [s]": ev.wall_time})
    return row


def _power(metrics, key) -> float:
    v = metrics.get(key)
    return v if isinstance(v, float) else math.nan


def sweep_uncertainty(problem: GripperProblem, scenario: FabricationScenario, samples,
                      designs=None, executor=None, log=None, progress=None,
                      retry: GripperProblem | None = None) -> pd.DataFrame:
    """Evaluate every design at every sample of the scenario.

    Parameters
    ----------
    problem : GripperProblem
        Nominal problem (mode, temperature limit, power cap, unsampled parameters).
    scenario : FabricationScenario
    samples : DataFrame
        From ``scenario.sample(n, seed, method)`` (columns: the scenario's parameters, SI).
    designs : mapping, vector, sequence of them, or None (the start design)
    executor : Executor, optional
        Default serial; not closed here.
    log : path, optional
        Evaluation log CSV: logged points are reused, each new point is appended as soon as
        it finishes. Identical points (e.g. every sample with the uncertainty off) are
        evaluated once.
    progress : callable, optional
        ``progress(done, total)`` over the points computed.
    retry : GripperProblem, optional
        Problem (e.g. ``replace(problem, power_step=..., max_power_step=...)``: smaller power
        steps) that evaluates once more every point whose simulation failed; its result
        replaces the first one (column ``attempts`` = 2). Retries are not logged.

    Returns
    -------
    DataFrame
        One row per (design, sample), designs outer: design variables [um], ``sample``, the
        sampled inputs (display units: deg, um, ppm/K, W/(m K)), ``success``, ``status``,
        ``works`` (both stages met and ``T <= T_limit``), ``category``
        (:func:`sample_category`), powers [mW] (empty when not met), ``temperature [degC]``,
        ``message``, ``wall_time [s]``, ``attempts`` (1, or 2 when retried).
    """
    import pandas as pd

    point = GripperSampleProblem(problem, scenario.parameters)
    missing = [p for p in scenario.parameters if p not in samples.columns]
    if missing:
        raise ParameterError(f"sweep_uncertainty: samples lack columns {missing}.")
    xs = design_list(problem.space, designs)
    params = samples[list(scenario.parameters)].to_numpy(dtype=float)
    vecs = [np.concatenate([problem.space.to_vector(x), p]) for x in xs for p in params]
    logger.info("uncertainty sweep: %d designs x %d samples on %r", len(xs), len(params),
                executor)
    evs = evaluate_points([(point, v) for v in vecs], executor, progress, log)
    retried = _retry_failed(retry, scenario, evs, vecs, executor)
    n = len(params)
    rows = [_row(point, scenario, xs[i // n], i % n, ev) for i, ev in enumerate(evs)]
    for i, row in enumerate(rows):
        row["attempts"] = 2 if i in retried else 1
    return pd.DataFrame(rows)


def _retry_failed(retry, scenario, evs: list, vecs, executor) -> set:
    """Evaluate the failed points of ``evs`` again with the ``retry`` problem (in place: the
    retry's evaluation replaces the first); returns the indices retried."""
    if retry is None:
        return set()
    point = GripperSampleProblem(retry, scenario.parameters)
    failed = [i for i, ev in enumerate(evs) if ev.status == "failed"]
    logger.info("uncertainty sweep: retrying %d failed points with smaller power steps",
                len(failed))
    for i, ev in zip(failed, evaluate_points([(point, vecs[i]) for i in failed], executor)):
        evs[i] = ev
    return set(failed)


def summarize_yield(table: pd.DataFrame, scenario: FabricationScenario,
                    quantiles=(0.5, 0.9), confidence: float = 0.95, by=()) -> tuple:
    """Per design: yield and power spread; per design and input: rank correlations.

    ``by``: further columns that tell designs apart (e.g. a ``design`` label column, so that
    two labels with equal variables stay two rows).

    Returns
    -------
    summary : DataFrame
        One row per design: the design [um], ``samples``, ``solver_failed`` (samples whose
        simulation failed: no verdict on the device), ``yield [-]`` (share of working devices
        among the other, evaluated samples), ``yield_low [-]``, ``yield_high [-]`` (Wilson
        interval at ``confidence``), ``power_q<q> [mW]`` (quantiles
        of the total power, unmet samples counted as infinite: empty when the quantile is not
        met), ``power_mean [mW]`` and ``power_std [mW]`` (over the samples that met both
        stages), ``temperature_max [degC]``.
    sensitivity : DataFrame
        Per design, input and output (``total_power [mW]``, ``temperature [degC]``):
        Spearman's rho with its Fisher-z interval (:func:`rank_correlations`).
    """
    import pandas as pd

    dcols = list(by) + [c for c in table.columns if c.split(" ")[0] in ("W", "La", "L1", "L2")]
    rows, sens = [], []
    for values, group in table.groupby(dcols, sort=False):
        n, ok = len(group), int(group["works"].sum())
        failed = int((~group["success"].astype(bool) & (group["status"] == "failed")).sum())
        judged = n - failed
        low, high = wilson_interval(ok, judged, confidence) if judged else (math.nan,) * 2
        row = dict(zip(dcols, values))
        row.update({"samples": n, "solver_failed": failed,
                    "yield [-]": ok / judged if judged else math.nan, "yield_low [-]": low,
                    "yield_high [-]": high})
        for q in quantiles:
            v = quantile(group["total_power [mW]"], q)
            row[f"power_q{q:g} [mW]"] = v if math.isfinite(v) else math.nan
        met = group["total_power [mW]"].dropna()
        row.update({"power_mean [mW]": met.mean() if len(met) else math.nan,
                    "power_std [mW]": met.std(ddof=1) if len(met) > 1 else math.nan,
                    "temperature_max [degC]": group["temperature [degC]"].max()})
        rows.append(row)
        for out in ("total_power [mW]", "temperature [degC]"):
            s = rank_correlations(group, input_columns(scenario), out, confidence)
            sens.append(s.assign(**dict(zip(dcols, values))))
    sensitivity = pd.concat(sens, ignore_index=True) if sens else pd.DataFrame()
    if len(sensitivity):
        sensitivity = sensitivity[dcols + [c for c in sensitivity.columns if c not in dcols]]
    return pd.DataFrame(rows), sensitivity


@dataclass(frozen=True)
class RobustYieldProblem(DesignProblem):
    """Minimise a quantile of the total power subject to a yield target.

    Every design is evaluated at the same ``samples`` samples of the scenario (drawn once
    from ``seed``: common random numbers), one after the other in the calling process
    (parallelise over designs). Objective: the ``q`` quantile of the total power [W] (unmet
    samples count as infinite; if the quantile is unmet the evaluation is ``not_met``).
    Constraints: the size bounds and ``yield`` = ``yield_target - yield`` (<= 0 when met).

    Parameters
    ----------
    base : GripperProblem
    scenario : FabricationScenario
    samples : int
    seed : int
    method : {"mc", "lhs"}
    q : float
        Power quantile (0 < q < 1).
    yield_target : float
        Required share of working devices (0 < target <= 1).
    """

    base: GripperProblem
    scenario: FabricationScenario
    samples: int = 8
    seed: int = 0
    method: str = "lhs"
    q: float = 0.9
    yield_target: float = 0.9
    name: str = "robust_yield"
    report_metric = "temperature [degC]"
    _table: tuple = field(init=False, repr=False, compare=False, default=())

    def __post_init__(self):
        if not 0 < self.q < 1:
            raise ParameterError(f"RobustYieldProblem.q = {self.q!r} must be in (0, 1).")
        if not 0 < self.yield_target <= 1:
            raise ParameterError(f"RobustYieldProblem.yield_target = {self.yield_target!r} "
                                 "must be in (0, 1].")
        table = self.scenario.sample(self.samples, self.seed, self.method)
        object.__setattr__(self, "_table", tuple(map(tuple, table.to_numpy(dtype=float))))

    @property
    def space(self):
        return self.base.space

    def _evaluate(self, values):
        point = GripperSampleProblem(self.base, self.scenario.parameters)
        x = [values[n] for n in self.space.names]
        evs = [point.evaluate(x + list(p)) for p in self._table]
        works = sum(ev.feasible for ev in evs)
        powers = [ev.objective if ev.success else math.inf for ev in evs]
        objective = quantile(powers, self.q)
        fraction = works / len(evs)
        low, high = wilson_interval(works, len(evs))
        constraints = dict(self.space.bound_margins(values))
        constraints["yield"] = self.yield_target - fraction
        metrics = {"yield [-]": fraction, "yield_low [-]": low, "yield_high [-]": high,
                   f"power_q{self.q:g} [mW]": 1e3 * objective if math.isfinite(objective)
                   else None, "samples": len(evs),
                   "temperature [degC]": max((ev.metrics.get("temperature [degC]", -math.inf)
                                              for ev in evs), default=math.nan)}
        met = sum(ev.success for ev in evs)
        if not math.isfinite(objective):
            return EvaluationOutcome(
                math.inf, constraints, metrics, "not_met",
                f"power quantile {self.q:g} not met: {len(evs) - met} of {len(evs)} samples "
                "did not meet both stages")
        return EvaluationOutcome(objective, constraints, metrics, None,
                                 f"yield {works}/{len(evs)}, {met} met both stages")

    def settings(self) -> dict:
        return {"problem": self.name, "scenario": self.scenario.to_dict(),
                "samples": self.samples, "seed": self.seed, "method": self.method,
                "q": self.q, "yield_target": self.yield_target, "base": self.base.settings()}
