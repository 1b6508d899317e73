"""Node-to-triangle penalty contact with exact gradients and Hessians.

For a point ``P`` and a triangle ``(T1, T2, T3)`` the distance ``d`` is the exact
closest-point distance, written per Voronoi zone (Ericson's region tests):

* zone 0 (face):   ``d = |a . (b x c)| / |b x c|`` with ``a = P - T1``, ``b = T2 - T1``,
  ``c = T3 - T1``;
* zone 1 (vertex): ``d = |P - Tv|``;
* zone 2 (edge):   ``d = |r x e| / |e|`` with ``e = Tb - Ta``, ``r = P - Ta``
  (distance to the line through the edge).

Each zone is differentiated with respect to at most three difference vectors
("slots" ``P - Ta``, ``Ta+1 - Ta``, ``Ta+2 - Ta`` with anchor ``Ta = T1`` for the
face) and mapped to the 12 node DOFs ``(P, T1, T2, T3)`` (node-major) by a constant
3 x 4 selection matrix per anchor; slots a zone does not use carry zeros.

Penalty (for ``d <= d0``, zero beyond): ``phi = pi/2 (1 - d/d0)``,
``U = ke [ln(sec phi) - phi^2/2]``; ``U``, ``U'``, ``U''`` vanish at ``d = d0``.

Degenerate cases are finite by construction: distances below
``dmin = 1e-12 d0`` (penetrated / touching points) are clamped to ``dmin`` in the
potential and in the ``1/d`` factors of the derivatives; zero-length edges are
treated as vertices; the face area is floored at ``1e-12`` of the triangle size.
"""

from __future__ import annotations

import logging

import numpy as np

from ._vec import cross

__all__ = ["point_triangle_distance", "distance_derivatives", "contact_potential",
           "contact_kernel"]

logger = logging.getLogger(__name__)

_EPS = 1e-12                        # relative floor for lengths and clamped distances
_TINY = 1e-100                      # absolute floor (keeps 1/d^3 finite)
_I3 = np.eye(3)
# Maclaurin coefficients of tan(x) - x (x^3 ... x^15); those of ln(sec x) - x^2/2 follow
# by term-wise integration (divide by 4, 6, ... 16).
_TAN = np.array([1 / 3, 2 / 15, 17 / 315, 62 / 2835, 1382 / 155925, 21844 / 6081075,
                 929569 / 638512875])
_TAN_POW = np.arange(4.0, 17.0, 2.0)
# _MAPS[a] (3, 4): nodes (P, T1, T2, T3) -> slots (P - Ta, Ta+1 - Ta, Ta+2 - Ta) for anchor a
_MAPS = np.array([[np.eye(4)[k] - np.eye(4)[1 + a] for k in (0, 1 + (a + 1) % 3, 1 + (a + 2) % 3)]
                  for a in range(3)])


def _dot(u, v):
    return np.einsum("ni,ni->n", u, v)


def _outer(g, h):
    """(m, k, 3) x (m, l, 3) -> (m, k, 3, l, 3)."""
    return np.einsum("npi,nqj->npiqj", g, h)


def _skew(v):
    z = np.zeros(len(v))
    return np.stack([z, -v[:, 2], v[:, 1], v[:, 2], z, -v[:, 0], -v[:, 1], v[:, 0], z],
                    axis=1).reshape(-1, 3, 3)


def _col(s):
    """Broadcast a per-pair scalar (m,) against (m, ...) arrays of rank 3 or 5."""
    return s[:, None, None], s[:, None, None, None, None]


