"""Bar areas and spring stiffnesses against the reference's single-fold values (theory 3.4)."""

import numpy as np
import pytest

from simulator.errors import ParameterError
from simulator.model.mesh import make_mesh
from simulator.geometry.example_patterns import single_fold_pattern
from simulator.model import BarHingeParameters, spring_rest_angles
from simulator.model.properties import mechanical_properties

RTOL = 1e-9  # the reference values are printed to 10 significant digits


@pytest.fixture(scope="module")
def mesh_props():
    mesh = make_mesh(single_fold_pattern())
    return mesh, mechanical_properties(mesh, BarHingeParameters(diagonal_rate=1000))


def test_bar_areas(mesh_props):
    mesh, pr = mesh_props
    a = pr.bar_area
    np.testing.assert_allclose(a[0:4], 1.04604721e-07, rtol=RTOL)
    np.testing.assert_allclose(a[4:8], 4.393398282e-09, rtol=RTOL)
    np.testing.assert_allclose(a[8:12], 2.531617926e-07, rtol=RTOL)
    np.testing.assert_allclose(a[mesh.crease_bars[0, [0, 3, 6, 9]]], 1.373626374e-10, rtol=RTOL)
    np.testing.assert_allclose(a[mesh.crease_bars[0, [1, 2, 4, 5, 7, 8]]], 1.501632494e-10,
                               rtol=RTOL)
    np.testing.assert_allclose(a[22:], np.repeat(a[[0, 4, 8]], 4), rtol=1e-14)


def test_spring_stiffnesses(mesh_props):
    mesh, pr = mesh_props
    k = pr.spring_stiffness[mesh.crease_springs[0]]
    np.testing.assert_allclose(k[:2], 1.5625e-10, rtol=1e-12)
    np.testing.assert_allclose(k[4:6], 7.8125e-11, rtol=1e-12)
    np.testing.assert_allclose(k[[2, 3, 6, 7]], 8.414320011e-08, rtol=RTOL)
    spokes = pr.spring_stiffness[8:]
    np.testing.assert_allclose(spokes[:4], 0.03682847819, rtol=RTOL)
    np.testing.assert_allclose(spokes[4:8], 2.728548292e-06, rtol=RTOL)
    np.testing.assert_allclose(spokes[8:], [0.09115513345, 0.09299646529, 0.08586842236,
                                            0.08758869822], rtol=RTOL)


def test_series_fold_stiffness_is_plate_value(mesh_props):
    """Three fold lines in series give E t^3 L / (12 W)."""
    mesh, pr = mesh_props
    k = pr.spring_stiffness[mesh.crease_springs[0]]
    k_centre = k[4] + k[5]
    series = 1 / (1 / k[0] + 1 / k[1] + 1 / k_centre)
    E, t, L, W = 2e9, 0.5e-6, 0.5e-3, 200e-6
    assert series == pytest.approx(E * t**3 * L / (12 * W), rel=1e-12)


def test_moduli(mesh_props):
    mesh, pr = mesh_props
    assert np.all(pr.bar_modulus == 2e9)


def test_rest_angle_split(mesh_props):
    mesh, _ = mesh_props
    rest = spring_rest_angles(mesh, np.array([np.pi + 0.4]))
    cs = mesh.crease_springs[0]
    np.testing.assert_allclose(rest[cs[:2]], np.pi + 0.1)
    np.testing.assert_allclose(rest[cs[4:6]], np.pi + 0.2)
    np.testing.assert_allclose(rest[cs[[2, 3, 6, 7]]], np.pi)
    lines = rest[cs[0]] + rest[cs[1]] + rest[cs[4]] - 3 * np.pi
    assert lines == pytest.approx(0.4)


@pytest.mark.parametrize("kwargs, match", [
    ({"diagonal_rate": 0}, "diagonal_rate"),
    ({"panel_bending_width": -1.0}, "panel_bending_width"),
    ({"centre_line_share": 1.5}, "centre_line_share"),
])
def test_parameter_errors(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        BarHingeParameters(**kwargs)
