"""simulator.geometry.polygons: the one polygon helper (rings, centroids, fans, vector areas, normals)."""

import numpy as np
import pytest

from simulator.geometry.polygons import (area_vectors, centroids, fan_normals, rings, triangle_areas,
                                unit_normals)

# unit square (counter-clockwise), right triangle (clockwise), L-shape of area 3 (ccw)
SQUARE = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
TRIANGLE = [[0, 0, 0], [0, 2, 0], [3, 0, 0]]
L_SHAPE = [[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]]
SIZES = np.array([4, 3, 6])
CORNERS = np.array(SQUARE + TRIANGLE + L_SHAPE, float)


def _shoelace(xy):
    x, y = np.asarray(xy, float)[:, 0], np.asarray(xy, float)[:, 1]
    return 0.5 * (x @ np.roll(y, -1) - y @ np.roll(x, -1))


def test_rings_address_corners_cyclically():
    r = rings(SIZES)
    np.testing.assert_array_equal(r.first, [0, 4, 7])
    np.testing.assert_array_equal(r.owner, [0] * 4 + [1] * 3 + [2] * 6)
    np.testing.assert_array_equal(r.local, [0, 1, 2, 3, 0, 1, 2, 0, 1, 2, 3, 4, 5])
    np.testing.assert_array_equal(r.nxt, [1, 2, 3, 0, 5, 6, 4, 8, 9, 10, 11, 12, 7])
    np.testing.assert_array_equal(r.prev, [3, 0, 1, 2, 6, 4, 5, 12, 7, 8, 9, 10, 11])


def test_vector_areas_equal_the_shoelace_formula():
    a = area_vectors(CORNERS, SIZES)
    expected = [_shoelace(p) for p in (SQUARE, TRIANGLE, L_SHAPE)]
    np.testing.assert_allclose(a[:, 2], expected, rtol=1e-14)
    np.testing.assert_allclose(expected, [1.0, -3.0, 3.0])
    np.testing.assert_array_equal(a[:, :2], 0.0)
    # the fans' cross products are twice the fan areas and add up to twice the polygon's
    fans = fan_normals(CORNERS, SIZES)
    np.testing.assert_allclose(np.add.reduceat(fans, rings(SIZES).first), 2 * a, rtol=1e-14)


def test_area_vector_is_independent_of_the_fan_centre_and_rotates_with_the_polygon():
    rng = np.random.default_rng(1)
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    x = CORNERS @ q.T + [0.3, -2.0, 5.0]
    a = area_vectors(x, SIZES)
    np.testing.assert_allclose(area_vectors(x, SIZES, centre=rng.standard_normal((3, 3))), a,
                               atol=1e-12)
    np.testing.assert_allclose(a, area_vectors(CORNERS, SIZES) @ q.T, atol=1e-12)


def test_centroids_and_unit_normals():
    np.testing.assert_allclose(centroids(CORNERS, SIZES)[:2], [[0.5, 0.5, 0], [1, 2 / 3, 0]])
    n = unit_normals(CORNERS, SIZES)
    np.testing.assert_allclose(n, [[0, 0, 1], [0, 0, -1], [0, 0, 1]])
    np.testing.assert_allclose(unit_normals(CORNERS, SIZES, upward=True), [[0, 0, 1]] * 3)


@pytest.mark.parametrize("scale", [1.0, 1e-6])
def test_triangle_areas(scale):
    a = np.zeros((2, 3))
    b = np.array([[3.0, 0, 0], [0, 0, 2]]) * scale
    c = np.array([[0, 4.0, 0], [0, 5, 0]]) * scale
    np.testing.assert_allclose(triangle_areas(a, b, c), np.array([6.0, 5.0]) * scale**2,
                               rtol=1e-14)
