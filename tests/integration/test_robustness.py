"""Residual-fold robustness: grids, sweeps identical across executors, the robust problem.

Runs about 20 gripper evaluations (bisect mode, ~1 s each) plus a process pool and a local
Dask cluster with two workers each.
"""

import logging
import math
import pickle
import time

import numpy as np
import pytest

from design.core.executors import SerialExecutor, make_executor
from design import GripperHeatModel, GripperProblem
from design.analysis.robustness import (TIMING_COLUMNS, RobustGripperProblem,
                               residual_fold_grid, sweep_residual_fold, with_residual_fold)
from simulator.errors import ParameterError

logger = logging.getLogger(__name__)

#: The paper setting (the chain heat loss): the sweep machinery on the reference's model.
PAPER = GripperHeatModel(loss_model="chain")
PROBLEM = GripperProblem(mode="bisect", heat=PAPER)
DESIGNS = [{}, {"W": 150e-6, "La": 900e-6}]          # start design, a narrower-crease one
GRID = residual_fold_grid([-10, 0])
R10 = math.radians(-10)


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory):
    """The 2 x 2 sweep with each executor (serial one logged); tables, CSV paths, timings."""
    tmp = tmp_path_factory.mktemp("sweeps")
    out = {"log": tmp / "log.csv"}
    for kind in ("serial", "process", "dask"):
        t0 = time.perf_counter()
        with make_executor(kind, workers=2) as ex:
            t1 = time.perf_counter()
            table = sweep_residual_fold(PROBLEM, DESIGNS, GRID, executor=ex,
                                        log=out["log"] if kind == "serial" else None)
            t2 = time.perf_counter()
        path = tmp / f"{kind}.csv"
        table.drop(columns=list(TIMING_COLUMNS)).to_csv(path, index=False)
        out[kind] = (table, path)
        logger.info("sweep %s: start %.2f s, sweep %.2f s", kind, t1 - t0, t2 - t1)
    return out


def test_residual_fold_grid():
    assert GRID == [{"all": R10}, {"all": 0.0}]
    prod = residual_fold_grid([-10, 0], creases=("base", "arm"))
    assert prod == [{"base": R10, "arm": R10}, {"base": R10, "arm": 0.0},
                    {"base": 0.0, "arm": R10}, {"base": 0.0, "arm": 0.0}]
    assert residual_fold_grid({"base": [-10], "arm": [0, 5]}) == [
        {"base": R10, "arm": 0.0}, {"base": R10, "arm": math.radians(5)}]
    with pytest.raises(ParameterError, match="crease groups"):
        residual_fold_grid([0], creases=("hinge",))
    with pytest.raises(ParameterError, match="give radians"):
        sweep_residual_fold(PROBLEM, None, [-10.0])          # degrees passed as radians
    with pytest.raises(ParameterError, match="no residual folds"):
        sweep_residual_fold(PROBLEM, None, [])


def test_sweep_csv_identical_across_executors(sweeps):
    table, path = sweeps["serial"]
    assert list(table["W [um]"]) == [200.0, 200.0, 150.0, 150.0]       # designs outer
    assert list(table["residual_fold [deg]"]) == [-10.0, 0.0, -10.0, 0.0]
    assert table["success"].all() and table["status"].isin(["feasible", "infeasible"]).all()
    for col in ("assembly_power [mW]", "grip_power [mW]", "total_power [mW]",
                "temperature [degC]", "margin temperature [-]", "wall_time [s]", "message"):
        assert col in table.columns
    np.testing.assert_allclose(table["total_power [mW]"],
                               table["assembly_power [mW]"] + table["grip_power [mW]"], rtol=1e-14)
    np.testing.assert_array_equal(table["feasible"], table["margin temperature [-]"] >= 0)
    serial = path.read_bytes()
    for kind in ("process", "dask"):
        assert sweeps[kind][1].read_bytes() == serial, kind


def test_sweep_reuses_its_evaluation_log(sweeps):
    done = []
    again = sweep_residual_fold(PROBLEM, DESIGNS, GRID, executor=SerialExecutor(),
                                log=sweeps["log"], progress=lambda d, t: done.append(d))
    assert done == []                                        # nothing recomputed
    assert again.to_csv(index=False) == sweeps["serial"][0].to_csv(index=False)


def test_negative_residual_fold_needs_more_power(sweeps):
    """Creases starting folded the other way (-10 deg) need more power to assemble and grip."""
    t = sweeps["serial"][0]
    neg, zero = t[t["residual_fold [deg]"] == -10.0], t[t["residual_fold [deg]"] == 0.0]
    for col in ("assembly_power [mW]", "grip_power [mW]", "total_power [mW]",
                "temperature [degC]"):
        assert (neg[col].to_numpy() > zero[col].to_numpy()).all(), col


