"""Fabrication uncertainty: distributions, seeded sampling, statistics, yield sweeps.

The gripper part runs about 20 gripper evaluations (bisect mode), on a 2-process pool (one
worker killed mid-sweep) and a 2-worker local Dask cluster.
"""

import math
import os
import signal

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from design.core.executors import ProcessExecutor, SerialExecutor, make_executor
from design import GripperProblem
from design.analysis.robustness import residual_fold_grid, sweep_residual_fold
from design.analysis.uncertainty import (Distribution, FabricationScenario, UncertainInput, quantile,
                                rank_correlations, residual_fold_per_crease, wilson_interval)
from design.analysis.uncertainty_sweep import (GripperSampleProblem, RobustYieldProblem,
                                      summarize_yield, sweep_uncertainty)
from simulator.errors import ParameterError

PROBLEM = GripperProblem(mode="bisect")
DEG = math.pi / 180
SCENARIO = FabricationScenario(
    residual_fold_per_crease(Distribution.normal(-5 * DEG, 4 * DEG, -20 * DEG, 10 * DEG))
    + (UncertainInput("t_gold", Distribution.normal(0.2e-6, 0.01e-6, 0.17e-6, 0.23e-6)),
       UncertainInput("t_su8", Distribution.normal(0.8e-6, 0.04e-6, 0.68e-6, 0.92e-6)),
       UncertainInput("delta_alpha", Distribution.uniform(34e-6, 42e-6)),
       UncertainInput("env_conductivity", Distribution.uniform(0.024, 0.030))),
    correlations=(("residual_fold", 0.7),), name="test")
TIMING = ["wall_time [s]"]


def test_distributions():
    u = np.array([0.025, 0.5, 0.975])
    np.testing.assert_allclose(Distribution.normal(1.0, 2.0).ppf(u), 1 + 2 * stats.norm.ppf(u))
    cut = Distribution.normal(0.0, 1.0, -0.5, 2.0).ppf(np.linspace(1e-9, 1 - 1e-9, 50))
    assert cut.min() >= -0.5 and cut.max() <= 2.0 and np.all(np.diff(cut) > 0)
    np.testing.assert_allclose(Distribution.uniform(2, 4).ppf(u), 2 + 2 * u)
    assert (Distribution.fixed(3.0).ppf(u) == 3.0).all()
    with pytest.raises(ParameterError, match="positive, finite standard deviation"):
        Distribution.normal(0, 0)
    with pytest.raises(ParameterError, match="kind"):
        Distribution("lognormal")
    with pytest.raises(ParameterError, match="must be below high"):
        Distribution.uniform(1, 1)


def test_scenario_validation():
    with pytest.raises(ParameterError, match="use one of"):
        UncertainInput("thickness", Distribution.fixed(1e-6))
    with pytest.raises(ParameterError, match="allowed range"):
        UncertainInput("t_gold", Distribution.uniform(-1e-6, 1e-6))
    dup = UncertainInput("t_gold", Distribution.fixed(0.2e-6))
    with pytest.raises(ParameterError, match="repeat"):
        FabricationScenario((dup, dup))
    with pytest.raises(ParameterError, match=r"rho\['residual_fold'\]"):
        FabricationScenario(SCENARIO.inputs, (("residual_fold", 1.5),))
    with pytest.raises(ParameterError, match="has no input"):
        FabricationScenario(SCENARIO.inputs, (("wafer", 0.5),))
    with pytest.raises(ParameterError, match="'mc' or 'lhs'"):
        SCENARIO.sample(4, 0, "sobol")


@pytest.mark.parametrize("method", ["mc", "lhs"])
def test_sampling_is_seeded_and_correlated_by_group(method):
    a = SCENARIO.sample(400, 7, method)
    assert a.equals(SCENARIO.sample(400, 7, method)) and not a.equals(SCENARIO.sample(400, 8,
                                                                                     method))
    assert list(a.columns) == list(SCENARIO.parameters)
    creases = a[["residual_fold_c2", "residual_fold_c3"]].to_numpy()
    rho = stats.spearmanr(creases[:, 0], creases[:, 1]).statistic
    assert 0.55 < rho < 0.8                                    # copula rho 0.7 (normal scores)
    assert abs(stats.spearmanr(a["t_gold"], a["t_su8"]).statistic) < 0.15     # independent
    assert a["residual_fold_c2"].between(-20 * DEG, 10 * DEG).all()
    if method == "lhs":                                        # one sample per stratum
        strata = np.floor(400 * (a["delta_alpha"] - 34e-6) / 8e-6).astype(int)
        assert sorted(strata) == list(range(400))


