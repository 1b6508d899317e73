"""Kernels of the boundary-integral heat-loss model: the single-layer potential of flat triangles.

The medium around the sheet (conductivity ``k``) obeys Laplace's equation; its temperature rise
is the single-layer potential ``u(x) = int_S sigma(y) G(x, y) dS_y`` of the heat-flux density
``sigma`` [W/m^2] leaving the sheet through BOTH faces (the jump of the normal flux: the sheet is
a two-sided screen), with ``G = 1 / (4 pi k |x - y|)`` in an unbounded medium and
``G = (1 / |x - y| - 1 / |x - y*|) / (4 pi k)`` above an isothermal plane (``y*`` the mirror
image of ``y``). The density is constant per triangle and the equation ``u = T`` is collocated
at the triangle centroids.

* :func:`triangle_potential`: ``int_T 1 / |p - y| dS_y`` over flat triangles, in closed form
  (Wilton et al. 1984, IEEE Trans. Antennas Propag. 32(3) 276), for any point, also on the
  triangle (the singular self-integral) or in its plane;
* :func:`collocation_matrix`: ``V_ij = int_j G(c_i, y) dS_y`` [K m^2/W], the closed form for
  pairs closer than :data:`NEAR_FACTOR` source diameters, a 3-point rule of degree 2 up to
  ``MID_FACTOR x NEAR_FACTOR`` and the centroid rule ``A_j G(c_i, c_j)`` beyond;
* :func:`single_layer_operator`: ``S = V / A`` symmetrised, the operator the loss factorises;
* :func:`subdivision`: barycentric coordinates of the uniform refinement of a triangle into
  ``m^2`` sub-triangles.
"""

from __future__ import annotations

import math

import numpy as np

from . import _single_layer_jit

__all__ = ["triangle_potential", "collocation_matrix", "single_layer_operator", "subdivision",
           "subdivision_edges", "sub_triangle_corners", "pair_values", "mirror",
           "NEAR_FACTOR"]

#: Pairs whose centroid distance is below this many source diameters use the closed form.
NEAR_FACTOR = 1.5
#: Pairs between NEAR_FACTOR and MID_FACTOR x NEAR_FACTOR source diameters use the 3-point rule
#: of degree 2 (barycentric (2/3, 1/6, 1/6) and permutations), farther ones the centroid rule.
MID_FACTOR = 2.0
#: The rule thresholds are raised by this relative amount, so that a distance exactly at one
#: (common on structured meshes: a centroid offset of (1.5, 1.5) times a right triangle's legs
#: is 1.5 of its diameters) takes the closer pair's rule whatever the round-off of a rotated or
#: mirrored sheet: without it a rigid rotation moved temperatures by up to 2e-5 K.
TIE = 1e-9


