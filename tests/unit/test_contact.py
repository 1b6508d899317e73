"""Tests of simulator.mechanics.elements.contact (node-to-triangle penalty contact)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from fd_harness import check_kernel, relative_error
from simulator.mechanics.elements.contact import (contact_kernel, contact_potential, distance_derivatives,
                                        point_triangle_distance)

D0, KE = 40e-6, 1e-4                     # contact range [m], penalty stiffness [J]
CASES = [(0, -1), (1, 0), (1, 1), (1, 2), (2, 0), (2, 1), (2, 2)]   # (zone, feature)
EDGES = [(0, 1), (1, 2), (2, 0)]


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _triangles(rng, n, size=(1e-4, 1e-3)):
    """Well-shaped random triangles (perturbed equilateral, random pose) [m]."""
    ang = 2 * np.pi * np.arange(3) / 3
    base = np.stack([np.cos(ang), np.sin(ang), np.zeros(3)], axis=1)
    tri = base + 0.15 * rng.uniform(-1, 1, (n, 3, 3)) * [1, 1, 0]
    rot = np.linalg.qr(rng.standard_normal((n, 3, 3)))[0]
    L = np.exp(rng.uniform(*np.log(size), n))[:, None, None]
    return L * (tri @ np.swapaxes(rot, 1, 2)) + 0.3 * L * rng.uniform(-1, 1, (n, 1, 3))


def _points(tri, zone, feature, dist, rng):
    """Points at distance ``dist`` safely inside the requested Voronoi zone."""
    n = len(tri)
    nrm = _unit(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))
    side = rng.choice([-1.0, 1.0], n)[:, None]
    alpha = rng.uniform(-1, 1, n)[:, None]               # elevation out of plane [rad]
    dist = np.asarray(dist, float).reshape(-1, 1)
    if zone == 0:
        u, v = rng.uniform(0.2, 0.4, (2, n, 1))
        return tri[:, 0] + u * (tri[:, 1] - tri[:, 0]) + v * (tri[:, 2] - tri[:, 0]) \
            + side * dist * nrm
    if zone == 1:
        tk = tri[:, feature]
        out = -_unit(_unit(tri[:, (feature + 1) % 3] - tk) + _unit(tri[:, (feature + 2) % 3] - tk))
        return tk + dist * (np.cos(alpha) * out + np.sin(alpha) * nrm)
    ta, tb = EDGES[feature]
    e = tri[:, tb] - tri[:, ta]
    m = _unit(np.cross(e, nrm))
    m *= -np.sign(np.einsum("ni,ni->n", m, tri[:, 3 - ta - tb] - tri[:, ta]))[:, None]
    s = rng.uniform(0.25, 0.75, (n, 1))
    return tri[:, ta] + s * e + dist * (np.cos(alpha) * m + np.sin(alpha) * nrm)


def _pairs(rng, zone, feature, dist, n=20, size=(1e-4, 1e-3)):
    tri = _triangles(rng, n, size)
    return np.concatenate([_points(tri, zone, feature, dist, rng)[:, None], tri], axis=1)


def _dist_kernel(x):
    return distance_derivatives(x[:, 0], x[:, 1:])[:3]


def _contact(x):
    return contact_kernel(x, D0, KE)


def _reference_distance(p, tri):
    """Brute force: minimise |q(u, v) - p|^2 over barycentric (u, v) with SLSQP."""
    b, c, a = tri[1] - tri[0], tri[2] - tri[0], p - tri[0]
    fun = lambda z: np.sum((z[0] * b + z[1] * c - a) ** 2)
    jac = lambda z: 2 * np.array([b @ (z[0] * b + z[1] * c - a), c @ (z[0] * b + z[1] * c - a)])
    res = minimize(fun, [1 / 3, 1 / 3], jac=jac, method="SLSQP", bounds=[(0, 1), (0, 1)],
                   constraints=[{"type": "ineq", "fun": lambda z: 1 - z[0] - z[1],
                                 "jac": lambda z: np.array([-1.0, -1.0])}],
                   options={"ftol": 1e-16, "maxiter": 500})
    u, v = res.x
    return np.sqrt(max(res.fun, 0.0)), np.array([1 - u - v, u, v])


# 1. distance and zones -------------------------------------------------------------------

def test_distance_matches_brute_force():
    rng = np.random.default_rng(1)
    tri = _triangles(rng, 300, size=(1.0, 1.0))
    p = tri.mean(axis=1) + rng.uniform(-1.5, 1.5, (300, 3))
    d, zone, feature = point_triangle_distance(p, tri)
    assert set(zone) == {0, 1, 2}
    checked = 0
    for i in range(len(p)):
        d_ref, bary = _reference_distance(p[i], tri[i])
        assert d[i] == pytest.approx(d_ref, rel=1e-6, abs=1e-9)
        zero, clear = bary < 1e-7, (bary < 1e-7) | (bary > 1e-4)
        if not clear.all():
            continue                                      # too close to a zone border
        checked += 1
        if zero.sum() == 0:
            assert (zone[i], feature[i]) == (0, -1)
        elif zero.sum() == 1:                             # bary weight 0 opposite the edge
            assert (zone[i], feature[i]) == (2, [1, 2, 0][int(np.argmax(zero))])
        else:
            assert (zone[i], feature[i]) == (1, int(np.argmin(zero)))
    assert checked > 250


def test_zone_classification_hand_made():
    tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    p = np.array([[0.2, 0.2, 0.5], [0.3, 0.3, -0.2], [-1, -1, 0.3], [2, -0.5, 0.1],
                  [-0.5, 2, 0], [0.5, -1, 0.2], [1, 1, 0.3], [-1, 0.5, 0.1]])
    d, zone, feature = point_triangle_distance(p, np.broadcast_to(tri, (len(p), 3, 3)))
    np.testing.assert_array_equal(zone, [0, 0, 1, 1, 1, 2, 2, 2])
    np.testing.assert_array_equal(feature, [-1, -1, 0, 1, 2, 0, 1, 2])
    expected = np.sqrt([0.25, 0.04, 2.09, 1.26, 1.25, 1.04, 0.59, 1.01])
    np.testing.assert_allclose(d, expected, rtol=1e-14)


# 2. exact derivatives of the distance ----------------------------------------------------

@pytest.mark.parametrize("zone,feature", CASES)
def test_distance_derivatives_fd(zone, feature):
    rng = np.random.default_rng(10 + 3 * zone + feature)
    tri = _triangles(rng, 20)
    size = np.linalg.norm(tri[:, 1] - tri[:, 0], axis=1)
    x = np.concatenate([_points(tri, zone, feature, rng.uniform(0.2, 0.6, 20) * size, rng)[:, None],
                        tri], axis=1)
    d, grad, hess, z = distance_derivatives(x[:, 0], x[:, 1:])
    assert np.all(z == zone)
    assert np.all(point_triangle_distance(x[:, 0], x[:, 1:])[2] == feature)
    np.testing.assert_allclose(np.linalg.norm(grad[:, :3], axis=1), 1.0, rtol=1e-12)
    involved = [0, 1, 2] if zone == 0 else [feature] if zone == 1 else list(EDGES[feature])
    idle = [3 * (1 + k) + i for k in range(3) if k not in involved for i in range(3)]
    assert not grad[:, idle].any() and not hess[:, idle].any() and not hess[:, :, idle].any()
    errs = check_kernel(_dist_kernel, x)
    assert errs["gradient"] < 1e-7 and errs["hessian"] < 1e-7


# 3. contact kernel at the SI micro scale -------------------------------------------------

@pytest.mark.parametrize("zone,feature", CASES)
def test_contact_kernel_fd(zone, feature):
    rng = np.random.default_rng(40 + 3 * zone + feature)
    x = _pairs(rng, zone, feature, rng.uniform(0.3, 0.7, 20) * D0)
    d, z, _ = point_triangle_distance(x[:, 0], x[:, 1:])
    assert np.all(z == zone) and np.all((d > 0.29 * D0) & (d < 0.71 * D0))
    energy, grad, hess = _contact(x)
    assert np.all(energy > 0)
    errs = check_kernel(_contact, x)
    assert errs["gradient"] < 1e-7 and errs["hessian"] < 1e-7


# 4. continuity across zone borders --------------------------------------------------------

def _border_points(kind, sigma, rng_seed=7):
    """Pairs crossing a face/edge (sigma < 0: face) or edge/vertex border (sigma < 0: edge)."""
    rng = np.random.default_rng(rng_seed)
    tri = _triangles(rng, 5, size=(5e-4, 5e-4))
    nrm = _unit(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))
    e = tri[:, 1] - tri[:, 0]
    ehat, m = _unit(e), _unit(np.cross(e, nrm))
    m *= -np.sign(np.einsum("ni,ni->n", m, tri[:, 2] - tri[:, 0]))[:, None]
    L = np.linalg.norm(e, axis=1, keepdims=True)
    if kind == "face/edge":
        p = tri[:, 0] + 0.4 * e + sigma * L * m + 0.5 * D0 * nrm
    else:
        p = tri[:, 1] + sigma * L * ehat + 0.3 * D0 * m + 0.4 * D0 * nrm
    return np.concatenate([p[:, None], tri], axis=1)


@pytest.mark.parametrize("kind,zones", [("face/edge", (0, 2)), ("edge/vertex", (2, 1))])
def test_continuity_across_borders(kind, zones):
    jumps_d, jumps_g = [], []
    for delta in [1e-2, 1e-3, 1e-4, 1e-6]:
        (dm, gm, _, zm), (dp, gp, _, zp) = (distance_derivatives(x[:, 0], x[:, 1:]) for x in
                                            (_border_points(kind, -delta),
                                             _border_points(kind, delta)))
        assert np.all(zm == zones[0]) and np.all(zp == zones[1])
        jumps_d.append(np.max(np.abs(dp - dm)) / D0)
        jumps_g.append(np.max(np.linalg.norm(gp - gm, axis=1)))
    assert np.all(np.diff(jumps_d) < 0) and np.all(np.diff(jumps_g) < 0)
    assert jumps_d[-1] < 1e-9 and jumps_g[-1] < 1e-3
    for sigma in (-1e-3, 1e-3):                           # FD on both sides, 1e-3 size away
        x = _border_points(kind, sigma)
        check_kernel(_dist_kernel, x)
        check_kernel(_contact, x)


# 5. penalty potential ---------------------------------------------------------------------

def test_potential_properties():
    U, dU, d2U = contact_potential(np.array([D0, 1.0001 * D0, 2 * D0, 1.0]), D0, KE)
    assert np.all(U == 0) and np.all(dU == 0) and np.all(d2U == 0)
    d = np.linspace(0.05, 0.95, 19) * D0
    U, dU, d2U = contact_potential(d, D0, KE)
    assert np.all(U > 0) and np.all(dU < 0) and np.all(d2U > 0)
    h = 1e-6 * D0
    Up, dUp, _ = contact_potential(d + h, D0, KE)
    Um, dUm, _ = contact_potential(d - h, D0, KE)
    assert relative_error(dU[:, None], ((Up - Um) / (2 * h))[:, None]) < 1e-7
    assert relative_error(d2U[:, None], ((dUp - dUm) / (2 * h))[:, None]) < 1e-7
    # approaching d0 from below, U, U', U'' go to zero continuously
    near = contact_potential(D0 * (1 - np.array([1e-2, 1e-4, 1e-6])), D0, KE)
    assert all(np.all(np.diff(np.abs(q)) < 0) for q in near)
    # strong repulsion as d -> 0, finite (clamped) for d <= 0
    U0, dU0, d2U0 = contact_potential(np.array([1e-9 * D0, 0.5 * D0, 0.0, -1e-6]), D0, KE)
    assert U0[0] > 100 * U0[1] and dU0[0] < 1e6 * dU0[1]
    assert np.all(np.isfinite([U0, dU0, d2U0])) and U0[2] == U0[3] > U0[0]
    # per-pair d0 and ke
    d0s, kes = np.array([30e-6, 40e-6, 50e-6]), np.array([1e-4, 2e-4, 3e-4])
    vec = contact_potential(np.full(3, 20e-6), d0s, kes)
    for i in range(3):
        for q_vec, q_one in zip(vec, contact_potential(20e-6, d0s[i], kes[i])):
            assert q_vec[i] == pytest.approx(float(q_one), rel=1e-15)


# 6. inactive pairs and degenerate input ---------------------------------------------------

def test_inactive_pairs_are_exact_zeros():
    rng = np.random.default_rng(5)
    far = np.concatenate([_pairs(rng, z, f, rng.uniform(1.01, 3, 5) * D0, n=5) for z, f in CASES])
    near = _pairs(rng, 0, -1, rng.uniform(0.3, 0.7, 5) * D0, n=5)
    energy, grad, hess = contact_kernel(far, D0, KE)
    assert not energy.any() and not grad.any() and not hess.any()
    mixed = np.concatenate([far, near])
    e_mix, g_mix, h_mix = contact_kernel(mixed, D0, KE)
    e_near, g_near, h_near = contact_kernel(near, D0, KE)
    np.testing.assert_array_equal(e_mix[len(far):], e_near)
    np.testing.assert_array_equal(g_mix[len(far):], g_near)
    np.testing.assert_array_equal(h_mix[len(far):], h_near)
    assert not e_mix[:len(far)].any()


def test_degenerate_input_is_finite():
    t = np.array([[0.0, 0, 0], [1e-4, 0, 0], [0, 1e-4, 0]])
    line = np.array([[0.0, 0, 0], [1e-4, 0, 0], [2e-4, 0, 0]])
    pinch = np.array([[0.0, 0, 0], [0, 0, 0], [0, 1e-4, 0]])
    point = np.zeros((3, 3))
    cases = [([3e-5, 3e-5, 0], t, 0.0), (t[1], t, 0.0), ([5e-5, 0, 0], t, 0.0),
             ([5e-5, 5e-5, 0], t, 0.0), ([3e-5, 3e-5, -1e-9], t, 1e-9),
             ([1.5e-4, 2e-5, 0], line, 2e-5), ([3e-4, 0, 1e-5], line, np.hypot(1e-4, 1e-5)),
             ([1e-5, -1e-5, 1e-5], pinch, np.sqrt(3) * 1e-5), ([0, 0, 0], pinch, 0.0),
             ([1e-5, 0, 0], point, 1e-5), ([0, 0, 0], point, 0.0)]
    p = np.array([c[0] for c in cases], float)
    tri = np.array([c[1] for c in cases])
    with np.errstate(over="raise", divide="raise", invalid="raise"):
        d, zone, _ = point_triangle_distance(p, tri)
        out = distance_derivatives(p, tri)
        kern = contact_kernel(np.concatenate([p[:, None], tri], axis=1), D0, KE)
    np.testing.assert_allclose(d, [c[2] for c in cases], rtol=1e-12, atol=1e-20)
    for arr in (*out, *kern):
        assert np.all(np.isfinite(arr))
    assert np.all(kern[0][d < D0] > 0)
    assert np.all(zone[[-4, -3, -2, -1]] == 1)            # zero-length edges act as vertices


# 7. batched evaluation (pre-filter, zone grouping, scatter) -------------------------------

def _mixed_batch(rng, n=6):
    """Pairs of every zone at 0.05 - 2 d0 (active and inactive), some in the triangle's plane."""
    x = np.concatenate([_pairs(rng, z, f, rng.uniform(0.05, 2.0, n) * D0, n=n) for z, f in CASES])
    flat = _pairs(rng, 2, 1, rng.uniform(0.5, 1.5, n) * D0, n=n)     # edge zone, coplanar
    tri = flat[:, 1:]
    e = tri[:, 2] - tri[:, 1]
    nrm = _unit(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))
    out = -_unit(np.cross(e, nrm))
    out *= -np.sign(np.einsum("ni,ni->n", out, tri[:, 0] - tri[:, 1]))[:, None]
    flat[:, 0] = tri[:, 1] + 0.5 * e + rng.uniform(0.5, 1.5, (n, 1)) * D0 * out
    x = np.concatenate([x, flat])
    return x[rng.permutation(len(x))]


