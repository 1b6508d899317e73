"""Timoshenko bimorph curvature."""

import numpy as np
import pytest

from simulator.model.bimorph import Actuators, Bimorph, crease_temperature_weights, timoshenko_curvature
from simulator.errors import ParameterError
from simulator.model.mesh import make_mesh
from simulator.geometry.example_patterns import single_fold_pattern


def test_single_fold_curvature_value():
    """Ex01 layers: kappa/dT = 113.79 1/(m K), d_theta/dT = 0.022759 rad/K for W = 200 um."""
    b = Bimorph(E1=39.5e9, t1=0.1e-6, E2=2e9, t2=0.4e-6)
    k = b.curvature(38e-6, 1.0)
    assert 113.79 <= k < 113.80                   # printed truncated: 113.79 (theory 5.2)
    assert k * 200e-6 == pytest.approx(0.022759, abs=5e-7)
    act = Actuators(b, {2: 38e-6})
    assert act.rotation_per_kelvin(make_mesh(single_fold_pattern()))[0] == pytest.approx(k * 200e-6)


def test_symmetric_layers_closed_form():
    """m = n = 1: kappa = 3 delta_alpha dT / (2 h)."""
    h = 2e-6
    k = timoshenko_curvature(20e-6, 50.0, 1e9, h / 2, 1e9, h / 2)
    assert k == pytest.approx(3 * 20e-6 * 50.0 / (2 * h), rel=1e-14)


def test_general_closed_form_and_layer_swap_invariance():
    rng = np.random.default_rng(3)
    E1, E2 = rng.uniform(1e9, 1e11, 20), rng.uniform(1e9, 1e11, 20)
    t1, t2 = rng.uniform(0.1e-6, 2e-6, 20), rng.uniform(0.1e-6, 2e-6, 20)
    k = timoshenko_curvature(1e-5, 10.0, E1, t1, E2, t2)
    # Timoshenko (1925) in the paper's notation m = t2/t1, n = E2/E1
    m, n, h = t2 / t1, E2 / E1, t1 + t2
    ref = 6 * 1e-5 * 10.0 * (1 + m) ** 2 / (h * (3 * (1 + m) ** 2 + (1 + m * n) * (m**2 + 1 / (m * n))))
    np.testing.assert_allclose(k, ref, rtol=1e-13)
    np.testing.assert_allclose(timoshenko_curvature(1e-5, 10.0, E2, t2, E1, t1), k, rtol=1e-13)


def test_linear_in_temperature_and_mismatch_sign():
    b = Bimorph(50e9, 0.2e-6, 2e9, 0.8e-6)
    assert b.curvature(-38e-6, 10.0) == pytest.approx(-b.curvature(38e-6, 10.0))
    assert b.curvature(38e-6, 20.0) == pytest.approx(2 * b.curvature(38e-6, 10.0))


def test_weights_sum_to_one():
    w = crease_temperature_weights()
    assert w.sum() == pytest.approx(1.0)
    assert w[4:].sum() == pytest.approx(0.5)


@pytest.mark.parametrize("make, match", [
    (lambda: Bimorph(-1, 1e-7, 2e9, 4e-7), "E1"),
    (lambda: Bimorph(1e9, 0.0, 2e9, 4e-7), "t1"),
    (lambda: Actuators(Bimorph(1e9, 1e-7, 2e9, 4e-7), {2: float("nan")}), "crease 2"),
    (lambda: Actuators(Bimorph(1e9, 1e-7, 2e9, 4e-7), {2: 1e-5}, scatter=0.5), "scatter = 0.5"),
    (lambda: Actuators(Bimorph(1e9, 1e-7, 2e9, 4e-7), {2: 1e-5}, scatter=-1e-4), "scatter"),
    (lambda: Actuators(Bimorph(1e9, 1e-7, 2e9, 4e-7), {2: 1e-5}, scatter=1e-4, seed=-1),
     "seed = -1"),
])
def test_bad_input(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


def test_unknown_actuated_crease():
    act = Actuators(Bimorph(1e9, 1e-7, 2e9, 4e-7), {7: 1e-5})
    with pytest.raises(ValueError, match="boundary edge"):
        act.delta_alpha_array(make_mesh(single_fold_pattern()))


def test_actuation_scatter_is_seeded_per_crease_and_zero_by_default():
    """Actuators.scatter (theory 6.12): each crease's rotation per kelvin times 1 + scatter z,
    one standard normal draw per crease id from the seed; none by default."""
    mesh = make_mesh(single_fold_pattern())
    bim = Bimorph(1e9, 1e-7, 2e9, 4e-7)
    base = Actuators(bim, {2: 1e-5}).rotation_per_kelvin(mesh)
    a = Actuators(bim, {2: 1e-5}, scatter=1e-3, seed=3)
    z = np.random.default_rng(3).standard_normal(mesh.crease_ids.max() + 1)[mesh.crease_ids]
    np.testing.assert_allclose(a.rotation_per_kelvin(mesh), base * (1 + 1e-3 * z), rtol=1e-15)
    assert np.all(a.rotation_per_kelvin(mesh) != base)
    other = Actuators(bim, {2: 1e-5}, scatter=1e-3, seed=4).rotation_per_kelvin(mesh)
    assert np.all(other != a.rotation_per_kelvin(mesh))
    assert a.to_dict()["scatter"] == 1e-3 and a.to_dict()["seed"] == 3
    assert "scatter" not in Actuators(bim, {2: 1e-5}).to_dict()
