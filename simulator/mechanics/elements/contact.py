"""Node-to-triangle penalty contact with exact gradients and Hessians.

For a point ``P`` and a triangle ``(T1, T2, T3)`` the distance ``d`` is the exact
closest-point distance, written per Voronoi zone (Ericson's region tests) in terms of
three difference vectors ("slots") ``r = P - Ta``, ``e = Ta+1 - Ta``, ``c = Ta+2 - Ta``
of an anchor vertex ``Ta`` (``T1`` for the face):

* zone 0 (face):   ``d = |V| / |N|`` with ``V = r . N``, ``N = e x c``;
* zone 1 (vertex): ``d = |r|``;
* zone 2 (edge):   ``d = |r - t e|``, ``t = r . e / |e|^2`` (distance to the edge's line).

Derivatives are formed in slot space (9 DOFs; vertex and edge pairs share one expression,
with ``t = 0`` for vertices) and mapped to the 12 node DOFs ``(P, T1, T2, T3)``
(node-major) by a constant 9 x 12 matrix per anchor.

Penalty (for ``d <= d0``, zero beyond): ``phi = pi/2 (1 - d/d0)``,
``U = ke [ln(sec phi) - phi^2/2]``; ``U``, ``U'``, ``U''`` vanish at ``d = d0``.

Degenerate cases are finite by construction: distances below
``dmin = 1e-12 d0`` (penetrated / touching points) are clamped to ``dmin`` in the
potential and in the ``1/d`` factors of the derivatives; zero-length edges are
treated as vertices; the face area is floored at ``1e-12`` of the triangle size.

Every step is a fixed, small number of whole-array numpy calls (the kernel runs at each
Newton iteration, mostly on a few pairs): 0/+-1-coefficient maps (cross products, slot
differences, region tests) and the face polynomials are products with constant matrices.
"""

from __future__ import annotations

import logging
from itertools import permutations

import numpy as np

__all__ = ["point_triangle_distance", "distance_derivatives", "contact_potential",
           "contact_kernel"]

logger = logging.getLogger(__name__)

_EPS = 1e-12                        # relative floor for lengths and clamped distances
_TINY = 1e-100                      # absolute floor (keeps 1/d^3 finite)
_I3 = np.eye(3)
_LEVI = np.cross(_I3[:, None], _I3[None, :])             # Levi-Civita eps_ijk
_CROSS = _LEVI.reshape(9, 3)                             # u x v = (u v^T).ravel() @ _CROSS
# Maclaurin series of (tan x - x) / x (x^2 ... x^14) and, by term-wise integration, of
# ln(sec x) - x^2/2 (x^4 ... x^16): columns of (9, 2), coefficients of x^0, x^2, ... x^16
_TAN = np.array([1 / 3, 2 / 15, 17 / 315, 62 / 2835, 1382 / 155925, 21844 / 6081075,
                 929569 / 638512875])
_SERIES = np.zeros((9, 2))
_SERIES[1:8, 0], _SERIES[2:, 1] = _TAN, _TAN / np.arange(4.0, 17.0, 2.0)
_POW = np.arange(9.0)
# Voronoi regions in Ericson's test order (V1, V2, E12, V3, E31, E23, face):
# rows (zone, feature, anchor)
_CODES = np.array([[1, 1, 2, 1, 2, 2, 0], [0, 1, 0, 2, 2, 1, -1], [0, 1, 0, 2, 2, 1, 0]]).T
# _MAPS[a] (3, 4): nodes (P, T1, T2, T3) -> slots (P - Ta, Ta+1 - Ta, Ta+2 - Ta) of anchor a;
# _K[a] (9, 12): the same on DOFs
_MAPS = np.array([[np.eye(4)[k] - np.eye(4)[1 + a] for k in (0, 1 + (a + 1) % 3, 1 + (a + 2) % 3)]
                  for a in range(3)])
_K = np.einsum("akA,ij->akiAj", _MAPS, _I3).reshape(3, 9, 12)
# q (7): dot products of rows _QI, _QJ of (ap, N, ab, ac), i.e.
# V = ap.N, A2 = N.N, ab.ab, ac.ac, ab.ap, ac.ap, ab.ac;  q @ _Q_D = (ab, ac) . (ap, bp, cp)
_QI, _QJ = np.array([0, 1, 2, 3, 2, 3, 2]), np.array([1, 1, 2, 3, 0, 0, 3])
_Q_D = np.zeros((7, 2, 3))
_Q_D[4, 0], _Q_D[5, 1] = 1.0, 1.0
_Q_D[[2, 6], 0, [1, 2]] = _Q_D[[6, 3], 1, [1, 2]] = -1.0          # bp = ap - ab, cp = ap - ac
_Q_D = _Q_D.reshape(7, 6)


