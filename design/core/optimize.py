"""Optimisers behind one entry point: ``optimize(problem, method, ...)``.

* ``"cd"`` (``"coordinate_descent"``): the paper's fixed-step coordinate descent (method
  theory 10.6, GripperOptimization.m) with correct bound checks. Coordinates in space order;
  for each, the minus candidate (if inside the bounds), then the plus candidate; a candidate
  is accepted when it is feasible and its objective strictly lower than the current one, and
  the move applies at once. A cycle without a move ends the search (``"converged"``), else
  after ``max_cycles`` (15) cycles (``"max_cycles"``). Candidates lie on the lattice
  ``x0 + k step``. With ``parallel_candidates`` both candidates of a coordinate are computed
  side by side on the executor (:meth:`~design.core.evaluation_log.EvaluationRun.prefetch`) and
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

With ``out``, evaluations go to ``out/evaluations.csv`` (see :mod:`design.core.evaluation_log`),
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

from ._contract import check_outcome
from ._coordinate_descent import _coordinate_descent
from ._nlopt_methods import _NLOPT, _run_nlopt
from .evaluation_log import (EvaluationLog, EvaluationRun, LoggedProblem, StopOptimization,
                             settings_hash)
from .problem import Evaluation

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["optimize", "OptimizationResult", "StopOptimization", "METHODS"]

logger = logging.getLogger(__name__)

_ALIASES = {"coordinate_descent": "cd", "nelder-mead": "neldermead", "nelder_mead": "neldermead",
            "subplex": "sbplx", "direct_l": "direct"}
#: Accepted method names (aliases included).
METHODS = ("cd",) + tuple(_NLOPT) + tuple(_ALIASES)
_CD_OPTIONS = {"max_cycles": 15, "parallel_candidates": False, "metric": "temperature [degC]"}
_NLOPT_OPTIONS = {"xtol_rel": 1e-4, "ftol_rel": 1e-6, "xtol_abs": 1e-6, "ftol_abs": 0.0,
                  "initial_step": None, "constraint_handling": None, "penalty": 100.0,
                  "failure_value": None, "max_time": None}


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
