"""Optimisers behind one entry point: ``optimize(problem, method, ...)``.

* ``"cd"`` (``"coordinate_descent"``): the paper's fixed-step coordinate descent (method
  digest 8.7, GripperOptimization.m) with correct bound checks. Coordinates in space order;
  for each, the minus candidate (if inside the bounds), then the plus candidate; a candidate
  is accepted when it is feasible and its objective strictly lower than the current one, and
  the move applies at once. A cycle without a move ends the search (``"converged"``), else
  after ``max_cycles`` (15) cycles (``"max_cycles"``). Candidates lie on the lattice
  ``x0 + k step``. With ``parallel_candidates`` both candidates of a coordinate are computed
  side by side on the executor (:meth:`~design.evaluation_log.EvaluationRun.prefetch`) and
  enter the run in the serial order: history, evaluations and result are the serial run's; a
  plus candidate not needed (the minus one was accepted) is dropped.
* NLopt derivative-free methods in normalised variables ``z in [0, 1]^n``: ``"cobyla"``
  (LN_COBYLA, constraints passed to NLopt), ``"bobyqa"``, ``"neldermead"``, ``"sbplx"``
  (constraints by an exact penalty or NLopt's AUGLAG) and ``"direct"`` (GN_DIRECT_L, global,
  penalty). Bounds, tolerances and an evaluation budget are always set. The wrapper never lets
  an exception escape into NLopt: a failed evaluation returns a finite penalty and counts as
  infeasible; a stop request uses ``opt.force_stop()``. Each design is evaluated once per run
  (objective and constraint callbacks share a cache). The returned design is the best
  *feasible* evaluation seen, not NLopt's last point.

With ``out``, evaluations go to ``out/evaluations.csv`` (see :mod:`design.evaluation_log`),
and re-running the same command reuses them: an interrupted run resumes and, the methods being
deterministic, ends at the same result. ``out/result.json``, ``out/history.csv`` and, for
coordinate descent, ``out/cycles.csv`` are written at the end.
"""

from __future__ import annotations

import json
import logging
import math
import os
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from simulator.errors import ParameterError

from .evaluation_log import (BudgetExhausted, EvaluationLog, EvaluationRun, LoggedProblem,
                             settings_hash)
from ._contract import check_outcome
from .problem import Evaluation

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["optimize", "OptimizationResult", "StopOptimization", "METHODS"]

logger = logging.getLogger(__name__)

_NLOPT = {"cobyla": "LN_COBYLA", "bobyqa": "LN_BOBYQA", "neldermead": "LN_NELDERMEAD",
          "sbplx": "LN_SBPLX", "direct": "GN_DIRECT_L"}
_ALIASES = {"coordinate_descent": "cd", "nelder-mead": "neldermead", "nelder_mead": "neldermead",
            "subplex": "sbplx", "direct_l": "direct"}
#: Accepted method names (aliases included).
METHODS = ("cd",) + tuple(_NLOPT) + tuple(_ALIASES)
_CD_OPTIONS = {"max_cycles": 15, "parallel_candidates": False, "metric": "temperature [degC]"}
_NLOPT_OPTIONS = {"xtol_rel": 1e-4, "ftol_rel": 1e-6, "xtol_abs": 1e-6, "ftol_abs": 0.0,
                  "initial_step": None, "constraint_handling": None, "penalty": 100.0,
                  "failure_value": None, "max_time": None}


class StopOptimization(Exception):
    """Raise from a ``callback`` to stop an optimisation and return its result so far."""


