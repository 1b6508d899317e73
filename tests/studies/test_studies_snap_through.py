"""Study snap_through: files, a figure re-created from the CSV alone, the physics of the quick
run (the roof's branches, the Miura passing its snap)."""

import json

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from studies import snap_through


@pytest.fixture(scope="module")
def quick(quick_study):
    _, out, df = quick_study("snap_through")
    return out, df


@pytest.mark.slow
def test_snap_through_study_quick(quick):
    out, df = quick
    assert (out / "snap_through.png").stat().st_size > 10_000
    assert json.loads((out / "meta.json").read_text())["rows"] == len(df)
    assert {"load [mN]", "power [mW]", "displacement [um]", "stable"} <= set(df.columns)
    roof = df[(df["table"] == "roof") & (df["method"] == "arc length")]
    assert (roof["stable"] == False).any() and (roof["stable"] == True).any()  # noqa: E712
    assert roof["load [mN]"].min() < 0 < roof["load [mN]"].max()
    miura = df[df["table"] == "miura"]
    assert miura["power [mW]"].iloc[-1] == pytest.approx(12.0)
    assert np.isfinite(miura["displacement [um]"]).all()
    fig = snap_through.plot(pd.read_csv(out / "snap_through.csv"))
    assert isinstance(fig, Figure) and all(ax.has_data() for ax in fig.axes)
    dashed = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_linestyle() == "--"]
    assert dashed                                       # unstable branches are dashed
