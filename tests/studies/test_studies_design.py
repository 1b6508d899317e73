"""Design studies (studies/gripper_optimization, gripper_robustness, miura_design): quick runs
write their files, figures are re-created from the CSV alone, the tables are consistent, and
the evaluation time limit turns a stalled design into a failed evaluation."""

import ast
import importlib
import io
import json
import math
import pathlib
import signal
import threading
import time

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from studies import gripper_robustness
from studies.gripper_optimization import (
    EvaluationTimeout,
    TimeLimitedGripperProblem,
    cd_optimum,
    time_limit,
)

ROOT = pathlib.Path(__file__).resolve().parents[2]
STUDIES = {  # study -> figure stems
    "gripper_optimization": ("gripper_optimization", "gripper_optimization_methods"),
    "gripper_robustness": ("gripper_robustness",),
    "miura_design": ("miura_design", "miura_design_optimum"),
}
START_UM = {"W [um]": 200.0, "La [um]": 700.0, "L1 [um]": 1000.0, "L2 [um]": 1000.0}


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    """Runs each study's ``main`` in quick mode once, on demand: name -> (module, dir, df).

    gripper_robustness runs without the study gripper_optimization's CSV (fallback CD), so
    the result does not depend on the repository's results/ folder.
    """
    cache = {}
    missing = tmp_path_factory.mktemp("none") / "gripper_optimization.csv"

    def get(name):
        if name not in cache:
            module = importlib.import_module(f"studies.{name}")
            out = tmp_path_factory.mktemp(name)
            mp = pytest.MonkeyPatch()
            if name == "gripper_robustness":
                mp.setattr(module, "OPTIMUM_CSV", missing)
            try:
                assert module.main(["--quick", "--out", str(out), "--no-progress"]) == out
            finally:
                mp.undo()
            cache[name] = (module, out, pd.read_csv(out / f"{name}.csv"))
        return cache[name]

    return get


def _table(df, kind):
    return df[df["table"] == kind].dropna(axis=1, how="all")


def _bool(series):
    return series.astype(str).str.lower() == "true"


# ----------------------------------------------------------------------------- files
@pytest.mark.parametrize("name", STUDIES)
def test_main_writes_csv_pngs_and_meta(quick, name):
    module, out, df = quick(name)
    assert len(df) > 0 and "table" in df.columns
    for stem in STUDIES[name]:
        assert (out / f"{stem}.png").stat().st_size > 10_000, stem
    meta = json.loads((out / "meta.json").read_text())
    assert meta["study"] == name and meta["settings"] == {"quick": True}
    assert meta["rows"] == len(df) and 0 < meta["wall_time [s]"] < 60
    assert module.main.__module__ == f"studies.{name}" and module.__doc__.count("Outputs") == 1


@pytest.mark.parametrize("name", STUDIES)
def test_plot_recreates_figures_from_csv(quick, name):
    module, out, _ = quick(name)
    figs = module.plot(pd.read_csv(out / f"{name}.csv"))
    figs = figs if isinstance(figs, dict) else {name: figs}
    assert set(figs) == set(STUDIES[name])
    for stem, fig in figs.items():
        assert isinstance(fig, Figure)
        for ax in fig.axes:
            assert ax.has_data(), (stem, ax.get_title())
            assert ax.get_ylabel(), (stem, ax.get_title())
        assert any(ax.get_xlabel() for ax in fig.axes)
        fig.savefig(io.BytesIO(), format="png", dpi=40)


@pytest.mark.parametrize("name, columns", [
    ("gripper_optimization", ["method", "cycle", "W [um]", "La [um]", "total_power [mW]",
                              "assembly_power [mW]", "grip_power [mW]", "wall_time [s]",
                              "temperature_margin [degC]", "margin temperature [-]",
                              "best_so_far [mW]"]),
    ("gripper_robustness", ["design", "residual_fold [deg]", "total_power [mW]",
                            "temperature [degC]", "feasible", "margin temperature [-]",
                            "temperature_margin [degC]"]),
    ("miura_design", ["a [um]", "gamma [deg]", "W [um]", "power [mW]", "lift [um]",
                      "lift_per_power [um/mW]", "max_crease_temperature [degC]"]),
])
def test_columns_carry_units(quick, name, columns):
    _, _, df = quick(name)
    assert set(columns) <= set(df.columns)
    assert not any(c.endswith(("[rad]", "[m]", "[W]", "[K]")) for c in df.columns)


def test_study_modules_import_matplotlib_only_for_plotting():
    for name in STUDIES:
        text = (ROOT / "studies" / f"{name}.py").read_text()
        for node in ast.parse(text).body:
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                mods = [a.name for a in node.names] if isinstance(node, ast.Import) else [
                    node.module or ""]
                assert not any(m.startswith("matplotlib") for m in mods), (name, mods)
        assert "pyplot" not in text


