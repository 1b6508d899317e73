"""The gripper with either heat-loss model: ``GripperHeatModel(loss_model=...)`` (theory 4.7),
the evaluation's choice (issue 31: no longer the design's; the old fields warn)."""

import dataclasses

import pytest

from design import GripperHeatModel, GripperProblem
from design.devices.gripper import (GripperDesign, evaluate_gripper, gripper_settings,
                                    make_gripper_model)
from simulator import EtorigamiDeprecationWarning, ParameterError, Substrate

#: Coordinate-descent cycle 9 (results/gripper_optimization): a fast evaluation.
CYCLE9 = dict(W=290e-6, La=1150e-6, L1=550e-6, L2=550e-6)
CHAIN = GripperHeatModel(loss_model="chain")


def test_default_heat_model_is_the_integral_loss_and_the_chain_settings_keep_their_dict():
    """The default heat loss is the integral model (issue 29, 7 Dec 2026); a chain setting's
    dict is the one it had as the default (no ``loss_model``), so its logs still match."""
    assert GripperHeatModel().loss_model == "integral"
    model, _ = make_gripper_model(GripperDesign())
    assert model.thermal.loss.model == "integral"
    assert model.thermal.substrate == Substrate.plane((0.0, 0.0, -150e-6), (0.0, 0.0, 1.0))
    paper, _ = make_gripper_model(GripperDesign(), heat=CHAIN)
    assert paper.thermal.loss.model == "chain" and paper.thermal.substrate == Substrate()
    assert "loss_model" not in gripper_settings(GripperDesign(), CHAIN)
    assert "integral_refinement" not in gripper_settings(
        GripperDesign(), GripperHeatModel(loss_model="chain", integral_refinement=3))
    # with the integral model it and m are always named (m's default changed from 2 to 3)
    assert gripper_settings(GripperDesign())["loss_model"] == "integral"
    assert gripper_settings(GripperDesign())["integral_refinement"] == 3
    # the design's own dict names no heat model
    assert not {"loss_model", "integral_refinement", "conduction"} & set(
        GripperDesign().to_dict())


def test_integral_design_uses_the_substrate_plane_under_the_sheet():
    design = GripperDesign(**CYCLE9)
    heat = GripperHeatModel(loss_model="integral", integral_refinement=4)
    thermal = make_gripper_model(design, heat=heat)[0].thermal
    chain = make_gripper_model(GripperDesign(**CYCLE9), heat=CHAIN)[0].thermal
    assert (thermal.loss.model, thermal.loss.refinement) == ("integral", 4)
    assert thermal.substrate.as_tuple() == (0.0, 0.0, -design.undercut, 0.0, 0.0, 1.0)
    assert thermal.substrate == Substrate.plane((0.0, 0.0, -design.undercut), (0.0, 0.0, 1.0))
    # everything else (medium, room temperature, held panels and nodes) is the chain model's
    assert dataclasses.replace(thermal, loss=chain.loss, substrate=chain.substrate) == chain
    assert gripper_settings(design, heat)["loss_model"] == "integral"
    assert gripper_settings(design, heat)["integral_refinement"] == 4


