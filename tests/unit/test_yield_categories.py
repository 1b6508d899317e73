"""Sample categories and the yield among evaluated samples (design.analysis.uncertainty_sweep),
and the gripper problem's power-search steps."""

import math

import pandas as pd
import pytest

from design import GripperProblem
from design.analysis.uncertainty import SCENARIOS
from design.analysis.uncertainty_sweep import CATEGORIES, sample_category, summarize_yield
from design.core.problem import Evaluation
from simulator import ParameterError


def _ev(success=True, status="", temperature=-0.1, size=-0.5):
    return Evaluation({"W": 1.0}, 1e-3 if success else math.inf,
                      {"temperature": temperature, "W": size} if success else {},
                      success=success, status=status)


def test_each_evaluation_gets_one_category():
    assert sample_category(_ev()) == "works"
    assert sample_category(_ev(temperature=0.2)) == "too hot"
    assert sample_category(_ev(size=0.1)) == "outside bounds"
    assert sample_category(_ev(False, "not_met")) == "target not met"
    assert sample_category(_ev(False, "failed")) == "solver failed"
    assert set(CATEGORIES) >= {"works", "too hot", "target not met", "solver failed"}


def _table(statuses):
    """A sweep table of one design: ``statuses`` of its samples."""
    scenario = SCENARIOS["default"]
    rows = []
    for k, status in enumerate(statuses):
        ok = status in ("feasible", "infeasible")
        row = {"W [um]": 200.0, "sample": k, "success": ok, "status": status,
               "works": status == "feasible", "total_power [mW]": 10.0 + k if ok else math.nan,
               "temperature [degC]": 200.0}
        row.update({c: float(k) for c in (i.column for i in scenario.inputs)})
        rows.append(row)
    return pd.DataFrame(rows), scenario


def test_yield_leaves_solver_failures_out_and_counts_them():
    table, scenario = _table(["feasible"] * 6 + ["infeasible", "not_met", "failed", "failed"])
    summary, _ = summarize_yield(table, scenario)
    row = summary.iloc[0]
    assert row["samples"] == 10 and row["solver_failed"] == 2
    assert row["yield [-]"] == 6 / 8                  # not met and too hot count as broken
    assert row["yield_low [-]"] < 6 / 8 < row["yield_high [-]"]


def test_yield_of_a_design_whose_every_sample_failed_is_unknown():
    table, scenario = _table(["failed", "failed"])
    row = summarize_yield(table, scenario)[0].iloc[0]
    assert row["solver_failed"] == 2 and math.isnan(row["yield [-]"])


def test_power_steps_default_to_the_searchs_and_are_checked():
    default = GripperProblem()
    assert "power_steps [W]" not in default.settings()       # cache keys as before
    small = GripperProblem(power_step=0.05e-3, max_power_step=0.1e-3)
    assert small.settings()["power_steps [W]"] == [0.05e-3, 0.1e-3]
    with pytest.raises(ParameterError, match="power_step = -1"):
        GripperProblem(power_step=-1)
