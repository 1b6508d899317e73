"""make_model: argument type checks; materials: T_g; the one gravity constant."""

import pytest

from simulator import (Actuators, Bimorph, ChainLoss, ContactParameters, Material, ParameterError,
                       Supports, ThermalParameters, make_mesh, make_model)
from simulator.materials import SPR, SU8
from simulator.model import REFERENCE_GRAVITY
from simulator.geometry.example_patterns import single_fold_pattern


@pytest.fixture(scope="module")
def pattern():
    return single_fold_pattern(substrate=False)


@pytest.mark.parametrize("kwargs, match", [
    (dict(supports=[0, 1, 2]), r"supports is a list .* Supports or Mapping or None; pass Supports"),
    (dict(params={"diagonal_rate": 4}), r"params is a dict .* BarHingeParameters or None"),
    (dict(contact="on"), r"contact is a str .* ContactParameters or bool or None; pass .*True"),
    (dict(thermal=0.026), r"thermal is a float .* ThermalParameters or None"),
    (dict(actuators={2: 38e-6}), r"actuators is a dict .* Actuators or None; pass Actuators\("),
])
def test_make_model_rejects_wrong_argument_types(pattern, kwargs, match):
    with pytest.raises(ParameterError, match=match):
        make_model(pattern, **kwargs)


def test_make_model_rejects_a_non_pattern():
    with pytest.raises(ParameterError, match=r"pattern_or_mesh is a str .* Pattern or BarHing"):
        make_model("single_fold")


def test_make_model_accepts_every_documented_form(pattern):
    mesh = make_mesh(pattern)
    act = Actuators(Bimorph(E1=39.5e9, t1=0.1e-6, E2=2e9, t2=0.4e-6),
                    {int(mesh.crease_ids[0]): 38e-6})
    m = make_model(mesh, {0: "xyz"}, contact=True,
                   thermal=ThermalParameters(loss=ChainLoss(thickness=1e-3)), actuators=act)
    assert isinstance(m.supports, Supports) and m.supports.fixed == {0: "xyz"}
    assert isinstance(m.contact, ContactParameters)
    assert make_model(pattern, Supports(), contact=False).contact is None


def test_glass_transition_is_a_material_property():
    assert SU8.glass_transition == 210.0
    assert SPR.glass_transition is None
    assert Material("x", 1e9).glass_transition is None
    with pytest.raises(ParameterError, match="glass_transition = 'hot'.*finite number"):
        Material("x", 1e9, glass_transition="hot")


def test_design_problems_read_t_g_from_the_material():
    from design.devices.miura import MiuraProblem
    from design import GripperProblem
    assert GripperProblem().temperature_limit == pytest.approx(1.2 * SU8.glass_transition) == 252.0
    assert MiuraProblem().temperature_limit == 252.0
    assert GripperProblem(glass_transition=180.0).temperature_limit == pytest.approx(216.0)


def test_reference_gravity_is_the_reference_scripts_value():
    assert REFERENCE_GRAVITY == 9.8