@dataclass(frozen=True, eq=False)
class OptimizationResult:
    """Outcome of :func:`optimize`.

    Attributes
    ----------
    method : str
    x : dict
        Best feasible design (SI); the least-violating one if none was feasible.
    objective : float
        Its objective (``inf`` when no evaluation succeeded).
    constraints : dict
    success : bool
        A feasible design was found (``x`` satisfies every constraint). Whatever stopped the
        run (``status``), the best feasible design seen is returned; a run that stopped on
        its budget still succeeds if it found one.
    status : str
        Why the run stopped: ``converged``, ``max_cycles`` (cd); ``success``,
        ``xtol_reached``, ``ftol_reached``, ``roundoff_limited``, ``failure`` ... (NLopt);
        ``max_evaluations``, ``stopped``.
    message : str
    n_evaluations, n_computed, n_reused : int
        Distinct designs of the run; computed now; served from the log.
    wall_time : float [s]
    history : pandas.DataFrame
        One row per evaluation, in order (``reused`` marks those from the log).
    best : Evaluation or None
    cycles : pandas.DataFrame or None
        Coordinate descent: one row per cycle (row 0 is the start).
    options : dict
    """

    method: str
    x: dict
    objective: float
    constraints: dict
    success: bool
    status: str
    message: str
    n_evaluations: int
    n_computed: int
    n_reused: int
    wall_time: float
    history: pd.DataFrame
    best: Evaluation | None
    cycles: pd.DataFrame | None = None
    options: dict = field(default_factory=dict)

    def __post_init__(self):
        check_outcome(self)

    def to_dict(self) -> dict:
        """JSON-ready summary (non-finite numbers become None)."""
        def clean(v):
            if isinstance(v, dict):
                return {k: clean(u) for k, u in v.items()}
            if isinstance(v, (bool, np.bool_, int, np.integer)):
                return v.item() if isinstance(v, np.generic) else v
            if isinstance(v, (float, np.floating)):
                return float(v) if math.isfinite(v) else None
            if isinstance(v, (list, tuple, np.ndarray)):
                return [clean(u) for u in v]
            return v if isinstance(v, (str, type(None))) else repr(v)
        d = {k: getattr(self, k) for k in ("method", "success", "status", "message", "x",
                                           "objective", "constraints", "n_evaluations",
                                           "n_computed", "n_reused", "wall_time", "options")}
        if self.best is not None:
            d.update(metrics=self.best.metrics, best_message=self.best.message)
        return clean(d)


def _x_columns(space, x) -> dict:
    return {f"x.{v.name} [{v.unit}]": float(u) for v, u in zip(space.variables, x)}


def _coordinate_descent(run: EvaluationRun, x0, max_cycles=15, parallel_candidates=False,
                        metric="temperature [degC]"):
    space = run.space
    if not (isinstance(max_cycles, int) and max_cycles >= 1):
        raise ParameterError(f"max_cycles = {max_cycles!r} must be a positive integer.")
    tol = 1e-9 * (space.upper - space.lower)
    k = np.zeros(len(space), dtype=int)

    def point(kk):
        return np.clip(x0 + kk * space.step, space.lower, space.upper)

    def inside(kk, i):
        v = x0[i] + kk[i] * space.step[i]
        return space.lower[i] - tol[i] <= v <= space.upper[i] + tol[i]

    def row(cycle, moved, last, complete=True):
        m = lambda e: np.nan if e is None else e.metrics.get(metric, np.nan)
        return {"cycle": cycle, "moved": ";".join(moved), "complete": complete,
                **_x_columns(space, point(k)), "objective": current.objective,
                "feasible": current.feasible, f"last_candidate.{metric}": m(last),
                f"current.{metric}": m(current), "n_evaluations": len(run.evaluations)}

    cycles, status = [], "max_cycles"
    try:
        current = run.evaluate(point(k))
    except BudgetExhausted:  # pragma: no cover - budget >= 1 is enforced
        return [], "max_evaluations", "no evaluation allowed"
    cycles.append(row(0, [], None))
    for cycle in range(1, max_cycles + 1):
        moved, last = [], None
        try:
            for i, name in enumerate(space.names):
                cands = []
                for d in (-1, 1):
                    kk = k.copy()
                    kk[i] += d
                    if inside(kk, i):
                        cands.append((d, kk))
                if parallel_candidates and len(cands) > 1:
                    run.prefetch([point(c) for _, c in cands])   # side by side, kept aside
                for d, kk in cands:
                    last = run.evaluate(point(kk))
                    if last.feasible and last.objective < current.objective:
                        k, current = kk, last
                        moved.append(f"{name}{'-' if d < 0 else '+'}")
                        break
        except (BudgetExhausted, StopOptimization) as exc:
            cycles.append(row(cycle, moved, last, complete=False))
            if isinstance(exc, StopOptimization):
                return cycles, "stopped", f"stopped by the callback in cycle {cycle}: {exc}"
            return cycles, "max_evaluations", (f"evaluation budget ({run.budget}) exhausted in "
                                               f"cycle {cycle}")
        cycles.append(row(cycle, moved, last))
        if not moved:
            status = "converged"
            break
    msg = (f"no coordinate moved in cycle {len(cycles) - 1}" if status == "converged" else
           f"cycle limit ({max_cycles}) reached; the last cycle still moved")
    return cycles, status, msg


