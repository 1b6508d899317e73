"""Optimisers and the evaluation log, on cheap analytic problems (the gripper only in -m slow)."""

from __future__ import annotations

import itertools
import json
import math
import pickle

import numpy as np
import pandas as pd
import pytest

from design.core.evaluation_log import EvaluationLog, EvaluationRun, LoggedProblem, design_key
from design.core.optimize import (StopOptimization, get_optimizer, optimize, optimizers,
                                  register_optimizer, unregister_optimizer)
from design.core.problem import DesignProblem, Evaluation
from design.core.space import DesignSpace, Variable
from simulator.errors import ParameterError

NLOPT_METHODS = ["cobyla", "bobyqa", "neldermead", "sbplx", "direct"]
ALL_METHODS = ["cd"] + NLOPT_METHODS


def _var(name, lo, hi, step, start):
    return Variable(name, lo, hi, step, start, unit="-", display_scale=1.0, display_unit="-")


class Quad(DesignProblem):
    """min (x-1)^2 + (y-2)^2 s.t. x + y <= 2: optimum (0.5, 1.5), f = 0.5."""

    name = "quad"
    report_metric = "temperature [degC]"

    def __init__(self, start=(0.0, 0.0), shift=0.0):
        self.shift = shift
        self.space = DesignSpace([_var("x", -1, 3, 0.25, start[0]),
                                  _var("y", -1, 3, 0.25, start[1])])

    def _evaluate(self, v):
        x, y = v["x"], v["y"]
        cons = dict(self.space.bound_margins(v), sum=(x + y - 2) / 2)
        return ((x - 1) ** 2 + (y - 2) ** 2 + self.shift, cons,
                {"temperature [degC]": 100 + 10 * x, "label": f"p{x:.2f}", "count": 3}, None,
                "")

    def settings(self):
        return {"problem": self.name, "shift": self.shift}


class Lattice3(DesignProblem):
    """Separable quadratic in 3 variables, x <= 0.5 as a constraint, z limited by its bound."""

    name = "lattice3"
    report_metric = "temperature [degC]"
    space = DesignSpace([_var("x", -1, 1, 0.25, 0.0), _var("y", -1, 1, 0.25, 0.0),
                         _var("z", 0, 1.5, 0.25, 0.0)])

    def _evaluate(self, v):
        f = (v["x"] - 0.6) ** 2 + (v["y"] + 0.3) ** 2 + (v["z"] - 2.0) ** 2
        cons = dict(self.space.bound_margins(v), xmax=v["x"] - 0.5)
        return f, cons, {"temperature [degC]": 50 + v["z"]}, None, ""


class Flaky(Quad):
    """Quad whose simulation fails for x > 2.1 and whose evaluate() even raises for y < -0.1."""

    name = "flaky"

    def _evaluate(self, v):
        if v["x"] > 2.1:
            raise ValueError("simulated solver divergence")
        return super()._evaluate(v)

    def evaluate(self, x):
        if self.space.to_mapping(x)["y"] < -0.1:
            raise RuntimeError("broken problem: evaluate() raised")
        return super().evaluate(x)


class AlwaysFails(Quad):
    name = "always_fails"

    def _evaluate(self, v):
        raise RuntimeError("no convergence")


class Interrupt:
    """Callback raising KeyboardInterrupt at the k-th evaluation (emulates killing the run)."""

    def __init__(self, k):
        self.k, self.n = k, 0

    def __call__(self, ev):
        self.n += 1
        if self.n >= self.k:
            raise KeyboardInterrupt("killed")


class CountingExecutor:
    def __init__(self):
        self.sizes = []

    def map(self, fn, items):
        items = list(items)
        self.sizes.append(len(items))
        return [fn(x) for x in items]


def _assert_best_feasible(res):
    h = res.history
    feas = h[h["feasible"]]
    assert res.success and res.best.feasible
    assert res.objective == pytest.approx(feas["objective"].min(), rel=0, abs=0)
    assert len(h) == res.n_evaluations == res.n_computed + res.n_reused


