"""Study heat_transfer_models: chain, integral and 3-D FE side by side (issue 19 item 6).

The quick run (about 20-30 s: two strips, the double fold, the gripper at assembly and grip,
FE level 0) is made once into a temporary folder; its files, columns and physics are checked:
the three models see the same heat, the chain model runs cooler than the FE on the folded
shapes, the integral model converges towards the FE with its refinement.
"""

import json

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from simulator import get_case
from simulator.thermal import boundary_panel_plane, crease_temperatures
from studies import heat_transfer_models as htm
from studies.figure_notes import QUICK_STAMP

TEXT_COLUMNS = {"case", "shape", "structure", "medium", "crease name", "model", "message",
                "success", "measure", "within acceptance"}
KEY = ["case", "shape", "structure", "medium", "W/L [-]", "crease [-]"]


@pytest.fixture(scope="module")
def quick(quick_study):
    return quick_study(htm.NAME)


@pytest.fixture(scope="module")
def fe_quick(quick):
    pytest.importorskip("skfem")
    pytest.importorskip("gmsh")
    return quick


def _temps(df, model, refinement=None, measure="T_crease"):
    sel = df["model"] == model
    if refinement is not None:
        sel &= df["integral_refinement [-]"] == refinement
    return df[sel].set_index(KEY)[f"{measure} [degC]"]


def test_quick_run_writes_csvs_figures_and_meta(quick):
    _, out, df = quick
    meta = json.loads((out / "meta.json").read_text())
    assert meta["study"] == htm.NAME and meta["settings"] == {"quick": True}
    assert meta["rows"] == len(df) > 0
    for stem in ("heat_transfer_models_strip", "heat_transfer_models_folded"):
        assert (out / f"{stem}.png").stat().st_size > 10_000
    assert all(c.endswith("]") for c in df.columns if c not in TEXT_COLUMNS)
    for m in htm.MEASURES:
        assert {f"{m} [degC]", f"{m} error vs FE [%]",
                f"{m} error vs FE extrapolated [%]"} <= set(df.columns)
    assert set(df["case"]) == {"strip", "double fold", "gripper"}
    assert set(df.loc[df["case"] == "gripper", "shape"]) == {"assembly", "grip"}
    assert df["success"].all()
    err = pd.read_csv(out / htm.ERROR_CSV)
    assert all(c.endswith("]") for c in err.columns if c not in TEXT_COLUMNS)
    assert set(err["acceptance [%]"]) <= {3.0, 5.0}


def test_figures_replot_from_the_csv_and_are_stamped_quick(quick, tmp_path):
    _, out, df = quick
    figs = htm.plot(pd.read_csv(out / f"{htm.NAME}.csv"))
    assert sorted(figs) == ["heat_transfer_models_folded", "heat_transfer_models_strip"]
    assert all(isinstance(f, Figure) and f.axes for f in figs.values())
    from studies.plotting import save_figure

    fig = figs["heat_transfer_models_strip"]
    save_figure(fig, tmp_path / "s.png", quick=True)
    texts = [t.get_text() for t in fig.texts]
    assert QUICK_STAMP in texts
    assert any("3-D FE: mesh level 0" in t for t in texts)          # the level is stated


def test_every_model_gets_the_same_heat_on_the_same_cases(fe_quick):
    _, _, df = fe_quick
    power = df.pivot_table(index=KEY, columns="model", values="crease power [W]",
                           aggfunc="first", dropna=False)
    assert {"chain", "integral", "FE"} <= set(power.columns)
    np.testing.assert_array_equal(power["chain"], power["FE"])
    np.testing.assert_array_equal(power["chain"], power["integral"])


def test_chain_is_cooler_than_fe_on_the_folded_shapes(fe_quick):
    """The per-node chains do not see the medium heated by the neighbouring creases: on
    every folded shape the chain model's heated creases are cooler than the FE's, the
    integral model's within 15 % of the FE's rise already at m = 2."""
    _, _, df = fe_quick
    d = df[(df["case"] != "strip") & (df["crease power [W]"] > 0)]
    chain, fe = _temps(d, "chain"), _temps(d, "FE")
    assert (chain < fe).all()
    err = d.loc[d["model"] == "integral", "T_crease error vs FE [%]"]
    assert err.notna().all() and err.abs().max() < 15
    assert d.loc[d["model"] == "chain", "T_crease error vs FE [%]"].lt(0).all()


