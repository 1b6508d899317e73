"""The gripper's physics switches of issue 30 (``GripperHeatModel``: crease conduction, hot
air, radiation; ``GripperDesign``: the electrical drive) and its drive at full function
(``gripper_drive``)."""

import math

import numpy as np
import pytest

from design.devices.gripper import (GripperDesign, GripperHeatModel, GripperResult, StageResult,
                                    evaluate_gripper, gripper_settings, make_gripper_model)
from design.devices.gripper_drive import gripper_circuits, gripper_drive
from simulator import ParameterError

CYCLE9 = dict(W=290e-6, La=1150e-6, L1=550e-6, L2=550e-6)
HEAT = dict(crease_conduction="layers", k_gold=300.0, temperature_dependent_air=True,
            emissivity_polymer=0.7, emissivity_gold=0.03)
DRIVE = dict(lead_fraction=0.1, heater_tcr=0.002)
SWITCHES = {**HEAT, **DRIVE}


def test_the_switches_keep_the_old_dict_at_their_defaults():
    """Old evaluation-log hashes stay valid: at the defaults none of the new names appears."""
    old = {"W", "L1", "L2", "La", "t_gold", "t_su8", "grip_range", "undercut",
           "panel_thickness", "residual_fold", "residual_fold_base", "residual_fold_arm"}
    chain = GripperHeatModel(loss_model="chain")
    assert set(gripper_settings(GripperDesign(), chain)) == old
    assert set(gripper_settings(GripperDesign())) == old | {
        "loss_model", "integral_refinement", "conduction", "sheet_refinement", "integral_levels"}
    d = gripper_settings(GripperDesign(**DRIVE), GripperHeatModel(**HEAT))
    assert {k: d[k] for k in SWITCHES} == SWITCHES
    layers = GripperHeatModel(crease_conduction="layers")
    assert gripper_settings(GripperDesign(), layers)["crease_conduction"] == "layers"
    assert "k_gold" not in gripper_settings(GripperDesign(), layers)


def test_the_switches_are_named_with_units_in_the_result_dict():
    assess = StageResult(True, "met", "criterion met", 1e-3, 2.0, 100.0, 110.0, 1, 1)
    row = GripperResult(GripperDesign(**DRIVE), "bisect", assess, assess,
                        GripperHeatModel(**HEAT)).to_dict()
    assert row["k_gold [W/(m K)]"] == 300.0 and row["heater_tcr [1/K]"] == 0.002
    assert row["emissivity_polymer [-]"] == 0.7 and row["temperature_dependent_air [-]"]


def test_the_default_model_is_the_paper_setting():
    model, _ = make_gripper_model(GripperDesign())
    pattern = model.mesh.pattern
    assert model.thermal.crease_conduction == "paper"
    assert not model.thermal.medium.temperature_dependent
    assert model.thermal.medium.thermal_conductivity == 0.026
    assert pattern.crease_material.emissivity == 0
    assert all(m.emissivity == 0 for m in pattern.panel_material)


def test_the_switches_reach_the_model():
    model, _ = make_gripper_model(GripperDesign(**DRIVE), heat=GripperHeatModel(**HEAT))
    pattern, thermal = model.mesh.pattern, model.thermal
    assert thermal.crease_conduction == "layers" and model.actuators.bimorph.k1 == 300.0
    assert thermal.medium.temperature_dependent and thermal.medium.conductivity(120.0) > 0.03
    assert [m.emissivity for m in pattern.panel_material[:5]] == [0.7] * 5
    assert pattern.crease_material.emissivity == pytest.approx((0.7 + 0.03) / 2)
    layers = make_gripper_model(GripperDesign(),
                                heat=GripperHeatModel(crease_conduction="layers"))[0]
    assert layers.actuators.bimorph.k1 == 150.0           # Bimorph's thin-film default


