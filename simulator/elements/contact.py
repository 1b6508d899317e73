"""Node-to-triangle penalty contact with exact gradients and Hessians.

For a point ``P`` and a triangle ``(T1, T2, T3)`` the distance ``d`` is the exact
closest-point distance, written per Voronoi zone (Ericson's region tests) in terms of
three difference vectors ("slots") ``r = P - Ta``, ``e = Ta+1 - Ta``, ``c = Ta+2 - Ta``
of an anchor vertex ``Ta`` (``T1`` for the face):

* zone 0 (face):   ``d = |V| / |N|`` with ``V = r . N``, ``N = e x c``;
* zone 1 (vertex): ``d = |r|``;
* zone 2 (edge):   ``d = |r - t e|``, ``t = r . e / |e|^2`` (distance to the edge's line).

The derivatives are formed per pair in slot space (9 DOFs; vertex and edge pairs share one
expression, with ``t = 0`` for vertices) and mapped to the 12 node DOFs
``(P, T1, T2, T3)`` (node-major) by a constant 9 x 12 matrix per anchor.

Penalty (for ``d <= d0``, zero beyond): ``phi = pi/2 (1 - d/d0)``,
``U = ke [ln(sec phi) - phi^2/2]``; ``U``, ``U'``, ``U''`` vanish at ``d = d0``.

Degenerate cases are finite by construction: distances below
``dmin = 1e-12 d0`` (penetrated / touching points) are clamped to ``dmin`` in the
potential and in the ``1/d`` factors of the derivatives; zero-length edges are
treated as vertices; the face area is floored at ``1e-12`` of the triangle size.

All functions are vectorised over pairs with a fixed number of numpy calls, so that a
few pairs cost tens of microseconds and large batches run at array speed.
"""

from __future__ import annotations

import logging
from itertools import permutations

import numpy as np

from ._vec import cross

__all__ = ["point_triangle_distance", "distance_derivatives", "contact_potential",
           "contact_kernel"]

logger = logging.getLogger(__name__)

_EPS = 1e-12                        # relative floor for lengths and clamped distances
_TINY = 1e-100                      # absolute floor (keeps 1/d^3 finite)
_I3 = np.eye(3)
# Maclaurin coefficients of tan(x) - x (x^3 ... x^15) and, by term-wise integration,
# of ln(sec x) - x^2/2 (x^4 ... x^16), as Horner rows (7, 2) in x^2.
_TAN = np.array([1 / 3, 2 / 15, 17 / 315, 62 / 2835, 1382 / 155925, 21844 / 6081075,
                 929569 / 638512875])
_SERIES = np.stack([_TAN, _TAN / np.arange(4.0, 17.0, 2.0)], axis=1)
# Ericson's region tests in order (V1, V2, E12, V3, E31, E23, face): zone and feature
_ZONE = np.array([1, 1, 2, 1, 2, 2, 0])
_FEATURE = np.array([0, 1, 0, 2, 2, 1, -1])
# _MAPS[a] (3, 4): nodes (P, T1, T2, T3) -> slots (P - Ta, Ta+1 - Ta, Ta+2 - Ta), anchor a;
# _K[a] (9, 12) is the same map on DOFs
_MAPS = np.array([[np.eye(4)[k] - np.eye(4)[1 + a] for k in (0, 1 + (a + 1) % 3, 1 + (a + 2) % 3)]
                  for a in range(3)])
_K = np.einsum("akA,ij->akiAj", _MAPS, _I3).reshape(3, 9, 12)
_KT = np.ascontiguousarray(_K.transpose(0, 2, 1))


def _triple_product_hessian():
    """(9, 81): the Hessian of ``V = a . (b x c)`` wrt ``y = (a, b, c)`` is ``y @ this``."""
    levi = np.cross(_I3[:, None], _I3[None, :])          # levi[i, j, k] = eps_ijk
    out = np.zeros((3, 3, 3, 3, 3, 3))                   # (slot u, k, slot s, i, slot t, j)
    for s, t, u in permutations(range(3)):
        out[u, :, s, :, t, :] = levi.transpose(u, s, t)
    return out.reshape(9, 81)


def _area_hessian():
    """(36, 36): Hessian of ``A2 = |b x c|^2 = (b.b)(c.c) - (b.c)^2`` wrt ``z = (b, c)``
    is ``(z z^T).ravel() @ this`` (product rule on the three quadratic forms)."""
    P, R, S = (np.kron(m, _I3) for m in ([[1.0, 0], [0, 0]], [[0, 0], [0, 1.0]],
                                         [[0, 0.5], [0.5, 0]]))
    H = (2 * np.einsum("rs,pq->rspq", R, P) + 2 * np.einsum("rs,pq->rspq", P, R)
         + 4 * np.einsum("pr,qs->rspq", P, R) + 4 * np.einsum("pr,qs->rspq", R, P)
         - 8 * np.einsum("pr,qs->rspq", S, S) - 4 * np.einsum("rs,pq->rspq", S, S))
    return H.reshape(36, 36)


_HV, _HA = _triple_product_hessian(), _area_hessian()


