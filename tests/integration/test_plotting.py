"""Plotting module (studies/plotting.py): figures, files and the matplotlib layering rule.

Results are built from mechanics only (a SelfFold of the single fold demo); temperatures and
powers are synthetic, written into the cached history, so no heating solve is needed.
"""

import dataclasses
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from simulator.cases import single_fold_model
from simulator import SelfFold, simulate
from studies.plotting import (animate, heat_loss_note, note_assumptions, plot_fold_vs_power,
                              plot_shape, plot_temperature_vs_power, save_figure)


@pytest.fixture(scope="module")
def cold():
    """Mechanics-only result: 6 records, uniform 21 deg C, zero power."""
    res = simulate(single_fold_model(), [SelfFold({2: 0.5}, increments=5)])
    assert res.success
    return res


@pytest.fixture(scope="module")
def hot(cold):
    """Same motion with synthetic node temperatures (hot at the crease) and rising power."""
    res = dataclasses.replace(cold)  # fresh instance: no cached history
    h = dict(cold.history)
    x = res.model.mesh.nodes[:, 0]
    ramp = np.linspace(0.0, 1.0, len(h["u"]))[:, None]
    h["temperature"] = 21.0 + 150.0 * ramp * np.exp(-((x - 0.6e-3) / 0.3e-3) ** 2)[None]
    h["power"] = 20e-3 * ramp
    res.__dict__["history"] = h
    return res