def triangle_potential(p, tri) -> np.ndarray:
    """``int_T 1 / |p - y| dS_y`` [m] of flat triangles ``tri`` (..., 3, 3) at points ``p`` (..., 3).

    Closed form (Wilton et al. 1984): with ``d`` the height of ``p`` over the triangle's plane,
    ``rho`` its projection and, per edge, ``P0`` the signed in-plane distance of ``rho`` to the
    edge line, ``l-``, ``l+`` the edge ends' coordinates along it and ``R-``, ``R+`` their
    distances to ``p``::

        sum_edges  P0 ln((R+ + l+) / (R- + l-))
                 - |d| [atan(P0 l+ / (R0^2 + |d| R+)) - atan(P0 l- / (R0^2 + |d| R-))]

    with ``R0^2 = P0^2 + d^2``. Exact also for ``p`` on the triangle (the integrable singular
    case: ``d = 0``) and in its plane; edges whose line passes through ``rho`` contribute 0.
    """
    p, tri = np.asarray(p, float), np.asarray(tri, float)
    a, b = tri, np.roll(tri, -1, axis=-2)                       # edge i from vertex i to i+1
    normal = np.cross(tri[..., 1, :] - tri[..., 0, :], tri[..., 2, :] - tri[..., 0, :])
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    d = np.einsum("...j,...j->...", p - tri[..., 0, :], normal)
    rho = p - d[..., None] * normal
    edge = b - a
    length = np.linalg.norm(edge, axis=-1)
    t = edge / length[..., None]
    u = np.cross(t, normal[..., None, :])                      # outward in-plane edge normal
    ra, rb = a - rho[..., None, :], b - rho[..., None, :]
    p0 = np.einsum("...ij,...ij->...i", ra, u)
    l_minus, l_plus = np.einsum("...ij,...ij->...i", ra, t), np.einsum("...ij,...ij->...i", rb, t)
    ad = np.abs(d)[..., None]
    r_minus = np.sqrt(l_minus ** 2 + p0 ** 2 + ad ** 2)
    r_plus = np.sqrt(l_plus ** 2 + p0 ** 2 + ad ** 2)
    r0sq = p0 ** 2 + ad ** 2
    tiny = 1e-12 * length
    on_line = np.abs(p0) <= tiny
    with np.errstate(divide="ignore", invalid="ignore"):
        # r + l without cancellation where l < 0 (r + l = r0^2 / (r - l))
        num = np.where(l_plus >= 0, r_plus + l_plus, r0sq / (r_plus - l_plus))
        den = np.where(l_minus >= 0, r_minus + l_minus, r0sq / (r_minus - l_minus))
        log = np.log(num / den)
        angle = (np.arctan2(p0 * l_plus, r0sq + ad * r_plus)
                 - np.arctan2(p0 * l_minus, r0sq + ad * r_minus))
    term = np.where(on_line, 0.0, p0 * log - ad * angle)
    return term.sum(axis=-1)


def subdivision(level: int):
    """Uniform refinement of a triangle into ``level^2`` sub-triangles.

    Returns
    -------
    vertices : (level^2, 3, 3) array
        Barycentric coordinates (rows: sub-triangle corners, columns: weights of the parent
        vertices 0, 1, 2); every sub-triangle has the orientation of its parent.
    centroids : (level^2, 3) array
        Barycentric coordinates of the sub-triangle centroids.
    """
    m = int(level)
    corners = []
    for i in range(m):
        for j in range(m - i):
            p = [(i, j), (i + 1, j), (i, j + 1)]
            corners.append(p)
            if j < m - i - 1:
                corners.append([(i + 1, j), (i + 1, j + 1), (i, j + 1)])
    ij = np.array(corners, float) / m                           # (m^2, 3, 2): weights of v1, v2
    vertices = np.concatenate([1 - ij.sum(axis=-1, keepdims=True), ij], axis=-1)
    return vertices, vertices.mean(axis=1)


def sub_triangle_corners(x, triangles, bary, compiled=None) -> np.ndarray:
    """Corners [m] of the sub-triangles of the mesh ``triangles`` (n_tri, 3) (node ids) at node
    positions ``x`` (n, 3) [m], (n_tri s, 3, 3): corner a of sub-triangle q of triangle t is
    ``sum_b bary[q, a, b] x[triangles[t, b]]`` (``bary`` (s, 3, 3): :func:`subdivision`'s
    vertices). Compiled when ``compiled`` (default: when selected), numpy otherwise (the
    checked reference; both sum over b in the same order: the same values)."""
    if compiled is None:
        compiled = _single_layer_jit.use_compiled()
    if compiled:
        out = _single_layer_jit.corners(x, triangles, bary)
        if out is not None:
            return out
    return np.einsum("sab,tbk->tsak", bary, np.asarray(x, float)[triangles]).reshape(-1, 3, 3)


