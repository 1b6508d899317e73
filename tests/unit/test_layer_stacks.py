"""Panels and creases as layer stacks (``crease_conduction="layers"`` with ``sheet_layers``,
theory 4.10) and their heat capacity (theory 7.2).

The acceptance check of issue 30 item 1: a uniformly heated strip with two layers, its ends at
room temperature and no loss to the medium, conducts as one layer of sheet conductance
``S = k1 t1 + k2 t2``: its temperature rise is the 1-D profile ``q x (L - x) / (2 S)`` within
0.5 %; in time, the insulated strip stores heat in ``sum(rho c t) A``.
"""

import dataclasses

import numpy as np
import pytest

from simulator import (AIR, Actuators, Bimorph, ChainLoss, IntegralLoss, ParameterError, Pattern,
                       ThermalParameters, make_mesh, make_model)
from simulator.materials import GOLD_FILM, SPR, SU8
from simulator.thermal import Layer, SheetLayers
from simulator.thermal import ThermalModel
from simulator.thermal.transient import (ThetaStepper, areal_capacity, capacity_vector,
                                         heat_system)

#: The paper's gripper crease: 0.2 um gold film (150 W/(m K)) on 0.8 um SU-8 (0.3 W/(m K)).
BIMORPH = Bimorph(E1=79e9, t1=0.2e-6, E2=2e9, t2=0.8e-6)
#: Its sheet conductance [W/K] and areal heat capacity [J/(m^2 K)], written out: gold 19300
#: kg/m^3 x 129 J/(kg K), SU-8 1200 kg/m^3 x 2e6/1200 J/(kg K) (the toolkit's SU8).
S = 150.0 * 0.2e-6 + 0.3 * 0.8e-6
RHO_C_T = 19300.0 * 129.0 * 0.2e-6 + 2e6 * 0.8e-6
#: Strip: n panels of pitch 100 um (20 um creases between them), 100 um wide.
PITCH, WIDTH = 100e-6, 100e-6


def _strip(n=40, passive=False, held=True, loss=None, refinement=None):
    """A strip of ``n`` panels joined by ``n - 1`` creases, all of the bimorph's two layers: the
    panels by ``SheetLayers.panels``, the creases actuated (their bimorph) or, ``passive``,
    listed in ``SheetLayers.creases`` (a heater film without actuation). ``held``: the nodes of
    both ends at room temperature. No loss (medium conductivity 0, chains) unless ``loss``."""
    v = [(i * PITCH, y, 0.0) for y in (0.0, WIDTH) for i in range(n + 1)]
    panels = [(i, i + 1, n + 2 + i, n + 1 + i) for i in range(n)]
    pattern = Pattern(np.array(v), panels, crease_width=20e-6, crease_thickness=1e-6,
                      panel_thickness=1e-6, panel_material=SU8, crease_material=SU8)
    mesh = make_mesh(pattern)
    x = mesh.nodes[:, 0]
    ends = np.flatnonzero((x < 1e-12) | (x > n * PITCH - 1e-12)) if held else []
    creases = [int(c) for c in pattern.creases]
    stacks = SheetLayers({p: BIMORPH.layers for p in range(n)},
                         {c: BIMORPH.layers for c in creases} if passive else {})
    medium = AIR if loss else AIR.with_properties(thermal_conductivity=0.0)
    thermal = ThermalParameters(
        loss=loss or ChainLoss(thickness=1.0, layers=1), medium=medium, room_temperature=0.0,
        room_temperature_nodes=tuple(int(i) for i in ends), crease_conduction="layers",
        sheet_layers=stacks, sheet_refinement=refinement)
    actuators = Actuators(BIMORPH, {} if passive else {c: 38e-6 for c in creases})
    return make_model(mesh, thermal=thermal, actuators=actuators)


def _thermal_model(model):
    return ThermalModel(model.mesh, model.thermal, actuators=model.actuators)


def _uniform_heat(tm, flux):
    """Nodal heat [W] of a uniform areal heat ``flux`` [W/m^2] (each triangle a third of its
    heat to each vertex: the exact load of a uniform source on linear triangles)."""
    x = tm.mesh.nodes
    area = tm.triangle_areas(x)
    return np.bincount(tm.mesh.triangles.ravel(), np.repeat(flux * area / 3, 3),
                       minlength=len(x))


def test_layer_sums_of_a_gold_film_on_su8():
    gold, su8 = BIMORPH.layers
    assert gold.sheet_conductance == pytest.approx(150.0 * 0.2e-6)
    assert su8.areal_capacity == pytest.approx(2e6 * 0.8e-6)
    assert BIMORPH.sheet_conductance == pytest.approx(S)
    assert BIMORPH.areal_capacity == pytest.approx(RHO_C_T)
    film = Layer.of(GOLD_FILM, 0.1e-6)
    assert (film.conductivity, film.heat_capacity) == (150.0, pytest.approx(19300 * 129))


