"""The NLopt back end of :func:`design.core.optimize.optimize` (private): NLopt algorithms in
normalised variables (derivative-free ones, and the gradient-based ``LD_*`` ones on problems
that supply gradients), with callbacks that never let an exception escape into
NLopt (see :mod:`design.core.optimize`, whose registry names the algorithms: a new NLopt
method is one :func:`~design.core.optimize.register_optimizer` call with
:func:`nlopt_backend`). NLopt itself is imported only when a run starts."""

from __future__ import annotations

import functools
import math

import numpy as np

from simulator import ParameterError

from ._gradient_methods import bound_names, constraint_jacobian, z_gradient
from .evaluation_log import BudgetExhausted, EvaluationRun, StopOptimization
from .problem import Evaluation

#: NLopt algorithms that take inequality constraints themselves (``constraint_handling="native"``).
_NATIVE_CONSTRAINTS = ("LN_COBYLA", "LD_MMA", "LD_SLSQP", "LD_CCSAQ")


def _gradient_based(algorithm: str) -> bool:
    """An NLopt algorithm that uses gradients (``LD_*``, ``GD_*``): constraints native only."""
    return algorithm[1] == "D"


def _nlopt_codes(nlopt):
    return {nlopt.SUCCESS: ("success", "NLopt reported success"),
            nlopt.STOPVAL_REACHED: ("stopval_reached", "objective reached stopval"),
            nlopt.FTOL_REACHED: ("ftol_reached", "objective change below ftol_rel/ftol_abs"),
            nlopt.XTOL_REACHED: ("xtol_reached", "step below xtol_rel/xtol_abs"),
            nlopt.MAXEVAL_REACHED: ("max_evaluations", "evaluation budget reached"),
            nlopt.MAXTIME_REACHED: ("max_time", "time limit reached")}


def _global(algorithm: str) -> bool:
    """A global NLopt algorithm (``GN_*``): no initial step, constraints only by penalty."""
    return algorithm.startswith("GN_")


def _nlopt_initial_step(space, algorithm, o) -> np.ndarray:
    """Check the NLopt options of ``algorithm`` and return the normalised initial step."""
    handling = o["constraint_handling"]
    allowed = (("native",) if _gradient_based(algorithm) else
               ("native", "penalty") if algorithm in _NATIVE_CONSTRAINTS else
               ("penalty",) if _global(algorithm) else ("penalty", "auglag"))
    if handling not in allowed:
        raise ParameterError(f"constraint_handling = {handling!r} is not available for "
                             f"{algorithm}; use one of {allowed}.")
    for key in ("xtol_rel", "ftol_rel", "xtol_abs", "ftol_abs", "penalty",
                "constraint_margin"):
        if key in o and not (isinstance(o[key], (int, float)) and o[key] >= 0):
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
        self.margin = o.get("constraint_margin", 0.0)
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
        """NLopt objective ``f(z, grad)`` (``grad`` filled for gradient algorithms; not
        penalised: they take the constraints natively)."""
        big = self.failure_value if self.failure_value is not None else 1e300

        def value():
            ev = self._evaluate(z)
            if grad.size:
                grad[:] = z_gradient(self.run.space, ev.objective_gradient if ev.success
                                     else None)
            return self._value(ev)

        return self._guarded(value, lambda: big)

    def constraints(self, result, z, grad):
        """NLopt vector constraint ``c(result, z, grad)``, ``result <= 0`` when feasible."""
        def fill():
            ev = self._evaluate(z)
            result[:] = np.asarray(self._constraint_values(ev)) + self.margin
            if grad.size:
                grad[:] = self._constraint_jacobian(ev)

        self._guarded(fill, lambda: result.__setitem__(slice(None), 1.0))

    def _constraint_jacobian(self, ev) -> np.ndarray:
        """``(m, n)`` constraint gradients in normalised variables (of the largest constraint
        for the aggregate one)."""
        space = self.run.space
        if self.names is not None:
            return constraint_jacobian(space, ev, self.names)
        g = {k: v for k, v in ev.constraints.items() if k not in self.bounds}
        if not (ev.success and g):
            return np.zeros((1, len(space)))
        return constraint_jacobian(space, ev, [max(g, key=g.get)])


def _nlopt_optimizers(nlopt, algorithm, n, handling, step, max_evaluations, o):
    """NLopt optimizer (and AUGLAG's local one) with bounds, tolerances and budgets set."""
    alg = getattr(nlopt, algorithm)
    opt = nlopt.opt(nlopt.AUGLAG if handling == "auglag" else alg, n)
    local = nlopt.opt(alg, n) if handling == "auglag" else None
    for p in filter(None, (opt, local)):
        p.set_lower_bounds(np.zeros(n))
        p.set_upper_bounds(np.ones(n))
        p.set_xtol_rel(o["xtol_rel"])
        p.set_xtol_abs(o["xtol_abs"])
        p.set_ftol_rel(o["ftol_rel"])
        p.set_ftol_abs(o["ftol_abs"])
        if not _global(algorithm):
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


def _run_nlopt(run: EvaluationRun, x0, max_evaluations, *, algorithm, **o):
    """Run NLopt ``algorithm`` (e.g. ``"LN_COBYLA"``) in normalised variables; return
    ``(status, message)``."""
    import nlopt

    space, n = run.space, len(run.space)
    handling = o["constraint_handling"]
    step = _nlopt_initial_step(space, algorithm, o)
    bounds = bound_names(space)
    names = _nlopt_constraint_names(run, x0, handling, bounds)
    callbacks = _NloptCallbacks(run, names, bounds, handling == "penalty", o)
    opt, local = _nlopt_optimizers(nlopt, algorithm, n, handling, step, max_evaluations, o)
    callbacks.opt = opt
    opt.set_min_objective(callbacks.objective)
    m = 1 if names is None else len(names)
    if handling in ("native", "auglag") and m:
        opt.add_inequality_mconstraint(callbacks.constraints, np.zeros(m))
    status, msg = _nlopt_status(nlopt, opt, space.normalize(x0))
    status, msg = _callback_status(callbacks.exc, status, msg)
    return status, f"{algorithm}" + (" (AUGLAG)" if local else "") + f": {msg}"


def nlopt_backend(algorithm: str):
    """The optimiser back end running NLopt's ``algorithm`` (a name of the ``nlopt`` module,
    e.g. ``"LN_COBYLA"``): ``backend(run, x0, max_evaluations, **options)``."""
    backend = functools.partial(_run_nlopt, algorithm=algorithm)
    functools.update_wrapper(backend, _run_nlopt)
    return backend
