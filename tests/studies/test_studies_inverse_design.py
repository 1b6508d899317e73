"""Study inverse_design (quick run: (a) a 3 x 3-cell Miura sheet, 12 heater powers, 20 s per
method; (b) the gripper's dimensions and heater powers, 8 variables, 15 s per method): files,
columns with units, and what the gradient runs found."""

import json

import pytest


@pytest.fixture(scope="module")
def quick(quick_study):
    return quick_study("inverse_design")


def _table(df, kind, case="a"):
    return df[(df["table"] == kind) & (df["case"] == case)].dropna(axis=1, how="all")


def test_writes_csv_png_and_meta(quick):
    module, out, df = quick
    assert (out / "inverse_design.png").stat().st_size > 10_000
    assert (out / "inverse_design_gripper.png").stat().st_size > 10_000
    meta = json.loads((out / "meta.json").read_text())
    assert meta["rows"] == len(df) and meta["settings"] == {"quick": True}
    assert set(df["table"]) == {"summary", "crease", "history", "design"}
    assert set(df["case"]) == {"a", "b"}
    assert {"wall_time [s]", "total_power [mW]", "best_power [mW]", "fold_error [deg]",
            "temperature [degC]", "max_fold_error [deg]"} <= set(df.columns)
    assert not any(c.endswith(("[rad]", "[W]", "[m]", "[K]")) for c in df.columns)
    assert set(module.plot(df)) == {"inverse_design", "inverse_design_gripper"}  # from the CSV
    old = df[df["case"] == "a"].drop(columns="case")    # results written before case (b)
    assert set(module.plot(old)) == {"inverse_design"}


def test_gradient_run_meets_targets_and_limit_below_the_reference(quick):
    _, _, df = quick
    s = _table(df, "summary").set_index("method")
    assert set(s.index) == {"reference", "mma", "cobyla"}
    assert (s["variables"] == 12).all()
    mma = s.loc["mma"]
    assert str(mma["success"]).lower() == "true", mma["message"]
    assert mma["max_fold_error [deg]"] <= 0.5 and mma["max_temperature [degC]"] <= 252.0
    assert mma["total_power [mW]"] < s.loc["reference", "total_power [mW]"]
    c = _table(df, "crease")
    c = c[c["method"] == "mma"]
    assert len(c) == 12 and (c["fold_error [deg]"].abs() <= 0.5).all()
    # both runs had the same budget; the derivative-free one spent it
    assert s.loc["cobyla", "wall_time [s]"] >= module_budget()
    assert s.loc["cobyla", "simulations"] > s.loc["mma", "simulations"]


def test_history_best_is_monotone_and_feasible(quick):
    _, _, df = quick
    h = _table(df, "history")
    for method, g in h.groupby("method"):
        best = g["best_power [mW]"].dropna()
        assert (best.diff().dropna() <= 1e-12).all(), method
        assert (g["wall_time [s]"].diff().dropna() > 0).all(), method


def test_gripper_case(quick):
    """Case (b): the reference (the paper's design at evaluate_gripper's powers) and both
    methods' rows; MMA, with gradients, improves on its infeasible start within its budget:
    its returned design violates the constraints less than the start (g = 757, tips 857 um
    apart) or is feasible."""
    _, _, df = quick
    s = _table(df, "summary", "b").set_index("method")
    assert set(s.index) == {"reference", "mma", "cobyla"} and (s["variables"] == 8).all()
    assert {"base_fold [deg]", "tip_distance [um]", "max_temperature [degC]"} <= set(s.columns)
    mma = s.loc["mma"]
    assert mma["simulations"] >= 2
    assert str(mma["success"]).lower() == "true" or mma["max_violation [-]"] < 757
    d = _table(df, "design", "b")
    assert set(d["variable"]) == {"W", "La", "L1", "L2", "power_2", "power_3", "power_5",
                                  "power_9"}
    assert d.groupby("method").size().eq(8).all()
    h = _table(df, "history", "b")
    assert set(h["method"]) == {"mma", "cobyla"}


def module_budget():
    from studies.inverse_design import QUICK

    return QUICK["budget"]
