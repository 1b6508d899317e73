"""Device studies (studies/single_fold, double_fold, miura_lifter, crane): files, figures
re-created from the CSV alone, and the physics of the quick runs."""

import ast
import io
import json
import pathlib

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from simulator.cases import get_case
from studies.single_fold import node_frame, shape_from_frame

ROOT = pathlib.Path(__file__).resolve().parents[2]
STUDIES = {  # study -> figure stems
    "single_fold": ("single_fold", "single_fold_shape"),
    "double_fold": ("double_fold", "double_fold_shape"),
    "miura_lifter": ("miura_lifter", "miura_lifter_shapes"),
    "crane": ("crane", "crane_creases", "crane_shapes", "crane_heat_models"),
}


@pytest.fixture(scope="module")
def quick(quick_study):
    """Each study's quick run, on demand: name -> (module, dir, df) (see conftest.py)."""
    return quick_study


def _table(df, kind):
    return df[df["table"] == kind].dropna(axis=1, how="all")


# ----------------------------------------------------------------------------- files
@pytest.mark.parametrize("name", STUDIES)
def test_main_writes_csv_pngs_and_meta(quick, name):
    module, out, df = quick(name)
    assert len(df) > 0 and "table" in df.columns
    for stem in STUDIES[name]:
        png = out / f"{stem}.png"
        assert png.stat().st_size > 10_000, stem
    meta = json.loads((out / "meta.json").read_text())
    assert meta["study"] == name and meta["settings"] == {"quick": True}
    assert meta["rows"] == len(df) and meta["wall_time [s]"] > 0
    assert module.main.__module__ == f"studies.{name}" and module.__doc__.count("Outputs") == 1


def test_single_fold_writes_small_animation(quick):
    _, out, _ = quick("single_fold")
    gif = out / "single_fold_-10deg.gif"
    assert gif.read_bytes()[:3] == b"GIF" and gif.stat().st_size < 2_000_000


@pytest.mark.parametrize("name", STUDIES)
def test_plot_recreates_figures_from_csv(quick, name):
    module, out, _ = quick(name)
    figs = module.plot(pd.read_csv(out / f"{name}.csv"))
    assert set(figs) == set(STUDIES[name])
    for stem, fig in figs.items():
        assert isinstance(fig, Figure)
        axes = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
        for ax in axes:
            assert ax.has_data(), (stem, ax.get_title())
            assert ax.get_ylabel(), (stem, ax.get_title())
        assert any(ax.get_xlabel() for ax in axes)
        fig.savefig(io.BytesIO(), format="png", dpi=40)


@pytest.mark.parametrize("name, columns", [
    ("single_fold", ["power [mW]", "fold_angle [deg]", "temperature [degC]", "deviation [deg]",
                     "threshold_power [mW]", "x [um]", "z [um]"]),
    ("double_fold", ["power [mW]", "fold_angle [deg]", "fold_change [deg]",
                     "temperature [degC]", "temperature_max [degC]"]),
    ("miura_lifter", ["power [mW]", "power_normalised [-]", "lift [um]", "x [um]",
                      "temperature [degC]"]),
    ("crane", ["variant", "crease_ref", "base_power [mW]", "power [mW]", "fold_angle [deg]",
               "temperature [degC]"]),
])
def test_columns_carry_units(quick, name, columns):
    _, _, df = quick(name)
    assert set(columns) <= set(df.columns)
    assert not any(c.endswith(("[rad]", "[m]", "[W]", "[K]")) for c in df.columns)


def test_study_modules_import_matplotlib_only_for_plotting():
    """No pyplot anywhere; matplotlib imported only inside plotting functions."""
    for name in STUDIES:
        tree = ast.parse((ROOT / "studies" / f"{name}.py").read_text())
        for node in tree.body:  # module level
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                mods = [a.name for a in node.names] if isinstance(node, ast.Import) else [
                    node.module or ""]
                assert not any(m.startswith("matplotlib") or m == "studies.plotting"
                               for m in mods), (name, mods)
        assert "pyplot" not in (ROOT / "studies" / f"{name}.py").read_text()


def test_node_rows_round_trip_to_a_plottable_shape():
    case = get_case("single_fold", thermal_steps=3, power_mW=10)
    res = case.run()
    rows = node_frame(res, [0, -1], variant="x")
    assert set(rows["variant"]) == {"x"} and len(rows) == 2 * case.model.mesh.n_nodes
    shape = shape_from_frame(pd.read_csv(io.StringIO(rows.to_csv(index=False))),
                             case.model.mesh)
    np.testing.assert_allclose(shape.history["u"], res.history["u"][[0, -1]], atol=1e-12)
    np.testing.assert_allclose(shape.history["temperature"],
                               res.history["temperature"][[0, -1]])
    assert list(shape.history["stage_name"]) == ["initial", "heat"]
    with pytest.raises(ValueError, match="nodes"):
        shape_from_frame(rows.iloc[:-1], case.model.mesh)


