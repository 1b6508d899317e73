"""Gradient-based back ends of :func:`design.core.optimize.optimize` (private): the design
gradients in normalised variables, shared with the NLopt back end, and scipy's ``SLSQP`` and
``trust-constr``. They run on problems that supply gradients
(:meth:`~design.core.problem.DesignProblem.evaluate_with_gradient`); the evaluation run
computes every design with its gradient. Constraints follow g(x) <= 0, bounds are the unit box
of the normalised variables ``z = (x - lower) / (upper - lower)``. The methods converge onto
the active constraints and may end on their far side by round-off, so they are asked for
``g <= -constraint_margin`` (default 1e-6 of the normalised constraints)."""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np

from simulator import ParameterError

from .evaluation_log import EvaluationRun
from .problem import Evaluation


def bound_names(space) -> set:
    """The names of the bound constraints a problem may report (``<variable>_lower/_upper``);
    the optimisers keep the bounds themselves."""
    return {f"{v}_{s}" for v in space.names for s in ("lower", "upper")}


def z_gradient(space, grad: dict | None) -> np.ndarray:
    """A gradient by variable (SI) as the gradient in normalised variables, ``(n,)``; zeros
    for a failed evaluation (None)."""
    if grad is None:
        return np.zeros(len(space))
    return np.array([grad[n] for n in space.names]) * (space.upper - space.lower)


def constraint_jacobian(space, ev: Evaluation, names) -> np.ndarray:
    """``(m, n)`` gradients in normalised variables of the constraints ``names`` (zeros for a
    failed evaluation)."""
    grads = ev.constraint_gradients or {}
    return np.array([z_gradient(space, grads.get(k)) for k in names]).reshape(len(names),
                                                                               len(space))


def constraint_values(ev: Evaluation, names) -> np.ndarray:
    """The constraints ``names`` (1 for each on a failed evaluation)."""
    return np.array([1.0 if not ev.success else float(ev.constraints.get(k, 0.0))
                     for k in names])


class _ScipyFunctions:
    """Objective and constraints in normalised variables for ``scipy.optimize.minimize``,
    the objective divided by the first finite objective's magnitude (scale-free tolerances)."""

    def __init__(self, run: EvaluationRun, names, failure_value, margin):
        self.run, self.space, self.names, self.margin = run, run.space, names, margin
        self.failure_value, self.scale = failure_value, None

    def evaluate(self, z) -> Evaluation:
        ev = self.run.evaluate(self.space.denormalize(np.clip(z, 0.0, 1.0)))
        if self.scale is None and ev.success and math.isfinite(ev.objective):
            self.scale = abs(ev.objective) or 1.0
        return ev

    def objective(self, z):
        ev = self.evaluate(z)
        scale = self.scale or 1.0
        if not ev.success:
            value = self.failure_value if self.failure_value is not None else 1e3
            return float(value), np.zeros(len(self.space))
        return ev.objective / scale, z_gradient(self.space, ev.objective_gradient) / scale

    def constraints(self, z) -> np.ndarray:
        return constraint_values(self.evaluate(z), self.names) + self.margin

    def jacobian(self, z) -> np.ndarray:
        return constraint_jacobian(self.space, self.evaluate(z), self.names)


def _scipy_status(res, method) -> tuple:
    if res.success:
        return "converged", f"scipy {method}: {res.message}"
    maxed = "iteration" in str(res.message).lower()
    return ("max_iterations" if maxed else "failure"), f"scipy {method}: {res.message}"


def _run_scipy(run: EvaluationRun, x0, max_evaluations, *, method, tol, max_iterations,
               failure_value, constraint_margin):
    """Run ``scipy.optimize.minimize(method=...)`` (``"SLSQP"`` or ``"trust-constr"``) in
    normalised variables with exact gradients; return ``(status, message)``."""
    from scipy.optimize import Bounds, NonlinearConstraint, minimize

    if not (isinstance(tol, (int, float)) and tol > 0):
        raise ParameterError(f"tol = {tol!r} must be a positive number.")
    if not (isinstance(max_iterations, int) and max_iterations >= 1):
        raise ParameterError(f"max_iterations = {max_iterations!r} must be a positive integer.")
    if not (isinstance(constraint_margin, (int, float)) and constraint_margin >= 0):
        raise ParameterError(f"constraint_margin = {constraint_margin!r} must be a "
                             "non-negative number.")
    space = run.space
    first = run.evaluate(x0)
    names = [k for k in first.constraints if k not in bound_names(space)]
    fns = _ScipyFunctions(run, names, failure_value, constraint_margin)
    if method == "SLSQP":
        cons = [{"type": "ineq", "fun": lambda z: -fns.constraints(z),
                 "jac": lambda z: -fns.jacobian(z)}] if names else []
    else:
        cons = [NonlinearConstraint(fns.constraints, -np.inf, 0.0, jac=fns.jacobian)] \
            if names else []
    with warnings.catch_warnings():     # trust-constr's quasi-Newton on a linear function
        warnings.filterwarnings("ignore", message="delta_grad == 0.0", category=UserWarning)
        res = minimize(fns.objective, space.normalize(x0), jac=True, method=method,
                       bounds=Bounds(np.zeros(len(space)), np.ones(len(space))),
                       constraints=cons, tol=tol, options={"maxiter": max_iterations})
    return _scipy_status(res, method)


def scipy_backend(method: str):
    """The optimiser back end running ``scipy.optimize.minimize(method=method)`` with the
    problem's gradients: ``backend(run, x0, max_evaluations, **options)``."""
    backend = functools.partial(_run_scipy, method=method)
    functools.update_wrapper(backend, _run_scipy)
    return backend