@pytest.mark.parametrize("passive", [False, True], ids=["actuated", "heater_film"])
def test_uniformly_heated_two_layer_strip_matches_the_1d_profile_of_sum_k_t(passive):
    """Issue 30's acceptance: within 0.5 % of ``q x (L - x) / (2 S)`` (measured: 1.3e-4 of
    the peak on 40 panels; the P1 error falls as h^2: 8.5e-3 on 5, 2.1e-3 on 10)."""
    model = _strip(passive=passive)
    tm = _thermal_model(model)
    x = model.mesh.nodes
    flux, L = 1e3, 40 * PITCH
    rise = tm.solve(x, _uniform_heat(tm, flux))
    exact = flux / (2 * S) * x[:, 0] * (L - x[:, 0])
    assert np.abs(rise - exact).max() < 0.005 * exact.max()
    assert exact.max() == pytest.approx(66.14, rel=1e-3)       # 1 kW/m^2 over 4 mm at 30 uW/K
    # the same strip with the paper's single SU-8 layer runs about 100 times hotter
    paper = dataclasses.replace(model.thermal, crease_conduction="paper", sheet_layers=None)
    hot = ThermalModel(model.mesh, paper).solve(x, _uniform_heat(tm, flux))
    assert hot.max() > 90 * rise.max()


def test_strip_steady_energy_balance():
    model = _strip()
    tm = _thermal_model(model)
    x = model.mesh.nodes
    q = _uniform_heat(tm, 1e3)
    rise = tm.solve(x, q)
    n = model.mesh.n_nodes
    flow = tm.conductivity_matrix(x).toarray()[:n, :n] @ rise     # heat out of each node [W]
    held = list(model.thermal.room_temperature_nodes)
    free = np.setdiff1d(np.arange(n), held)
    np.testing.assert_allclose(flow[free], q[free], rtol=1e-9, atol=1e-12 * q.max())
    # what the sheet takes from the held ends is what the heater puts in
    assert -flow[held].sum() == pytest.approx(q[free].sum(), rel=1e-9)
    assert q.sum() == pytest.approx(1e3 * 40 * PITCH * WIDTH, rel=1e-12)


@pytest.mark.parametrize("passive", [False, True], ids=["actuated", "heater_film"])
def test_uniformly_heated_strip_heats_at_power_over_sum_rho_c_t_area(passive):
    """dT/dt = P / C with C = sum(rho c t) A (2.098 J/(m^2 K) against the paper's SU-8 2.0):
    the first backward-Euler step of 1 us, over which heat diffuses about 4 um, raises every
    node two pitches from the held ends by P dt / C."""
    n = 10
    model = _strip(n=n, passive=passive)
    tm = _thermal_model(model)
    x = model.mesh.nodes
    area = n * PITCH * WIDTH
    np.testing.assert_allclose(areal_capacity(tm), RHO_C_T, rtol=1e-12)
    assert capacity_vector(tm, x).sum() == pytest.approx(RHO_C_T * area, rel=1e-12)
    hs = heat_system(tm, x)
    P, dt = 1e-3, 1e-6
    q = _uniform_heat(tm, P / area)[hs.free]
    rise = ThetaStepper(hs.K, hs.C, dt).step(np.zeros(len(hs.free)), q, q)
    inner = np.abs(x[hs.free, 0] - n * PITCH / 2) <= (n / 2 - 2) * PITCH
    assert inner.sum() > 20
    np.testing.assert_allclose(rise[inner], P * dt / (RHO_C_T * area), rtol=1e-9)


def test_transient_settles_on_the_steady_layered_profile():
    model = _strip(n=10)
    tm = _thermal_model(model)
    x = model.mesh.nodes
    q = _uniform_heat(tm, 1e3)
    hs = heat_system(tm, x)
    late = ThetaStepper(hs.K, hs.C, 1e6).step(np.zeros(len(hs.free)), q[hs.free], q[hs.free])
    np.testing.assert_allclose(late, tm.solve(x, q)[hs.free], rtol=1e-6)


def test_integral_loss_refined_sheet_keeps_the_stacks_and_their_capacity():
    model = _strip(n=4, held=False, loss=IntegralLoss(refinement=1), refinement=2)
    tm = _thermal_model(model)
    fine = tm.fine_model
    assert fine is not None and fine.conduction.layered.all() and tm.conduction.layered.all()
    np.testing.assert_allclose(fine.conduction.kt, S, rtol=1e-12)
    hs = heat_system(tm, model.mesh.nodes)
    assert hs.C.sum() == pytest.approx(RHO_C_T * 4 * PITCH * WIDTH, rel=1e-12)