# ----------------------------------------------------------------------------- physics
def test_single_fold_gravity_threshold(quick):
    _, _, df = quick("single_fold")
    thr = _table(df, "threshold").set_index("variant")
    sweep = _table(df, "sweep")
    ten = thr.loc["gravity, residual -10 deg"]
    assert ten["fold_start [deg]"] < -9.5                       # resting on the substrate
    assert 40 < ten["threshold_power [mW]"] < 70
    d = sweep[sweep["variant"] == "gravity, residual -10 deg"]
    below = d[d["power [mW]"] < 40]
    assert np.all(np.abs(below["fold_angle [deg]"] - ten["fold_start [deg]"]) < 0.5)
    assert ten["fold_final [deg]"] > ten["fold_start [deg]"] + 30  # then large folding
    # a more negative residual fold delays folding; without gravity there is no threshold
    assert (thr.loc["Example01 (ours)", "threshold_power [mW]"] < 10
            < thr.loc["gravity, residual 0 deg", "threshold_power [mW]"]
            < ten["threshold_power [mW]"])


def test_single_fold_in_air_needs_about_twenty_times_less_power(quick):
    """The reference script's k_env = 0.6 W/(m K) against air's 0.026: heat leaves the crease
    mainly through the environment, so the thresholds drop by 15-25x; the panel still starts
    on the substrate."""
    _, _, df = quick("single_fold")
    thr = _table(df, "threshold").set_index("variant")
    for r in (0, -10):
        water, air = thr.loc[f"gravity, residual {r} deg"], thr.loc[f"air, gravity, residual {r} deg"]
        assert water["env_conductivity [W/(m K)]"] == 0.6
        assert air["env_conductivity [W/(m K)]"] == 0.026
        assert 15 < water["threshold_power [mW]"] / air["threshold_power [mW]"] < 25
        assert air["fold_start [deg]"] < -9.5


def test_single_fold_example01_follows_the_reference(quick):
    _, _, df = quick("single_fold")
    sweep = _table(df, "sweep")
    ours = sweep[sweep["variant"] == "Example01 (ours)"]
    ref = sweep[sweep["variant"] == "Example01 reference"]
    assert len(ref) == 501 and ref["power [mW]"].max() == pytest.approx(100)
    assert ours["power [mW]"].max() == pytest.approx(100)
    np.testing.assert_allclose(ours["deviation [deg]"],
                               ours["fold_angle [deg]"] - ours["reference_fold_angle [deg]"])
    assert ours["deviation [deg]"].abs().max() < 0.25          # 50 increments in quick mode
    assert ours["fold_angle [deg]"].iloc[-1] > 50


def test_single_fold_integral_loss_lowers_every_threshold(quick):
    """Side by side (issue 29): the integral loss's thresholds are below the chains' at both
    media, and rise with the residual fold as theirs do."""
    _, _, df = quick("single_fold")
    thr = _table(df, "threshold").set_index("variant")["threshold_power [mW]"]
    chains = [v for v in thr.index if "gravity" in v and not v.endswith(", integral loss")]
    assert len(chains) >= 4
    for v in chains:
        assert thr[f"{v}, integral loss"] < 0.9 * thr[v]
    integral_air = [thr[f"air, gravity, residual {r:g} deg, integral loss"] for r in (0, -10)]
    assert integral_air[0] < integral_air[1]


@pytest.mark.parametrize("loss_model", ["chain", "integral"])
def test_double_fold_far_crease_hotter_and_folds_more(quick, loss_model):
    _, _, df = quick("double_fold")
    sweep = _table(df, "sweep")
    sweep = sweep[sweep["loss_model"] == loss_model]
    last = sweep.sort_values("step").groupby("fold").last()
    assert last.loc[2, "fold_angle [deg]"] > last.loc[1, "fold_angle [deg]"] + 10
    assert last.loc[2, "temperature [degC]"] > last.loc[1, "temperature [degC]"] + 20
    assert last["power [mW]"].tolist() == pytest.approx([10, 10])
    first = sweep.sort_values("step").groupby("fold").first()
    assert first["power [mW]"].tolist() == [0, 0] and first["fold_change [deg]"].tolist() == [0, 0]