def _nlopt_codes(nlopt):
    return {nlopt.SUCCESS: ("success", "NLopt reported success"),
            nlopt.STOPVAL_REACHED: ("stopval_reached", "objective reached stopval"),
            nlopt.FTOL_REACHED: ("ftol_reached", "objective change below ftol_rel/ftol_abs"),
            nlopt.XTOL_REACHED: ("xtol_reached", "step below xtol_rel/xtol_abs"),
            nlopt.MAXEVAL_REACHED: ("max_evaluations", "evaluation budget reached"),
            nlopt.MAXTIME_REACHED: ("max_time", "time limit reached")}


def _nlopt_initial_step(space, method, o) -> np.ndarray:
    """Check the NLopt options of ``method`` and return the normalised initial step."""
    handling = o["constraint_handling"]
    allowed = {"cobyla": ("native", "penalty"), "direct": ("penalty",)}.get(
        method, ("penalty", "auglag"))
    if handling not in allowed:
        raise ParameterError(f"constraint_handling = {handling!r} is not available for "
                             f"{method!r}; use one of {allowed}.")
    for key in ("xtol_rel", "ftol_rel", "xtol_abs", "ftol_abs", "penalty"):
        if not (isinstance(o[key], (int, float)) and o[key] >= 0):
            raise ParameterError(f"{key} = {o[key]!r} must be a non-negative number.")
    span = space.upper - space.lower
    step = np.broadcast_to(np.asarray(space.step / span if o["initial_step"] is None
                                      else o["initial_step"], float), (len(space),)).copy()
    if not np.all(step > 0):
        raise ParameterError(f"initial_step = {o['initial_step']!r} must be positive "
                             "(normalised units, fraction of each variable's range).")
    return step


def _nlopt_constraint_names(run: EvaluationRun, x0, handling, bounds):
    """Constraint names passed to NLopt, from the start design (None: one aggregate)."""
    if handling not in ("native", "auglag"):
        return None
    first = run.evaluate(x0)
    names = [k for k in first.constraints if k not in bounds] or None
    return names if names is not None or not first.success else []