# ---------------------------------------------------------------- coordinate descent
def test_cd_finds_lattice_optimum_and_respects_bounds_and_constraints():
    p = Lattice3()
    res = optimize(p, "coordinate_descent")
    grid = [np.arange(lo, hi + 1e-9, 0.25) for lo, hi in zip(p.space.lower, p.space.upper)]
    evs = [p.evaluate(x) for x in itertools.product(*grid)]
    best = min((e for e in evs if e.feasible), key=lambda e: e.objective)
    assert res.status == "converged"
    assert res.x == pytest.approx(best.x) and res.x == pytest.approx({"x": 0.5, "y": -0.25,
                                                                      "z": 1.5})
    assert res.objective == pytest.approx(best.objective)
    _assert_best_feasible(res)
    h = res.history
    for v in p.space.variables:  # never a candidate outside the bounds
        assert h[f"x.{v.name} [-]"].between(v.lower, v.upper).all()
    assert h["x.x [-]"].max() == 0.75 and not h.loc[h["x.x [-]"] > 0.5, "feasible"].any()
    c = res.cycles
    assert c["cycle"].tolist() == list(range(len(c))) and c["moved"].iloc[-1] == ""
    assert (np.diff(c["objective"]) <= 0).all() and c["feasible"].all()
    assert c["current.temperature [degC]"].iloc[-1] == pytest.approx(51.5)
    assert {"last_candidate.temperature [degC]", "x.z [-]", "n_evaluations"} <= set(c.columns)


def test_cd_reports_the_problems_metric_or_the_one_asked_for_or_none():
    class Plain(Quad):
        report_metric = None                       # the generic default: nothing to report

    plain = optimize(Plain(), "cd").cycles
    assert not [c for c in plain.columns if c.startswith(("current.", "last_candidate."))]
    assert optimize(Quad(), "cd").cycles["current.temperature [degC]"].notna().all()
    asked = optimize(Plain(), "cd", metric="count").cycles
    assert (asked["current.count"] == 3).all() and "last_candidate.count" in asked
    assert optimizers()["cd"].options["metric"] is None


def test_cd_start_on_lower_bound_and_cycle_limit():
    p = Quad(start=(-1.0, -1.0))
    res = optimize(p, "cd", max_cycles=2)
    assert res.status == "max_cycles" and len(res.cycles) == 3
    assert (res.history[["x.x [-]", "x.y [-]"]] >= -1.0).all().all()  # no minus candidate below -1
    assert res.x == {"x": -0.5, "y": -0.5}


def test_cd_parallel_candidates_gives_the_sequential_result():
    seq = optimize(Quad(), "cd")
    ex = CountingExecutor()
    par = optimize(Quad(), "cd", executor=ex, parallel_candidates=True)
    assert par.x == seq.x and par.objective == seq.objective and par.status == seq.status
    cols = ["cycle", "moved", "objective", "last_candidate.temperature [degC]", "x.x [-]",
            "x.y [-]"]
    pd.testing.assert_frame_equal(par.cycles[cols], seq.cycles[cols])
    assert 2 in ex.sizes and par.n_evaluations == seq.n_evaluations
    hist = [c for c in seq.history.columns if c != "wall_time [s]"]
    pd.testing.assert_frame_equal(par.history[hist], seq.history[hist])


class _Recording(Quad):
    """Quad that records the designs it computes (serial executor: same process)."""

    def __init__(self):
        super().__init__(start=(1.5, 0.0))          # x moves down: minus candidates accepted
        self.computed = []

    def _evaluate(self, v):
        self.computed.append((v["x"], v["y"]))
        return super()._evaluate(v)


