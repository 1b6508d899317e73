"""Thermal verification studies: heat_within_structure (Fig. 5 d-f), heat_loss_calibration (Fig. 6).

Command line and files of the quick versions, re-plotting from the CSV alone, the exact 1-D
solution of the strip (hand-derived closed form, energy balance, finite differences), agreement
with the reference implementation and physical trends.
"""

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure
from scipy.linalg import solve_banded

from simulator.cases import verification_strip
from studies import heat_loss_calibration as loss
from studies import heat_within_structure as within
from studies.heat_within_structure import Strip1D

TEXT_COLUMNS = {"sweep", "value", "structure", "environment"}


def _main_quick(module, out):
    module.main(["--quick", "--out", str(out), "--no-progress"])
    return pd.read_csv(out / f"{module.NAME}.csv")


@pytest.fixture(scope="module")
def within_quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("within")
    return out, _main_quick(within, out)


@pytest.fixture(scope="module")
def loss_quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("loss")
    return out, _main_quick(loss, out)


# ----------------------------------------------------------------------------- files
@pytest.mark.parametrize("which", ["within", "loss"])
def test_quick_main_writes_csv_pngs_meta_and_csv_replots(which, within_quick, loss_quick):
    module, (out, df) = {"within": (within, within_quick), "loss": (loss, loss_quick)}[which]
    pngs = {"within": ["heat_within_structure"],
            "loss": ["heat_loss_calibration", "heat_loss_materials"]}[which]
    for stem in pngs:
        assert (out / f"{stem}.png").stat().st_size > 10_000
    meta = json.loads((out / "meta.json").read_text())
    assert meta["study"] == module.NAME and meta["settings"] == {"quick": True}
    assert meta["rows"] == len(df) > 0
    # every non-text column says its unit or that it is non-dimensional
    assert all(c.endswith("]") for c in df.columns if c not in TEXT_COLUMNS)
    figs = module.plot(df)                       # from the CSV alone
    figs = figs if isinstance(figs, dict) else {module.NAME: figs}
    assert sorted(figs) == sorted(pngs)
    assert all(isinstance(f, Figure) and f.axes for f in figs.values())


def test_loss_writes_the_chain_error_against_3d_fe(loss_quick):
    """The FE columns and ``heat_loss_chain_error.csv`` (chosen parameters, unit columns):
    every material row has a 3-D and a 2-D FE value and the error is chain / FE - 1."""
    pytest.importorskip("skfem")
    out, df = loss_quick
    err = pd.read_csv(out / loss.ERROR_CSV)
    assert len(err) == (df["sweep"] == "material").sum() > 0
    assert all(c.endswith("]") for c in err.columns if c not in TEXT_COLUMNS)
    assert err[["T_max_fe3d [-]", "T_ave_fe3d [-]", "T_fe2d [-]"]].gt(0).all().all()
    np.testing.assert_allclose(err["T_max error vs fe3d [%]"],
                               100 * (err["T_max chain [-]"] / err["T_max_fe3d [-]"] - 1))
    assert set(err["beta [deg]"]) == {20.0} and set(err["t_env [-]"]) == {1.5}