def subdivision_edges(triangles, level: int) -> np.ndarray:
    """Ids of the edges of the sub-triangles of :func:`subdivision` of the mesh ``triangles``
    (n_tri, 3) (node ids), (n_tri level^2, 3): edge e of a sub-triangle runs from its corner e
    to corner e + 1; an edge that two sub-triangles share (inside a triangle, or along a mesh
    edge between two triangles) has one id."""
    m = int(level)
    weights = np.rint(subdivision(m)[0] * m).astype(np.int64)     # (s, 3 corners, 3 parents)
    tri = np.asarray(triangles, np.int64).reshape(-1, 3)
    nodes = np.broadcast_to(tri[:, None, None, :], (len(tri),) + weights.shape)
    w = np.broadcast_to(weights, nodes.shape)
    # a corner is its parents' (node, weight) pairs with weight > 0, sorted by node
    key_nodes = np.where(w > 0, nodes, -1).reshape(-1, 3)
    order = np.argsort(key_nodes, axis=1)
    key = np.zeros(len(key_nodes), np.int64)      # one integer per corner: nodes, then weights
    base = int(tri.max(initial=0)) + 2
    for column in np.take_along_axis(key_nodes, order, axis=1).T + 1:
        key = key * base + column
    for column in np.take_along_axis(w.reshape(-1, 3), order, axis=1).T:
        key = key * (m + 1) + column
    corner = np.unique(key, return_inverse=True)[1].reshape(-1, 3).astype(np.int64)
    ends = np.sort(np.stack([corner, np.roll(corner, -1, axis=1)], axis=2), axis=2)
    edge = ends[..., 0] * (int(corner.max(initial=0)) + 1) + ends[..., 1]   # corners e, e + 1
    return np.unique(edge, return_inverse=True)[1].reshape(-1, 3).astype(np.int64)


def mirror(points, plane):
    """Mirror images of ``points`` (..., 3) in the plane ``(origin, unit normal)``."""
    origin, normal = plane
    h = (points - origin) @ normal
    return points - 2 * h[..., None] * normal


def collocation_matrix(tri, conductivity: float, plane=None, near: float = NEAR_FACTOR,
                       compiled=None):
    """Collocation matrix ``V_ij = int_j G(c_i, y) dS_y`` [K m^2 / W] of flat triangles.

    Parameters
    ----------
    tri : (n, 3, 3) array
        Triangle corners [m].
    conductivity : float
        Medium conductivity k [W/(m K)], > 0.
    plane : (origin (3,), unit normal (3,)), optional
        Isothermal plane (image method, ``G = (1/r - 1/r*) / (4 pi k)``); the medium is on the
        side the normal points to.
    near : float
        Pairs closer than ``near`` source diameters use the closed form (:func:`triangle_potential`),
        the others the centroid rule.
    compiled : bool, optional
        Use the compiled kernel (default: when the numba backend is selected).

    Returns
    -------
    V : (n, n) array
    area : (n,) array of triangle areas [m^2]
    centroid : (n, 3) array [m]
    """
    tri = np.asarray(tri, float)
    if compiled is None:
        compiled = _single_layer_jit.use_compiled()
    if compiled:
        V, area, c, _ = _single_layer_jit.collocation(
            tri, _plane(plane), near, 1 / (4 * math.pi * conductivity))
        return V, area, c
    c = tri.mean(axis=1)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    diam = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
    V = _kernel_matrix(c, tri, c, area, diam, near)
    if plane is not None:
        plane = _plane(plane)
        V -= _kernel_matrix(c, mirror(tri, plane), mirror(c, plane), area, diam, near)
    return V / (4 * math.pi * conductivity), area, c