class _NloptCallbacks:
    """Objective and constraint callbacks for NLopt that never let an exception escape."""

    def __init__(self, run: EvaluationRun, names, bounds, penalised, o):
        self.run, self.names, self.bounds, self.penalised = run, names, bounds, penalised
        self.penalty, self.failure_value = o["penalty"], o["failure_value"]
        self.exc, self.ref, self.opt = None, None, None

    def _evaluate(self, z) -> Evaluation:
        """Evaluate the design at normalised ``z`` (clipped to the unit box)."""
        return self.run.evaluate(self.run.space.denormalize(np.clip(z, 0.0, 1.0)))

    def _value(self, ev) -> float:
        """Objective for NLopt: penalised if asked, a finite stand-in for a failure."""
        if ev.success and math.isfinite(ev.objective) and self.ref is None:
            self.ref = ev.objective
        ref = self.ref or 0.0
        scale = abs(ref) or 1.0
        if not ev.success or not math.isfinite(ev.objective):
            fv = self.failure_value
            return float(fv) if fv is not None else ref + 1e3 * scale
        if not self.penalised:
            return ev.objective
        viol = sum(max(0.0, g) for g in ev.constraints.values())
        return ev.objective + self.penalty * scale * viol

    def _constraint_values(self, ev) -> list:
        """Constraint values for NLopt (1 for each on a failed evaluation)."""
        if self.names is None:  # unknown names: one aggregated constraint
            g = [v for k, v in ev.constraints.items() if k not in self.bounds]
            return [1.0 if not ev.success else max(g, default=-1.0)]
        return [1.0 if not ev.success else float(ev.constraints.get(k, 0.0))
                for k in self.names]

    def _guarded(self, fn, fallback):
        """Call ``fn``; after any exception keep it, stop NLopt and use ``fallback``."""
        if self.exc is not None:
            return fallback()
        try:
            return fn()
        except BaseException as exc:  # noqa: BLE001 - nothing may escape into NLopt
            self.exc = exc
            self.opt.force_stop()
            return fallback()

    def objective(self, z, grad):
        """NLopt objective ``f(z, grad)``."""
        big = self.failure_value if self.failure_value is not None else 1e300
        return self._guarded(lambda: self._value(self._evaluate(z)), lambda: big)

    def constraints(self, result, z, grad):
        """NLopt vector constraint ``c(result, z, grad)``, ``result <= 0`` when feasible."""
        def fill():
            result[:] = self._constraint_values(self._evaluate(z))

        self._guarded(fill, lambda: result.__setitem__(slice(None), 1.0))


def _nlopt_optimizers(nlopt, method, n, handling, step, max_evaluations, o):
    """NLopt optimizer (and AUGLAG's local one) with bounds, tolerances and budgets set."""
    alg = getattr(nlopt, _NLOPT[method])
    opt = nlopt.opt(nlopt.AUGLAG if handling == "auglag" else alg, n)
    local = nlopt.opt(alg, n) if handling == "auglag" else None
    for p in filter(None, (opt, local)):
        p.set_lower_bounds(np.zeros(n))
        p.set_upper_bounds(np.ones(n))
        p.set_xtol_rel(o["xtol_rel"])
        p.set_xtol_abs(o["xtol_abs"])
        p.set_ftol_rel(o["ftol_rel"])
        p.set_ftol_abs(o["ftol_abs"])
        if method != "direct":
            p.set_initial_step(step)
    if local is not None:
        opt.set_local_optimizer(local)
    opt.set_maxeval(int(max_evaluations))
    if o["max_time"] is not None:
        opt.set_maxtime(float(o["max_time"]))
    return opt, local


def _nlopt_status(nlopt, opt, z0):
    """Run ``opt`` from ``z0``; return NLopt's outcome as ``(status, message)``."""
    codes = _nlopt_codes(nlopt)
    try:
        opt.optimize(z0)
        return codes.get(opt.last_optimize_result(), ("success", "NLopt finished"))
    except nlopt.RoundoffLimited:
        return "roundoff_limited", "NLopt: roundoff errors limited progress"
    except nlopt.ForcedStop:
        return "stopped", "stopped by the callback"
    except ValueError as exc:
        return "invalid_args", f"NLopt rejected the arguments: {exc}"
    except MemoryError:
        return "out_of_memory", "NLopt ran out of memory"
    except RuntimeError as exc:
        return "failure", f"NLopt failure: {exc}"


def _callback_status(exc, status, msg):
    """Let an exception caught in a callback override NLopt's outcome (or re-raise it)."""
    if isinstance(exc, BudgetExhausted):
        return "max_evaluations", "evaluation budget reached"
    if isinstance(exc, StopOptimization):
        return "stopped", f"stopped by the callback: {exc}"
    if exc is not None:
        raise exc
    return status, msg


