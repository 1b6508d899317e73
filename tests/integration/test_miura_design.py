"""Miura-ori lifter design problem (design.devices.miura): model, lift-power search, problem, table."""

import math
import pickle

import numpy as np
import pytest

from design.devices.miura import (
    MIURA_SPACE,
    LiftPowerResult,
    MiuraDesign,
    MiuraProblem,
    _lift_nodes,
    lift_per_power_table,
    lift_power,
    make_miura_model,
)
from design.devices import SU8_TG
from simulator.cases import get_case
from simulator.errors import ParameterError

TARGET = 100e-6          # default design over the substrate: ~7.7 mW per crease (~0.2-0.7 s)
STEP = 0.1e-3

#: The case's chains (the paper setting): the targets and powers here were chosen for them.
PAPER = MiuraDesign(loss_model="chain")


@pytest.fixture(scope="module")
def searches():
    return {mode: lift_power(PAPER, TARGET, mode=mode, step=STEP)
            for mode in ("staircase", "bisect")}


@pytest.mark.parametrize("substrate", [False, True])
def test_model_is_the_miura_lifter_case(substrate):
    """For the case's parameters make_miura_model builds the case's model: same mesh, same lift."""
    case = get_case("miura_lifter", cells_x=4, cells_y=2, thermal_steps=20, power_mW=9.0,
                    substrate=substrate)
    design = MiuraDesign(loss_model="chain", substrate=substrate)
    model = make_miura_model(design)
    np.testing.assert_array_equal(model.mesh.nodes, case.model.mesh.nodes)
    assert model.thermal == case.model.thermal and model.actuators == case.model.actuators
    assert model.supports.fixed == case.model.supports.fixed
    res = case.run()
    lift = 1e6 * res.state.u[_lift_nodes(case.model, design), 2].mean()
    table = lift_per_power_table({"case": design}, 9.0, increments=20)
    assert table["lift [um]"][0] == pytest.approx(lift, rel=1e-9)
    assert lift > 100


def test_default_design_reaches_target_in_both_modes(searches):
    stair, bis = searches["staircase"], searches["bisect"]
    for res in (stair, bis):
        assert isinstance(res, LiftPowerResult)
        assert res.success and res.status == "met", res.message
        assert res.lift >= TARGET
        assert res.n_creases == 10
        assert res.total_power == pytest.approx(res.n_creases * res.power_per_crease)
        assert 20 < res.max_crease_temperature < 1.2 * SU8_TG
    assert 5e-3 < stair.power_per_crease < 10e-3               # measured 7.7 mW
    assert abs(bis.power_per_crease - stair.power_per_crease) <= STEP
    assert bis.simulations < stair.simulations / 2             # measured 18 vs 77
    assert bis.to_dict()["power_per_crease [mW]"] == pytest.approx(1e3 * bis.power_per_crease)


@pytest.mark.parametrize("mode", ["bisect", "staircase"])
def test_unreachable_target_is_not_met_with_reason(mode):
    res = lift_power(PAPER, 5e-3, mode=mode, power_cap=3e-3)
    assert not res.success and res.status == "not_met"
    assert res.power_per_crease is None and res.total_power is None   # never 0 or inf
    assert res.to_dict()["total_power [mW]"] is None
    assert "power cap" in res.message and "3 mW" in res.message
    assert 0 < res.lift < 5e-3


def test_substrate_needs_more_power_for_the_same_lift(searches):
    """Paper 6.2: the substrate cools the creases near it, so the same lift costs more power."""
    free = lift_power(MiuraDesign(loss_model="chain", substrate=False), TARGET)
    assert free.success
    assert searches["bisect"].power_per_crease > 1.5 * free.power_per_crease   # 7.8 vs 3.4 mW