def test_strip_errors_are_finite_bounded_and_the_integral_model_converges(fe_quick):
    _, _, df = fe_quick
    d = df[df["case"] == "strip"]
    for m in ("T_max", "T_ave"):
        e = d.loc[d["model"] != "FE", f"{m} error vs FE [%]"]
        assert np.isfinite(e).all() and e.abs().max() < 30
        e2 = _temps(d, "integral", 2, m) / _temps(d, "FE", measure=m) - 1
        e8 = _temps(d, "integral", 8, m) / _temps(d, "FE", measure=m) - 1
        e3 = _temps(d, "integral", 3, m) / _temps(d, "FE", measure=m) - 1   # extrapolated
        assert (e8.abs() < e2.abs()).all()             # collocation converges with m
        assert (e3.abs() < e2.abs()).all()             # the default beats the plain m = 2
    fe = d[d["model"] == "FE"]
    assert (fe["FE level [-]"] == 0).all() and fe[[f"{m} error vs FE [%]" for m in
                                                   htm.MEASURES]].eq(0).all().all()


def test_error_table_ranges_match_the_rows(fe_quick):
    _, out, df = fe_quick
    err = htm.error_table(df)
    r = err[(err["case"] == "double fold") & (err["model"] == "chain")
            & (err["measure"] == "T_crease")].iloc[0]
    rows = df[(df["case"] == "double fold") & (df["model"] == "chain")]
    assert r["n [-]"] == 2
    assert r["error min [%]"] == pytest.approx(rows["T_crease error vs FE [%]"].min())
    assert r["max |error| [%]"] == pytest.approx(rows["T_crease error vs FE [%]"].abs().max())
    assert not r["within acceptance"]          # the chain model is far off on folded shapes
    assert "FE" not in set(err["model"])       # no extrapolation in a quick run


def test_crease_measures_pick_the_documented_nodes():
    mesh = get_case("double_fold").model.mesh
    T = np.arange(mesh.n_nodes, dtype=float)
    m = htm.crease_measures(mesh, T)
    cn = mesh.crease_nodes
    np.testing.assert_array_equal(m["T_max"], cn[:, 6])
    np.testing.assert_allclose(m["T_ave"], crease_temperatures(T, mesh, "centre_line"))
    np.testing.assert_array_equal(m["T_hottest"], cn.max(axis=1))
    np.testing.assert_allclose(htm.crease_measures(mesh, np.full(mesh.n_nodes, 7.0))
                               ["T_crease"], 7.0)           # the weights sum to one


def test_substrate_plane_is_the_boundary_panels_plane_facing_the_structure():
    model = get_case("double_fold").model
    plane = np.array(boundary_panel_plane(model, model.mesh.nodes))
    p, n = plane[:3], plane[3:]
    assert np.linalg.norm(n) == pytest.approx(1.0)
    panel = np.unique(model.mesh.triangles[np.isin(model.mesh.triangle_panel,
                                                   model.thermal.boundary_panels)])
    np.testing.assert_allclose((model.mesh.nodes[panel] - p) @ n, 0.0, atol=1e-12)
    assert np.mean((model.mesh.nodes - p) @ n) >= 0
    strip = get_case("verification_strip").model
    assert boundary_panel_plane(strip, strip.mesh.nodes) == ()


def test_committed_full_run_holds_the_acceptance_and_draws_the_crane():
    """The published table (results/heat_transfer_models, full run): the default integral
    model within 3 % (strip) and 5 % (folded shapes, the flat crane) of the extrapolated FE;
    the crane's chains (t_env = 1 mm) 70-90 % too cool in T_crease; its figure drawn from the
    CSV. (A check of the published table; the study's computation is tested on its quick run
    above.)"""
    import pathlib

    path = pathlib.Path(__file__).parents[2] / "results" / htm.NAME / f"{htm.NAME}.csv"
    df = pd.read_csv(path)
    table = htm.error_table(df)
    default = table[(table["model"] == "integral") & (table["integral_refinement [-]"] == 3)
                    & (table["integral_extrapolation [-]"].astype(str) == "True")]
    assert set(default["case"]) == {"strip", "double fold", "gripper", "crane"}
    assert default["within acceptance"].all(), default[~default["within acceptance"]]
    crane = table[(table["case"] == "crane") & (table["model"] == "chain")
                  & (table["measure"] == "T_crease")].iloc[0]
    assert -91 < crane["error extrapolated min [%]"] < -90         # documented: 70-90 % cool
    assert -71 < crane["error extrapolated max [%]"] < -70
    figs = htm.plot(df)
    assert set(figs) == {f"{htm.NAME}_strip", f"{htm.NAME}_folded", f"{htm.NAME}_crane"}
    assert len(figs[f"{htm.NAME}_crane"].axes) == 2