def test_batch_matches_single_pairs():
    rng = np.random.default_rng(11)
    x = _mixed_batch(rng)
    d0 = rng.uniform(0.8, 1.2, len(x)) * D0
    ke = rng.uniform(0.5, 2.0, len(x)) * KE
    energy, grad, hess = contact_kernel(x, d0, ke)
    d, zone, _ = point_triangle_distance(x[:, 0], x[:, 1:])
    active = d <= d0
    assert 0 < active.sum() < len(x) and set(zone[active]) == {0, 1, 2}
    assert np.all(energy[active] > 0) and not energy[~active].any()
    assert not grad[~active].any() and not hess[~active].any()
    dist = distance_derivatives(x[:, 0], x[:, 1:])
    for i in range(len(x)):
        single = contact_kernel(x[i:i + 1], d0[i], ke[i])
        for batch, one in zip((energy, grad, hess), single):
            np.testing.assert_allclose(batch[i], one[0], rtol=1e-12, atol=1e-300)
        single = distance_derivatives(x[i:i + 1, 0], x[i:i + 1, 1:])
        for batch, one in zip(dist, single):
            np.testing.assert_allclose(batch[i], one[0], rtol=1e-12, atol=1e-300)


def test_kernel_fd_near_contact_range():
    """d just inside d0: the potential's series branch, alone and mixed with the closed form."""
    rng = np.random.default_rng(12)
    x = np.concatenate([_pairs(rng, z, f, rng.uniform(0.93, 0.99, 3) * D0, n=3) for z, f in CASES])
    errs = check_kernel(_contact, x, h=3e-11)             # FD truncation ~ (h / (d0 - d))^2
    assert errs["gradient"] < 1e-7 and errs["hessian"] < 1e-7
    deeper = np.concatenate([x, _pairs(rng, 0, -1, [0.5 * D0] * 3, n=3)])
    np.testing.assert_allclose(contact_kernel(deeper, D0, KE)[2][:len(x)], _contact(x)[2],
                               rtol=1e-13)


def test_empty_batch_and_scalar_potential():
    energy, grad, hess = contact_kernel(np.zeros((0, 4, 3)), D0, KE)
    assert energy.shape == (0,) and grad.shape == (0, 12) and hess.shape == (0, 12, 12)
    U, dU, d2U = contact_potential(0.5 * D0, D0, KE)
    assert np.ndim(U) == np.ndim(dU) == np.ndim(d2U) == 0 and U > 0 > dU and d2U > 0
