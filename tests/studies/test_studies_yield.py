"""Study gripper_yield in quick mode: tables, figures, metadata."""

import json

import numpy as np
import pandas as pd

from design.analysis.uncertainty_sweep import CATEGORIES
from studies import gripper_yield


def test_gripper_yield_quick(tmp_path):
    out = tmp_path / "gy"
    assert gripper_yield.main(["--quick", "--out", str(out), "--no-progress"]) == out
    for name in ("gripper_yield.csv", "gripper_yield.png", "gripper_yield_inputs.png",
                 "meta.json"):
        assert (out / name).exists(), name
    assert json.loads((out / "meta.json").read_text())["settings"] == {"quick": True}
    df = pd.read_csv(out / "gripper_yield.csv")
    labels = [gripper_yield.START, gripper_yield.PAPER, gripper_yield.ROBUST,
              *gripper_yield.PATH]
    samples, summary = df[df["table"] == "samples"], df[df["table"] == "summary"]
    assert list(summary["design"]) == labels
    assert len(samples) == len(labels) * gripper_yield.SAMPLES_QUICK
    works = samples["works"].astype(str).str.lower() == "true"
    assert set(samples["category"]) <= set(CATEGORIES)
    assert ((samples["category"] == "works") == works).all()
    assert set(samples["attempts"]) <= {1, 2}
    for label, row in summary.set_index("design").iterrows():
        mine = samples[samples["design"] == label]
        failed = int((mine["category"] == "solver failed").sum())
        assert row["solver_failed"] == failed
        assert row["yield [-]"] == works[mine.index].sum() / (len(mine) - failed)
        assert row["yield_low [-]"] <= row["yield [-]"] <= row["yield_high [-]"]
    sens = df[df["table"] == "sensitivity"]
    assert len(sens) == len(labels) * 2 * len(gripper_yield.SCENARIO.inputs)
    assert np.all(np.abs(sens["spearman [-]"].dropna()) <= 1)
    robust = df[(df["table"] == "designs") & (df["design"] == gripper_yield.ROBUST)].iloc[0]
    assert robust["evaluations"] <= gripper_yield.ROBUST_BUDGET_QUICK