def _region_tests():
    """(15, 21): features ``(D.ravel(), (D[0] D[1]^T).ravel())`` -> Ericson's tests as
    ``value <= 0``, three per region (unused: 0)."""
    d1, d2, d3, d4, d5, d6, va, vb, vc = np.eye(9)       # va, vb, vc: D[0] x D[1]
    z = np.zeros(9)
    tests = np.array([d1, d2, z, -d3, d4 - d3, z, vc, -d1, d3, -d6, d5 - d6, z, vb, -d2, d6,
                      va, d3 - d4, d6 - d5, z, z, z]).T
    to_q = np.zeros((15, 9))
    to_q[range(6), [0, 2, 4, 1, 3, 5]], to_q[6:, 6:] = 1.0, _CROSS
    return to_q @ tests


def _face_polynomials():
    """Constant maps for the derivatives of ``V = a . (b x c)`` and ``A2 = |b x c|^2 =
    (b.b)(c.c) - (b.c)^2``, homogeneous polynomials of ``y = (a, b, c)`` (from their
    symmetrised coefficient tensors): ``d2V/dy2 = y @ HV``, ``(dV/dy, d2A2/dy2) =
    (y y^T).ravel() @ QUAD`` and ``dA2/dy = (N y^T).ravel() @ GA`` with ``N = b x c``."""
    def sym(T):
        perms = list(permutations(range(T.ndim)))
        return sum(T.transpose(p) for p in perms) / len(perms)
    a, b, c = np.eye(9).reshape(3, 3, 9)                 # slot selectors: b = (y @ b.T)
    V = sym(np.einsum("ijk,ip,jq,kr->pqr", _LEVI, a, b, c))
    A2 = sym(np.einsum("ip,iq,jr,js->pqrs", b, b, c, c)
             - np.einsum("ip,iq,jr,js->pqrs", b, c, b, c))
    GA = 2 * (np.einsum("kij,iq,kp->jqp", _LEVI, c, b) + np.einsum("kij,jq,kp->iqp", _LEVI, b, c))
    quad = np.hstack([3 * V.reshape(81, 9), 12 * A2.reshape(81, 81)])
    return 6 * V.reshape(9, 81), quad, GA.reshape(27, 9)


_REGIONS = _region_tests()
_GROUPS = np.kron(np.eye(7), np.ones((3, 1)))            # (21, 7): sums the tests per region
_HV, _QUAD, _GA = _face_polynomials()
# numpy >= 2: vecdot is a ufunc, with less overhead than einsum on small arrays
_dot = getattr(np, "vecdot", None) or (lambda u, v: np.einsum("...i,...i->...", u, v))


def _outer(u, v):
    return u[:, :, None] * v[:, None]


def _per_pair(v, n, scalar_ok=False):
    """``v`` as a float array of shape (n,) (or kept 0-d if ``scalar_ok``)."""
    v = np.asarray(v, float)
    return v if v.shape == (n,) or (scalar_ok and not v.ndim) else np.broadcast_to(v, (n,))


def _plane(x):
    """Dot products q (n, 7) (see ``_QI``), floored ``|N|^-1`` (n,) and the distance
    ``h <= d`` (n,) of ``P`` to the triangle's plane, for pairs ``x`` (n, 4, 3)."""
    W = x - x[:, 1:2]                                    # ap, 0, ab, ac
    W[:, 1] = _outer(W[:, 2], W[:, 3]).reshape(-1, 9) @ _CROSS
    q = _dot(W.take(_QI, axis=1), W.take(_QJ, axis=1))
    inv = np.maximum(q[:, 1], (_EPS * (q[:, 2] + q[:, 3])) ** 2 + _TINY) ** -0.5
    return q, inv, np.abs(q[:, 0]) * inv


