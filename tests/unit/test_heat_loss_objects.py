"""Heat loss as an object (issue 29 item 1): ChainLoss and IntegralLoss with only their own
options, the medium (a Fluid) and one Substrate, given to ThermalParameters; the old flat
spellings still read, and deprecated (each warns, naming the new spelling); FOLD model files
in the new form, old files still read (without a warning)."""

import dataclasses
import json
import logging
import math
import warnings

import numpy as np
import pytest

from simulator import (AIR, WATER, ChainLoss, EtorigamiDeprecationWarning, Heat, IntegralLoss,
                       ParameterError, Substrate, ThermalParameters, get_case, simulate)
from simulator.fold import read_model, write_model
from simulator.materials import Fluid
from simulator.thermal import boundary_panel_plane
from simulator.thermal import ThermalModel


def test_each_loss_has_only_its_own_options():
    chain = ChainLoss(thickness=1.5e-3)
    assert (chain.model, chain.layers, chain.dissipation_angle) == ("chain", 10,
                                                                    math.radians(20))
    integral = IntegralLoss()
    assert (integral.model, integral.refinement, integral.extrapolated) == ("integral", 3, True)
    assert not hasattr(integral, "thickness") and not hasattr(chain, "refinement")
    with pytest.raises(ParameterError, match=r"ChainLoss.thickness = 0.0 must be a finite "
                                             r"number > 0 \[m\]; the chains' medium thickness"):
        ChainLoss(thickness=0.0)
    with pytest.raises(ParameterError, match="ChainLoss.layers"):
        ChainLoss(thickness=1e-3, layers=0)
    with pytest.raises(ParameterError, match="IntegralLoss.refinement = 17"):
        IntegralLoss(refinement=17)


def test_thermal_parameters_from_the_objects_and_their_defaults():
    plane = Substrate.plane((0, 0, -1e-4), (0, 0, 2))
    p = ThermalParameters(loss=IntegralLoss(refinement=4), medium=WATER, substrate=plane)
    assert p.loss == IntegralLoss(refinement=4) and p.medium is WATER
    assert p.substrate.normal == (0.0, 0.0, 2.0)
    assert p.substrate.as_tuple() == (0, 0, -1e-4, 0, 0, 2)
    assert (p.loss.model, p.medium.thermal_conductivity) == ("integral", 0.6)
    bare = ThermalParameters()                 # calibration-free: nothing to give
    assert bare.loss == IntegralLoss() and bare.medium is AIR and bare.substrate == Substrate()
    assert len(dataclasses.fields(ThermalParameters)) == 11  # + sheet and crease conduction,
    #                       the sheet's layers, its refinement and the extrapolation in it
    assert bare.sheet_layers is None and bare.crease_conduction == "paper"
    assert bare.sheet_extrapolation is False
    with pytest.raises(ParameterError, match=r"the chain heat loss needs the medium thickness "
                                             r"t_env: give loss=ChainLoss\(thickness=\.\.\.\)"):
        bare.with_loss("chain")
    with pytest.raises(ParameterError, match="integral loss needs a medium conductivity > 0"):
        ThermalParameters(medium=Fluid("vacuum", 0.0, 0.0, 0.0))


def test_old_spellings_are_read_and_switch_the_loss():
    with pytest.deprecated_call():
        old = ThermalParameters(env_thickness=2e-3, layers=5, env_conductivity=0.6,
                                boundary_panels=[1], dissipation_angle=0.1)
        assert old.loss == ChainLoss(thickness=2e-3, layers=5, dissipation_angle=0.1)
        assert old.medium.name == "air with k changed" and old.env_conductivity == 0.6
        assert ThermalParameters(env_thickness=1e-3, **WATER.environment()).medium == WATER
        # the old switch, with the integral model's old fields, in one replace
        integral = dataclasses.replace(old, loss_model="integral", integral_refinement=4,
                                       substrate_plane=(0, 0, 0, 0, 0, 1))
        assert integral.loss == IntegralLoss(refinement=4)
        assert integral.substrate == Substrate.plane((0, 0, 0), (0, 0, 1))
        assert integral.boundary_panels == (1,) and integral.env_conductivity == 0.6
        assert dataclasses.replace(integral, substrate_plane=()).substrate is None
        back = dataclasses.replace(integral, loss_model="chain", env_thickness=2e-3)
        assert back.loss == ChainLoss(thickness=2e-3)      # the integral's options are its own
        assert ThermalParameters(2e-3, 0.6) == ThermalParameters(      # the old positions
            env_thickness=2e-3, env_conductivity=0.6)
    # errors name the field as it was given
    with pytest.raises(ParameterError, match=r"ThermalParameters.env_thickness = -1.0"), \
            pytest.deprecated_call():
        ThermalParameters(env_thickness=-1.0)
    with pytest.raises(ParameterError, match=r"ThermalParameters.integral_refinement = 0"), \
            pytest.deprecated_call():
        ThermalParameters(loss_model="integral", integral_refinement=0)
    with pytest.raises(ParameterError, match=r"ThermalParameters.env_density = -1.0"), \
            pytest.deprecated_call():
        ThermalParameters(env_density=-1.0)


