"""Gradients in the design layer: problems that supply them, the gradient methods of
``optimize`` (NLopt MMA, SLSQP, CCSAQ; scipy SLSQP, trust-constr), the log storing them; on an
analytic problem, and on heater powers of the double fold with adjoint gradients."""

from __future__ import annotations

import math

import numpy as np
import pytest

from design.core.evaluation_log import EvaluationLog, LoggedProblem
from design.core.executors import SerialExecutor, make_executor
from design.core.optimize import get_optimizer, optimize
from design.core.problem import DesignProblem
from design.core.space import DesignSpace, Variable
from design.devices import FoldTargetProblem
from simulator.errors import ParameterError

GRADIENT_METHODS = ["mma", "slsqp", "ccsaq", "scipy_slsqp", "trust_constr"]


def _var(name, lo, hi, start):
    return Variable(name, lo, hi, 0.25, start, unit="-", display_scale=1.0, display_unit="-")


class QuadGrad(DesignProblem):
    """min (x-1)^2 + (y-2)^2 s.t. x + y <= 2 (and the bound margins): optimum (0.5, 1.5)."""

    name = "quad_grad"

    def __init__(self, drop=None):
        self.drop = drop
        self.space = DesignSpace([_var("x", -1, 3, 0.0), _var("y", -1, 3, 0.0)])

    def _values(self, v):
        x, y = v["x"], v["y"]
        cons = dict(self.space.bound_margins(v), sum=(x + y - 2) / 2)
        return (x - 1) ** 2 + (y - 2) ** 2, cons, {"x+y": x + y}

    def _evaluate(self, v):
        return (*self._values(v), None, "")

    def _evaluate_with_gradient(self, v):
        f, cons, metrics = self._values(v)
        grads = {} if self.drop == "sum" else {"sum": {"x": 0.5, "y": 0.5}}
        return (f, cons, metrics, None, "", [2 * (v["x"] - 1), 2 * (v["y"] - 2)], grads)


class QuadPlain(QuadGrad):
    """The same without gradients."""

    _evaluate_with_gradient = DesignProblem._evaluate_with_gradient


@pytest.mark.parametrize("method", GRADIENT_METHODS)
def test_gradient_methods_solve_quad(method):
    r = optimize(QuadGrad(), method)
    assert r.success, r.message
    assert r.x["x"] == pytest.approx(0.5, abs=1e-3) and r.x["y"] == pytest.approx(1.5, abs=1e-3)
    assert r.n_evaluations < 40
    assert r.best.objective_gradient is not None and "sum" in r.best.constraint_gradients


def test_registry_marks_gradient_methods():
    assert all(get_optimizer(m).needs_gradient for m in GRADIENT_METHODS)
    assert not get_optimizer("cobyla").needs_gradient


def test_gradient_method_without_gradients_is_refused():
    assert not QuadPlain().supplies_gradients and QuadGrad().supplies_gradients
    with pytest.raises(ParameterError, match="method 'mma' needs gradients and QuadPlain "
                                             "supplies none: implement"):
        optimize(QuadPlain(), "mma")
    with pytest.raises(ParameterError, match="supplies no gradients"):
        QuadPlain().evaluate_with_gradient([0.0, 0.0])


def test_evaluation_carries_gradients_and_bound_margins():
    ev = QuadGrad().evaluate_with_gradient([0.0, 1.0])
    assert ev.objective_gradient == {"x": -2.0, "y": -2.0}
    assert ev.constraint_gradients["sum"] == {"x": 0.5, "y": 0.5}
    assert ev.constraint_gradients["x_lower"] == {"x": -0.25, "y": 0.0}
    assert ev.constraint_gradients["y_upper"] == {"x": 0.0, "y": 0.25}
    plain = QuadGrad().evaluate([0.0, 1.0])
    assert plain.objective_gradient is None and plain.constraint_gradients is None


def test_missing_constraint_gradient_fails_the_evaluation():
    ev = QuadGrad(drop="sum").evaluate_with_gradient([0.0, 1.0])
    assert ev.status == "failed" and "no gradient of constraint 'sum'" in ev.message


def test_log_stores_gradients_and_a_rerun_reuses_them(tmp_path):
    r1 = optimize(QuadGrad(), "mma", out=tmp_path)
    log = EvaluationLog(tmp_path / "evaluations.csv", QuadGrad())
    ev = log.lookup([r1.x["x"], r1.x["y"]])
    assert ev.objective_gradient == r1.best.objective_gradient            # bit-identical
    assert ev.constraint_gradients == r1.best.constraint_gradients
    r2 = optimize(QuadGrad(), "mma", out=tmp_path)
    assert r2.n_computed == 0 and r2.n_reused == r1.n_evaluations and r2.x == r1.x