def _locate(x, q, h):
    """Zone, feature, anchor (n,), slots S (n, 3, 3), distance d (n,) of pairs ``x`` (n, 4, 3)
    (``q``, ``h`` from :func:`_plane`) and ``line = (t, rho = r - t e, k = 1/|e|^2)`` of the
    closest point on the anchor's edge line (t = k = 0 off zone 2: the anchor)."""
    n = len(x)
    F = np.empty((n, 15))                                # D, D[0] x D[1]
    F[:, :6] = q @ _Q_D
    F[:, 6:] = _outer(F[:, :3], F[:, 3:6]).reshape(n, 9)
    # first region whose tests all hold (the face's always do); exact: 0/+-1 coefficients
    zone, feature, anchor = _CODES.take((np.maximum(F @ _REGIONS, 0.0) @ _GROUPS).argmin(axis=1),
                                        axis=0).T
    S = _MAPS.take(anchor, axis=0) @ x                  # exact: entries 0, +-1
    r, e = S[:, 0], S[:, 1]
    E = _dot(e, e)
    zone -= (zone == 2) & (E <= _EPS**2 * (q[:, 2] + q[:, 3]))   # zero-length edge: a vertex
    edge = zone == 2
    k = edge / np.where(edge, E, 1.0)
    t = _dot(r, e) * k
    rho = r - t[:, None] * e
    return zone, feature, anchor, S, np.where(zone == 0, h, np.sqrt(_dot(rho, rho))), (t, rho, k)


def _face(S, V, inv):
    """Slot gradient (m, 9) and Hessian (m, 9, 9) of ``d = s V inv`` (``inv = A2^-1/2``)
    on slots ``y = (a, b, c)``, with ``V``, ``inv`` from :func:`_plane`."""
    m = len(S)
    y = S.reshape(m, 9)
    quad = _outer(y, y).reshape(m, 81) @ _QUAD
    gV, HA = quad[:, :9], quad[:, 9:].reshape(m, 9, 9)  # dV/dy = (b x c, c x a, a x b)
    gA = _outer(gV[:, :3], y).reshape(m, 27) @ _GA      # dA2/dy = (0, 2 c x N, 2 N x b)
    # chain rule for f(V, A2) = s V A2^(-1/2): f_V = s inv, f_A = -s V inv^3 / 2,
    # f_VA = -s inv^3 / 2, f_AA = 3 s V inv^5 / 4
    i2 = (inv * inv)[:, None]
    cV = np.copysign(inv, V)[:, None]
    cVA = -0.5 * i2 * cV
    cA = cVA * V[:, None]
    hAA = -0.75 * i2 * cA
    u = cVA * gV + hAA * gA                              # f_AA gA gA + f_VA (gV gA + gA gV)
    X = _outer(u, gA)                                    #   = u gA^T + gA u^T
    H = ((cV * y) @ _HV).reshape(m, 9, 9)               # f_V d2V/dy2 (linear in y)
    H += cA[:, :, None] * HA
    H += X
    H += X.transpose(0, 2, 1)
    return cV * gV + cA * gA, H


def _vertex_edge(e, d, t, rho, k, dmin):
    """Slot gradient (m, 6) and Hessian (m, 6, 6) of ``d = |rho|`` on slots ``(r, e)``.

    With ``lam = (1, -t)`` and ``f = (e, rho - t e) / |e|`` (0 for vertices):
    ``grad = lam x rho / d``, ``Hess = (lam lam^T x I - f f^T - grad grad^T) / d``,
    ``1/d`` factors floored at ``dmin``.
    """
    m = len(e)
    dc = np.maximum(d, dmin).reshape(m, 1, 1)
    lam = np.empty((m, 2, 1))
    lam[:, 0] = 1.0
    lam[:, 1, 0] = -t
    g = (lam * (rho[:, None] / dc)).reshape(m, 6)
    f = lam * e[:, None]
    f[:, 1] += rho
    f = (f * np.sqrt(k).reshape(m, 1, 1)).reshape(m, 6)
    H = (lam[:, :, :, None, None] * lam[:, None, None] * _I3[:, None]).reshape(m, 6, 6)
    H -= _outer(f, f) + _outer(g, g)
    return g, H / dc


def _derivatives(nf, S, d, line, V, inv, dmin):
    """Slot gradient (m, s) and Hessian (m, s, s) (s = 6 without face pairs, else 9) of
    pairs located by :func:`_locate`; the ``nf`` face pairs come first."""
    m = len(S)
    if nf == m:
        return _face(S, V, inv)
    ve = _vertex_edge(S[nf:, 1], d[nf:], *(a[nf:] for a in line), dmin[nf:])
    if nf == 0:
        return ve
    G, H = np.zeros((m, 9)), np.zeros((m, 9, 9))
    G[:nf], H[:nf] = _face(S[:nf], V[:nf], inv[:nf])
    G[nf:, :6], H[nf:, :6, :6] = ve
    return G, H