# ----------------------------------------------------------------------------- optimisation
def test_optimization_tables(quick):
    module, _, df = quick("gripper_optimization")
    cycles, comp, hist = (_table(df, k) for k in ("cycles", "comparison", "history"))
    assert set(df["table"]) == {"cycles", "comparison", "history"}
    first = cycles.sort_values("cycle").iloc[0]
    assert {k: first[k] for k in START_UM} == START_UM
    assert list(comp["method"]) == ["cd"] + [m for m, _, _ in module.NLOPT_RUNS_QUICK]
    assert (comp["evaluations"] <= comp["budget"]).all()
    assert _bool(comp["success"]).all()
    start = comp["start_power [mW]"].iloc[0]
    assert 20 < start < 45                                      # the paper's start: ~30 mW
    assert (comp["total_power [mW]"] <= start).all()
    cd = comp["total_power [mW]"].iloc[0]
    np.testing.assert_array_equal(_bool(comp["reaches_cd"]), comp["total_power [mW]"] <= cd)
    np.testing.assert_allclose(comp["temperature_margin [degC]"],
                               comp["temperature_limit [degC]"] - comp["temperature [degC]"])
    for method, d in hist.groupby("method"):
        best = d.sort_values("evaluation")["best_so_far [mW]"].dropna().to_numpy()
        assert np.all(np.diff(best) <= 0), method
        row = comp[comp["method"] == method].iloc[0]
        assert best[-1] == pytest.approx(row["total_power [mW]"])
        assert len(d) == row["evaluations"]


def test_cd_optimum_reads_the_last_cycle():
    df = pd.DataFrame({"table": ["comparison", "cycles", "cycles"], "cycle": [np.nan, 1, 0],
                       "W [um]": [0, 300, 200], "La [um]": [0, 1450, 700],
                       "L1 [um]": [0, 500, 1000], "L2 [um]": [0, 550, 1000]})
    assert cd_optimum(df) == pytest.approx({"W": 300e-6, "La": 1450e-6, "L1": 500e-6,
                                            "L2": 550e-6})


def test_time_limit_fails_the_evaluation_and_restores_the_handler(monkeypatch):
    import design.devices.gripper_problem

    monkeypatch.setattr(design.devices.gripper_problem, "evaluate_gripper",     # a stalled simulation
                        lambda *args, **kwargs: time.sleep(10))
    before = signal.getsignal(signal.SIGALRM)
    problem = TimeLimitedGripperProblem(time_limit=0.05)
    t0 = time.perf_counter()
    ev = problem.evaluate(problem.space.start)
    assert time.perf_counter() - t0 < 2
    assert not ev.success and ev.status == "failed" and math.isinf(ev.objective)
    assert not ev.feasible
    assert "EvaluationTimeout" in ev.message and "time limit of 0.05 s" in ev.message
    assert signal.getsignal(signal.SIGALRM) is before
    assert signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0)
    assert problem.settings()["time_limit [s]"] == 0.05


def test_time_limit_raises_in_the_main_thread_only():
    with pytest.raises(EvaluationTimeout, match="0.02 s"), time_limit(0.02):
        time.sleep(1)
    done = []

    def work():
        with time_limit(0.01):                 # no SIGALRM outside the main thread
            time.sleep(0.05)
        done.append(True)

    th = threading.Thread(target=work)
    th.start()
    th.join()
    assert done == [True]


# ----------------------------------------------------------------------------- robustness
def test_robustness_tables(quick):
    module, _, df = quick("gripper_robustness")
    sweep, designs = _table(df, "sweep"), _table(df, "designs")
    labels = [module.START, module.PAPER, module.ROBUST]
    assert list(designs["design"]) == labels
    assert len(sweep) == len(labels) * len(module.RESIDUALS_QUICK)
    assert sorted(set(sweep["residual_fold [deg]"])) == sorted(module.RESIDUALS_QUICK)
    start = sweep[sweep["design"] == module.START].iloc[0]
    assert {k: start[k] for k in START_UM} == START_UM
    paper = designs[designs["design"] == module.PAPER].iloc[0]
    assert "re-run" in paper["source"] and paper["evaluations"] <= 3   # no CSV: fallback CD
    ok = sweep[_bool(sweep["success"])]
    np.testing.assert_allclose(ok["total_power [mW]"],
                               ok["assembly_power [mW]"] + ok["grip_power [mW]"])
    np.testing.assert_array_equal(_bool(ok["feasible"]), ok["temperature [degC]"]
                                  <= ok["temperature_limit [degC]"])