def test_double_fold_integral_loss_runs_hotter_and_folds_further_than_the_chains(quick):
    """The calibration-free model, which the 3-D FE supports here, loses less heat than the
    paper's chains: every fold further and hotter at the same power (side by side, issue 29;
    the crease centres 3.8-4 % hotter on the sheet refined r = 2, theory 4.11; 12-27 % on the
    mesh triangles, which run hot)."""
    _, _, df = quick("double_fold")
    sweep = _table(df, "sweep")
    last = sweep.sort_values("step").groupby(["loss_model", "fold"]).last()
    for fold in (1, 2):
        assert (last.loc[("integral", fold), "fold_angle [deg]"]
                > last.loc[("chain", fold), "fold_angle [deg]"] + 10)
        assert (last.loc[("integral", fold), "temperature_centre [degC]"]
                > 1.03 * last.loc[("chain", fold), "temperature_centre [degC]"])
    nodes = _table(df, "nodes")
    assert set(nodes["loss_model"]) == {"chain", "integral"}


def test_miura_integral_loss_lifts_more_than_the_chains_on_and_off_the_substrate(quick):
    """The calibration-free loss, side by side with the paper's chains (issue 29): it loses
    less heat on this lifter, so each variant lifts more and runs hotter."""
    _, _, df = quick("miura_lifter")
    lift = _table(df, "sweep").sort_values("step").groupby("variant")["lift [um]"].last()
    hot = _table(df, "crease").groupby("variant")["temperature_centre [degC]"].max()
    for variant in ("free", "on substrate"):
        assert lift[f"{variant}, integral loss"] > 1.5 * lift[variant]
        assert hot[f"{variant}, integral loss"] > hot[variant] + 20
    assert lift["on substrate, integral loss"] < 0.6 * lift["free, integral loss"]


def test_miura_substrate_lowers_lift_and_cools_anchored_end(quick):
    _, _, df = quick("miura_lifter")
    sweep = _table(df, "sweep")
    lift = sweep.sort_values("step").groupby("variant")["lift [um]"].last()
    assert lift["free"] > 50 and lift["on substrate"] < 0.5 * lift["free"]
    assert sweep.groupby("variant")["lift [um]"].first().abs().max() < 1e-6
    assert sweep["power_normalised [-]"].max() == pytest.approx(1)
    creases = _table(df, "crease")
    sub = creases[(creases["variant"] == "on substrate") & ~creases["clamped"].astype(bool)]
    median = sub["x [um]"].median()
    near = sub[sub["x [um]"] < median]["temperature [degC]"].mean()
    far = sub[sub["x [um]"] > median]["temperature [degC]"].mean()
    assert near < far - 5
    free = creases[creases["variant"] == "free"]
    assert free["temperature [degC]"].min() > sub["temperature [degC]"].max()


def test_crane_folds_with_and_without_two_creases(quick):
    _, _, df = quick("crane")
    creases = _table(df, "crease")
    full = creases[creases["variant"] == "all active"].set_index("crease_ref")
    deact = creases[creases["variant"] == "8 and 17 deactivated"].set_index("crease_ref")
    assert len(full) == len(deact) == 17
    assert full["heated"].astype(bool).all()
    assert sorted(deact.index[~deact["heated"].astype(bool)]) == [8, 17]
    assert (full["fold_angle [deg]"].abs() > 15).all()
    assert (deact["fold_angle [deg]"].abs() > 15).all()        # the unheated creases fold too
    np.testing.assert_array_equal(np.sign(full["fold_angle [deg]"]),
                                  np.sign(deact["fold_angle [deg]"]))
    assert (deact.loc[[8, 17], "temperature [degC]"] < full.loc[[8, 17], "temperature [degC]"]
            - 20).all()
    assert deact["fold_angle [deg]"].abs().mean() < full["fold_angle [deg]"].abs().mean()
    # the integral heat loss at its case power (0.7 mW): every crease folds the same way,
    # about as far on average, its hottest crease cooler (the heat is shared)
    integral = creases[creases["variant"] == "all active, integral heat loss"]
    integral = integral.set_index("crease_ref")
    assert (integral["loss_model"] == "integral").all() and (full["loss_model"] == "chain").all()
    np.testing.assert_allclose(integral["power [mW]"], full["power [mW]"] * 0.7 / 4.0)
    np.testing.assert_array_equal(np.sign(integral["fold_angle [deg]"]),
                                  np.sign(full["fold_angle [deg]"]))
    assert integral["fold_angle [deg]"].abs().mean() == pytest.approx(
        full["fold_angle [deg]"].abs().mean(), rel=0.1)
    assert integral["temperature [degC]"].max() < full["temperature [degC]"].max() - 10