def _run_nlopt(run: EvaluationRun, x0, method, max_evaluations, **o):
    """Run NLopt ``method`` in normalised variables; return ``(None, status, message)``."""
    import nlopt

    space, n = run.space, len(run.space)
    handling = o["constraint_handling"]
    step = _nlopt_initial_step(space, method, o)
    bounds = {f"{v}_{s}" for v in space.names for s in ("lower", "upper")}
    names = _nlopt_constraint_names(run, x0, handling, bounds)
    callbacks = _NloptCallbacks(run, names, bounds, handling == "penalty", o)
    opt, local = _nlopt_optimizers(nlopt, method, n, handling, step, max_evaluations, o)
    callbacks.opt = opt
    opt.set_min_objective(callbacks.objective)
    m = 1 if names is None else len(names)
    if handling in ("native", "auglag") and m:
        opt.add_inequality_mconstraint(callbacks.constraints, np.zeros(m))
    status, msg = _nlopt_status(nlopt, opt, space.normalize(x0))
    status, msg = _callback_status(callbacks.exc, status, msg)
    return None, status, f"{_NLOPT[method]}" + (" (AUGLAG)" if local else "") + f": {msg}"


def _resolve_method(method) -> str:
    """Canonical name of an optimisation ``method`` (aliases resolved)."""
    if not isinstance(method, str) or method.lower() not in METHODS:
        raise ParameterError(f"Unknown optimisation method {method!r}; use one of "
                             f"{', '.join(METHODS)}.")
    return _ALIASES.get(method.lower(), method.lower())


def _resolve_options(method, options, max_evaluations):
    """Check ``options`` and the budget of ``method``; return them with defaults filled in."""
    defaults = _CD_OPTIONS if method == "cd" else _NLOPT_OPTIONS
    unknown = sorted(set(options) - set(defaults))
    if unknown:
        raise ParameterError(f"Unknown option(s) {unknown} for method {method!r}; options: "
                             f"{', '.join(defaults)}.")
    opts = {**defaults, **options}
    if method != "cd" and opts["constraint_handling"] is None:
        opts["constraint_handling"] = "native" if method == "cobyla" else "penalty"
    if max_evaluations is None and method != "cd":
        max_evaluations = 60
    if max_evaluations is not None and not (isinstance(max_evaluations, (int, np.integer))
                                            and max_evaluations >= 1):
        raise ParameterError(f"max_evaluations = {max_evaluations!r} must be a positive integer.")
    return opts, max_evaluations


def _start_design(problem, x0) -> np.ndarray:
    """Check that ``problem`` is a design problem; return its validated start design."""
    if not hasattr(problem, "space") or not hasattr(problem, "evaluate"):
        raise ParameterError(f"optimize needs a design problem (space, evaluate); got "
                             f"{type(problem).__name__}.")
    return problem.space.validate(problem.space.start if x0 is None else x0)


def _logged_problem(problem, out) -> LoggedProblem:
    """``problem`` behind an evaluation log (``out/evaluations.csv`` with ``out``)."""
    if out is not None:
        os.makedirs(out, exist_ok=True)
    if isinstance(problem, LoggedProblem):
        return problem
    path = None if out is None else os.path.join(out, "evaluations.csv")
    return LoggedProblem(problem, EvaluationLog(path, problem))


def _dispatch(run: EvaluationRun, x0, method, max_evaluations, opts):
    """Run ``method``; return ``(cycles, status, message)``."""
    try:
        if method == "cd":
            return _coordinate_descent(run, x0, **opts)
        return _run_nlopt(run, x0, method, max_evaluations, **opts)
    except StopOptimization as exc:
        return None, "stopped", f"stopped by the callback: {exc}"


def _result(run: EvaluationRun, method, outcome, counts, t0, options) -> OptimizationResult:
    """Assemble the result from the run's best evaluation and ``(cycles, status, message)``."""
    import pandas as pd

    cycles, status, message = outcome
    logged, (c0, r0) = run.logged, counts
    best = run.best()
    if best is not None and not best.feasible:
        message += "; no feasible evaluation (the least-violating design is returned)"
    return OptimizationResult(
        method=method, x=dict(best.x) if best else {}, status=status, message=message,
        objective=best.objective if best else math.inf,
        constraints=dict(best.constraints) if best else {},
        success=bool(best and best.feasible), n_evaluations=len(run.evaluations),
        n_computed=logged.n_computed - c0, n_reused=logged.n_reused - r0,
        wall_time=time.perf_counter() - t0, history=run.history(), best=best,
        cycles=None if cycles is None else pd.DataFrame(cycles), options=options)