def test_cd_prefetched_candidates_enter_the_run_only_when_asked_for(tmp_path):
    """Candidates computed side by side but not needed (the minus one was accepted) are
    neither in the history nor in the log, nor counted against the budget; a budget that
    stops the serial run stops the parallel one at the same evaluation."""
    seq = optimize(_Recording(), "cd")
    prob, ex = _Recording(), CountingExecutor()
    par = optimize(prob, "cd", executor=ex, parallel_candidates=True, out=tmp_path)
    assert len(prob.computed) > par.n_evaluations == par.n_computed == seq.n_evaluations
    assert par.x == seq.x and par.history["objective"].tolist() == \
        seq.history["objective"].tolist()
    logged = pd.read_csv(tmp_path / "evaluations.csv")
    assert len(logged) == par.n_evaluations
    again = optimize(_Recording(), "cd", executor=ex, parallel_candidates=True, out=tmp_path)
    assert again.n_reused == again.n_evaluations and again.n_computed == 0
    for budget in (3, 6):
        a = optimize(_Recording(), "cd", max_evaluations=budget)
        b = optimize(_Recording(), "cd", executor=ex, max_evaluations=budget,
                     parallel_candidates=True)
        assert (b.status, b.n_evaluations, b.x) == (a.status, a.n_evaluations, a.x)
        assert b.history["objective"].tolist() == a.history["objective"].tolist()


def test_run_prefetch_is_a_cache_hit_with_the_same_result_and_misses_other_designs():
    run = EvaluationRun(LoggedProblem(Quad()), None, None, CountingExecutor())
    assert run.prefetch([(0.0, 0.0)]) == 0                          # alone: nothing to pair
    assert run.prefetch([(0.25, 0.0), (0.5, 0.0)]) == 2
    assert run.evaluations == [] and run.logged.n_computed == 0
    key = design_key(run.space, (0.5, 0.0))
    kept = run.prefetched[key]
    ev = run.evaluate((0.5, 0.0))                                   # hit: no computation
    assert ev is kept and key not in run.prefetched and run.executor.sizes == [2]
    assert ev.objective == Quad().evaluate((0.5, 0.0)).objective and run.logged.n_computed == 1
    assert run.prefetch([(0.5, 0.0), (0.25, 0.0)]) == 0             # both known already
    other = run.evaluate((0.75, 0.0))                               # not prefetched: computed
    assert other.objective == Quad().evaluate((0.75, 0.0)).objective
    assert run.executor.sizes == [2, 1] and len(run.evaluations) == 2


def test_cd_max_evaluations_and_stop_callback():
    res = optimize(Quad(), "cd", max_evaluations=4)
    assert res.status == "max_evaluations" and res.n_evaluations <= 4
    assert not res.cycles["complete"].iloc[-1]

    def stop(ev):
        if ev.objective < 3:
            raise StopOptimization("good enough")
    res = optimize(Quad(), "cd", callback=stop)
    assert res.status == "stopped" and "good enough" in res.message and res.objective < 3
    assert not res.cycles["complete"].iloc[-1]
    res = optimize(Quad(), "sbplx", callback=stop)
    assert res.status == "stopped" and "good enough" in res.message and res.objective < 3


# ---------------------------------------------------------------- NLopt
@pytest.mark.parametrize("method, options, tol", [
    ("cobyla", {}, 1e-3), ("bobyqa", {}, 1e-2), ("neldermead", {}, 1e-3), ("sbplx", {}, 1e-3),
    ("bobyqa", {"constraint_handling": "auglag"}, 1e-3),
    ("neldermead", {"constraint_handling": "auglag"}, 2e-2),
    ("direct", {}, 1e-2)])
def test_nlopt_methods_reach_the_constrained_optimum(method, options, tol):
    res = optimize(Quad(), method, max_evaluations=200, **options)
    assert res.objective == pytest.approx(0.5, abs=tol)
    assert res.x["x"] == pytest.approx(0.5, abs=20 * tol)
    assert res.x["y"] == pytest.approx(1.5, abs=20 * tol)
    assert res.constraints["sum"] <= 0
    _assert_best_feasible(res)
    assert res.status in ("success", "ftol_reached", "xtol_reached", "max_evaluations")
    assert res.message and res.n_evaluations <= 200


