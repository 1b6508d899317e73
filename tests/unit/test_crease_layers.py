"""A crease's in-plane conduction from its bimorph layers (``crease_conduction="layers"``,
theory 4.10): the paper's setting unchanged, the layered conductance ``k1 t1 + k2 t2`` on the
assembled matrix, the physical trend on the single fold, and the error paths."""

import dataclasses

import numpy as np
import pytest

from simulator import ParameterError
from simulator.cases import single_fold, verification_strip
from simulator.geometry.materials import GOLD_FILM_CONDUCTIVITY
from simulator.model.bimorph import Actuators, Bimorph
from simulator.thermal.fixed_shape import fixed_shape_temperatures
from simulator.thermal import ThermalParameters
from simulator.thermal import ThermalModel

#: The paper's gripper crease: 0.2 um gold on 0.8 um SU-8.
GOLD_ON_SU8 = Bimorph(E1=79e9, t1=0.2e-6, E2=2e9, t2=0.8e-6)


def _with(model, mode, actuators="model"):
    """``model`` with ``crease_conduction=mode`` (and other actuators if given)."""
    model = dataclasses.replace(model, thermal=dataclasses.replace(
        model.thermal, crease_conduction=mode))
    return model if actuators == "model" else dataclasses.replace(model, actuators=actuators)


def _strip(bimorph=GOLD_ON_SU8):
    """The conduction-only verification strip (crease 2 actuated by ``bimorph``)."""
    model = verification_strip("within").model
    return dataclasses.replace(model, actuators=Actuators(bimorph, {2: 38e-6}))


def _matrix(model):
    tm = ThermalModel(model.mesh, model.thermal, actuators=model.actuators)
    return tm.conductivity_matrix(model.mesh.nodes).toarray()


def test_bimorph_layer_conductivities_default_to_a_gold_film_on_su8():
    assert GOLD_ON_SU8.k1 == GOLD_FILM_CONDUCTIVITY == 150.0
    assert GOLD_ON_SU8.k2 == 0.3
    assert GOLD_ON_SU8.sheet_conductance == pytest.approx(150 * 0.2e-6 + 0.3 * 0.8e-6)


def test_paper_is_the_default_and_ignores_the_actuators():
    case = single_fold()
    model = case.model
    assert model.thermal.crease_conduction == "paper"
    x = model.mesh.nodes
    q = ThermalModel(model.mesh, model.thermal).heat_vector(np.array([0.1]))
    without = ThermalModel(model.mesh, model.thermal).solve(x, q)
    with_act = ThermalModel(model.mesh, model.thermal, actuators=model.actuators).solve(x, q)
    np.testing.assert_array_equal(with_act, without)


def test_layers_without_actuated_creases_is_the_paper_setting():
    model = _strip()
    passive = dataclasses.replace(model.actuators, delta_alpha={})
    np.testing.assert_array_equal(_matrix(_with(model, "layers", passive)),
                                  _matrix(_with(model, "paper")))


def test_layered_crease_conducts_with_sum_of_k_t_times_the_geometric_factor():
    model = _strip()
    k, tc = model.mesh.pattern.crease_material.thermal_conductivity, 0.001
    assert model.mesh.pattern.crease_thickness[2] == tc
    # the matrix is affine in the crease's k t: K = K_panels + (k t) G, G the crease
    # triangles' geometric factor; a reference bimorph (s0 = 1e-6 W/K) removes K_panels
    base = dataclasses.replace(GOLD_ON_SU8, k1=1.0, k2=1.0)
    s0 = base.sheet_conductance
    ref = _matrix(_with(model, "layers", dataclasses.replace(model.actuators, bimorph=base)))
    crease_paper = _matrix(_with(model, "paper")) - ref          # (k tc - s0) G
    crease_layers = _matrix(_with(model, "layers")) - ref        # (s - s0) G
    assert np.abs(crease_paper).max() > 0
    ratio = (GOLD_ON_SU8.sheet_conductance - s0) / (k * tc - s0)
    np.testing.assert_allclose(crease_layers, ratio * crease_paper, rtol=1e-9,
                               atol=1e-9 * np.abs(crease_layers).max())