def test_a_metal_film_on_some_panels_only():
    """Panels not listed keep their material's k t and rho c t; the listed ones their stack's."""
    model = _strip(n=3)
    film = SheetLayers({1: (Layer.of(GOLD_FILM, 0.1e-6), Layer.of(SPR, 1e-6))})
    thermal = dataclasses.replace(model.thermal, sheet_layers=film)
    tm = ThermalModel(model.mesh, thermal, actuators=model.actuators)
    panel = model.mesh.triangle_panel
    crease = model.mesh.triangle_crease
    np.testing.assert_allclose(tm.conduction.kt[panel == 1], 150 * 0.1e-6 + 0.3 * 1e-6, rtol=1e-12)
    np.testing.assert_allclose(tm.conduction.kt[panel == 0], 0.3 * 1e-6, rtol=1e-12)
    np.testing.assert_allclose(tm.conduction.kt[crease >= 0], S, rtol=1e-12)
    cap = areal_capacity(tm)
    np.testing.assert_allclose(cap[panel == 1], 19300 * 129 * 0.1e-6 + 2e6 * 1e-6, rtol=1e-12)
    np.testing.assert_allclose(cap[panel == 0], 2e6 * 1e-6, rtol=1e-12)


def test_sheet_layers_alone_need_no_actuators_and_round_trip():
    model = _strip(n=3, passive=True)
    tm = ThermalModel(model.mesh, model.thermal)                 # no actuators at all
    assert tm.conduction.layered.all()
    p = model.thermal
    assert ThermalParameters.from_dict(p.to_dict()) == p
    assert "sheet_layers" not in ThermalParameters().to_dict()
    assert "3 panel(s) and 2 passive crease(s)" in p.describe()


@pytest.mark.parametrize("make, match", [
    (lambda: ThermalParameters(sheet_layers=SheetLayers({0: (Layer(1e-6, 0.3),)})),
     r"sheet_layers: 1 panel and 0 crease stack\(s\) given with crease_conduction = 'paper', "
     r"which ignores them; give crease_conduction='layers'"),
    (lambda: Layer(0.0, 150.0), r"Layer\.thickness = 0\.0 must be a finite number > 0 \[m\]"),
    (lambda: Layer(1e-7, -1.0, name="gold"), r"Layer 'gold'\.conductivity = -1\.0 .*>= 0"),
    (lambda: SheetLayers({0: Layer(1e-6, 0.3)}),
     r"SheetLayers\.panels\[0\] = .* must be a non-empty sequence of Layer"),
    (lambda: SheetLayers(creases={2: ("gold",)}), r"SheetLayers\.creases\[2\] holds 'gold'"),
    (lambda: Bimorph(E1=79e9, t1=0.2e-6, E2=2e9, t2=0.8e-6, rho_c1=-1.0),
     r"Bimorph\.rho_c1 = -1\.0 .*J/\(m\^3 K\).*2\.49e6 for gold"),
])
def test_bad_layer_input_names_field_value_and_fix(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


def test_stacks_of_unknown_or_actuated_creases_and_unknown_panels_are_refused():
    model = _strip(n=3)
    crease = int(model.mesh.pattern.creases[0])
    for stacks, match in (
            (SheetLayers(creases={crease: BIMORPH.layers}),
             rf"SheetLayers\.creases lists the actuated crease\(s\) \[{crease}\]"),
            (SheetLayers({7: BIMORPH.layers}), r"SheetLayers\.panels: panel 7 does not exist"),
            (SheetLayers(creases={0: BIMORPH.layers}),
             r"SheetLayers\.creases: 0 is not a crease of the mesh")):
        thermal = dataclasses.replace(model.thermal, sheet_layers=stacks)
        with pytest.raises(ParameterError, match=match):
            ThermalModel(model.mesh, thermal, actuators=model.actuators)


def test_fold_model_file_keeps_the_sheet_layers(tmp_path):
    from simulator.fold import read_model, write_model

    model = _strip(n=3, passive=True)
    back, _ = read_model(write_model(model, (), tmp_path / "strip.fold"))
    assert back.thermal.sheet_layers == model.thermal.sheet_layers
    assert back.to_dict() == model.to_dict()


def test_integral_loss_on_the_refined_sheet_conducts_as_one_layer_of_sum_k_t():
    """The default integral path (monotone conduction on the refined sheet, r = 2): the
    layered strip gives the temperatures of the same strip of one material with k t = S."""
    model = _strip(n=6, loss=IntegralLoss(refinement=1), refinement=2)
    tm = _thermal_model(model)
    one = dataclasses.replace(SU8, thermal_conductivity=S / 1e-6)
    pattern = dataclasses.replace(model.mesh.pattern, panel_material=one, crease_material=one)
    paper = dataclasses.replace(model.thermal, crease_conduction="paper", sheet_layers=None)
    single = ThermalModel(dataclasses.replace(model.mesh, pattern=pattern), paper)
    x = model.mesh.nodes
    q = tm.heat_vector(np.full(model.mesh.n_creases, 1e-3))
    layered = tm.solve(x, q)
    assert layered.max() > 1.0
    np.testing.assert_allclose(layered, single.solve(x, q), rtol=1e-10)