def test_nlopt_default_budget_and_single_evaluation_per_point():
    res = optimize(Quad(), "cobyla")
    assert res.n_evaluations <= 60
    keys = res.history[["x.x [-]", "x.y [-]"]].round(12).apply(tuple, axis=1)
    assert keys.is_unique  # constraint callbacks never re-evaluate a design


@pytest.mark.parametrize("method", ALL_METHODS)
def test_failing_evaluations_do_not_crash(method):
    res = optimize(Flaky(start=(2.0, 0.0)), method, max_evaluations=120)
    failed = res.history[~res.history["success"]]
    assert len(failed) > 0 and (failed["status"] == "failed").all()
    assert failed["message"].str.contains("divergence|raised").all()
    assert res.success and res.objective < 10.0
    _assert_best_feasible(res)


@pytest.mark.parametrize("method", ["cd", "cobyla", "sbplx", "direct"])
def test_all_evaluations_failing(method):
    res = optimize(AlwaysFails(), method, max_evaluations=15)
    assert not res.success and not res.history["success"].any()
    assert "no feasible evaluation" in res.message and res.objective == math.inf


# ---------------------------------------------------------------- evaluation log
def test_log_round_trip_header_growth_and_truncated_row(tmp_path):
    path = tmp_path / "evaluations.csv"
    p = Quad()
    log = EvaluationLog(path, p)
    failed = Evaluation({"x": 9.0, "y": 0.0}, math.inf, success=False,
                        message="bad, \"x\"\nhere")
    good = p.evaluate([0.1 / 3, 1.0 + 1e-13])
    assert log.append(failed) == 1 and log.append(good) == 2  # new columns: header rewritten
    back = EvaluationLog(path, p)
    assert back.n_loaded == 2 and back.lookup([9.0, 0.0]).message == failed.message
    assert back.lookup([9.0, 0.0]).status == "failed"
    e = back.lookup(good.x)
    assert e.objective == good.objective and e.constraints == good.constraints
    assert e.metrics == good.metrics and e.x == good.x and e.success and e == good
    assert EvaluationLog(path, Quad(shift=1.0)).lookup(good.x) is None  # other settings
    assert back.lookup([0.5, 0.5]) is None
    with open(path, "a", encoding="utf-8") as fh:  # a write cut short by a kill
        fh.write("3,abc,0.5,0.")
    again = EvaluationLog(path, p)
    assert again.n_loaded == 2 and again.append(good) == 3
    assert pd.read_csv(path)["eval"].tolist() == [1, 2, 3]
    assert "x.x [-]" in pd.read_csv(path).columns
    assert (tmp_path / "evaluations.settings.json").exists()


def test_logged_problem_reuse_and_executor(tmp_path):
    lp = LoggedProblem(Quad(), EvaluationLog(tmp_path / "log.csv", Quad()))
    ex = CountingExecutor()
    evs = lp.evaluate_many([[0, 0], [1, 1], [0, 0]], executor=ex)
    assert ex.sizes == [2] and lp.n_computed == 2 and lp.n_reused == 1
    assert evs[0] is evs[2]
    lp2 = LoggedProblem(Quad(), EvaluationLog(tmp_path / "log.csv", Quad()))
    assert lp2.evaluate([1, 1]).objective == evs[1].objective and lp2.n_reused == 1
    assert lp2.n_computed == 0 and lp2.settings() == Quad().settings()
    with pytest.raises(TypeError, match="main process"):
        pickle.dumps(lp2)


@pytest.mark.parametrize("method, k", [("cd", 6), ("cobyla", 10), ("sbplx", 15),
                                       ("direct", 20), ("bobyqa", 8)])
