"""Optimisers behind one entry point: ``optimize(problem, method, ...)``, and their registry.

Every method is one entry of a registry (:func:`register_optimizer`, listed by
:func:`optimizers`): its back end, description, option defaults, default budget and aliases.
:func:`optimize`, the ``etorigami optimize --method`` choices and the documentation read
the registry, so a new optimiser is one :func:`register_optimizer` call. The built-in ones:

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
* Gradient methods, for problems that supply gradients
  (:meth:`~design.core.problem.DesignProblem.evaluate_with_gradient`), in the same normalised
  variables with the constraints passed natively: NLopt's ``"mma"`` (LD_MMA), ``"slsqp"``
  (LD_SLSQP), ``"ccsaq"`` (LD_CCSAQ), and scipy's ``"scipy_slsqp"`` and ``"trust_constr"``.
  Every design of their runs is evaluated with its gradients (which the log stores). A
  gradient method on a problem without gradients is refused.

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
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np

from simulator import ParameterError
from simulator._result import ResultFiles

from .contract import check_outcome
from ._coordinate_descent import coordinate_descent
from ._gradient_methods import scipy_backend
from ._nlopt_methods import nlopt_backend
from .evaluation_log import (BudgetExhausted, EvaluationLog, EvaluationRun, LoggedProblem,
                             StopOptimization, settings_hash)
from .problem import Evaluation

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["optimize", "OptimizationResult", "StopOptimization", "Optimizer",
           "register_optimizer", "unregister_optimizer", "optimizers", "get_optimizer"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class Optimizer:
    """A registered optimisation method (see :func:`register_optimizer`).

    Attributes
    ----------
    name : str
        Canonical name (lower case), as given to :func:`optimize`.
    run : callable
        ``run(evaluation_run, x0, max_evaluations, **options) -> (status, message)`` or
        ``(status, message, cycles)``: minimises from ``x0`` (SI vector inside the bounds) by
        calling ``evaluation_run.evaluate(x)`` / ``evaluate_many(xs)`` (each returns an
        :class:`~design.core.problem.Evaluation`; ``evaluation_run.space`` is the design
        space). The run keeps the history, the budget and the best design;
        ``BudgetExhausted`` and :class:`StopOptimization` raised by an evaluation may be left
        to :func:`optimize`. ``cycles``: rows (dicts) written to ``cycles.csv``.
    description : str
        One line for the CLI help and the documentation.
    options : mapping
        Option names and defaults; any other option is an error.
    max_evaluations : int or None
        Default budget of distinct evaluations (None: unlimited).
    needs_bounds : bool
        The method works in the space's bounded (normalised) box. Every
        :class:`~design.core.space.DesignSpace` has finite bounds, so today this is what the
        documentation says of a method; a back end for unbounded spaces would set False.
    aliases : tuple of str
        Further accepted names.
    needs_gradient : bool
        The method uses the gradients of the objective and the constraints: it runs only on
        problems that supply them (``problem.supplies_gradients``), and every design of its
        run is evaluated with them (``evaluate_with_gradient``).
    """

    name: str
    run: Callable
    description: str
    options: Mapping = field(default_factory=dict)
    max_evaluations: int | None = None
    needs_bounds: bool = True
    aliases: tuple = ()
    needs_gradient: bool = False


_REGISTRY: dict = {}      # canonical name -> Optimizer, in registration order
_ALIASES: dict = {}       # alias -> canonical name


def register_optimizer(name: str, run: Callable, *, description: str, options=None,
                       max_evaluations: int | None = None, needs_bounds: bool = True,
                       aliases=(), replace: bool = False,
                       needs_gradient: bool = False) -> Optimizer:
    """Make ``run`` available as ``optimize(problem, name)`` and ``--method name``.

    Parameters
    ----------
    name : str
        Method name (case-insensitive).
    run : callable
        The back end, see :attr:`Optimizer.run`.
    description : str
        One line for the CLI help and the documentation.
    options : mapping, optional
        Option names and their defaults (the method's ``**options`` of :func:`optimize`).
    max_evaluations : int, optional
        Default budget (None: unlimited).
    needs_bounds : bool
    aliases : sequence of str
    replace : bool
        Allow replacing a registered method of the same name.
    needs_gradient : bool
        The method uses gradients (:attr:`Optimizer.needs_gradient`).

    Returns
    -------
    Optimizer
    """
    if not callable(run):
        raise ParameterError(f"register_optimizer: run = {run!r} must be callable.")
    names = [name, *aliases]
    if not all(isinstance(n, str) and n.strip() for n in names):
        raise ParameterError(f"register_optimizer: names {names!r} must be non-empty strings.")
    key, aliases = name.lower(), tuple(a.lower() for a in aliases)
    owner = {**{n: n for n in _REGISTRY}, **_ALIASES}           # every taken name -> method
    others = [n for n in (key, *aliases) if owner.get(n, key) != key]
    if others or (key in _REGISTRY and not replace):
        raise ParameterError(f"register_optimizer: {others or [key]} already registered "
                             f"(methods: {', '.join(_REGISTRY)}); pass replace=True to replace "
                             "a method by its own name.")
    if max_evaluations is not None and (isinstance(max_evaluations, bool) or not (
            isinstance(max_evaluations, int) and max_evaluations >= 1)):
        raise ParameterError(f"register_optimizer: max_evaluations = {max_evaluations!r} "
                             "must be a positive integer or None.")
    spec = Optimizer(key, run, description, MappingProxyType(dict(options or {})),
                     max_evaluations, bool(needs_bounds), aliases, bool(needs_gradient))
    unregister_optimizer(key, missing_ok=True)
    _REGISTRY[key] = spec
    _ALIASES.update(dict.fromkeys(spec.aliases, key))
    return spec


def unregister_optimizer(name: str, missing_ok: bool = False) -> None:
    """Remove a registered method (and its aliases)."""
    spec = _REGISTRY.pop(str(name).lower(), None)
    if spec is None and not missing_ok:
        raise ParameterError(f"unregister_optimizer: no method {name!r}; registered: "
                             f"{', '.join(_REGISTRY)}.")
    for alias in () if spec is None else spec.aliases:
        _ALIASES.pop(alias, None)


def optimizers() -> Mapping:
    """The registered methods: a read-only mapping canonical name -> :class:`Optimizer`, in
    registration order."""
    return MappingProxyType(dict(_REGISTRY))


_NLOPT_OPTIONS = {"xtol_rel": 1e-4, "ftol_rel": 1e-6, "xtol_abs": 1e-6, "ftol_abs": 0.0,
                  "initial_step": None, "constraint_handling": "penalty", "penalty": 100.0,
                  "failure_value": None, "max_time": None}

# The built-in methods: the one list of them (CLI choices, documentation and tests read it).
register_optimizer(
    "cd", coordinate_descent, aliases=("coordinate_descent",),
    options={"max_cycles": 15, "parallel_candidates": False, "metric": None},
    description="the paper's fixed-step coordinate descent on the lattice x0 + k step "
                "(deterministic, feasible moves only)")
for _name, _algorithm, _aliases, _what in (
        ("cobyla", "LN_COBYLA", (), "local, linear approximations; constraints passed to NLopt"),
        ("bobyqa", "LN_BOBYQA", (), "local, quadratic models; constraints by penalty or AUGLAG"),
        ("neldermead", "LN_NELDERMEAD", ("nelder-mead", "nelder_mead"),
         "local simplex; constraints by penalty or AUGLAG"),
        ("sbplx", "LN_SBPLX", ("subplex",),
         "local, Nelder-Mead on subspaces; constraints by penalty or AUGLAG"),
        ("direct", "GN_DIRECT_L", ("direct_l",), "global, dividing rectangles; penalty")):
    register_optimizer(
        _name, nlopt_backend(_algorithm), aliases=_aliases, max_evaluations=60,
        options={**_NLOPT_OPTIONS,
                 "constraint_handling": "native" if _name == "cobyla" else "penalty"},
        description=f"NLopt {_algorithm}: {_what}")
#: Gradient methods are asked for g <= -margin: they converge onto active constraints and
#: would otherwise end on their infeasible side by round-off.
_MARGIN = 1e-6
for _name, _algorithm, _what in (
        ("mma", "LD_MMA", "method of moving asymptotes"),
        ("slsqp", "LD_SLSQP", "sequential quadratic programming"),
        ("ccsaq", "LD_CCSAQ", "conservative convex separable quadratic approximations")):
    register_optimizer(
        _name, nlopt_backend(_algorithm), needs_gradient=True, max_evaluations=100,
        options={**_NLOPT_OPTIONS, "constraint_handling": "native",
                 "constraint_margin": _MARGIN},
        description=f"NLopt {_algorithm}: local, {_what}; gradients, constraints passed to "
                    "NLopt")
for _name, _algorithm, _what in (
        ("scipy_slsqp", "SLSQP", "sequential least squares programming"),
        ("trust_constr", "trust-constr", "trust-region interior point")):
    register_optimizer(
        _name, scipy_backend(_algorithm), needs_gradient=True, max_evaluations=100,
        aliases=(_name.replace("_", "-"),),
        options={"tol": 1e-8, "max_iterations": 100, "failure_value": None,
                 "constraint_margin": _MARGIN},
        description=f"scipy {_algorithm}: local, {_what}; gradients, constraints passed to "
                    "scipy")
del _name, _algorithm, _aliases, _what


@dataclass(frozen=True, eq=False)
class OptimizationResult(ResultFiles):
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

    def to_frame(self) -> pd.DataFrame:
        """The evaluation history, one row per evaluation (:attr:`history`)."""
        return self.history

    def _tables(self) -> dict:
        return {"history.csv": self.history, "cycles.csv": self.cycles}

    def _meta(self) -> dict:
        return self.to_dict()


def get_optimizer(method) -> Optimizer:
    """The registered optimiser called ``method`` (case-insensitive, or one of its aliases);
    an unknown name is a :class:`~simulator.errors.ParameterError` listing the registered
    ones."""
    key = method.lower() if isinstance(method, str) else None
    spec = _REGISTRY.get(_ALIASES.get(key, key))
    if spec is None:
        aliases = f" (aliases: {', '.join(_ALIASES)})" if _ALIASES else ""
        raise ParameterError(f"Unknown optimisation method {method!r}; use one of "
                             f"{', '.join(_REGISTRY)}{aliases}.")
    return spec


def _resolve_options(spec: Optimizer, options, max_evaluations):
    """Check ``options`` and the budget of ``spec``; return them with defaults filled in."""
    unknown = sorted(set(options) - set(spec.options))
    if unknown:
        raise ParameterError(f"Unknown option(s) {unknown} for method {spec.name!r}; options: "
                             f"{', '.join(spec.options) or 'none'}.")
    opts = {**spec.options, **options}
    if max_evaluations is None:
        max_evaluations = spec.max_evaluations
    if max_evaluations is not None and not (isinstance(max_evaluations, (int, np.integer))
                                            and max_evaluations >= 1):
        raise ParameterError(f"max_evaluations = {max_evaluations!r} must be a positive integer.")
    return opts, max_evaluations


def _check_gradients(problem, spec: Optimizer) -> None:
    """Refuse a gradient method on a problem that supplies no gradients."""
    if spec.needs_gradient and not getattr(problem, "supplies_gradients", False):
        free = ", ".join(n for n, s in _REGISTRY.items() if not s.needs_gradient)
        raise ParameterError(f"method {spec.name!r} needs gradients and "
                             f"{type(problem).__name__} supplies none: implement its "
                             "_evaluate_with_gradient(values) or use a derivative-free "
                             f"method ({free}).")


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


def _dispatch(run: EvaluationRun, x0, spec: Optimizer, max_evaluations, opts):
    """Run the back end of ``spec``; return ``(cycles, status, message)``."""
    try:
        status, message, *cycles = spec.run(run, x0, max_evaluations, **opts)
    except StopOptimization as exc:
        return None, "stopped", f"stopped by the callback: {exc}"
    except BudgetExhausted:
        return None, "max_evaluations", f"evaluation budget ({max_evaluations}) exhausted"
    return (cycles[0] if cycles else None), status, message


def _result(run: EvaluationRun, method, outcome, counts, t0, options) -> OptimizationResult:
    """Assemble the result from the run's best evaluation and ``(cycles, status, message)``."""
    import pandas as pd

    cycles, status, message = outcome
    logged, (c0, r0) = run.logged, counts
    best = run.best()
    if best is not None and not best.feasible:
        message += ("; no feasible evaluation (the least-violating design is returned: "
                    f"{best.message})")
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
        A registered method (:func:`optimizers`) or alias: built in ``"cd"``
        (``"coordinate_descent"``), ``"cobyla"``, ``"bobyqa"``, ``"neldermead"``, ``"sbplx"``,
        ``"direct"``; with gradients (problems that supply them,
        :meth:`~design.core.problem.DesignProblem.evaluate_with_gradient`): ``"mma"``,
        ``"slsqp"``, ``"ccsaq"`` (NLopt) and ``"scipy_slsqp"``, ``"trust_constr"`` (scipy);
        more by :func:`register_optimizer`.
    x0 : mapping or sequence, optional
        Start design (SI); the space's start values by default. Must lie inside the bounds.
    out : path, optional
        Output folder: evaluation log ``evaluations.csv`` (reused on re-runs), ``result.json``,
        ``history.csv`` and (cd) ``cycles.csv``.
    executor : object, optional
        ``executor.map(fn, items) -> list`` (ordered); used by cd's ``parallel_candidates``.
    max_evaluations : int, optional
        Budget of distinct evaluations of the run (reused ones included); default the
        method's (:attr:`Optimizer.max_evaluations`): cd unlimited, NLopt 60.
    callback : callable, optional
        ``callback(evaluation)`` after each new evaluation of the run; raise
        :class:`StopOptimization` to stop and get the result so far (other exceptions propagate
        after the evaluation has been logged).
    **options
        The method's options (:attr:`Optimizer.options`; others are an error). cd: ``max_cycles`` (15), ``parallel_candidates`` (False: compute the minus and plus
        candidates side by side on ``executor``, same run as without), ``metric``
        (a metric reported per cycle; default the problem's ``report_metric``, none if it
        has none). NLopt: ``xtol_rel`` (1e-4), ``ftol_rel``
        (1e-6), ``xtol_abs`` (1e-6, normalised), ``ftol_abs`` (0), ``initial_step``
        (normalised; default the cd step), ``constraint_handling`` ("native" for cobyla,
        "penalty" or "auglag"), ``penalty`` (100, weight of the exact penalty
        ``f + penalty |f_ref| sum max(g, 0)``, ``f_ref`` the first finite objective),
        ``failure_value`` (value of a failed evaluation; default ``f_ref + 1000 |f_ref|``),
        ``max_time`` [s] (a time limit makes a re-run stop elsewhere: not reproducible);
        mma, slsqp, ccsaq: the same, constraints native only, and ``constraint_margin``
        (1e-6: the optimiser is asked for ``g <= -constraint_margin``, so that it does not
        end on an active constraint's infeasible side by round-off). scipy: ``tol`` (1e-8, on the
        objective divided by the first one's magnitude, in normalised variables),
        ``max_iterations`` (100), ``failure_value``, ``constraint_margin`` (1e-6).

    Returns
    -------
    OptimizationResult
    """
    t0 = time.perf_counter()
    spec = get_optimizer(method)
    _check_gradients(problem, spec)
    opts, max_evaluations = _resolve_options(spec, options, max_evaluations)
    x0 = _start_design(problem, x0)
    logged = _logged_problem(problem, out)
    counts = (logged.n_computed, logged.n_reused)
    run = EvaluationRun(logged, max_evaluations, callback, executor, spec.needs_gradient)
    outcome = _dispatch(run, x0, spec, max_evaluations, opts)
    method = spec.name
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
