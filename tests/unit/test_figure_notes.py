"""What study figures say about themselves (studies.figure_notes, studies.plotting): footers,
full/quick stamps, the palette, shared 3-D scales, and the one 1.2 T_g measure."""

import matplotlib.colors as mcolors
import numpy as np
import pytest
from matplotlib.figure import Figure

from design.devices.miura import MiuraProblem
from simulator import ParameterError, get_case
from simulator.thermal import crease_temperatures
from studies import plotting
from studies.figure_notes import PALETTE, environment_note, figure_style, note_assumptions


def _texts(fig, gid):
    return [t for t in fig.texts if t.get_gid() == gid]


def test_footer_and_full_stamp_sit_below_the_axes(tmp_path):
    fig = Figure(figsize=(5, 3), layout="constrained")
    ax = fig.add_subplot()
    ax.plot([0, 1], [0, 1])
    note_assumptions(fig, environment_note("air", 0.026, -10, 0.9, extra=["substrate"]),
                     plotting.NO_HEAT)
    plotting.save_figure(fig, tmp_path / "f.png")
    (note,) = _texts(fig, "assumptions")
    assert " ".join(note.get_text().split()) == ("environment: air, k_env = 0.026 W/(m K); residual fold -10 deg; "
                               "gravity x 0.9; substrate " + plotting.NO_HEAT)
    (stamp,) = _texts(fig, "full-stamp")
    fig.canvas.draw()
    bottom = ax.get_tightbbox().transformed(fig.transFigure.inverted()).y0
    for text in (note, stamp):
        assert text.get_window_extent().transformed(fig.transFigure.inverted()).y1 < bottom
    plotting.save_figure(fig, tmp_path / "q.png", quick=True)   # quick replaces "full run"
    assert not _texts(fig, "full-stamp") and len(_texts(fig, "quick-stamp")) == 1


def test_environment_note_says_no_gravity_and_scenarios():
    assert environment_note("air", gravity=0) == "environment: air; no gravity"
    assert "assumed scenario: spread" in environment_note("air", scenario="spread")


def test_figure_style_cycles_the_colour_blind_safe_palette_with_line_styles():
    with figure_style():
        fig = Figure()
        ax = fig.add_subplot()
        lines = [ax.plot([0, 1], [0, k])[0] for k in range(3)]
    assert [mcolors.to_hex(l.get_color()) for l in lines] == [c.lower() for c in PALETTE[:3]]
    assert [l.get_linestyle() for l in lines] == ["-", "--", "-."]


def test_side_by_side_3d_panels_share_one_scale():
    fig = Figure()
    axes = [fig.add_subplot(1, 2, k + 1, projection="3d") for k in range(2)]
    small = np.array([[0, 0, 0], [1, 1, 0.1]])
    tall = np.array([[5, 5, 0], [6, 5.5, 0.4]])
    text = plotting.share_3d_scale(axes, [small, tall], z_stretch=2)
    spans = [[np.ptp(getattr(ax, f"get_{a}lim")()) for a in "xyz"] for ax in axes]
    np.testing.assert_allclose(spans[0], spans[1])
    np.testing.assert_allclose(spans[0], [1, 1, 0.4])
    assert "z stretched 2x" in text
    assert plotting.share_3d_scale(axes, [small, tall]) == "all panels at one true scale"


def test_the_limit_rings_only_the_measure_lines():
    fig = Figure()
    ax = fig.add_subplot()
    (measure,) = ax.plot([0, 1, 2], [100, 200, 240])
    ax.plot([0, 1, 2], [110, 230, 270])                      # hottest node, not the measure
    assert plotting.mark_temperature_limit(ax, lines=[measure]) == 0
    assert plotting.mark_temperature_limit(ax) == 1


def test_centre_line_temperature_is_the_mean_of_a_b_ctr():
    res = get_case("single_fold", thermal_steps=5, power_mW=20.0).run()
    mesh = res.model.mesh
    t = res.history["temperature"]
    expected = crease_temperatures(t.T, mesh, "centre_line").T
    np.testing.assert_array_equal(res.crease_temperature_centre_line, expected)
    np.testing.assert_array_equal(plotting.centre_line_temperatures(t, mesh), expected)
    assert np.all(res.crease_temperature_centre_line <= res.crease_temperature_max + 1e-12)


def test_the_miura_problem_checks_the_same_measure():
    assert MiuraProblem().temperature_measure == "centre_line"
    assert MiuraProblem().settings()["temperature_measure"] == "centre_line"
    with pytest.raises(ParameterError, match="temperature_measure = 'hot'"):
        MiuraProblem(temperature_measure="hot")