def test_interrupted_run_resumes_from_the_log(tmp_path, method, k):
    fresh = optimize(Flaky(start=(2.0, 0.0)), method, out=tmp_path / "fresh",
                     max_evaluations=80)
    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):
        optimize(Flaky(start=(2.0, 0.0)), method, out=out, max_evaluations=80,
                 callback=Interrupt(k))
    assert len(pd.read_csv(out / "evaluations.csv")) == k
    assert not (out / "result.json").exists()
    res = optimize(Flaky(start=(2.0, 0.0)), method, out=out, max_evaluations=80)
    assert res.n_reused == k and res.n_computed == fresh.n_evaluations - k
    assert res.x == fresh.x and res.objective == fresh.objective
    assert (res.status, res.n_evaluations) == (fresh.status, fresh.n_evaluations)
    again = optimize(Flaky(start=(2.0, 0.0)), method, out=out, max_evaluations=80)
    assert again.n_computed == 0 and again.x == fresh.x
    assert len(pd.read_csv(out / "evaluations.csv")) == fresh.n_evaluations


def test_small_budget_then_larger_budget_reuses(tmp_path):
    first = optimize(Quad(), "cd", out=tmp_path, max_evaluations=5)
    assert first.status == "max_evaluations"
    res = optimize(Quad(), "cd", out=tmp_path)
    assert res.n_reused == 5 and res.x == optimize(Quad(), "cd").x


def test_output_files(tmp_path):
    res = optimize(Quad(), "cd", out=tmp_path)
    data = json.loads((tmp_path / "result.json").read_text())
    assert data["status"] == "converged" and data["x"] == res.x
    assert data["objective"] == res.objective and data["settings"] == Quad().settings()
    assert data["n_evaluations"] == res.n_evaluations and "settings_hash" in data
    cyc = pd.read_csv(tmp_path / "cycles.csv")
    assert len(cyc) == len(res.cycles) and len(pd.read_csv(tmp_path / "history.csv")) == len(
        res.history)
    optimize(Quad(), "cobyla", out=tmp_path / "nl")
    assert json.loads((tmp_path / "nl" / "result.json").read_text())["method"] == "cobyla"
    assert not (tmp_path / "nl" / "cycles.csv").exists()


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize("kwargs, match", [
    ({"method": "newton"}, "Unknown optimisation method 'newton'"),
    ({"method": "cd", "x0": {"x": 5.0}}, "design variable x = 5 .* outside its bounds"),
    ({"method": "cobyla", "x0": [0.0, -2.0]}, "design variable y = -2"),
    ({"method": "cd", "max_cycles": 0}, "max_cycles"),
    ({"method": "cd", "xtol_rel": 1e-3}, r"Unknown option\(s\) \['xtol_rel'\]"),
    ({"method": "cobyla", "max_evaluations": 0}, "max_evaluations"),
    ({"method": "direct", "constraint_handling": "auglag"}, "constraint_handling"),
    ({"method": "sbplx", "xtol_rel": -1.0}, "xtol_rel"),
    ({"method": "bobyqa", "initial_step": 0.0}, "initial_step"),
    ({"method": "cd", "x0": [0.0]}, "needs 2 values")])