@pytest.mark.parametrize("kwargs, match", [
    ({"crease_conduction": "gold"}, r"GripperHeatModel.crease_conduction = 'gold'.*'layers'"),
    ({"crease_conduction": "layers", "k_gold": -5.0}, r"GripperHeatModel.k_gold = -5.*100-300"),
    ({"k_gold": 150.0}, r"GripperHeatModel.k_gold = 150.0 W/\(m K\) acts only with "
                        r"crease_conduction='layers'"),
    ({"temperature_dependent_air": "yes"}, r"temperature_dependent_air = 'yes' must be True"),
    ({"emissivity_polymer": 1.5},
     r"GripperHeatModel.emissivity_polymer = 1.5.*\[0, 1\].*0.5-0.9"),
    ({"emissivity_gold": -0.1}, r"GripperHeatModel.emissivity_gold = -0.1"),
])
def test_bad_heat_switches_are_refused_by_name_value_and_fix(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        GripperHeatModel(**kwargs)


@pytest.mark.parametrize("kwargs, match", [
    ({"lead_fraction": -0.1}, r"GripperDesign.lead_fraction = -0.1.*>= 0.*0 without leads"),
    ({"heater_tcr": math.nan}, r"GripperDesign.heater_tcr = nan.*0.0011-0.0034"),
])
def test_bad_drive_switches_are_refused_by_name_value_and_fix(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        GripperDesign(**kwargs)


def test_hot_air_with_another_constant_air_is_refused_where_both_meet():
    """The air's law is the heat model's, its constant the design's: checked together."""
    hot = GripperHeatModel(temperature_dependent_air=True)
    with pytest.raises(ParameterError, match=r"env_conductivity = 0.03 W/\(m K\) with "
                       r"GripperHeatModel.temperature_dependent_air=True.*leave "
                       r"env_conductivity at 0.026"):
        make_gripper_model(GripperDesign(env_conductivity=0.03), heat=hot)


def _result(design, pa, pg, t_base, t_arm):
    """A met GripperResult with given powers [W] and crease temperatures [deg C]."""
    temps = [21.0] * 4
    rows = {2: 0, 3: 1, 5: 2, 9: 3}                      # crease rows: pattern.creases order
    for c, t in ((2, t_base), (5, t_base), (3, t_arm), (9, t_arm)):
        temps[rows[c]] = t
    stage = dict(measure=0.0, temperature=t_base, max_crease_temperature=t_base,
                 simulations=1, increments=1)
    a = StageResult(True, "met", "criterion met", pa, **stage)
    g = StageResult(True, "met", "criterion met", pg, **stage, crease_temperatures=tuple(temps))
    return GripperResult(design, "bisect", a, g)


def test_drive_of_series_circuits_at_their_operating_point():
    """Analytic: two equal heaters in series at dT, leads f R0: V I = P (1 + f / (1 + a dT)),
    V^2 / R0_total = P (1 + a dT + f)^2 / ((1 + a dT)(1 + f))."""
    design = GripperDesign(**CYCLE9, lead_fraction=0.2, heater_tcr=0.003)
    assert [len(c.heaters) for c in gripper_circuits(design)] == [2, 2]
    r0 = 0.15 * 550 / 290
    assert gripper_circuits(design)[0].lead_resistance == pytest.approx(0.2 * 2 * r0)
    drive = gripper_drive(_result(design, 5e-3, 1e-3, 121.0, 71.0))
    assert drive.success and drive.heater_power == pytest.approx(12e-3)
    expected = vi = quoted = 0.0
    for p, dt in ((10e-3, 100.0), (2e-3, 50.0)):
        g = 1 + 0.003 * dt
        vi += p * (1 + 0.2 / g)
        quoted += p * (g + 0.2) ** 2 / (g * 1.2)
        expected += p * 0.2 / g
    assert drive.electrical_power == pytest.approx(vi, rel=1e-12)
    assert drive.quoted_power == pytest.approx(quoted, rel=1e-12)
    assert drive.lead_loss == pytest.approx(expected, rel=1e-12)
    i = math.sqrt(10e-3 / (2 * r0 * 1.3))
    assert drive.current[0] == pytest.approx(i) and drive.voltage[0] == pytest.approx(
        i * 2 * r0 * 1.5)
    assert drive.heater_temperature == (121.0, 71.0)
    assert drive.resistance_ratio[0] == pytest.approx(1.5 / 1.2)


def test_drive_without_a_full_function_says_so():
    design = GripperDesign(**CYCLE9)
    met = StageResult(True, "met", "criterion met", 1e-3, 0.0, 50.0, 50.0, 1, 1)
    unmet = StageResult(False, "not_met", "criterion not met below the power cap", None, 0.0,
                        50.0, 50.0, 1, 1)
    drive = gripper_drive(GripperResult(design, "bisect", met, unmet))
    assert not drive.success and drive.status == "not_met"
    assert "no full function" in drive.message and drive.electrical_power is None


def test_evaluation_records_crease_temperatures_and_drives_the_heaters():
    res = evaluate_gripper(GripperDesign(**CYCLE9, lead_fraction=0.1))
    assert res.success and len(res.grip.crease_temperatures) == 4
    drive = gripper_drive(res)
    # the base hinges run hotter than the arm hinges, both above room temperature
    assert drive.heater_temperature[0] > drive.heater_temperature[1] > 21.0
    assert drive.heater_power == pytest.approx(2 * res.total_power)
    assert drive.heater_power < drive.electrical_power < 1.1 * drive.heater_power
    assert np.isclose(drive.electrical_power - drive.heater_power, drive.lead_loss)
