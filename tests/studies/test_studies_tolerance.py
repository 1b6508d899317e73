"""Study tolerance_sensitivity (quick run): the report's table, the Monte Carlo comparison and
the figures."""

import json

import numpy as np
import pytest


@pytest.fixture(scope="module")
def quick(quick_study):
    return quick_study("tolerance_sensitivity")


def test_writes_csv_figures_and_meta(quick):
    module, out, df = quick
    for stem in (module.NAME, f"{module.NAME}_mc"):
        assert (out / f"{stem}.png").stat().st_size > 10_000
    meta = json.loads((out / "meta.json").read_text())
    assert meta["rows"] == len(df) and meta["settings"] == {"quick": True}
    assert set(df["table"]) == {"parameters", "outputs", "samples"}


def test_parameters_are_sorted_by_their_effect_on_fold_5(quick):
    module, _, df = quick
    p = df[df["table"] == "parameters"]
    assert set(p["parameter"]) == set(module.TOLERANCES)
    effect = p["d fold_5 [deg] per tolerance"].abs().to_numpy()
    assert np.all(np.diff(effect) <= 0) and effect[0] > 0
    assert p["fold_5 variance share [-]"].sum() == pytest.approx(1.0, rel=1e-9)
    # the air's conductivity (10 %) moves the fold and the temperature most
    assert p["parameter"].iloc[0] == "medium_conductivity"


def test_monte_carlo_rows_beside_first_order(quick):
    module, _, df = quick
    o = df[df["table"] == "outputs"].set_index("output")
    assert list(o.index) == [*module.OUTPUTS, "all limits"]
    assert (o.loc[list(module.OUTPUTS), "sigma (FOSM)"] > 0).all()
    assert (o["n_samples"] == module.SAMPLES_QUICK).all()
    s = df[df["table"] == "samples"]
    assert len(s) == module.SAMPLES_QUICK and s["success"].astype(bool).all()
    # each sample's first-order prediction is close to its simulation: within the spread
    err = (s["fold_5 [deg]"] - s["fold_5 FOSM [deg]"]).abs()
    assert err.max() < o.loc["fold_5", "sigma (FOSM)"]
