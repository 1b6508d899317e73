"""Study device_power_physics (issue 30 item 5): the measured grippers with metal layers, hot
air, radiation and electrical drive. The quick run: cycle 9, the paper setting, the crease
metal at 150 W/(m K) and all the physics at central values."""

import json

import pytest
from matplotlib.figure import Figure

from design.devices.gripper import GripperDesign, GripperHeatModel
from design.devices.gripper_heat import HEAT_FIELDS
from studies import device_power_physics as study


@pytest.fixture(scope="module")
def quick(quick_study):
    return quick_study("device_power_physics")


def test_quick_run_writes_its_files_stamped_quick(quick):
    _, out, df = quick
    assert (out / "device_power_physics.png").stat().st_size > 10_000
    meta = json.loads((out / "meta.json").read_text())
    assert meta["study"] == "device_power_physics" and meta["settings"] == {"quick": True}
    assert list(df["variant"]) == list(study.QUICK_VARIANTS)
    assert set(df["table"]) == {"power"}           # one design: no ratio
    assert not any(c.endswith(("[W]", "[m]", "[K]")) for c in df.columns)


def test_paper_setting_is_the_default_evaluation_and_the_physics_raise_the_power(quick):
    df = quick[2].set_index("variant")
    paper, metal, full = (df.loc[v] for v in study.QUICK_VARIANTS)
    assert df["success"].all() and (df["measured_power [mW]"] == 21.6).all()
    # the paper setting is the toolkit's default gripper evaluation (test_cli_design: 13.125)
    assert paper["full_function_power [mW]"] == pytest.approx(13.125, abs=0.02)
    assert paper["full_function_power [mW]"] == pytest.approx(paper["heater_power [mW]"])
    assert paper["change [%]"] == 0 and paper["crease_conduction"] == "paper"
    assert metal["crease_conduction"] == "layers" and metal["k_gold [W/(m K)]"] == 150
    # every switch on: more heat, and leads of 10 % of R0 on top: R_lead / R(T) of the heaters
    # (the resistance ratio is the circuit's, leads included: (R + 0.1 R0) / (1.1 R0); the
    # arm circuit carries under 0.1 % of the power)
    assert full["heater_power [mW]"] > metal["heater_power [mW]"] > paper["heater_power [mW]"]
    leads = full["vi_power [mW]"] / full["heater_power [mW]"] - 1
    heater_ratio = 1.1 * full["resistance_ratio [-]"] - 0.1
    assert leads == pytest.approx(0.1 / heater_ratio, rel=1e-3)
    assert full["error [%]"] == pytest.approx(
        100 * (full["full_function_power [mW]"] / 21.6 - 1))


def test_quoted_power_is_larger_by_the_heaters_resistance_ratio(quick):
    paper = quick[2].set_index("variant").loc["paper setting"]
    ratio = paper["quoted_power [mW]"] / paper["vi_power [mW]"]
    assert ratio == pytest.approx(paper["resistance_ratio [-]"], rel=0.05)
    assert 1.2 < ratio < 1.6      # gold at 0.0034 / K, the base hinges about 115 degC


def test_variants_are_valid_designs_and_the_combined_ends_bracket_the_centre():
    for name, group, switches, definition in study.VARIANTS:
        heat = {k: v for k, v in switches.items() if k in HEAT_FIELDS}
        GripperDesign(**study.DESIGNS[0][2], **{k: v for k, v in switches.items()
                                                if k not in heat})       # no error
        GripperHeatModel(**heat)
        assert definition in (study.VI, study.QUOTED) and group in (
            "paper", "effect", "electrical", "combined", "resolution"), name
    ends = {v[0]: v[2] for v in study.VARIANTS if v[1] == "combined"}
    for key in ("k_gold", "emissivity_polymer", "lead_fraction"):
        assert ends["all, low"][key] <= ends["all, central"][key] <= ends["all, high"][key]


def test_figure_redraws_from_the_csv(quick):
    fig = study.plot(quick[2])
    assert isinstance(fig, Figure) and all(ax.has_data() for ax in fig.axes)
