"""Every study figure names the physics that made it: its footer names the heat-loss model
(and its settings) and the medium (issue 29, item 3); save_figure refuses one that does not."""

import importlib
import pathlib
import shutil

import pytest
from matplotlib.figure import Figure

from simulator import get_case
from studies.figure_notes import NO_HEAT, check_footer, heat_loss_note, note_assumptions
from studies.plotting import save_figure

RESULTS = pathlib.Path(__file__).resolve().parents[2] / "results"
STUDIES = sorted(p.name for p in RESULTS.iterdir() if (p / f"{p.name}.csv").is_file())


def test_save_figure_refuses_a_figure_whose_footer_does_not_name_its_heat_loss(tmp_path):
    fig = Figure()
    fig.add_subplot().plot([0, 1])
    with pytest.raises(ValueError, match="does not name the heat-loss model and the medium"):
        save_figure(fig, tmp_path / "bare.png")
    note_assumptions(fig, "environment: air, k_env = 0.026 W/(m K)")
    with pytest.raises(ValueError, match="does not name the heat-loss model"):
        save_figure(fig, tmp_path / "bare.png")
    assert not (tmp_path / "bare.png").exists()
    note_assumptions(fig, heat_loss_note(get_case("double_fold").model))
    assert save_figure(fig, tmp_path / "named.png").is_file()


def test_heat_loss_note_says_model_settings_medium_and_substrate():
    assert heat_loss_note(None) == NO_HEAT
    chain = heat_loss_note(get_case("double_fold").model)
    assert chain == ("heat loss: chain model (the paper's; t_env = 600 um, 10 layers, beta = "
                     "20 deg); medium: air, k = 0.026 W/(m K); t_env capped at the boundary "
                     "panels (3)")
    integral = heat_loss_note(get_case("crane", loss_model="integral").model)
    assert integral.startswith("heat loss: integral model (calibration-free; m = 3, "
                               "extrapolated); medium: air") and integral.endswith("no substrate")


@pytest.mark.parametrize("name", STUDIES)
def test_every_committed_figure_replots_with_a_footer_naming_its_heat_loss(name, tmp_path):
    out = tmp_path / name
    shutil.copytree(RESULTS / name, out)
    module = importlib.import_module(f"studies.{name}")
    module.main(["--figures-only", "--out", str(out)])     # save_figure checks every footer
    pngs = sorted(out.glob("*.png"))
    assert pngs and all(p.stat().st_mtime >= (out / f"{name}.csv").stat().st_mtime
                        for p in pngs)


def test_check_footer_reads_the_footer_only():
    fig = Figure()
    fig.suptitle("heat loss: chain; medium: air")        # a title is not a footer
    with pytest.raises(ValueError):
        check_footer(fig)