def test_run_does_not_load_matplotlib():
    code = ("import sys\n"
            "from studies import heat_within_structure as a, heat_loss_calibration as b\n"
            "a.run(quick=True, progress=False); b.run(quick=True, progress=False)\n"
            "print(any(m.split('.')[0] == 'matplotlib' for m in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_quick_grids_are_small(within_quick, loss_quick):
    assert len(within_quick[1]) == 3 * 2 * 2          # 3 sweeps x 2 values x 2 W/L
    assert len(loss_quick[1]) == (3 * 2 + 2 * 2) * 2  # 3 sweeps x 2 values + 2 x 2 materials


# ----------------------------------------------------------------------------- reference
def test_within_quick_equals_reference_csv(within_quick):
    df = within_quick[1]
    assert df["T_max_ref [-]"].notna().all()        # every quick row is a reference row
    for col in ("T_max", "T_ave"):
        np.testing.assert_allclose(df[f"{col}_BH [-]"], df[f"{col}_ref [-]"], rtol=1e-9)
        np.testing.assert_allclose(df[f"{col}_BH - ref [-]"],
                                   df[f"{col}_BH [-]"] - df[f"{col}_ref [-]"], atol=1e-15)


def test_loss_quick_equals_reference_csv(loss_quick):
    df = loss_quick[1]
    has = df["T_max_ref [-]"].notna()
    assert has.sum() == 14                 # all SU-8/air rows; Si and water are not in it
    assert not has[df["structure"] != "SU-8"].any() and not has[df["environment"] != "air"].any()
    for col in ("T_max", "T_ave"):
        np.testing.assert_allclose(df.loc[has, f"{col} [-]"], df.loc[has, f"{col}_ref [-]"],
                                   rtol=1e-9)


def test_material_strip_rebuild_equals_verification_strip():
    ours = loss.strip_case(0.3, beta_deg=30, t_env=1.5, layers=5, k=0.3, k_env=0.026).run()
    ref = verification_strip("loss", W=0.3, beta_deg=30, t_env=1.5, layers=5).run()
    np.testing.assert_allclose(ours.state.temperature, ref.state.temperature, rtol=1e-12,
                               atol=1e-15)


# ----------------------------------------------------------------------------- 1-D solution
def test_symmetric_closed_form_by_hand():
    # L1 = L2, tc = tp: T_max = q (W^2/8 + W L1/2) / k, T_ave = q (W^2/12 + W L1/2) / k
    s = Strip1D(W=0.4, L1=1.0, L2=1.0, tc=0.01, tp=0.01, q=10.0, k=1.0)
    assert s.alpha == pytest.approx(0.2, rel=1e-14)               # peak in the middle
    assert s.t_max == pytest.approx(10 * (0.02 + 0.2), rel=1e-14)  # 2.2
    assert s.t_ave == pytest.approx(10 * (0.16 / 12 + 0.2), rel=1e-14)
    # the verification's own geometry (tc/tp = 0.1: panels act as r = 0.1), k = 2
    s = Strip1D(W=0.4, L1=1.0, L2=1.0, tc=0.001, tp=0.01, q=10.0, k=2.0)
    assert s.t_max == pytest.approx(10 / 2 * (0.4 ** 2 / 8 + 0.4 * 0.1 / 2), rel=1e-14)
    assert float(s.temperature(1.2)) == pytest.approx(s.t_max, rel=1e-14)


@pytest.mark.parametrize("W, L1, L2, tc, tp", [(0.4, 1, 1, 0.001, 0.01), (0.1, 2, 1, 0.001, 0.01),
                                               (1.0, 0.5, 3, 0.002, 0.01), (0.3, 1, 1, 0.02, 0.01)])
def test_energy_balance_flux_out_of_both_ends_is_Q(W, L1, L2, tc, tp):
    s = Strip1D(W, L1, L2, tc, tp, q=10.0, k=1.0)
    Q_per_length = 10.0 * W * tc                         # Q = 10 W L tc over the length L
    assert sum(s.end_fluxes) == pytest.approx(Q_per_length, rel=1e-12)
    # the same from the temperature profile: k tp |dT/dx| at the two far ends
    h = 1e-6
    x_end = L1 + W + L2
    out1 = tp * (s.temperature(h) - s.temperature(0.0)) / h
    out2 = tp * (s.temperature(x_end - h) - s.temperature(x_end)) / h
    assert float(out1 + out2) == pytest.approx(Q_per_length, rel=1e-8)
    assert float(s.temperature(0.0)) == 0.0 and float(s.temperature(x_end)) == 0.0


def _finite_difference(W, L1, L2, tc, tp, q=10.0, k=1.0, n=2000):
    """Fine 1-D linear-element / finite-volume solution; returns (crease x, crease T)."""
    x = np.unique(np.concatenate([np.linspace(0, L1, n + 1), np.linspace(L1, L1 + W, n + 1),
                                  np.linspace(L1 + W, L1 + W + L2, n + 1)]))
    h = np.diff(x)
    mid = (x[:-1] + x[1:]) / 2
    in_crease = (mid > L1) & (mid < L1 + W)
    t = np.where(in_crease, tc, tp)
    g = k * t / h                                       # element conductance per unit width
    half = np.where(in_crease, q * tc * h / 2, 0.0)     # element generation, half to each node
    diag = np.concatenate([g, [0]]) + np.concatenate([[0], g])
    b = np.concatenate([half, [0]]) + np.concatenate([[0], half])
    # both far ends at T = 0: solve the tridiagonal system of the interior nodes
    ab = np.zeros((3, len(x) - 2))
    ab[0, 1:], ab[1], ab[2, :-1] = -g[1:-1], diag[1:-1], -g[1:-1]
    T = np.zeros(len(x))
    T[1:-1] = solve_banded((1, 1), ab, b[1:-1])
    sel = (x >= L1 - 1e-12) & (x <= L1 + W + 1e-12)
    return x[sel], T[sel]


@pytest.mark.parametrize("W, L1, L2, tc, tp", [(0.4, 1, 1, 0.001, 0.01), (0.2, 2, 1, 0.001, 0.01),
                                               (1.0, 0.5, 2, 0.002, 0.01), (0.3, 1, 1, 0.01, 0.01)])
def test_analytic_equals_fine_finite_difference(W, L1, L2, tc, tp):
    s = Strip1D(W, L1, L2, tc, tp, q=10.0, k=1.0)
    xc, Tc = _finite_difference(W, L1, L2, tc, tp)
    t_ave = np.sum((Tc[1:] + Tc[:-1]) / 2 * np.diff(xc)) / W
    assert Tc.max() == pytest.approx(s.t_max, rel=1e-6)
    assert t_ave == pytest.approx(s.t_ave, rel=1e-6)
    np.testing.assert_allclose(Tc, s.temperature(xc), rtol=1e-6)


def test_bar_and_hinge_error_is_independent_of_the_panels():
    """For L1 = L2 the BH model gets the panel term exactly: T^BH - T^1D depends on W only."""
    W = 0.4
    diffs = [within.bar_hinge(W, tc, L1, L1)[0] - Strip1D(W, L1, L1, tc, within.TP).t_max
             for tc, L1 in [(0.0005, 1.0), (0.002, 1.0), (0.001, 0.7), (0.001, 3.0)]]
    np.testing.assert_allclose(diffs, diffs[0], rtol=1e-9)
    assert diffs[0] > 0                        # the coarse crease mesh overestimates T_max


# ----------------------------------------------------------------------------- trends
def test_thicker_crease_brings_bar_and_hinge_closer_to_1d():
    """Larger tc/tp (panels dominate the resistance): |T^BH / T^1D - 1| shrinks."""
    df = within.run(quick=False, progress=False)
    d = df[df["sweep"] == "tc/tp"]
    for col in (within.RATIO_MAX, within.RATIO_AVE, "T_ave_BH/T_ave_1D [-]"):
        dev = (d.pivot(index="W/L [-]", columns="tc/tp [-]", values=col) - 1).abs()
        assert (np.diff(dev.to_numpy(), axis=1) < 0).all(), col
    # the BH peak is always above the 1-D peak, the centre-line mean below it (Fig. 5)
    assert (df[within.RATIO_MAX] > 1).all() and (df[within.RATIO_AVE] < 1).all()
    # mirror images L1/L2 = 0.5 and 2 give the same temperatures
    f = df[df["sweep"] == "L1/L2"].pivot(index="W/L [-]", columns="value [-]",
                                         values="T_max_BH [-]")
    np.testing.assert_allclose(f[0.5], f[2.0], rtol=1e-12)


def test_heat_loss_trends(loss_quick):
    df = loss_quick[1]
    mat = df[df["sweep"] == "material"].pivot_table(
        index=["structure", "W/L [-]"], columns="environment", values="T_max [-]")
    assert (mat["water"] < mat["air"]).all()                       # water cools better
    for sweep, sign in (("t_env", +1), ("beta", -1), ("N", +1)):
        d = df[df["sweep"] == sweep].copy()
        d["v"] = pd.to_numeric(d["value"])
        for col in ("T_max [-]", "T_ave [-]"):
            p = d.pivot(index="W/L [-]", columns="v", values=col)
            assert (sign * np.diff(p.to_numpy(), axis=1) > 0).all(), (sweep, col)
    # a better conducting structure spreads the heat: Si is cooler than SU-8 in both media
    k = df[df["sweep"] == "material"].pivot_table(
        index=["environment", "W/L [-]"], columns="structure", values="T_max [-]")
    assert (k["Si"] < k["SU-8"]).all()
    # wider creases carry more heat (Q ~ W) and get hotter
    base = df[(df["sweep"] == "beta") & (df["beta [deg]"] == 20)].sort_values("W/L [-]")
    assert np.all(np.diff(base["T_max [-]"]) > 0)