def test_sampling_and_statistics_are_scipys():
    """The Latin hypercube is scipy's (seeded from the same generator), truncated normals are
    scipy's truncnorm and the yield interval is scipy's Wilson interval."""
    one = FabricationScenario((UncertainInput("delta_alpha", Distribution.uniform(34e-6,
                                                                                  42e-6)),))
    u = stats.qmc.LatinHypercube(1, rng=np.random.default_rng(5)).random(16)[:, 0]
    np.testing.assert_allclose(one.sample(16, 5, "lhs")["delta_alpha"], 34e-6 + 8e-6 * u,
                               rtol=1e-14)
    p = np.linspace(0.01, 0.99, 9)
    cut = Distribution.normal(1.0, 2.0, -0.5, 2.0)
    np.testing.assert_allclose(cut.ppf(p), stats.truncnorm.ppf(p, -0.75, 0.5, loc=1.0,
                                                               scale=2.0), rtol=1e-14)
    for k, n in ((0, 7), (3, 10), (37, 64), (64, 64)):
        ci = stats.binomtest(k, n).proportion_ci(0.9, method="wilson")
        assert wilson_interval(k, n, 0.9) == (ci.low, ci.high)
    assert all(math.isnan(v) for v in wilson_interval(0, 0))


def test_statistics():
    low, high = wilson_interval(5, 10)
    assert low == pytest.approx(0.2366, abs=1e-4) and high == pytest.approx(0.7634, abs=1e-4)
    assert wilson_interval(0, 10)[0] == 0.0 and wilson_interval(10, 10)[1] == 1.0
    assert quantile([1.0, 2.0, math.nan, 3.0], 0.5) == 2.0
    assert quantile([1.0, math.nan], 0.9) == math.inf             # unmet counts as infinite
    x = np.linspace(0, 1, 30)
    table = pd.DataFrame({"x": x, "flat": 1.0, "y": x ** 3, "noise": np.sin(97 * x)})
    r = rank_correlations(table, ["x", "flat", "noise"], "y").set_index("input")
    assert r.loc["x", "spearman [-]"] == pytest.approx(1.0)
    assert math.isnan(r.loc["flat", "spearman [-]"])
    assert r.loc["noise", "low [-]"] < r.loc["noise", "spearman [-]"] < r.loc["noise",
                                                                              "high [-]"]


def _kill_first_worker(ex):
    def progress(done, total):
        if done == 1:
            os.kill(ex.worker_pids()[0], signal.SIGKILL)
    return progress


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    """The start design at 4 samples: serial (logged), process pool with a worker killed
    after the first point, local Dask cluster."""
    tmp = tmp_path_factory.mktemp("unc")
    samples = SCENARIO.sample(4, 11, "lhs")
    out = {"log": tmp / "evaluations.csv", "samples": samples}
    out["serial"] = sweep_uncertainty(PROBLEM, SCENARIO, samples, log=out["log"])
    with ProcessExecutor(2) as ex:
        out["process"] = sweep_uncertainty(PROBLEM, SCENARIO, samples, executor=ex,
                                           progress=_kill_first_worker(ex))
    with make_executor("dask", workers=2) as ex:
        out["dask"] = sweep_uncertainty(PROBLEM, SCENARIO, samples, executor=ex)
    return out


