"""Study pattern_robustness (issue 28 item 8): files, a figure re-created from the CSV alone, and
the claim of the quick run: every classic pattern heated at its top power ends converged on a
stable state, with the same fold angles at 25 and 50 steps."""

import numpy as np
import pandas as pd

from studies import pattern_robustness
from studies._classic_patterns import PATTERNS


def test_quick_run_every_pattern_folds_stably_and_the_same_at_both_step_counts(quick_study):
    _, out, df = quick_study("pattern_robustness")
    assert set(df["pattern"]) == set(PATTERNS) and len(df) == 2 * len(PATTERNS)
    assert df["success"].all() and (df["status"] == "converged").all()
    assert df["stable"].astype(bool).all()
    assert (df["spread [deg]"] < 1.0).all(), df[["pattern", "spread [deg]"]]
    assert (df["fold_max [deg]"] > 40.0).all()                 # driven far at the top power
    for folds in df["folds [deg]"]:
        assert np.isfinite([float(x) for x in folds.split(";")]).all()
    assert (out / "pattern_robustness.png").stat().st_size > 10_000
    fig = pattern_robustness.plot(pd.read_csv(out / "pattern_robustness.csv"))
    assert len(fig.axes) == 3