@pytest.mark.parametrize("kwargs, match", [
    ({"loss_model": "fe"}, r"GripperHeatModel.loss_model = 'fe'.*'chain', 'integral'"),
    ({"integral_refinement": 0}, "GripperHeatModel.integral_refinement = 0"),
    ({"integral_refinement": 2.5}, "GripperHeatModel.integral_refinement"),
])
def test_bad_loss_model_settings_are_refused_by_name(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        GripperHeatModel(**kwargs)


def test_integral_model_needs_less_power_than_the_chains():
    """The chain model runs 35-40 % cooler than the 3-D FE on the gripper (docs/heat_fe.md),
    the integral model within about 10 %: with it both stages need less power."""
    chain = evaluate_gripper(GripperDesign(**CYCLE9), heat=CHAIN)
    integral = evaluate_gripper(GripperDesign(**CYCLE9), heat=GripperHeatModel())
    assert chain.success and integral.success, (chain.message, integral.message)
    assert integral.assembly.power_per_crease < 0.75 * chain.assembly.power_per_crease
    assert integral.grip.power_per_crease < chain.grip.power_per_crease
    assert integral.to_dict()["loss_model [-]"] == "integral"
    assert chain.heat == CHAIN and "loss_model [-]" not in chain.to_dict()


def test_problem_with_the_integral_heat_model_records_it_but_not_as_a_metric():
    problem = GripperProblem()
    assert problem.settings()["base"]["loss_model"] == "integral"
    ev = problem.evaluate(problem.space.to_vector(CYCLE9))
    assert ev.success, ev.message
    assert not any(k.startswith(("loss_model", "integral_refinement", "conduction"))
                   for k in ev.metrics)
    assert problem.settings() != GripperProblem(heat=CHAIN).settings()


def test_conduction_follows_the_loss_model_and_is_named_with_the_integral_model():
    """The sheet conduction (theory 4.9): T3 with the chains, monotone with the integral loss,
    named in the dict of an integral setting so that older logs (T3) never match."""
    design = GripperDesign()
    assert "conduction" not in gripper_settings(design, CHAIN)
    assert make_gripper_model(design, heat=CHAIN)[0].thermal.conduction_method == "t3"
    assert gripper_settings(design)["conduction"] == "monotone"
    assert make_gripper_model(design)[0].thermal.conduction_method == "monotone"
    chosen = GripperHeatModel(loss_model="chain", conduction="monotone")
    assert gripper_settings(design, chosen)["conduction"] == "monotone"
    assert make_gripper_model(design, heat=chosen)[0].thermal.conduction_method == "monotone"
    with pytest.raises(ParameterError, match="GripperHeatModel.conduction = 'p1'"):
        GripperHeatModel(conduction="p1")


def test_the_old_heat_fields_of_the_design_warn_and_give_the_same_model_and_keys():
    """``GripperDesign(loss_model=...)`` (before issue 31) still works for one release: a
    deprecation warning naming GripperHeatModel, the same model, the same problem settings
    (so evaluation logs written before still match), and a problem moves them into ``heat``."""
    with pytest.warns(EtorigamiDeprecationWarning, match=r"GripperDesign\(loss_model='chain', "
                      r"conduction='monotone'\) is deprecated.*GripperHeatModel") as rec:
        old = GripperDesign(**CYCLE9, loss_model="chain", conduction="monotone")
    assert len(rec) == 1 and rec[0].filename == __file__
    new = GripperHeatModel(loss_model="chain", conduction="monotone")
    assert old.loss_model == "chain"                       # what was given, kept
    a = make_gripper_model(old)[0]
    b = make_gripper_model(GripperDesign(**CYCLE9), heat=new)[0]
    assert a.thermal == b.thermal
    problem = GripperProblem(base=old)
    assert problem.heat == new and problem.base == GripperDesign(**CYCLE9)
    assert problem.settings() == GripperProblem(base=GripperDesign(**CYCLE9), heat=new).settings()
    assert gripper_settings(old) == gripper_settings(GripperDesign(**CYCLE9), new)
    with pytest.raises(ParameterError, match="GripperHeatModel.loss_model = 'fe'"), \
            pytest.warns(EtorigamiDeprecationWarning):
        GripperDesign(loss_model="fe")


def test_the_levels_in_force_are_the_heat_models_and_the_designs_old_properties_warn():
    assert GripperHeatModel().integral_levels_in_force == "4/2"
    assert GripperHeatModel().sheet_refinement_in_force == 2
    assert CHAIN.sheet_refinement_in_force == 1
    with pytest.warns(EtorigamiDeprecationWarning, match="GripperHeatModel.integral_levels"):
        assert GripperDesign().integral_levels_in_force == "4/2"
    with pytest.warns(EtorigamiDeprecationWarning, match="GripperHeatModel.sheet_refinement"):
        assert GripperDesign().sheet_refinement_in_force == 2
    with pytest.raises(ParameterError, match="must be a GripperDesign"):
        GripperProblem(base=CHAIN)