#: Every old keyword with a value, and the same parameters in the new spelling (a fragment of
#: which the warning names).
OLD_KEYWORDS = [
    ("env_thickness", {"env_thickness": 2e-3}, {"loss": ChainLoss(thickness=2e-3)},
     "loss=ChainLoss(thickness=...)"),
    ("layers", {"env_thickness": 2e-3, "layers": 5}, {"loss": ChainLoss(2e-3, layers=5)},
     "loss=ChainLoss(layers=...)"),
    ("dissipation_angle", {"env_thickness": 2e-3, "dissipation_angle": 0.1},
     {"loss": ChainLoss(2e-3, dissipation_angle=0.1)}, "loss=ChainLoss(dissipation_angle=...)"),
    ("loss_model", {"loss_model": "integral"}, {"loss": IntegralLoss()},
     "loss=IntegralLoss()"),
    ("integral_refinement", {"integral_refinement": 4}, {"loss": IntegralLoss(refinement=4)},
     "loss=IntegralLoss(refinement=...)"),
    ("integral_extrapolation", {"integral_extrapolation": False},
     {"loss": IntegralLoss(extrapolation=False)}, "loss=IntegralLoss(extrapolation=...)"),
    ("integral_shape_tol", {"integral_shape_tol": 0.05}, {"loss": IntegralLoss(shape_tol=0.05)},
     "loss=IntegralLoss(shape_tol=...)"),
    ("integral_correction_tol", {"integral_correction_tol": 0.0},
     {"loss": IntegralLoss(correction_tol=0.0)}, "loss=IntegralLoss(correction_tol=...)"),
    ("env_conductivity", {"env_conductivity": 0.6},
     {"medium": AIR.with_properties(thermal_conductivity=0.6)},
     "medium=AIR.with_properties(thermal_conductivity=...)"),
    ("env_density", {"env_density": 2.0}, {"medium": AIR.with_properties(density=2.0)},
     "medium=AIR.with_properties(density=...)"),
    ("env_specific_heat", {"env_specific_heat": 800.0},
     {"medium": AIR.with_properties(specific_heat=800.0)},
     "medium=AIR.with_properties(specific_heat=...)"),
    ("substrate_plane", {"substrate_plane": (0, 0, 1, 0, 0, 2)},
     {"substrate": Substrate.plane((0, 0, 1), (0, 0, 2))}, "substrate=Substrate.plane("),
    ("substrate_plane", {"substrate_plane": ()}, {"substrate": None}, "substrate=None"),
]


@pytest.mark.parametrize("name, old, new, spelling", OLD_KEYWORDS,
                         ids=[f"{k[0]}={list(k[1].values())[-1]!r}" for k in OLD_KEYWORDS])
def test_every_old_keyword_warns_and_means_the_new_spelling(name, old, new, spelling):
    with pytest.warns(EtorigamiDeprecationWarning) as record:
        got = ThermalParameters(**old)
    assert got == ThermalParameters(**new)
    said = [str(w.message) for w in record if f"({name}=...)" in str(w.message)]
    assert len(said) == 1 and said[0].startswith(f"ThermalParameters({name}=...) is deprecated; "
                                                 "use ") and spelling in said[0], said
    assert {w.filename for w in record} == {__file__}           # the caller's line
    # the same through dataclasses.replace, also said at the caller's line
    with pytest.warns(EtorigamiDeprecationWarning) as record:
        assert dataclasses.replace(ThermalParameters(**new), **old) == got
    assert [w for w in record if f"({name}=...)" in str(w.message)]
    assert {w.filename for w in record} == {__file__}