def test_uncertainty_table_identical_on_every_executor(tables):
    serial = tables["serial"].drop(columns=TIMING)
    assert len(serial) == 4 and serial["success"].all()
    assert list(serial["sample"]) == [0, 1, 2, 3]
    np.testing.assert_allclose(serial["residual_fold_c2 [deg]"],
                               tables["samples"]["residual_fold_c2"] / DEG, rtol=1e-15)
    text = serial.to_csv(index=False)
    for kind in ("process", "dask"):                  # process: a worker was killed mid-sweep
        assert tables[kind].drop(columns=TIMING).to_csv(index=False) == text, kind


def test_uncertainty_sweep_resumes_from_its_log(tables):
    done = []
    again = sweep_uncertainty(PROBLEM, SCENARIO, tables["samples"], log=tables["log"],
                              progress=lambda d, t: done.append(d))
    assert done == []
    assert again.to_csv(index=False) == tables["serial"].to_csv(index=False)


def test_summary_and_robust_problem_use_the_same_samples(tables):
    summary, sens = summarize_yield(tables["serial"], SCENARIO, quantiles=(0.5, 0.75))
    table = tables["serial"]
    row = summary.iloc[0]
    assert row["samples"] == 4 and row["yield [-]"] == table["works"].mean()
    assert row["yield_low [-]"] <= row["yield [-]"] <= row["yield_high [-]"]
    assert row["power_q0.5 [mW]"] == sorted(table["total_power [mW]"])[1]
    assert set(sens["output"]) == {"total_power [mW]", "temperature [degC]"}
    assert len(sens) == 2 * len(SCENARIO.inputs)
    robust = RobustYieldProblem(PROBLEM, SCENARIO, samples=4, seed=11, method="lhs", q=0.75,
                                yield_target=0.5)
    ev = robust.evaluate({})
    assert ev.success and ev.metrics["yield [-]"] == row["yield [-]"]
    assert 1e3 * ev.objective == row["power_q0.75 [mW]"]
    assert ev.constraints["yield"] == 0.5 - row["yield [-]"]
    with pytest.raises(ParameterError, match="yield_target"):
        RobustYieldProblem(PROBLEM, SCENARIO, yield_target=0)


def test_yield_with_uncertainty_off_is_the_deterministic_evaluation(tmp_path):
    off = FabricationScenario((UncertainInput("residual_fold", Distribution.fixed(0.0)),
                               UncertainInput("env_conductivity", Distribution.fixed(0.026))))
    done = []
    table = sweep_uncertainty(PROBLEM, off, off.sample(6, 3, "mc"), executor=SerialExecutor(),
                              progress=lambda d, t: done.append(t))
    assert set(done) == {1}                                    # six identical points, one run
    summary, _ = summarize_yield(table, off)
    ev = PROBLEM.evaluate(PROBLEM.space.start)
    assert summary["yield [-]"].iloc[0] == float(ev.feasible)     # 0 or 1
    assert (table["total_power [mW]"] == 1e3 * ev.objective).all()
    assert GripperSampleProblem(PROBLEM, ("t_gold",)).space.names[-1] == "t_gold"


@pytest.mark.slow
def test_one_input_yield_matches_a_fine_deterministic_sweep():
    """Residual fold uniform on [-20, 0] deg: the Monte Carlo yield (16 samples) and its
    Wilson interval contain the working fraction of a 20-point midpoint sweep. With the
    paper's chains, whose hotter creases cross the temperature limit inside this range (with
    the integral loss, the default since 7 Dec 2026, every point of it works)."""
    from design.devices import GripperHeatModel

    problem = GripperProblem(mode="bisect", heat=GripperHeatModel(loss_model="chain"))
    one = FabricationScenario((UncertainInput("residual_fold",
                                              Distribution.uniform(-20 * DEG, 0.0)),))
    with ProcessExecutor(2) as ex:
        table = sweep_uncertainty(problem, one, one.sample(16, 5, "mc"), executor=ex)
        fine = sweep_residual_fold(problem, None, residual_fold_grid(np.arange(-19.5, 0, 1.0)),
                                   executor=ex)
    fraction = fine["feasible"].mean()
    assert 0 < fraction < 1                                     # the limit is crossed
    summary, _ = summarize_yield(table, one)
    row = summary.iloc[0]
    assert row["yield_low [-]"] <= fraction <= row["yield_high [-]"], (row, fraction)
