"""Study heater_allocation (quick run): files, and what the allocations found."""

import json

import numpy as np
import pytest


@pytest.fixture(scope="module")
def quick(quick_study):
    _, out, df = quick_study("heater_allocation")
    return out, df


def test_the_bound_is_the_centre_line_measure_and_the_figure_says_so(quick_study):
    module, _, df = quick_study("heater_allocation")
    s = df[(df["table"] == "summary") & (df["variant"] != "flat-shape LP")]
    assert (s["temperature_measure"] == "centre_line").all()
    # the limit measure (centre-line mean) is below the hottest node and within 1.2 T_g
    assert (s["limit_temperature [degC]"] < s["max_crease_temperature [degC]"]).all()
    assert (s["limit_temperature [degC]"] <= 252.0 + 1e-6).all()
    note = " ".join(t.get_text() for t in module.plot(df).texts
                    if t.get_gid() == "assumptions").replace("\n", " ")
    assert "centre-line mean (nodes A, B, Ctr) of every crease <= 1.2 T_g = 252" in note
    assert (f"allocations {s['limit_temperature [degC]'].max():.0f} °C (centre line), hottest "
            f"node {s['max_crease_temperature [degC]'].max():.0f} °C") in note
    assert "flat-shape LP" in note


def test_writes_csv_png_and_meta(quick):
    out, df = quick
    assert (out / "heater_allocation.png").stat().st_size > 10_000
    meta = json.loads((out / "meta.json").read_text())
    assert meta["rows"] == len(df) and meta["settings"] == {"quick": True}
    assert set(df["table"]) == {"summary", "crease", "rounds"}


def test_crane_allocations_find_the_reference_power_and_shape(quick):
    _, df = quick
    s = df[(df["table"] == "summary") & (df["case"] == "crane")].set_index("variant")
    for variant in ("per-crease heaters", "paper circuits"):
        row = s.loc[variant]
        assert row["status"] == "converged", row["message"]
        assert row["worst_fold_error [deg]"] <= 0.5
        assert row["total_power [mW]"] == pytest.approx(row["reference_power [mW]"], rel=0.02)
    # the paper's circuits give the paper's powers back: 16, 6, 8, 4, 2 mW
    c = df[(df["table"] == "crease") & (df["case"] == "crane")
           & (df["variant"] == "paper circuits")]
    np.testing.assert_allclose(c["power [mW]"], c["reference_power [mW]"], rtol=0.03)
    # one LP at the flat shape misses the shape by tens of degrees
    assert s.loc["flat-shape LP", "worst_fold_error [deg]"] > 10


def test_double_fold_band_saves_power(quick):
    _, df = quick
    s = df[(df["table"] == "summary") & (df["case"] == "double_fold")].set_index("band [deg]")
    assert (s["status"] == "converged").all()
    assert s.loc[3, "total_power [mW]"] < s.loc[0, "total_power [mW]"] - 0.3
    assert s.loc[0, "total_power [mW]"] == pytest.approx(s.loc[0, "reference_power [mW]"],
                                                          rel=0.02)