CHAIN = ThermalParameters(loss=ChainLoss(thickness=2e-3, layers=5, dissipation_angle=0.1),
                          medium=WATER, substrate=Substrate.plane((0, 0, 1), (0, 0, 2)))
INTEGRAL = ThermalParameters(loss=IntegralLoss(refinement=4, extrapolation=False, shape_tol=0.05,
                                               correction_tol=0.2), substrate=None)
#: Every old property on parameters where it means something, and its new spelling.
OLD_PROPERTIES = [
    ("env_thickness", CHAIN, lambda p: p.loss.thickness, "loss.thickness"),
    ("layers", CHAIN, lambda p: p.loss.layers, "loss.layers"),
    ("dissipation_angle", CHAIN, lambda p: p.loss.dissipation_angle, "loss.dissipation_angle"),
    ("loss_model", CHAIN, lambda p: p.loss.model, "loss.model"),
    ("loss_model", INTEGRAL, lambda p: p.loss.model, "loss.model"),
    ("integral_refinement", INTEGRAL, lambda p: p.loss.refinement, "loss.refinement"),
    ("integral_extrapolation", INTEGRAL, lambda p: p.loss.extrapolation, "loss.extrapolation"),
    ("integral_shape_tol", INTEGRAL, lambda p: p.loss.shape_tol, "loss.shape_tol"),
    ("integral_correction_tol", INTEGRAL, lambda p: p.loss.correction_tol,
     "loss.correction_tol"),
    ("extrapolated", INTEGRAL, lambda p: p.loss.extrapolated, "loss.extrapolated"),
    ("env_conductivity", CHAIN, lambda p: p.medium.thermal_conductivity,
     "medium.thermal_conductivity"),
    ("env_density", CHAIN, lambda p: p.medium.density, "medium.density"),
    ("env_specific_heat", CHAIN, lambda p: p.medium.specific_heat, "medium.specific_heat"),
    ("substrate_plane", CHAIN, lambda p: p.substrate.as_tuple(), "substrate.as_tuple()"),
    ("plane", CHAIN, lambda p: (p.substrate.point, np.array(p.substrate.normal) / 2),
     "substrate.point and substrate.normal"),
]


@pytest.mark.parametrize("name, params, new, spelling", OLD_PROPERTIES,
                         ids=[f"{k[0]}-{k[1].loss.model}" for k in OLD_PROPERTIES])
def test_every_old_property_warns_and_reads_the_new_spelling(name, params, new, spelling):
    with pytest.warns(EtorigamiDeprecationWarning) as record:
        value = getattr(params, name)
    assert len(record) == 1 and record[0].filename == __file__
    assert str(record[0].message).startswith(f"ThermalParameters.{name} is deprecated; read "
                                             f"{spelling}")
    if name == "plane":
        np.testing.assert_array_equal(np.concatenate(value), np.concatenate(new(params)))
    else:
        assert value == new(params)


def test_old_properties_keep_their_old_answers_for_the_other_loss():
    with pytest.deprecated_call():
        assert (INTEGRAL.env_thickness, INTEGRAL.layers, INTEGRAL.dissipation_angle) == (
            None, 10, math.radians(20))
        assert (CHAIN.integral_refinement, CHAIN.extrapolated) == (3, True)
        assert INTEGRAL.substrate_plane == () and INTEGRAL.plane is None
        assert ThermalParameters().substrate_plane == () and ThermalParameters().plane is None


def test_the_new_spellings_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p = dataclasses.replace(CHAIN, room_temperature=20.0, boundary_panels=(1,))
        assert ThermalParameters(**p.to_dict()) == ThermalParameters.from_dict(p.to_dict()) == p
        assert p.with_loss(thickness=3e-3).loss == ChainLoss(3e-3, 5, 0.1)
        assert p.with_loss("integral", refinement=2).loss == IntegralLoss(refinement=2)
        assert p.describe().startswith("heat loss: chain model")
        assert AIR.with_properties(thermal_conductivity=0.026) is AIR


