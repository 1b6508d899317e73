"""Time-domain studies (studies/actuation_speed, studies/natural_modes): files, figures
re-created from the CSV alone, and the physics of the quick runs."""

import json

import numpy as np
import pytest
from matplotlib.figure import Figure

from studies import actuation_speed

TEXT_COLUMNS = {"table", "mode", "success", "device", "stage"}


@pytest.fixture(scope="module", params=["actuation_speed", "natural_modes"])
def quick(request, quick_study):
    return quick_study(request.param)


def test_quick_main_writes_files_and_replots_from_csv(quick):
    module, out, df = quick
    assert (out / f"{module.NAME}.png").stat().st_size > 10_000
    meta = json.loads((out / "meta.json").read_text())
    assert meta["study"] == module.NAME and meta["rows"] == len(df) > 0
    assert all(c.endswith("]") for c in df.columns if c not in TEXT_COLUMNS)
    fig = module.plot(df)
    assert isinstance(fig, Figure) and fig.axes


def test_physics_of_the_quick_runs(quick):
    module, _, df = quick
    if module is actuation_speed:
        summary = df[df["table"] == "summary"]
        assert (summary["rise_time [s]"] > summary["thermal_time_constant [s]"]).all()
        assert ((summary["release_time [s]"] > 0) & (summary["release_time [s]"] < 0.1)).all()
        s = summary[summary["device"] == "single crease"].set_index("power [mW]")
        assert s["change [deg or um]"].is_monotonic_increasing          # more power, more fold
        # lifted off the substrate, the panel swings on its crease: 10x slower than resting
        assert (s["mechanical_period_heated [s]"] > 5 * s["mechanical_period_unheated [s]"]).all()
        np.testing.assert_allclose(s["energy [mJ]"], s.index * actuation_speed.PHASE_QUICK)
        g = summary.set_index("device")
        assert g.loc["gripper assembly", "change [deg or um]"] > 90         # assembled
        assert g.loc["gripper grip", "change [deg or um]"] < -500           # arms closed [um]
        np.testing.assert_allclose(g.loc["gripper assembly", "energy [mJ]"],
                                   2 * 28.0 * actuation_speed.PHASE_QUICK)
        w = df[df["table"] == "square_wave"]
        assert w["relative_amplitude [-]"].iloc[-1] < 0.7                   # 100 Hz: filtered
        assert 10 < w["bandwidth [Hz]"].iloc[0] < 100
    else:
        assert df["success"].all()
        first = df[df["mode"] == 1]
        low = first[first["device"].str.startswith("single crease")].set_index("power [mW]")
        assert low["fold_angle [deg]"].is_monotonic_increasing
        # resting on the substrate's contact layer vs lifted off: 10x lower
        assert low.loc[0.0, "frequency [Hz]"] > 5 * low.loc[4.0, "frequency [Hz]"]
        assert (df.groupby(["device", "power [mW]"])["frequency [Hz]"].apply(
            lambda f: np.all(np.diff(f.to_numpy()) >= 0))).all()               # sorted modes
        g = first.set_index(["device", "power [mW]"])
        assert g.loc[("gripper assembly", 28.0), "fold_angle [deg]"] > 90
        assert g.loc[("gripper grip", 6.0), "tip_distance [um]"] < 100


@pytest.mark.parametrize("t, y, level, expected", [
    ([0.0, 1.0, 2.0], [0.0, 1.0, 2.0], 1.5, 1.5),
    ([0.0, 1.0, 2.0], [2.0, 1.0, 0.0], 0.5, 1.5),
    ([0.0, 1.0], [0.0, 1.0], 3.0, np.nan),
])
def test_crossing_and_bandwidth_helpers(t, y, level, expected):
    np.testing.assert_allclose(actuation_speed.crossing(t, y, level), expected)
    assert actuation_speed.bandwidth([1, 10, 100], [1.0, 1.0, 0.5]) == pytest.approx(
        10 * 10 ** (np.log(1 / np.sqrt(2)) / np.log(0.5)))