def single_layer_operator(tri, conductivity: float, plane=None, near: float = NEAR_FACTOR,
                          compiled=None, edges=None):
    """The symmetrised collocation operator ``S = (V / A + (V / A)^T) / 2`` [K/W] of flat
    triangles (``S_ij = V_ij / A_j``, :func:`collocation_matrix`), and the triangles' diameters
    [m] (longest edge), (n,): what :class:`~simulator.thermal.integral.IntegralOperator`
    factorises. Same parameters as :func:`collocation_matrix`; compiled in one pass, in which
    the triangles sharing an edge (``edges``: :func:`subdivision_edges`) share the closed
    form's logarithm of that edge (the same value)."""
    tri = np.asarray(tri, float)
    if compiled is None:
        compiled = _single_layer_jit.use_compiled()
    if compiled:
        S, _, _, diam = _single_layer_jit.collocation(
            tri, _plane(plane), near, 1 / (4 * math.pi * conductivity), operator=True,
            edges=edges)
        return S, diam
    V, area, _ = collocation_matrix(tri, conductivity, plane, near, compiled=False)
    S = V / area[None, :]
    return 0.5 * (S + S.T), np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)


def _plane(plane):
    """``(origin, unit normal)`` as float arrays, or None."""
    return None if plane is None else (np.asarray(plane[0], float), np.asarray(plane[1], float))


def _kernel_matrix(points, tri, centroid, area, diam, near):
    """``int_j 1 / |p_i - y| dS_y`` for all points and triangles: centroid rule, 3-point rule,
    closed form near (the numpy reference of :mod:`simulator.thermal._single_layer_jit`)."""
    near = near * (1 + TIE)
    diff = points[:, None, :] - centroid[None, :, :]
    dist = np.sqrt(np.einsum("ijk,ijk->ij", diff, diff))
    close = dist < near * diam[None, :]
    with np.errstate(divide="ignore"):
        out = area[None, :] / dist
    i, j = np.nonzero(~close & (dist < MID_FACTOR * near * diam[None, :]))
    q = (3 * tri[j][:, :, None, :] * np.eye(3)[None, :, :, None]
         + tri[j][:, None, :, :]).sum(axis=2) / 6          # (2/3, 1/6, 1/6) points, (p, 3, 3)
    out[i, j] = area[j] * (1 / np.linalg.norm(q - points[i][:, None, :], axis=2)).mean(axis=1)
    i, j = np.nonzero(close)
    out[i, j] = triangle_potential(points[i], tri[j])
    return out


def pair_values(points, tri, centroid, area, diam, rows, cols, near: float = NEAR_FACTOR,
                compiled=None) -> np.ndarray:
    """``int_j 1 / |p_i - y| dS_y`` [m] of the pairs ``(rows[k], cols[k])``, (p,): the entries
    of :func:`_kernel_matrix` at those pairs only, by the same rule (closed form within
    ``near`` source diameters, the 3-point rule up to ``MID_FACTOR`` times that, the centroid
    rule beyond), for the near field of the fast operator
    (:mod:`simulator.thermal.integral_fast`). Compiled when ``compiled`` (default: when
    selected), numpy otherwise (the checked reference)."""
    rows, cols = np.asarray(rows, np.int64), np.asarray(cols, np.int64)
    if compiled is None:
        compiled = _single_layer_jit.use_compiled()
    if compiled:
        out = _single_layer_jit.pair_values(points, tri, centroid, area, diam, near, rows, cols)
        if out is not None:
            return out
    out = np.empty(len(rows))
    near = near * (1 + TIE)
    dist = np.linalg.norm(points[rows] - centroid[cols], axis=1)
    close = dist < near * diam[cols]
    mid = ~close & (dist < MID_FACTOR * near * diam[cols])
    far = ~close & ~mid
    out[far] = area[cols[far]] / dist[far]
    i, j = rows[mid], cols[mid]
    q = (3 * tri[j][:, :, None, :] * np.eye(3)[None, :, :, None]
         + tri[j][:, None, :, :]).sum(axis=2) / 6
    out[mid] = area[j] * (1 / np.linalg.norm(q - points[i][:, None, :], axis=2)).mean(axis=1)
    out[close] = triangle_potential(points[rows[close]], tri[cols[close]])
    return out