def test_with_loss_keeps_or_replaces_the_loss_and_names_what_is_wrong():
    assert INTEGRAL.with_loss(refinement=3).loss == dataclasses.replace(INTEGRAL.loss,
                                                                        refinement=3)
    assert INTEGRAL.with_loss("integral") == INTEGRAL
    assert INTEGRAL.with_loss("chain", thickness=1e-3).loss == ChainLoss(thickness=1e-3)
    assert CHAIN.with_loss("integral").loss == IntegralLoss()     # the new model's defaults
    with pytest.raises(ParameterError, match=r"refinement is not a field of ChainLoss; its "
                                             r"fields are thickness, layers"):
        CHAIN.with_loss(refinement=2)
    with pytest.raises(ParameterError, match="needs the medium thickness"):
        INTEGRAL.with_loss("chain")


def test_a_medium_with_other_properties_is_named_after_the_fluid_it_equals():
    assert AIR.with_properties() is AIR
    assert AIR.with_properties(density=998.0, specific_heat=4182.0,
                               thermal_conductivity=0.6) is WATER
    custom = AIR.with_properties(thermal_conductivity=0.6)
    assert (custom.name, custom.density, custom.thermal_conductivity) == ("air with k changed",
                                                                          1.293, 0.6)
    assert custom.with_properties(density=1.0).name == "air with rho, k changed"
    with pytest.raises(ParameterError, match="'viscosity' is not a property of a fluid"):
        AIR.with_properties(viscosity=1.0)
    with pytest.deprecated_call(match=r"Fluid.environment\(\) is deprecated"):
        assert WATER.environment()["env_conductivity"] == 0.6


def test_to_dict_is_json_and_reads_back():
    for p in (ThermalParameters(loss=ChainLoss(thickness=1e-3), room_temperature_nodes=(4,)),
              ThermalParameters(loss=IntegralLoss(extrapolation=False), substrate=None),
              ThermalParameters(substrate=Substrate.plane((1, 2, 3), (0, 1, 0)),
                                medium=WATER)):
        d = json.loads(json.dumps(p.to_dict()))
        assert ThermalParameters(**d) == ThermalParameters.from_dict(d) == p


def _folded(model):
    res = simulate(model, [Heat({2: 5e-3, 5: 5e-3}, increments=2)])
    assert res.success, res.message
    return model.mesh.nodes + res.state.u


def test_the_new_spelling_solves_what_the_old_one_did():
    """The integral loss through the new interface against the operator the old flat fields
    selected, on the double fold (boundary panel on the substrate): the same temperatures
    (1e-12 relative); the default substrate is the boundary panels' plane."""
    model = get_case("double_fold", thermal_steps=2).model
    x = _folded(model)
    q = ThermalModel(model.mesh, model.thermal).heat_vector(np.full(model.mesh.n_creases, 5e-3))
    with pytest.deprecated_call():
        old = dataclasses.replace(model.thermal, loss_model="integral",
                                  substrate_plane=boundary_panel_plane(model))
    new = dataclasses.replace(model.thermal, loss=IntegralLoss())          # Substrate()
    explicit = dataclasses.replace(new, substrate=Substrate.plane(
        boundary_panel_plane(model)[:3], boundary_panel_plane(model)[3:]))
    T = [ThermalModel(model.mesh, p).solve(x, q) - 21.0 for p in (old, new, explicit)]
    assert T[0].max() > 50.0
    np.testing.assert_allclose(T[1], T[0], rtol=1e-12, atol=1e-12 * T[0].max())
    np.testing.assert_allclose(T[2], T[0], rtol=1e-12, atol=1e-12 * T[0].max())
    # without the substrate the sheet runs hotter (no image plane below it)
    free = ThermalModel(model.mesh, dataclasses.replace(new, substrate=None),
                        warn_no_plane=False).solve(x, q) - 21.0
    assert free.max() > T[0].max()