def _classify(p, tri):
    """Ericson's Voronoi-region tests -> zone (n,), feature (n,)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, ac = b - a, c - a
    d1, d2 = _dot(ab, p - a), _dot(ac, p - a)
    d3, d4 = _dot(ab, p - b), _dot(ac, p - b)
    d5, d6 = _dot(ab, p - c), _dot(ac, p - c)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    conds = [(d1 <= 0) & (d2 <= 0), (d3 >= 0) & (d4 <= d3),
             (vc <= 0) & (d1 >= 0) & (d3 <= 0), (d6 >= 0) & (d5 <= d6),
             (vb <= 0) & (d2 >= 0) & (d6 <= 0), (va <= 0) & (d4 >= d3) & (d5 >= d6)]
    zone = np.select(conds, [1, 1, 2, 1, 2, 2], 0)
    feature = np.select(conds, [0, 1, 0, 2, 2, 1], -1)
    # zero-length edges (degenerate triangles) are vertices of their first end
    edges = tri[:, [1, 2, 0]] - tri
    e2 = np.einsum("nki,nki->nk", edges, edges)
    k = np.maximum(feature, 0)
    degenerate = (zone == 2) & (e2[np.arange(len(p)), k] <= _EPS**2 * e2.sum(axis=1))
    zone[degenerate] = 1
    return zone, feature


def _geometry(p, tri, zone, feature):
    """Slot vectors r (= a), e (= b), c, squared size L2 = |b|^2 + |c|^2, anchor index."""
    idx = np.arange(len(p))
    ta = np.where(zone == 0, 0, feature)
    r = p - tri[idx, ta]
    e = tri[idx, (ta + 1) % 3] - tri[idx, ta]
    b, c = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    return r, e, c, _dot(b, b) + _dot(c, c), ta


def _distance(r, e, c, L2, zone):
    d = np.empty(len(r))
    f, v, g = zone == 0, zone == 1, zone == 2
    N = cross(e[f], c[f])
    d[f] = np.abs(_dot(r[f], N)) * np.maximum(_dot(N, N), (_EPS * L2[f]) ** 2 + _TINY) ** -0.5
    d[v] = np.sqrt(_dot(r[v], r[v]))
    w = cross(r[g], e[g])
    d[g] = np.sqrt(_dot(w, w) / _dot(e[g], e[g]))
    return d


def _cross_sq(u, v):
    """q = |u x v|^2 with gradient (m, 2, 3) and Hessian (m, 2, 3, 2, 3) wrt (u, v)."""
    w = cross(u, v)
    g = 2.0 * np.stack([cross(v, w), cross(w, u)], axis=1)
    uu, vv, uv = _dot(u, u), _dot(v, v), _dot(u, v)
    H = np.empty((len(u), 2, 3, 2, 3))
    H[:, 0, :, 0] = 2.0 * (vv[:, None, None] * _I3 - v[:, :, None] * v[:, None, :])
    H[:, 1, :, 1] = 2.0 * (uu[:, None, None] * _I3 - u[:, :, None] * u[:, None, :])
    H[:, 0, :, 1] = (4.0 * u[:, :, None] * v[:, None, :] - 2.0 * v[:, :, None] * u[:, None, :]
                     - 2.0 * uv[:, None, None] * _I3)
    H[:, 1, :, 0] = np.swapaxes(H[:, 0, :, 1], 1, 2)
    return _dot(w, w), g, H


def _face(a, b, c, L2):
    """d = s V A2^(-1/2), V = a . (b x c), A2 = |b x c|^2: d, grad (m,3,3), Hess (m,3,3,3,3)."""
    m = len(a)
    N = cross(b, c)
    V = _dot(a, N)
    A2, gA2, HA2 = _cross_sq(b, c)
    inv = np.maximum(A2, (_EPS * L2) ** 2 + _TINY) ** -0.5
    s = np.where(V < 0, -1.0, 1.0)
    gV = np.stack([N, cross(c, a), cross(a, b)], axis=1)
    HV = np.zeros((m, 3, 3, 3, 3))
    HV[:, 0, :, 1], HV[:, 0, :, 2], HV[:, 1, :, 2] = -_skew(c), _skew(b), -_skew(a)
    HV[:, 1, :, 0], HV[:, 2, :, 0], HV[:, 2, :, 1] = _skew(c), -_skew(b), _skew(a)
    gA = np.zeros((m, 3, 3))
    gA[:, 1:] = gA2
    HA = np.zeros((m, 3, 3, 3, 3))
    HA[:, 1:, :, 1:] = HA2
    # chain rule for f(V, A2) = V A2^(-1/2), times the sign s
    cV, cA = s * inv, -0.5 * s * V * inv**3
    cVA, cAA = -0.5 * s * inv**3, 0.75 * s * V * inv**5
    G = _col(cV)[0] * gV + _col(cA)[0] * gA
    H = (_col(cV)[1] * HV + _col(cA)[1] * HA + _col(cAA)[1] * _outer(gA, gA)
         + _col(cVA)[1] * (_outer(gV, gA) + _outer(gA, gV)))
    return s * V * inv, G, H


def _edge_sq(r, e):
    """D = |r x e|^2 / |e|^2 with gradient (m, 2, 3) and Hessian wrt (r, e)."""
    m = len(r)
    q, gq, Hq = _cross_sq(r, e)
    E = _dot(e, e)
    gE = np.zeros((m, 2, 3))
    gE[:, 1] = 2.0 * e
    HE = np.zeros((m, 2, 3, 2, 3))
    HE[:, 1, :, 1] = 2.0 * _I3
    (q3, q5), (E3, E5) = _col(q), _col(E)
    gD = gq / E3 - q3 * gE / E3**2
    HD = (Hq / E5 - (_outer(gq, gE) + _outer(gE, gq)) / E5**2 - q5 * HE / E5**2
          + 2.0 * q5 * _outer(gE, gE) / E5**3)
    return q / E, gD, HD


def _sqrt_chain(D, gD, HD, dmin):
    """d = sqrt(D): d, grad, Hess, with 1/d factors floored at dmin."""
    d = np.sqrt(D)
    d3, d5 = _col(np.maximum(d, dmin))
    return d, gD / (2.0 * d3), HD / (2.0 * d5) - _outer(gD, gD) / (4.0 * d5**3)


def _derivatives(r, e, c, L2, zone, anchor, dmin):
    """d, grad (n, 12), hess (n, 12, 12); unused slots (zones 1, 2) stay zero."""
    n = len(r)
    d, G, H = np.empty(n), np.zeros((n, 3, 3)), np.zeros((n, 3, 3, 3, 3))
    f, v, g = zone == 0, zone == 1, zone == 2
    if f.any():
        d[f], G[f], H[f] = _face(r[f], e[f], c[f], L2[f])
    if v.any():
        rv = r[v]
        HD = np.broadcast_to(2.0 * _I3[None, None, :, None, :], (len(rv), 1, 3, 1, 3))
        d[v], G[v, :1], H[v, :1, :, :1] = _sqrt_chain(_dot(rv, rv), 2.0 * rv[:, None], HD,
                                                      dmin[v])
    if g.any():
        d[g], G[g, :2], H[g, :2, :, :2] = _sqrt_chain(*_edge_sq(r[g], e[g]), dmin[g])
    M = _MAPS[anchor]
    grad = np.einsum("npA,npi->nAi", M, G).reshape(n, 12)
    half = np.einsum("npA,npiqj->nAiqj", M, H)           # two plain contractions are far
    hess = np.einsum("nAiqj,nqB->nAiBj", half, M).reshape(n, 12, 12)   # cheaper than optimize=True
    return d, grad, hess


def point_triangle_distance(p, tri):
    """Exact distance from points to closed triangles, with its Voronoi zone.

    Parameters
    ----------
    p : (n, 3) array
        Points [m].
    tri : (n, 3, 3) array
        Triangle vertices ``(T1, T2, T3)`` per pair [m].

    Returns
    -------
    d : (n,) array
        Closest-point distance [m].
    zone : (n,) int array
        0 face, 1 vertex, 2 edge.
    feature : (n,) int array
        Vertex index 0..2 for zone 1; edge index (0 = T1T2, 1 = T2T3, 2 = T3T1)
        for zone 2; -1 for zone 0.
    """
    p, tri = np.asarray(p, float), np.asarray(tri, float)
    zone, feature = _classify(p, tri)
    r, e, c, L2, _ = _geometry(p, tri, zone, feature)
    return _distance(r, e, c, L2, zone), zone, feature


def distance_derivatives(p, tri):
    """Distance with its exact gradient and Hessian wrt ``(P, T1, T2, T3)``.

    Parameters ``p`` (n, 3) and ``tri`` (n, 3, 3) [m] as in :func:`point_triangle_distance`.

    Returns
    -------
    d : (n,) array
        Distance [m].
    grad : (n, 12) array
        ``dd/dx`` [-], node-major ``(P, T1, T2, T3)``; zero for uninvolved nodes.
    hess : (n, 12, 12) array
        ``d2d/dx2`` [1/m]. ``1/d`` factors (zones 1, 2) are floored at
        ``1e-12`` times the triangle size.
    zone : (n,) int array
        0 face, 1 vertex, 2 edge.
    """
    p, tri = np.asarray(p, float), np.asarray(tri, float)
    zone, feature = _classify(p, tri)
    r, e, c, L2, ta = _geometry(p, tri, zone, feature)
    dmin = np.maximum(_EPS * np.sqrt(L2), _TINY)
    return (*_derivatives(r, e, c, L2, zone, ta, dmin), zone)


def contact_potential(d, d0, ke):
    """Penalty energy ``U(d)`` and its first two derivatives.

    Parameters
    ----------
    d : (n,) array
        Distance [m]. Values below ``1e-12 d0`` (including ``d <= 0``) are clamped
        to ``1e-12 d0``: all outputs stay finite (very large, repulsive).
    d0 : float or (n,) array
        Contact range [m], > 0.
    ke : float or (n,) array
        Penalty stiffness [J].

    Returns
    -------
    U, dU, d2U : (n,) arrays
        Energy [J], ``dU/dd`` [J/m] (<= 0) and ``d2U/dd2`` [J/m^2] (>= 0); exact
        zeros for ``d >= d0``.
    """
    d, d0, ke = np.broadcast_arrays(np.asarray(d, float), np.asarray(d0, float),
                                    np.asarray(ke, float))
    phi = 0.5 * np.pi * (1.0 - np.clip(d, _EPS * d0, d0) / d0)      # in [0, pi/2)
    dphi = -0.5 * np.pi / d0
    # ln(sec phi) - phi^2/2 and tan(phi) - phi without cancellation near d0 (series)
    p2, big = phi**2, phi > 0.1
    lnsec = np.where(big, -np.log1p(-2.0 * np.sin(0.5 * phi) ** 2) - 0.5 * p2,
                     p2**2 * np.polynomial.polynomial.polyval(p2, _TAN / _TAN_POW))
    tan_m = np.where(big, np.tan(phi) - phi,
                     phi * p2 * np.polynomial.polynomial.polyval(p2, _TAN))
    return ke * lnsec, ke * tan_m * dphi, ke * dphi**2 * np.tan(phi) ** 2


def contact_kernel(x, d0, ke):
    """Energy, gradient and Hessian of node-to-triangle penalty contact pairs.

    Parameters
    ----------
    x : (n, 4, 3) array
        Current coordinates of ``(P, T1, T2, T3)`` per pair [m].
    d0 : float or (n,) array
        Contact range [m].
    ke : float or (n,) array
        Penalty stiffness [J].

    Returns
    -------
    energy [J] (n,), grad [N] (n, 12) node-major ``(P, T1, T2, T3)``, hess [N/m] (n, 12, 12)
        Derivatives are evaluated only for pairs with ``d <= d0``; the others get
        exact zeros.
    """
    x = np.asarray(x, float)
    n = len(x)
    p, tri = x[:, 0], x[:, 1:]
    d0, ke = np.broadcast_to(d0, (n,)).astype(float), np.broadcast_to(ke, (n,)).astype(float)
    zone, feature = _classify(p, tri)
    r, e, c, L2, ta = _geometry(p, tri, zone, feature)
    act = np.flatnonzero(_distance(r, e, c, L2, zone) <= d0)
    logger.debug("contact_kernel: %d of %d pairs active", act.size, n)
    d, g, h = _derivatives(r[act], e[act], c[act], L2[act], zone[act], ta[act], _EPS * d0[act])
    U, dU, d2U = contact_potential(d, d0[act], ke[act])
    h *= dU[:, None, None]
    h += np.einsum("n,ni,nj->nij", d2U, g, g)
    g *= dU[:, None]
    if act.size == n:
        return U, g, h
    energy, grad, hess = np.zeros(n), np.zeros((n, 12)), np.zeros((n, 12, 12))
    energy[act], grad[act], hess[act] = U, g, h
    return energy, grad, hess