def test_bad_input_raises_parameter_error(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        optimize(Quad(), **kwargs)


# ---------------------------------------------------------------- the registry
def _random_search(run, x0, max_evaluations, seed=0):
    """A toy optimiser: the start, then uniform random designs until the budget ends."""
    rng = np.random.default_rng(seed)
    run.evaluate(x0)
    while True:                     # optimize() turns the exhausted budget into the status
        run.evaluate(run.space.denormalize(rng.random(len(run.space))))


@pytest.fixture
def toy():
    spec = register_optimizer("toy", _random_search, options={"seed": 0}, max_evaluations=12,
                              aliases=("random-search",), description="uniform random search")
    yield spec
    unregister_optimizer("toy")


def test_registered_optimiser_runs_through_optimize(toy, tmp_path):
    res = optimize(Quad(), "toy", out=tmp_path)
    assert res.method == "toy" and res.status == "max_evaluations" and res.n_evaluations == 12
    assert "budget (12)" in res.message
    _assert_best_feasible(res)
    assert res.options == {"max_evaluations": 12, "seed": 0}
    again = optimize(Quad(), "Random-Search", out=tmp_path, max_evaluations=5, seed=1)
    assert again.n_reused == 1 and again.n_evaluations == 5      # the start design: from the log
    assert json.loads((tmp_path / "result.json").read_text())["method"] == "toy"
    assert not (tmp_path / "cycles.csv").exists()
    with pytest.raises(ParameterError, match=r"Unknown option\(s\) \['xtol_rel'\] for method "
                                             r"'toy'; options: seed"):
        optimize(Quad(), "toy", xtol_rel=1e-3)


def test_registry_lists_builtins_and_the_cli_offers_registered_methods(toy, capsys):
    from design.cli import _parser, main

    assert list(optimizers())[:6] == ALL_METHODS and optimizers()["toy"] is toy
    assert get_optimizer("Coordinate_Descent").name == "cd"
    assert get_optimizer("nelder-mead").options["constraint_handling"] == "penalty"
    assert get_optimizer("cobyla").options["constraint_handling"] == "native"
    assert _parser().parse_args(["optimize", "gripper", "--method", "toy"]).method == "toy"
    with pytest.raises(SystemExit):
        main(["optimize", "--help"])
    assert "toy (random-search): uniform random search" in " ".join(capsys.readouterr().out.split())
    unregister_optimizer("toy")
    with pytest.raises(SystemExit):
        _parser().parse_args(["optimize", "gripper", "--method", "toy"])
    assert "invalid choice: 'toy' (choose from 'cd', 'cobyla'" in capsys.readouterr().err
    register_optimizer("toy", _random_search, description="again")        # for the fixture


def test_unknown_or_clashing_optimiser_names(toy):
    with pytest.raises(ParameterError, match="Unknown optimisation method 'anneal'; use one of "
                                             "cd, cobyla, bobyqa, neldermead, sbplx, direct, mma, "
                                             "slsqp, ccsaq, scipy_slsqp, trust_constr, toy"):
        optimize(Quad(), "anneal")
    with pytest.raises(ParameterError, match=r"\['toy'\] already registered"):
        register_optimizer("toy", _random_search, description="twice")
    with pytest.raises(ParameterError, match=r"\['subplex'\] already registered"):
        register_optimizer("mine", _random_search, aliases=("subplex",), description="clash")
    with pytest.raises(ParameterError, match="max_evaluations = True"):
        register_optimizer("mine", _random_search, max_evaluations=True, description="-")
    with pytest.raises(ParameterError, match="must be callable"):
        register_optimizer("mine", "not a function", description="-")
    with pytest.raises(ParameterError, match="no method 'mine'"):
        unregister_optimizer("mine")
    replaced = register_optimizer("toy", _random_search, description="v2", replace=True)
    assert optimizers()["toy"] is replaced
    with pytest.raises(ParameterError, match="'random-search'"):       # its aliases went too
        get_optimizer("random-search")


def test_readme_lists_the_registered_methods():
    """The README's CLI table names the built-in methods of the registry, in its order."""
    import pathlib
    import re

    readme = (pathlib.Path(__file__).resolve().parents[2] / "README.md").read_text()
    listed = re.search(r"--method ((?:\w+\\?\|)+\w+)", readme).group(1).replace("\\", "")
    assert listed.split("|") == list(optimizers())


# ---------------------------------------------------------------- the real gripper
@pytest.mark.slow
def test_gripper_coordinate_descent_one_cycle(tmp_path):
    from design import GripperProblem

    res = optimize(GripperProblem(), "cd", out=tmp_path, max_cycles=1)
    assert res.status in ("converged", "max_cycles") and res.success
    assert res.objective <= res.history["objective"].iloc[0]
    assert len(res.cycles) == 2 and (tmp_path / "cycles.csv").exists()
    again = optimize(GripperProblem(), "cd", out=tmp_path, max_cycles=1)
    assert again.n_computed == 0 and again.x == res.x