def _to_nodes(G, H, anchor):
    """Slot-space grad (m, s) and Hess (m, s, s) -> node DOFs (m, 12), (m, 12, 12)."""
    K = _K.take(anchor, axis=0)[:, :G.shape[1]]
    return (G[:, None] @ K)[:, 0], K.transpose(0, 2, 1) @ (H @ K)


def _faces_first(zone):
    """Order putting the face pairs first (stable), and their number."""
    face = zone == 0
    nf = np.count_nonzero(face)
    return (np.argsort(~face, kind="stable") if 0 < nf < len(zone) else slice(None)), nf


def _pairs(p, tri):
    return np.concatenate([np.asarray(p, float)[:, None], np.asarray(tri, float)], axis=1)


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
    x = _pairs(p, tri)
    q, _, h = _plane(x)
    zone, feature, _, _, d, _ = _locate(x, q, h)
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
    x = _pairs(p, tri)
    q, inv, h = _plane(x)
    zone, _, anchor, S, d, line = _locate(x, q, h)
    order, nf = _faces_first(zone)
    q, d = q[order], d[order]
    dmin = np.maximum(_EPS * np.sqrt(q[:, 2] + q[:, 3]), _TINY)
    G, H = _derivatives(nf, S[order], d, [a[order] for a in line], q[:, 0], inv[order], dmin)
    out = np.empty_like(d), np.empty((len(d), 12)), np.empty((len(d), 12, 12))
    out[0][order], (out[1][order], out[2][order]) = d, _to_nodes(G, H, anchor[order])
    return (*out, zone)


def _potential(d, d0, ke):
    phi = 0.5 * np.pi * (1.0 - np.minimum(np.maximum(d / d0, _EPS), 1.0))      # [0, pi/2)
    p2, small = phi * phi, phi <= 0.1
    # ln(sec phi) - phi^2/2, tan(phi) - phi and tan(phi): series where phi <= 0.1 (the closed
    # forms cancel there); each branch is evaluated only if some pair needs it
    n_small = np.count_nonzero(small)
    if n_small:
        series = (p2[..., None] ** _POW) @ _SERIES
        lnsec, tan_m = series[..., 1], phi * series[..., 0]
        tan = phi + tan_m
    if n_small < small.size:
        tan_c = np.tan(phi)
        closed = 0.5 * (np.log1p(tan_c * tan_c) - p2), tan_c - phi, tan_c
        lnsec, tan_m, tan = closed if not n_small else \
            [np.where(small, s, c) for s, c in zip((lnsec, tan_m, tan), closed)]
    dphi = -0.5 * np.pi / d0
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
    d0, ke = _per_pair(d0, n), _per_pair(ke, n, scalar_ok=True)
    energy, grad, hess = np.zeros(n), np.zeros((n, 12)), np.zeros((n, 12, 12))
    q, inv, h = _plane(x)
    near = (h <= d0).nonzero()[0]                        # exact pre-filter: h <= d
    if not near.size:
        return energy, grad, hess
    zone, _, anchor, S, d, line = _locate(x.take(near, axis=0), q.take(near, axis=0),
                                          h.take(near))
    act = (d <= d0.take(near)).nonzero()[0]
    logger.debug("contact_kernel: %d of %d pairs active", act.size, n)
    if not act.size:
        return energy, grad, hess
    order, nf = _faces_first(zone.take(act))
    act = act[order]
    idx = near.take(act)
    d, d0 = d.take(act), d0.take(idx)
    G, H = _derivatives(nf, S.take(act, axis=0), d, [a.take(act, axis=0) for a in line],
                        q[:, 0].take(idx), inv.take(idx), _EPS * d0)
    U, dU, d2U = _potential(d, d0, ke.take(idx) if ke.ndim else ke)
    H *= dU[:, None, None]
    H += d2U[:, None, None] * _outer(G, G)
    G *= dU[:, None]
    energy[idx] = U
    grad[idx], hess[idx] = _to_nodes(G, H, anchor.take(act))
    return energy, grad, hess