def _dot(u, v):
    return np.einsum("ni,ni->n", u, v)


def _plane_distance(x):
    """Distance of ``P`` to the triangle's plane, a lower bound of ``d`` (n,), and
    ``L2 = |T2 - T1|^2 + |T3 - T1|^2`` (n,) for pairs ``x`` (n, 4, 3)."""
    q = x - x[:, 1:2]
    N = cross(q[:, 2], q[:, 3])
    L2 = np.einsum("nki,nki->n", q[:, 2:], q[:, 2:])
    return np.abs(_dot(q[:, 0], N)) * np.maximum(_dot(N, N), (_EPS * L2) ** 2 + _TINY) ** -0.5, L2


def _classify(x):
    """Ericson's Voronoi-region tests on pairs (n, 4, 3) -> zone (n,), feature (n,)."""
    tri = x[:, 1:]
    D = (tri[:, 1:] - tri[:, :1]) @ np.swapaxes(x[:, :1] - tri, 1, 2)   # (ab, ac).(ap, bp, cp)
    (d1, d3, d5), (d2, d4, d6) = D[:, 0].T, D[:, 1].T
    va, vb, vc = cross(D[:, 0], D[:, 1]).T
    cond = np.ones((len(x), 7), bool)                    # first true column wins
    cond[:, 0] = (d1 <= 0) & (d2 <= 0)
    cond[:, 1] = (d3 >= 0) & (d4 <= d3)
    cond[:, 2] = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    cond[:, 3] = (d6 >= 0) & (d5 <= d6)
    cond[:, 4] = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    cond[:, 5] = (va <= 0) & (d4 >= d3) & (d5 >= d6)
    code = cond.argmax(axis=1)
    zone, feature = _ZONE[code], _FEATURE[code]
    # zero-length edges (degenerate triangles) are vertices of their first end
    edges = tri[:, [1, 2, 0]] - tri
    e2 = np.einsum("nki,nki->nk", edges, edges)
    zone -= (zone == 2) & (e2[np.arange(len(x)), feature] <= _EPS**2 * e2.sum(axis=1))
    return zone, feature


def _line(S, edge):
    """Foot parameter ``t`` (0 unless ``edge``), ``rho = r - t e`` and ``edge / |e|^2``."""
    r, e = S[:, 0], S[:, 1]
    k = edge / np.where(edge, _dot(e, e), 1.0)
    t = _dot(r, e) * k
    return t, r - t[:, None] * e, k


def _locate(x, h):
    """Zone, feature, anchor, slots (n, 3, 3) and distance of pairs ``x`` with plane
    distances ``h``."""
    zone, feature = _classify(x)
    anchor = np.maximum(feature, 0)
    S = _MAPS[anchor] @ x                                # exact: entries 0, +-1
    rho = _line(S, zone == 2)[1]
    return zone, feature, anchor, S, np.where(zone == 0, h, np.sqrt(_dot(rho, rho)))


def _face(S, L2):
    """d = s V A2^(-1/2) on slots ``(a, b, c)``: d (m,), grad (m, 9), Hess (m, 9, 9)."""
    m = len(S)
    y = S.reshape(m, 9)
    HV = (y @ _HV).reshape(m, 9, 9)
    gV = 0.5 * (HV @ y[:, :, None])[:, :, 0]             # (b x c, c x a, a x b)
    N = gV[:, :3]
    gA = 2.0 * (N[:, None] @ HV[:, :3, 3:])[:, 0]        # (2 c x N, 2 N x b), slots b, c
    z = y[:, 3:]
    HA = ((z[:, :, None] * z[:, None]).reshape(m, 36) @ _HA).reshape(m, 6, 6)
    V = _dot(S[:, 0], N)
    inv = np.maximum(_dot(N, N), (_EPS * L2) ** 2 + _TINY) ** -0.5
    # chain rule for f(V, A2) = V A2^(-1/2), times the sign s
    cV = np.where(V < 0, -inv, inv)
    cVA = -0.5 * cV * inv**2
    cA = cVA * V
    cAA = -1.5 * cA * inv**2
    G = cV[:, None] * gV
    G[:, 3:] += cA[:, None] * gA
    H = cV[:, None, None] * HV
    H[:, 3:, 3:] += cA[:, None, None] * HA
    u = cVA[:, None] * gV                                # cAA gA gA + cVA (gV gA + gA gV)
    u[:, 3:] += 0.5 * cAA[:, None] * gA                  # = u gA + gA u
    X = u[:, :, None] * gA[:, None]
    H[:, :, 3:] += X
    H[:, 3:] += np.swapaxes(X, 1, 2)
    return np.abs(V) * inv, G, H