def test_simulator_import_does_not_load_matplotlib():
    out = subprocess.run([sys.executable, "-c", "import simulator, sys; "
                          "print('matplotlib' in sys.modules)"],
                         capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_plotting_does_not_load_pyplot():
    out = subprocess.run([sys.executable, "-c", "import studies.plotting, sys; "
                          "print('matplotlib.pyplot' in sys.modules)"],
                         capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_plot_shape_colours_faces_by_hottest_node_on_the_nodal_range(hot):
    fig = plot_shape(hot)
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 2  # 3-D axes + colorbar
    ax, cax = fig.axes
    assert ax.name == "3d"
    assert [ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()] == ["x [mm]", "y [mm]", "z [mm]"]
    assert "°C" in cax.get_ylabel()
    assert "self_fold" in ax.get_title() and "increment 5" in ax.get_title()
    (coll,) = ax.collections
    mesh = hot.model.mesh
    t = hot.history["temperature"][-1]
    np.testing.assert_allclose(coll.get_array(), t[mesh.triangles].max(axis=1))
    assert coll.norm.vmin == pytest.approx(t.min())       # the colour bar spans the nodes
    assert coll.norm.vmax == pytest.approx(t.max())


def test_plot_shape_limits_bound_the_deformed_shape_with_equal_aspect(cold):
    ax = plot_shape(cold, record=-1).axes[0]
    x = (cold.model.mesh.nodes + cold.history["u"][-1]) * 1e3
    lims = np.array([ax.get_xlim(), ax.get_ylim(), ax.get_zlim()])
    assert np.all(lims[:, 0] <= x.min(axis=0) + 1e-9) and np.all(lims[:, 1] >= x.max(axis=0) - 1e-9)
    assert x[:, 2].max() > 0.1  # the panel is visibly folded up (0.5 rad on a 0.5 mm panel)
    span = lims[:, 1] - lims[:, 0]
    aspect = np.asarray(ax.get_box_aspect())
    np.testing.assert_allclose(aspect / aspect[0], span / span[0], rtol=1e-6)


def test_plot_shape_options(cold):
    fig = plot_shape(cold, record=0, color_by=None, show_reference=True)
    assert len(fig.axes) == 1  # no colorbar
    ax = fig.axes[0]
    assert len(ax.collections) == 2  # deformed faces + reference wireframe
    assert "initial" in ax.get_title()
    with pytest.raises(ValueError, match="color_by"):
        plot_shape(cold, color_by="stress")
    with pytest.raises(IndexError):
        plot_shape(cold, record=99)
    with pytest.raises(ValueError, match="3-D"):
        plot_shape(cold, ax=Figure().add_subplot())


def test_plot_shape_draws_into_a_given_axes(cold):
    fig = Figure()
    ax = fig.add_subplot(1, 2, 2, projection="3d")
    assert plot_shape(cold, ax=ax) is fig
    assert len(ax.collections) == 1


def test_plot_fold_vs_power(hot):
    fig = plot_fold_vs_power(hot)
    (ax,) = fig.axes
    assert ax.get_xlabel() == "power [mW]" and ax.get_ylabel() == "fold angle [deg]"
    (line,) = ax.get_lines()
    assert line.get_label() == "crease 2"
    np.testing.assert_allclose(line.get_xdata(), hot.history["power"][:, 0] * 1e3)
    np.testing.assert_allclose(line.get_ydata(), np.degrees(hot.fold_angle[:, 0]))


def test_plot_temperature_vs_power(hot):
    fig = plot_temperature_vs_power(hot)
    (ax,) = fig.axes
    assert ax.get_xlabel() == "power [mW]" and "°C" in ax.get_ylabel()
    mean, peak = ax.get_lines()
    assert mean.get_linestyle() == "-" and peak.get_linestyle() == "--"
    assert mean.get_color() == peak.get_color()
    np.testing.assert_allclose(mean.get_ydata(), hot.crease_temperature[:, 0])
    np.testing.assert_allclose(peak.get_ydata(), hot.crease_temperature_max[:, 0])
    assert np.all(peak.get_ydata() >= mean.get_ydata() - 1e-12)
    assert peak.get_ydata()[-1] > 100.0


def test_curves_from_csv_round_trip(hot, tmp_path):
    hot.to_frame().to_csv(tmp_path / "creases.csv", index=False)
    df = pd.read_csv(tmp_path / "creases.csv")
    for plot, n_lines in ((plot_fold_vs_power, 1), (plot_temperature_vs_power, 2)):
        from_csv, from_result = plot(df, creases=[2]).axes[0], plot(hot).axes[0]
        assert len(from_csv.get_lines()) == n_lines
        for a, b in zip(from_csv.get_lines(), from_result.get_lines()):
            np.testing.assert_allclose(a.get_xydata(), b.get_xydata())
    fig = Figure()
    ax = fig.add_subplot()
    assert plot_fold_vs_power(df.sample(frac=1, random_state=0), ax=ax) is fig  # shuffled rows
    np.testing.assert_allclose(ax.get_lines()[0].get_xdata(), hot.history["power"][:, 0] * 1e3)


def test_curves_reject_bad_input(hot):
    with pytest.raises(ValueError, match="unknown crease"):
        plot_fold_vs_power(hot, creases=[7])
    with pytest.raises(ValueError, match="column"):
        plot_temperature_vs_power(hot.to_frame().drop(columns="temperature_max [degC]"))


def test_save_figure_writes_png(hot, tmp_path):
    shape, curves = plot_shape(hot), plot_fold_vs_power(hot)
    for fig in (shape, curves):
        note_assumptions(fig, heat_loss_note(hot.model))     # save_figure requires the physics
    out = save_figure(shape, tmp_path / "figs" / "shape")
    assert out == tmp_path / "figs" / "shape.png"
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    out = save_figure(curves, tmp_path / "fold.png")
    assert out.stat().st_size > 0


def test_animate_writes_gif(hot, tmp_path):
    from PIL import Image

    out = animate(hot, tmp_path / "anim" / "fold.gif", every=2, fps=5)
    assert out == tmp_path / "anim" / "fold.gif"
    assert out.read_bytes()[:6] in (b"GIF87a", b"GIF89a")
    with Image.open(out) as im:
        assert im.n_frames == 4  # records 0, 2, 4 and the last one (5)
    with pytest.raises(ValueError, match="every"):
        animate(hot, tmp_path / "x.gif", every=0)
