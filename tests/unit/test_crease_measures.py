"""Each crease's temperature measures (:func:`simulator.thermal.crease_temperatures`, issue 29):
the one place that knows which crease nodes carry which measure; the results, the fixed-shape
and FE results, the limit and the studies read them from it."""

import numpy as np
import pytest

from simulator import ParameterError, get_case
from simulator.model import sharp_model
from simulator.thermal import (CREASE_MEASURES, crease_limit_temperatures, crease_temperatures,
                               fixed_shape_temperatures)

#: The seven crease nodes by name (``BarHingeMesh.crease_nodes``).
N11, N12, N21, N22, A, B, CTR = range(7)


@pytest.fixture(scope="module")
def double_fold():
    return get_case("double_fold").model


def test_each_measure_reads_the_documented_nodes(double_fold):
    mesh = double_fold.mesh
    rng = np.random.default_rng(2)
    T = 21.0 + 100 * rng.random(mesh.n_nodes)
    node = lambda k: T[mesh.crease_nodes[:, k]]                    # noqa: E731
    edges = (node(N11) + node(N12) + node(N21) + node(N22)) / 4
    line = (node(A) + node(B) + node(CTR)) / 3
    np.testing.assert_allclose(crease_temperatures(T, mesh), (edges + line) / 2, rtol=1e-14)
    np.testing.assert_allclose(crease_temperatures(T, mesh, "centre_line"), line, rtol=1e-14)
    np.testing.assert_array_equal(crease_temperatures(T, mesh, "centre"), node(CTR))
    np.testing.assert_array_equal(crease_temperatures(T, mesh, "crease_max"),
                                  np.max([node(k) for k in range(7)], axis=0))
    np.testing.assert_array_equal(crease_limit_temperatures(T, mesh), line)
    assert CREASE_MEASURES == ("actuation", "centre_line", "centre", "crease_max")


def test_linear_measures_map_columns_of_rises(double_fold):
    """Node values (n, k), node axis first (rises per heater watt): column by column."""
    mesh = double_fold.mesh
    T = np.linspace(0, 1, mesh.n_nodes)
    both = np.column_stack([T, 3 * T])
    for measure in ("actuation", "centre_line", "centre"):
        out = crease_temperatures(both, mesh, measure)
        assert out.shape == (mesh.n_creases, 2)
        np.testing.assert_allclose(out[:, 1], 3 * crease_temperatures(T, mesh, measure),
                                   rtol=1e-14)


def test_results_and_fixed_shape_temperatures_use_it(double_fold):
    res = get_case("double_fold", thermal_steps=3).run()
    mesh, T = res.model.mesh, res.history["temperature"]
    np.testing.assert_allclose(res.crease_temperature, crease_temperatures(T.T, mesh).T,
                               rtol=1e-14)
    np.testing.assert_array_equal(res.crease_temperature_centre_line,
                                  crease_temperatures(T.T, mesh, "centre_line").T)
    np.testing.assert_array_equal(res.crease_temperature_max,
                                  crease_temperatures(T.T, mesh, "crease_max").T)
    fixed = fixed_shape_temperatures(double_fold, "chain", np.full(mesh.n_creases, 5e-3))
    assert fixed.success and fixed.status == "converged"
    for field, measure in (("crease_temperature", "actuation"), ("crease_t_ctr", "centre"),
                           ("crease_t_ave", "centre_line"),
                           ("crease_temperature_max", "crease_max")):
        np.testing.assert_array_equal(getattr(fixed, field),
                                      crease_temperatures(fixed.temperature, mesh, measure))


def test_a_concentrated_hinge_is_the_mean_of_its_two_nodes():
    model = sharp_model(get_case("single_fold").model.mesh.pattern)
    mesh = model.mesh
    T = np.arange(mesh.n_nodes, dtype=float)
    pair = T[mesh.crease_nodes]
    assert pair.shape[1] == 2
    for measure in ("actuation", "centre_line", "centre"):
        np.testing.assert_array_equal(crease_temperatures(T, mesh, measure), pair.mean(axis=1))
    np.testing.assert_array_equal(crease_temperatures(T, mesh, "crease_max"), pair.max(axis=1))


def test_an_unknown_measure_is_refused_with_the_choices(double_fold):
    with pytest.raises(ParameterError, match="'centre_line' is the measure of the 1.2 T_g"):
        crease_temperatures(np.zeros(double_fold.mesh.n_nodes), double_fold.mesh, "mean")