def test_layered_strip_conducts_as_one_layer_of_the_summed_conductance():
    """Two layers (k1 t1 + k2 t2) give the temperatures of one layer with k t equal to it."""
    model = _strip(Bimorph(E1=1e9, t1=4e-4, E2=1e9, t2=6e-4, k1=2.0, k2=0.5))
    layered = _with(model, "layers")
    tm = ThermalModel(layered.mesh, layered.thermal, actuators=layered.actuators)
    one = dataclasses.replace(layered.mesh.pattern.crease_material,
                              thermal_conductivity=(2.0 * 4e-4 + 0.5 * 6e-4) / 1e-3)
    pattern = dataclasses.replace(layered.mesh.pattern, crease_material=one)
    single = ThermalModel(dataclasses.replace(layered.mesh, pattern=pattern), model.thermal)
    x = model.mesh.nodes
    q = tm.heat_vector(np.array([1e-3]))
    np.testing.assert_allclose(tm.solve(x, q), single.solve(x, q), rtol=1e-12)


def test_layers_lower_the_single_fold_crease_and_spread_heat_to_the_panel():
    model = single_fold().model            # chains, 100 mW (the reference's power)
    out = {mode: fixed_shape_temperatures(_with(model, mode), "chain",
                                          crease_power=np.array([0.1]))
           for mode in ("paper", "layers")}
    rt = model.thermal.room_temperature
    paper, layers = (out[m] for m in ("paper", "layers"))
    assert layers.crease_temperature_max[0] - rt < 0.95 * (paper.crease_temperature_max[0] - rt)
    assert layers.crease_temperature[0] < paper.crease_temperature[0]
    folding = np.unique(model.mesh.triangles[model.mesh.triangle_panel == 1])
    assert layers.temperature[folding].max() > paper.temperature[folding].max()


def test_crease_conduction_round_trips_and_old_dicts_read_as_paper():
    p = ThermalParameters(crease_conduction="layers")
    assert p.to_dict()["crease_conduction"] == "layers"
    assert ThermalParameters.from_dict(p.to_dict()) == p
    old = {k: v for k, v in ThermalParameters().to_dict().items() if k != "crease_conduction"}
    assert ThermalParameters.from_dict(old).crease_conduction == "paper"
    assert "bimorph layers" in p.describe()
    assert "bimorph" not in ThermalParameters().describe()


def test_fold_model_file_keeps_the_crease_conduction_and_layer_conductivities(tmp_path):
    from simulator.fold import read_model, write_model

    case = single_fold(thermal_steps=2)
    model = _with(case.model, "layers", dataclasses.replace(
        case.model.actuators, bimorph=dataclasses.replace(case.model.actuators.bimorph,
                                                          k1=120.0)))
    back, _ = read_model(write_model(model, case.steps, tmp_path / "m.fold"))
    assert back.thermal.crease_conduction == "layers"
    assert back.actuators.bimorph.k1 == 120.0
    assert back.to_dict() == model.to_dict()


@pytest.mark.parametrize("make, match", [
    (lambda: Bimorph(E1=79e9, t1=0.2e-6, E2=2e9, t2=0.8e-6, k1=-1.0),
     r"Bimorph\.k1 = -1\.0 .*>= 0 \[W/\(m K\)\]; give the layer's in-plane thermal "
     r"conductivity, e\.g\. 150"),
    (lambda: Bimorph(E1=79e9, t1=0.2e-6, E2=2e9, t2=0.8e-6, k2=float("nan")),
     r"Bimorph\.k2 = nan .*0\.3 for SU-8"),
    (lambda: ThermalParameters(crease_conduction="layer"),
     r"ThermalParameters\.crease_conduction = 'layer' must be one of 'paper', 'layers'"),
    (lambda: ThermalParameters.from_dict({"crease_conduction": 1}),
     r"ThermalParameters\.crease_conduction = 1 .*'paper' for the reference"),
])
def test_bad_layer_input_names_field_value_and_fix(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


def test_layers_without_actuators_says_what_to_give():
    model = verification_strip("within").model
    prm = dataclasses.replace(model.thermal, crease_conduction="layers")
    with pytest.raises(ParameterError, match=r"crease_conduction = 'layers' needs the model's "
                                             r"actuators .*got actuators = None; give "
                                             r"make_model\(\.\.\., actuators=.*or "
                                             r"crease_conduction='paper'"):
        ThermalModel(model.mesh, prm)
