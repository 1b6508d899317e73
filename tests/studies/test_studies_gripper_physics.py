"""Study gripper_physics (issue 30 item 5): the paper's coordinate descent with the chains,
the calibration-free integral loss and the device physics. The quick run: three evaluations
per descent, three cross evaluations."""

import json

import numpy as np
import pytest

from design.devices.gripper import GripperDesign, evaluate_gripper
from studies import gripper_physics as study


@pytest.fixture(scope="module")
def quick(quick_study):
    return quick_study("gripper_physics")


def test_quick_run_writes_its_files_stamped_quick(quick):
    _, out, df = quick
    assert (out / "gripper_physics.png").stat().st_size > 10_000
    meta = json.loads((out / "meta.json").read_text())
    assert meta["study"] == "gripper_physics" and meta["settings"] == {"quick": True}
    assert set(df["table"]) == {"cycles", "cross"}
    assert not any(c.endswith(("[W]", "[m]", "[K]")) for c in df.columns)


def test_each_descent_starts_at_the_paper_start_and_never_climbs(quick):
    cycles = quick[2][quick[2]["table"] == "cycles"]
    assert set(cycles["setting"]) == set(study.SETTINGS)
    for _, c in cycles.groupby("setting"):
        c = c.sort_values("cycle")
        assert list(c[study.UM].iloc[0]) == [200, 700, 1000, 1000]
        assert np.all(np.diff(c[study.POWER]) <= 1e-9) and c["feasible"].all()
    start = cycles[cycles["cycle"] == 0].set_index("setting")[study.POWER]
    # the chains run the creases cool (more power); the physics (hot air, radiation, the gold
    # layer) needs more than the integral loss alone
    assert start["paper"] > start["physics"] > start["integral"]


def test_the_cross_evaluation_is_the_evaluation_of_the_design(quick):
    cross = quick[2][quick[2]["table"] == "cross"].set_index(["design", "setting"])
    row = cross.loc[("start", "physics")]
    assert row["success"] and row[study.FULL] == pytest.approx(2 * row[study.POWER])
    # the same design and setting as the physics descent's cycle 0
    cycles = quick[2][quick[2]["table"] == "cycles"]
    c0 = cycles[(cycles["setting"] == "physics") & (cycles["cycle"] == 0)][study.POWER]
    assert row[study.POWER] == pytest.approx(float(c0.iloc[0]), rel=1e-9)


def test_the_physics_setting_is_the_device_physics_at_central_values():
    heat = study.SETTINGS["physics"]
    assert heat.loss_model == "integral" and heat.crease_conduction == "layers"
    assert heat.k_gold == 150 and heat.temperature_dependent_air
    assert heat.emissivity_polymer == 0.7 and heat.emissivity_gold == 0.03
    assert study.SETTINGS["paper"].loss_model == "chain"
    # the electrical knobs are left out: the objective is the heat balance's (the settings
    # are heat models; the descents' designs keep the default drive)
    assert not {"lead_fraction", "heater_tcr"} & set(study.PHYSICS)


def test_committed_results_are_a_full_run_whose_optima_hold_under_their_own_model():
    """results/gripper_physics: each descent's last design is its optimum, and re-evaluating
    the physics optimum gives the committed power (the run is reproducible)."""
    import pathlib

    import pandas as pd

    out = pathlib.Path(__file__).parents[2] / "results" / "gripper_physics"
    assert json.loads((out / "meta.json").read_text())["settings"] == {"quick": False}
    df = pd.read_csv(out / "gripper_physics.csv")
    cross = df[df["table"] == "cross"].set_index(["design", "setting"])
    for s in study.SETTINGS:
        own = cross.loc[(s, s), study.POWER]
        assert own <= cross.loc[("start", s), study.POWER] / 2     # halved at least
    x = cross.loc[("physics", "physics"), study.UM] * 1e-6
    res = evaluate_gripper(GripperDesign(**dict(zip(study.VARIABLES, x))), mode="bisect",
                           heat=study.SETTINGS["physics"])
    assert 1e3 * res.total_power == pytest.approx(cross.loc[("physics", "physics"),
                                                            study.POWER], rel=1e-9)