def _vertex_edge(S, edge, dmin):
    """d = |rho| on slots ``(r, e)`` (t = 0 for vertices): d, grad (m, 6), Hess (m, 6, 6).

    With ``lam = (1, -t)`` and ``f = (e, rho - t e) / |e|`` (0 for vertices):
    ``grad = lam x rho / d``, ``Hess = (lam lam^T x I - f f^T - grad grad^T) / d``,
    ``1/d`` factors floored at ``dmin``.
    """
    m = len(S)
    t, rho, k = _line(S, edge)
    d = np.sqrt(_dot(rho, rho))
    dc = np.maximum(d, dmin)[:, None]
    lam = np.ones((m, 2, 1))
    lam[:, 1, 0] = -t
    g = (lam * (rho / dc)[:, None]).reshape(m, 6)
    f = np.empty((m, 2, 3))
    f[:, 0] = S[:, 1]
    f[:, 1] = rho - t[:, None] * S[:, 1]
    f = f.reshape(m, 6) * np.sqrt(k)[:, None]
    H = (lam[:, :, :, None, None] * lam[:, None, None] * _I3[:, None]).reshape(m, 6, 6)
    H -= f[:, :, None] * f[:, None] + g[:, :, None] * g[:, None]
    H /= dc[:, :, None]
    return d, g, H


def _derivatives(S, zone, nf, L2, dmin):
    """d, grad (m, 9), Hess (m, 9, 9) in slot space; the ``nf`` face pairs come first."""
    m = len(S)
    d, G, H = np.empty(m), np.zeros((m, 9)), np.zeros((m, 9, 9))
    if nf:
        d[:nf], G[:nf], H[:nf] = _face(S[:nf], L2[:nf])
    if nf < m:
        d[nf:], G[nf:, :6], H[nf:, :6, :6] = _vertex_edge(S[nf:], zone[nf:] == 2, dmin[nf:])
    return d, G, H


def _to_nodes(G, H, anchor):
    """Slot-space grad (m, 9) and Hess (m, 9, 9) -> node DOFs (m, 12), (m, 12, 12)."""
    K = _K[anchor]
    return (G[:, None] @ K)[:, 0], _KT[anchor] @ (H @ K)


def _faces_first(zone):
    """Stable order putting face pairs first, and their number."""
    face = zone == 0
    return np.argsort(~face, kind="stable"), np.count_nonzero(face)


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
    x = np.concatenate([np.asarray(p, float)[:, None], np.asarray(tri, float)], axis=1)
    zone, feature, _, _, d = _locate(x, _plane_distance(x)[0])
    return d, zone, feature


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
    x = np.concatenate([np.asarray(p, float)[:, None], np.asarray(tri, float)], axis=1)
    h, L2 = _plane_distance(x)
    zone, _, anchor, S, _ = _locate(x, h)
    order, nf = _faces_first(zone)
    dmin = np.maximum(_EPS * np.sqrt(L2[order]), _TINY)
    d, G, H = _derivatives(S[order], zone[order], nf, L2[order], dmin)
    out = np.empty_like(d), np.empty((len(d), 12)), np.empty((len(d), 12, 12))
    out[0][order], (out[1][order], out[2][order]) = d, _to_nodes(G, H, anchor[order])
    return (*out, zone)


def _potential(d, d0, ke):
    phi = 0.5 * np.pi * (1.0 - np.minimum(np.maximum(d, _EPS * d0), d0) / d0)   # [0, pi/2)
    dphi = -0.5 * np.pi / d0
    # ln(sec phi) - phi^2/2 and tan(phi) - phi without cancellation near d0 (series)
    p2, big, tan = phi * phi, phi > 0.1, np.tan(phi)
    series, x2 = _SERIES[-1], p2[..., None]
    for coef in _SERIES[-2::-1]:
        series = series * x2 + coef
    lnsec = np.where(big, -np.log1p(-2.0 * np.sin(0.5 * phi) ** 2) - 0.5 * p2,
                     p2 * p2 * series[..., 1])
    tan_m = np.where(big, tan - phi, phi * p2 * series[..., 0])
    kd = ke * dphi
    return ke * lnsec, kd * tan_m, kd * dphi * tan * tan


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
    return _potential(*np.broadcast_arrays(np.asarray(d, float), np.asarray(d0, float),
                                           np.asarray(ke, float)))


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
    d0, ke = np.broadcast_to(np.asarray(d0, float), (n,)), np.broadcast_to(ke, (n,))
    energy, grad, hess = np.zeros(n), np.zeros((n, 12)), np.zeros((n, 12, 12))
    h, L2 = _plane_distance(x)
    near = np.flatnonzero(h <= d0)                       # exact pre-filter: h <= d
    if near.size:
        zone, _, anchor, S, d = _locate(x[near], h[near])
        act = np.flatnonzero(d <= d0[near])
        order, nf = _faces_first(zone[act])
        act = act[order]
        idx = near[act]
        d, G, H = _derivatives(S[act], zone[act], nf, L2[idx], _EPS * d0[idx])
        U, dU, d2U = _potential(d, d0[idx], ke[idx])
        H *= dU[:, None, None]
        H += d2U[:, None, None] * (G[:, :, None] * G[:, None])
        G *= dU[:, None]
        energy[idx] = U
        grad[idx], hess[idx] = _to_nodes(G, H, anchor[act])
    logger.debug("contact_kernel: %d of %d pairs active", np.count_nonzero(energy), n)
    return energy, grad, hess