def test_lift_per_power_table_trends():
    designs = {"substrate": PAPER, "free": MiuraDesign(loss_model="chain", substrate=False),
               "thick_su8": MiuraDesign(loss_model="chain", t_su8=1.6e-6)}
    table = lift_per_power_table(designs, [9.0, 3.0], increments=10)
    assert len(table) == 6 and table["success"].all()
    assert {"lift [um]", "max_crease_temperature [degC]", "power [mW]", "total_power [mW]",
            "a [um]", "gamma [deg]", "status", "message"} <= set(table)
    lift = table.set_index(["label", "power [mW]"])["lift [um]"]
    temp = table.set_index(["label", "power [mW]"])["max_crease_temperature [degC]"]
    for label in designs:
        assert lift[label, 9.0] > lift[label, 3.0] > 0
        assert temp[label, 9.0] > temp[label, 3.0]
    assert lift["free", 9.0] > 2 * lift["substrate", 9.0]
    assert lift["thick_su8", 9.0] < lift["substrate", 9.0]     # stiffer, less curvature


def test_problem_evaluates_default_design():
    problem = MiuraProblem(target_lift=TARGET, base=PAPER)
    assert pickle.loads(pickle.dumps(problem)) == problem
    ev = problem.evaluate(problem.space.start)
    assert ev.feasible, ev.message
    assert ev.objective > 0 and ev.objective == pytest.approx(
        1e-3 * ev.metrics["total_power [mW]"])
    assert set(ev.constraints) == {f"{v}_{s}" for v in ("a", "b", "gamma", "W")
                                   for s in ("lower", "upper")} | {"temperature"}
    assert ev.metrics["lift [um]"] >= 100 and "max_crease_temperature [degC]" in ev.metrics
    assert problem.settings()["T_limit [degC]"] == pytest.approx(1.2 * SU8_TG)


def test_problem_reports_hot_and_unmeshable_designs():
    problem = MiuraProblem(target_lift=TARGET, base=PAPER)
    hot = problem.evaluate({"a": 0.5e-3, "b": 0.5e-3, "gamma": math.radians(75), "W": 100e-6})
    assert hot.success and not hot.feasible and hot.constraints["temperature"] > 0
    assert hot.status == "infeasible"
    bad = problem.evaluate({"a": 0.5e-3, "b": 0.5e-3, "gamma": math.radians(45), "W": 300e-6})
    assert not bad.success and bad.status == "failed" and math.isinf(bad.objective)
    assert "W = 300 um" in bad.message
    out = problem.evaluate({"a": 2e-3, "b": 1e-3, "gamma": 1.0, "W": 200e-6})
    assert not out.success and "outside its bounds" in out.message


def test_space_reports_gamma_in_degrees():
    gamma = MIURA_SPACE["gamma"]
    assert gamma.display_unit == "deg" and gamma.display_scale == pytest.approx(180 / math.pi)
    assert gamma.lower == pytest.approx(math.radians(45))
    assert gamma.upper == pytest.approx(math.radians(75))


@pytest.mark.parametrize("kwargs, match", [
    ({"a": -1e-3}, "MiuraDesign.a"), ({"W": math.nan}, "MiuraDesign.W"),
    ({"gamma": math.radians(95)}, "gamma"), ({"cells_x": 1}, "cells_x"),
    ({"cells_y": 2.0}, "cells_y"), ({"substrate": "yes"}, "substrate"),
    ({"t_su8": 0.0}, "t_su8"),
    ({"a": 0.5e-3, "b": 0.5e-3, "gamma": math.radians(45), "W": 300e-6}, r"W < 207\.1 um"),
])
def test_invalid_designs_raise(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        MiuraDesign(**kwargs)


def test_invalid_search_settings_raise():
    with pytest.raises(ParameterError, match="mode"):
        lift_power(MiuraDesign(), TARGET, mode="newton")
    with pytest.raises(ParameterError, match="target_lift"):
        lift_power(MiuraDesign(), -1e-6)
    with pytest.raises(ParameterError, match="mode"):
        MiuraProblem(mode="grid")


def test_the_default_design_uses_the_integral_loss_and_a_chain_design_keeps_its_dict():
    """Issue 29: MiuraDesign's heat loss defaults to the integral model over the substrate's
    plane; a chain design's dict is the one it had before the field (its logs still match)."""
    model = make_miura_model(MiuraDesign())
    assert model.thermal.loss.model == "integral"
    assert make_miura_model(PAPER).thermal.loss.model == "chain"
    assert "loss_model" not in PAPER.to_dict()
    assert MiuraDesign().to_dict()["loss_model"] == "integral"
    with pytest.raises(ParameterError, match="MiuraDesign.loss_model = 'fe'"):
        MiuraDesign(loss_model="fe")