def test_gradient_run_recomputes_logged_designs_without_gradient(tmp_path):
    path = tmp_path / "evaluations.csv"
    logged = LoggedProblem(QuadGrad(), EvaluationLog(path, QuadGrad()))
    logged.evaluate([0.0, 0.0])
    again = LoggedProblem(QuadGrad(), EvaluationLog(path, QuadGrad()))
    ev = again.evaluate_many([[0.0, 0.0]], SerialExecutor(), gradient=True)[0]
    assert again.n_computed == 1 and ev.objective_gradient == {"x": -2.0, "y": -4.0}


@pytest.mark.parametrize("kind", ["process", "dask"])
def test_pooled_executors_carry_gradients(kind):
    """The process pool and a local Dask cluster return each design's gradients as the serial
    run computes them."""
    xs = [[0.0, 0.0], [0.5, 1.0], [2.0, -1.0]]
    serial = LoggedProblem(QuadGrad()).evaluate_many(xs, SerialExecutor(), gradient=True)
    with make_executor(kind, workers=2) as ex:
        assert ex.kind == kind
        pooled = LoggedProblem(QuadGrad()).evaluate_many(xs, ex, gradient=True)
    assert [e.objective_gradient for e in pooled] == [e.objective_gradient for e in serial]
    assert [e.constraint_gradients for e in pooled] == [e.constraint_gradients for e in serial]
    assert pooled[1].objective_gradient == {"x": -1.0, "y": -2.0}


# ---------------------------------------------------------------- heater powers, double fold
TARGETS = {2: math.radians(30.0), 5: math.radians(80.0)}
LIMIT = 250.0


@pytest.fixture(scope="module")
def fold_problem():
    return FoldTargetProblem(TARGETS, temperature_limit=LIMIT)


def test_fold_target_gradients_match_central_differences(fold_problem):
    """Adjoint gradients of every constraint against central differences of ``evaluate``
    (``h = eps^(1/3) max(|P|, 1 mW)``, tight Newton and coupling tolerances)."""
    x = np.array([0.010, 0.012])
    ev = fold_problem.evaluate_with_gradient(x)
    assert ev.success, ev.message
    assert ev.objective_gradient == {"power_2": 1.0, "power_5": 1.0}
    for i, var in enumerate(fold_problem.space.names):
        h = np.finfo(float).eps ** (1 / 3) * max(abs(x[i]), 1e-3)
        plus = fold_problem.evaluate(x + h * np.eye(2)[i])
        minus = fold_problem.evaluate(x - h * np.eye(2)[i])
        for name, grad in ev.constraint_gradients.items():
            fd = (plus.constraints[name] - minus.constraints[name]) / (2 * h)
            assert fd != 0
            assert grad[var] == pytest.approx(fd, rel=1e-5), (name, var)


def test_fold_target_gradient_optimum_beats_cobyla(fold_problem):
    """MMA meets the targets (0.5 deg) and the limit, and reaches COBYLA's power within 1 %
    with fewer simulations than COBYLA's run."""
    mma = optimize(fold_problem, "mma")
    assert mma.success, mma.message
    m = mma.best.metrics
    for c, target in TARGETS.items():
        assert abs(math.degrees(m[f"fold_{c} [rad]"] - target)) <= 0.5
    assert all(m[f"temperature_{c} [degC]"] <= LIMIT for c in (2, 5))
    cobyla = optimize(fold_problem, "cobyla", max_evaluations=100)
    assert cobyla.success, cobyla.message
    assert mma.objective == pytest.approx(cobyla.objective, rel=0.01)
    assert mma.n_computed < cobyla.n_computed, (mma.n_computed, cobyla.n_computed)


@pytest.mark.parametrize("method", ["slsqp", "scipy_slsqp", "trust-constr"])
def test_fold_target_other_gradient_methods(fold_problem, method):
    r = optimize(fold_problem, method)
    assert r.success, r.message
    for c, target in TARGETS.items():
        assert abs(math.degrees(r.best.metrics[f"fold_{c} [rad]"] - target)) <= 0.5
    assert all(r.best.metrics[f"temperature_{c} [degC]"] <= LIMIT for c in (2, 5))