def test_robustness_takes_the_paper_optimum_from_the_optimisation_csv(tmp_path,
                                                                      monkeypatch):
    csv = tmp_path / "gripper_optimization.csv"
    pd.DataFrame({"table": ["cycles", "cycles"], "cycle": [0, 1], "W [um]": [200, 210],
                  "La [um]": [700, 750], "L1 [um]": [1000, 950],
                  "L2 [um]": [1000, 950]}).to_csv(csv, index=False)
    monkeypatch.setattr(gripper_robustness, "ROBUST_BUDGET_QUICK", 1)
    monkeypatch.setattr(gripper_robustness, "RESIDUALS_QUICK", (0.0,))
    df = gripper_robustness.run(quick=True, progress=False, optimum_csv=csv)
    designs = _table(df, "designs").set_index("design")
    paper = designs.loc[gripper_robustness.PAPER]
    assert "gripper_optimization.csv" in paper["source"]
    assert [paper[k] for k in START_UM] == pytest.approx([210, 750, 950, 950])
    assert len(_table(df, "sweep")) == 3


# ----------------------------------------------------------------------------- Miura
def test_miura_tables(quick):
    module, _, df = quick("miura_design")
    grid, opt, cycles = (_table(df, k) for k in ("grid", "optimum", "cycles"))
    n_grid = int(np.prod([len(v) for v in module.GRID_QUICK.values()]))
    assert len(grid) == n_grid * len(module.POWERS_MW_QUICK)
    assert _bool(grid["success"]).all()
    np.testing.assert_allclose(grid["lift_per_power [um/mW]"],
                               grid["lift [um]"] / grid["total_power [mW]"])
    np.testing.assert_allclose(grid["total_power [mW]"],
                               grid["power [mW]"] * grid["n_creases"])
    assert (grid["lift [um]"] > 0).all()
    assert list(opt["label"]) == ["start", "optimum"]
    start, best = opt.iloc[0], opt.iloc[1]
    assert (start["a [um]"], start["gamma [deg]"], start["W [um]"]) == pytest.approx(
        (1000, 60, 200))
    assert best["total_power [mW]"] <= start["total_power [mW]"]
    assert best["lift [um]"] >= 1e6 * module.TARGET_LIFT - 1e-6
    assert cycles["total_power [mW]"].iloc[-1] == pytest.approx(best["total_power [mW]"])
    np.testing.assert_allclose(opt["power_staircase [mW]"], opt["power [mW]"], rtol=0.1)


def test_miura_grid_reports_a_design_that_does_not_mesh():
    from studies.miura_design import _grid_task

    values = {"a": 0.5e-3, "b": 0.5e-3, "gamma": math.radians(45), "W": 300e-6}
    table = _grid_task((values, (4.0, 8.0), 5))
    assert len(table) == 2 and not table["success"].any()
    assert table["message"].str.contains("collapses").all()
    assert table["b [um]"].iloc[0] == pytest.approx(500)


# ----------------------------------------------------------------------------- regression
def test_quick_study_numbers_stay_as_they_are(quick):
    """Key numbers of the quick studies, as before the result contract (issue 8; equal to
    the last digit in CSV before and after). A change here is a change of behaviour."""
    _, _, df = quick("gripper_optimization")
    comp = _table(df, "comparison").set_index("method")
    assert comp.loc["cd", "start_power [mW]"] == pytest.approx(32.3, rel=1e-9)
    assert comp["total_power [mW]"].to_dict() == pytest.approx(
        {"cd": 31.11875, "cobyla": 30.64375, "sbplx": 29.5625}, rel=1e-9)
    assert [comp.loc["sbplx", k] for k in START_UM] == pytest.approx([220, 750, 1000, 1000])
    assert comp.loc["sbplx", "temperature [degC]"] == pytest.approx(212.819022, rel=1e-7)
    assert list(comp["status"]) == ["max_evaluations"] * 3 and _bool(comp["success"]).all()

    _, _, df = quick("gripper_robustness")
    sweep = _table(df, "sweep")
    start = sweep[sweep["design"] == "start"].set_index("residual_fold [deg]")
    assert start["total_power [mW]"].to_dict() == pytest.approx({-10.0: 36.75625, 0.0: 32.3},
                                                                rel=1e-9)
    assert start["assembly_power [mW]"].to_dict() == pytest.approx(
        {-10.0: 29.4125, 0.0: 26.4375}, rel=1e-9)
    assert list(start["status"]) == ["infeasible", "feasible"]     # 257 degC at -10 deg

    _, _, df = quick("miura_design")
    grid, opt = _table(df, "grid"), _table(df, "optimum").set_index("label")
    np.testing.assert_allclose(grid["lift [um]"], [56.051001, 102.461910], rtol=1e-7)
    assert opt["total_power [mW]"].to_dict() == pytest.approx(
        {"start": 115.078125, "optimum": 100.078125}, rel=1e-9)
    assert opt.loc["optimum", "lift [um]"] == pytest.approx(206.407324, rel=1e-7)