def test_a_model_file_keeps_its_heat_loss_and_old_files_are_read(tmp_path, caplog):
    case = get_case("single_fold", thermal_steps=2)
    thermal = dataclasses.replace(case.model.thermal, loss=IntegralLoss(refinement=2),
                                  substrate=Substrate.plane((0, 0, -5e-5), (0, 0, 1)),
                                  medium=WATER)
    model = dataclasses.replace(case.model, thermal=thermal)
    path = write_model(model, case.steps, tmp_path / "m.fold")
    raw = json.loads(path.read_text())["etorigami:thermal"]
    assert raw["loss"] == {"model": "integral", "refinement": 2, "extrapolation": None,
                           "shape_tol": 0.02, "correction_tol": 0.1}
    assert raw["substrate"] == {"point": [0.0, 0.0, -5e-5], "normal": [0.0, 0.0, 1.0]}
    assert read_model(path)[0].thermal == thermal
    # a file of the old form
    data = json.loads(path.read_text())
    data["etorigami:thermal"] = {"env_thickness": 1.5e-3, "env_conductivity": 0.026,
                                 "room_temperature_nodes": []}
    old = tmp_path / "old.fold"
    old.write_text(json.dumps(data))
    with warnings.catch_warnings(), caplog.at_level(logging.INFO):
        warnings.simplefilter("error")                        # read without a warning
        read = read_model(old)[0].thermal
    assert read.loss == ChainLoss(thickness=1.5e-3) and read.medium == AIR
    assert [r for r in caplog.records if r.levelno == logging.INFO
            and "old flat form (env_thickness, env_conductivity)" in r.getMessage()]
    # its errors name the old field, as the file gives it
    data["etorigami:thermal"]["env_thickness"] = -1.0
    old.write_text(json.dumps(data))
    with pytest.raises(ParameterError, match=r"etorigami:thermal: "
                                             r"ThermalParameters.env_thickness = -1.0"):
        read_model(old)


def test_a_model_without_chain_parameters_runs_the_integral_model_and_the_fe():
    """ThermalParameters() (no t_env): the integral fixed-shape solve and the 3-D FE reference
    run on it; the chain model refuses, naming what it needs."""
    from simulator.fe import solve_fe3d
    from simulator.thermal import fixed_shape_temperatures

    case = get_case("single_fold")
    thermal = ThermalParameters(boundary_panels=case.model.thermal.boundary_panels,
                                room_temperature_nodes=case.model.thermal.room_temperature_nodes)
    model = dataclasses.replace(case.model, thermal=thermal)
    power = np.full(model.mesh.n_creases, 5e-3)
    fe = solve_fe3d(model, crease_power=power, level=0, accuracy=1.0)
    integral = fixed_shape_temperatures(model, "integral", power)
    assert fe.status == integral.status == "converged"
    # the coarsest FE level against the integral model: the same heating, within 10 %
    rise = lambda r: r.crease_t_ave - 21.0                   # noqa: E731
    assert rise(integral)[0] > 50 and abs(rise(fe)[0] / rise(integral)[0] - 1) < 0.1
    with pytest.raises(ParameterError, match=r"chain heat loss needs the medium thickness"):
        fixed_shape_temperatures(model, "chain", power)


def test_chains_are_calibrated_for_a_model_that_has_none():
    """calibrate_environment on a model with the integral loss only: the chains start from
    1.5 panel lengths and are fitted to the integral model."""
    from simulator.thermal import calibrate_environment

    case = get_case("double_fold", thermal_steps=2)
    thermal = ThermalParameters(boundary_panels=case.model.thermal.boundary_panels,
                                room_temperature_nodes=case.model.thermal.room_temperature_nodes)
    model = dataclasses.replace(case.model, thermal=thermal)
    fit = calibrate_environment(model, np.full(model.mesh.n_creases, 5e-3))
    assert fit.success and fit.env_thickness > 0 and np.isfinite(fit.rms_error)
    chained = calibrate_environment(case.model, np.full(model.mesh.n_creases, 5e-3))
    # as good as the fit from the model's own chains (t_env beyond the substrate's cap is
    # free there: 1.15 against 0.60 mm at beta -> 0, the same residual)
    assert fit.rms_error == pytest.approx(chained.rms_error, rel=1e-6)


def test_a_point_normal_pair_is_a_deprecated_spelling_of_substrate_plane():
    from simulator.thermal.substrate import resolve_substrate

    model = get_case("double_fold").model
    plane = Substrate.plane((0.0, 0.0, -1e-4), (0.0, 0.0, 1.0))
    assert resolve_substrate(plane, model.mesh, model.thermal) == plane.as_tuple()
    with pytest.deprecated_call(match=r"Substrate.plane\(point, normal\)"):
        old = resolve_substrate(((0, 0, -1e-4), (0, 0, 1)), model.mesh, model.thermal)
    assert old == plane.as_tuple()
    with pytest.raises(ParameterError, match="must be 'model', a Substrate"):
        resolve_substrate((0, 0, 0), model.mesh, model.thermal)
