"""Report figures: colour bars reach the hottest node, 1.2 T_g marks, the default output
folder, ``--figures-only``, the gripper shapes study and the index results/README.md."""

import pathlib
import re

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from simulator.cases import get_case
from studies import _common, double_fold, gripper_shapes
from studies.plotting import T_LIMIT, mark_temperature_limit, nodal_range, plot_shape

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def double_fold_result():
    return get_case("double_fold", thermal_steps=20).run()


def test_colour_bar_spans_the_nodal_range(double_fold_result):
    res = double_fold_result
    fig = plot_shape(res, record=-1)
    coll = fig.axes[0].collections[0]
    t = res.history["temperature"][-1]
    assert coll.norm.vmax == pytest.approx(t.max())
    assert coll.norm.vmin == pytest.approx(t.min())
    # facets take their hottest node, so the hottest facet has the colour bar's top
    assert np.asarray(coll.get_array()).max() == pytest.approx(t.max())


def test_shared_colour_scale_and_hidden_panels(double_fold_result):
    res = double_fold_result
    t = res.history["temperature"][-1]
    lo, hi = nodal_range(t, t + 100.0)
    assert (lo, hi) == (pytest.approx(t.min()), pytest.approx(t.max() + 100.0))
    fig = plot_shape(res, t_range=(lo, hi), colorbar=False)
    coll = fig.axes[0].collections[0]
    assert coll.norm.vmax == pytest.approx(hi) and len(fig.axes) == 1     # no colour bar
    mesh = res.model.mesh
    panel = int(mesh.triangle_panel.max())
    fig = plot_shape(res, hide_panels=(panel,))
    assert len(fig.axes[0].collections[0].get_array()) == int((mesh.triangle_panel != panel).sum())


def test_mark_temperature_limit_rings_points_above():
    fig = Figure()
    ax = fig.add_subplot()
    ax.plot([0, 1, 2, 3], [100, 200, 260, 300], label="T")
    ax.legend()
    assert mark_temperature_limit(ax) == 2
    assert any(f"{T_LIMIT:.0f}" in t.get_text() for t in ax.get_legend().texts)
    cool = Figure().add_subplot()
    cool.plot([0, 1], [20, 60])
    assert mark_temperature_limit(cool) == 0 and len(cool.get_lines()) == 1


def test_default_output_is_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert _common.default_out("double_fold") == tmp_path / "results" / "double_fold"


def test_figures_only_redraws_from_the_csv(tmp_path):
    src = ROOT / "results" / "double_fold"
    (tmp_path / "double_fold.csv").write_bytes((src / "double_fold.csv").read_bytes())
    assert double_fold.main(["--figures-only", "--out", str(tmp_path)]) == tmp_path
    assert (tmp_path / "double_fold_shape.png").stat().st_size > 10_000
    assert not (tmp_path / "meta.json").exists()
    with pytest.raises(SystemExit, match="run the study first"):
        double_fold.main(["--figures-only", "--out", str(tmp_path / "empty")])


def test_gripper_shapes_quick(tmp_path):
    out = gripper_shapes.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    df = pd.read_csv(out / "gripper_shapes.csv")
    d = df[df["table"] == "designs"].set_index(["design", "stage"])
    assert d["success"].all()
    assert (d.xs("assembly", level="stage")["base_fold [deg]"] > 89.5).all()
    assert (d.xs("grip", level="stage")["tip_distance [um]"] < 101).all()
    # the optimum needs less power and runs cooler than the start
    grip = d.xs("grip", level="stage")
    assert grip.loc["our optimum", "electrical_power [mW]"] < grip.loc["start",
                                                                       "electrical_power [mW]"]
    assert grip.loc["our optimum", "max_temperature [degC]"] < grip.loc["start",
                                                                        "max_temperature [degC]"]
    assert {p.name for p in out.glob("*.png")} == {"gripper_shapes.png", "gripper_descent.png"}


def test_results_readme_names_existing_files():
    text = (ROOT / "results" / "README.md").read_text()
    rows = [line for line in text.splitlines()
            if line.startswith("|") and not set(line) <= set("|-: ")][1:]     # skip header
    assert len(rows) >= 10
    for row in rows:
        files = re.findall(r"`([\w./-]+\.(?:png|csv|gif))`", row)
        assert files, f"row names no file: {row}"
        for name in files:
            assert (ROOT / "results" / name).is_file(), f"{name} missing ({row[:60]})"


def test_main_writes_under_the_working_directory_by_default(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "results" / "double_fold"
    out.mkdir(parents=True)
    (out / "double_fold.csv").write_bytes(
        (ROOT / "results" / "double_fold" / "double_fold.csv").read_bytes())
    assert double_fold.main(["--figures-only"]) == out
    assert (out / "double_fold.png").is_file()


def test_gripper_shapes_reads_a_descent_in_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert gripper_shapes._cd_csv() == ROOT / "results" / gripper_shapes.CD_CSV
    local = tmp_path / "results" / gripper_shapes.CD_CSV
    local.parent.mkdir(parents=True)
    local.write_text("table,cycle\n")
    assert gripper_shapes._cd_csv() == local
    with pytest.raises(FileNotFoundError, match="run `python -m studies.gripper_optimization`"):
        gripper_shapes._cd_cycles(tmp_path / "none.csv")