def test_robust_objective_is_worst_case(sweeps):
    robust = RobustGripperProblem(PROBLEM, GRID)
    assert pickle.loads(pickle.dumps(robust)) == robust
    assert robust.space is PROBLEM.space and robust.settings()["residual_folds"] == ["-10deg",
                                                                                     "0deg"]
    ev = robust.evaluate(DESIGNS[0])
    rows = sweeps["serial"][0].iloc[:2]
    assert ev.success and ev.status == "infeasible"      # -10 deg is too hot; the message says so
    assert ev.message == ("all 2 residual folds met; residual fold -10deg: both stages met; not "
                          "feasible: crease 2: centre-line mean 257.13 degC > 1.2 T_g = 252 degC")
    assert 1e3 * ev.objective == rows["total_power [mW]"].max()
    assert ev.constraints["temperature"] == (-rows["margin temperature [-]"]).max()
    assert ev.metrics["total_power@-10deg [mW]"] == rows["total_power [mW]"].iloc[0]
    assert ev.metrics["total_power@0deg [mW]"] == rows["total_power [mW]"].iloc[1]
    assert ev.feasible == rows["feasible"].all()


def test_failed_point_and_robust_evaluation_failed_by_one_residual(tmp_path):
    # the start design assembles with 26.4 mW per crease at 0 deg, 29.4 mW at -10 deg
    capped = GripperProblem(mode="bisect", power_cap=28e-3, heat=PAPER)
    row = sweep_residual_fold(capped, None, GRID[:1], log=tmp_path / "log.csv")
    assert not row["success"].any() and (row["status"] == "not_met").all()
    assert not row["feasible"].any()
    assert row[["assembly_power [mW]", "grip_power [mW]", "total_power [mW]"]].isna().to_numpy().all()
    assert row["message"].iloc[0].startswith("assembly: criterion not met below the power cap")
    again = sweep_residual_fold(capped, None, GRID[:1], log=tmp_path / "log.csv")
    assert again.to_csv(index=False) == row.to_csv(index=False)         # read back from the log

    robust = RobustGripperProblem(capped, GRID)
    ev = robust.evaluate({})
    assert not ev.success and ev.status == "not_met" and math.isinf(ev.objective)
    assert not ev.feasible and ev.metrics["total_power [mW]"] is None
    assert ev.message.startswith("residual fold -10deg: assembly: criterion not met")
    assert "residual fold 0deg" not in ev.message
    assert ev.metrics["total_power@-10deg [mW]"] is None          # not met: None, never inf
    assert ev.metrics["assembly_power@-10deg [mW]"] is None
    assert math.isfinite(ev.metrics["total_power@0deg [mW]"])


def test_per_group_residual_folds(sweeps):
    """Equal group values reproduce the uniform sweep bit for bit; a residual on the arms
    only raises the grip power, not the assembly power."""
    table = sweep_residual_fold(PROBLEM, DESIGNS[0],
                                [{"base": R10, "arm": R10}, {"base": 0.0, "arm": R10}])
    assert ["residual_fold base [deg]", "residual_fold arm [deg]"] == list(table.columns[4:6])
    uniform = sweeps["serial"][0].drop(columns=["residual_fold [deg]", *TIMING_COLUMNS])
    same = table.drop(columns=["residual_fold base [deg]", "residual_fold arm [deg]",
                               *TIMING_COLUMNS])
    assert same.iloc[:1].to_csv(index=False) == uniform.iloc[:1].to_csv(index=False)
    arm_only, flat = table.iloc[1], sweeps["serial"][0].iloc[1]
    assert arm_only["grip_power [mW]"] > flat["grip_power [mW]"]
    assert abs(arm_only["assembly_power [mW]"] - flat["assembly_power [mW]"]) < 0.5


def test_with_residual_fold_builds_the_point_problems():
    p = with_residual_fold(PROBLEM, R10)
    assert type(p) is GripperProblem and p.residual_fold == R10
    g = with_residual_fold(PROBLEM, {"arm": R10})
    assert type(g) is GripperProblem and g.group_folds() == {"base": 0.0, "arm": R10}
    assert g.settings()["residual_fold [rad]"] == {"base": 0.0, "arm": R10}
    assert g.design({}).crease_residual_folds() == {2: 0.0, 5: 0.0, 3: R10, 9: R10}
    assert with_residual_fold(g, R10).group_folds() == {"base": R10, "arm": R10}
    with pytest.raises(ParameterError, match="crease groups"):
        with_residual_fold(PROBLEM, {"all": 0.0, "arm": 0.1})