def optimize(problem, method: str, x0=None, *, out=None, executor=None,
             max_evaluations: int | None = None, callback=None, **options) -> OptimizationResult:
    """Minimise ``problem``'s objective subject to its constraints (g <= 0).

    Parameters
    ----------
    problem : DesignProblem or LoggedProblem
        Has ``space``, ``evaluate(x) -> Evaluation`` and ``settings()``.
    method : str
        ``"cd"``/``"coordinate_descent"``, ``"cobyla"``, ``"bobyqa"``, ``"neldermead"``,
        ``"sbplx"`` or ``"direct"``.
    x0 : mapping or sequence, optional
        Start design (SI); the space's start values by default. Must lie inside the bounds.
    out : path, optional
        Output folder: evaluation log ``evaluations.csv`` (reused on re-runs), ``result.json``,
        ``history.csv`` and (cd) ``cycles.csv``.
    executor : object, optional
        ``executor.map(fn, items) -> list`` (ordered); used by cd's ``parallel_candidates``.
    max_evaluations : int, optional
        Budget of distinct evaluations of the run (reused ones included): cd unlimited,
        NLopt 60 by default.
    callback : callable, optional
        ``callback(evaluation)`` after each new evaluation of the run; raise
        :class:`StopOptimization` to stop and get the result so far (other exceptions propagate
        after the evaluation has been logged).
    **options
        cd: ``max_cycles`` (15), ``parallel_candidates`` (False: compute the minus and plus
        candidates side by side on ``executor``, same run as without), ``metric``
        ("temperature [degC]", reported per cycle). NLopt: ``xtol_rel`` (1e-4), ``ftol_rel``
        (1e-6), ``xtol_abs`` (1e-6, normalised), ``ftol_abs`` (0), ``initial_step``
        (normalised; default the cd step), ``constraint_handling`` ("native" for cobyla,
        "penalty" or "auglag"), ``penalty`` (100, weight of the exact penalty
        ``f + penalty |f_ref| sum max(g, 0)``, ``f_ref`` the first finite objective),
        ``failure_value`` (value of a failed evaluation; default ``f_ref + 1000 |f_ref|``),
        ``max_time`` [s] (a time limit makes a re-run stop elsewhere: not reproducible).

    Returns
    -------
    OptimizationResult
    """
    t0 = time.perf_counter()
    method = _resolve_method(method)
    opts, max_evaluations = _resolve_options(method, options, max_evaluations)
    x0 = _start_design(problem, x0)
    logged = _logged_problem(problem, out)
    counts = (logged.n_computed, logged.n_reused)
    run = EvaluationRun(logged, max_evaluations, callback, executor)
    outcome = _dispatch(run, x0, method, max_evaluations, opts)
    result = _result(run, method, outcome, counts, t0,
                     options={"max_evaluations": max_evaluations, **opts})
    logger.info("%s: %s (%s) after %d evaluations (%d computed, %d reused): objective %.6g",
                method, result.status, result.message, result.n_evaluations, result.n_computed,
                result.n_reused, result.objective)
    if out is not None:
        _write(out, result, logged)
    return result


def _write(out, result: OptimizationResult, logged):
    d = result.to_dict()
    d["settings_hash"] = settings_hash(logged.settings())
    d["settings"] = logged.settings()
    with open(os.path.join(out, "result.json"), "w", encoding="utf-8") as fh:
        json.dump(d, fh, indent=1, default=repr)
    result.history.to_csv(os.path.join(out, "history.csv"), index=False)
    if result.cycles is not None:
        result.cycles.to_csv(os.path.join(out, "cycles.csv"), index=False)
