"""The integral heat-loss model's steady operator and its exact derivative in the shape (theory
12.6).

With the integral loss the structure rise dT solves ``A(x) dT = q`` on the free nodes with
``A(x) = sum_e K_e(alpha_e) + L(x)``: the sheet's T3 conduction (as with the chains,
:class:`~simulator.sensitivity.chain.ChainOperator`) and the dense loss conductance ``L =
M^T S(x)^-1 M`` of :class:`~simulator.thermal.integral.IntegralOperator` (or the Richardson
combination ``sum_l w_l L_l`` of two such levels). ``M``, the interpolation of the nodal rises
at the sub-triangle centroids, does not depend on the shape, so that

    d(L dT) = -M^T S^-1 (dS p),      p = S^-1 M dT,

and ``D = d(S p)/dx`` at fixed ``p`` is assembled pair by pair: ``S = (S' + S'^T) / 2`` with
``S'_ij = V_ij / A_j``, the mean of ``1 / (4 pi k r)`` over sub-triangle j seen from the
centroid of sub-triangle i, by the same rule as the operator (the centroid rule far, the
3-point rule at mid range, in closed form near; with a substrate plane minus the same for the
mirror image of j). The centroid and 3-point rules are differentiated analytically; the closed
form (Wilton et al.) by central differences of the pair's own value in its 12 coordinates with
the step :data:`CLOSED_FORM_STEP` times the source's diameter (its error about 1e-9 of the
entry's derivative, theory 12.6). Each sub-triangle's corners and centroid are fixed
barycentric combinations of its mesh triangle's nodes: the chain rule to the nodes is linear.

What is not differentiated: the lumped conductance (``IntegralLoss.lumped``), a refined sheet,
the fast operator (``operator="fast"``), and the operator's rule thresholds, a discontinuity of
the discretisation at pairs exactly at ``NEAR_FACTOR`` (or its multiple) source diameters (the
rule's own error, about 1e-3 of that pair's entry; see theory 12.6). Nodes touching the
substrate (held at room temperature) or pressed onto it are reported as non-smooth points.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..linalg import dense_lapack
from ..thermal._single_layer import (MID_FACTOR, NEAR_FACTOR, TIE, mirror,
                                     single_layer_operator, triangle_potential)
from . import _integral_jit
from .chain import ChainOperator

__all__ = ["IntegralShapeOperator", "shape_operator", "loss_levels", "pair_derivative",
           "CLOSED_FORM_STEP"]

#: The closed form's central differences move one coordinate by this fraction of the source
#: sub-triangle's diameter: the truncation error ``(h / r)^2`` and the round-off ``eps r / h``
#: of a pair at ``r`` >= a sixth of that diameter both stay below about 1e-9 of the entry's
#: derivative.
CLOSED_FORM_STEP = 3e-6
#: Rows of the pair derivative assembled at a time (memory ``~ 100 n_sub`` doubles per row).
_BLOCK = 64


def shape_operator(tm, x):
    """The steady operator of the thermal model ``tm`` at positions ``x`` with its shape
    derivative: :class:`IntegralShapeOperator` with the integral loss, else
    :class:`~simulator.sensitivity.chain.ChainOperator`."""
    return IntegralShapeOperator(tm, x) if tm.integral is not None else ChainOperator(tm, x)


def loss_levels(loss) -> list:
    """``[(IntegralOperator, weight)]``: the levels whose weighted sum is the accurate loss
    conductance of the steady model's ``integral`` operator at a shape where it was rebuilt
    (``CorrectedLoss`` -> its accurate operator; ``ExtrapolatedLoss`` -> ``m / (m - c)`` and
    ``-c / (m - c)``). Raises :class:`~simulator.sensitivity.SensitivityNotSupported` for the
    fast operator."""
    from ..thermal.integral import IntegralOperator
    from ..thermal.integral_levels import CorrectedLoss, ExtrapolatedLoss
    from . import SensitivityNotSupported

    if isinstance(loss, CorrectedLoss):
        return loss_levels(loss.accurate)
    if isinstance(loss, ExtrapolatedLoss):
        m, c = loss.m, loss.c
        return [(loss.fine, m / (m - c)), (loss.coarse, -c / (m - c))]
    if isinstance(loss, IntegralOperator):
        return [(loss, 1.0)]
    raise SensitivityNotSupported(
        f"differentiate: the integral loss's {type(loss).__name__} (the fast path of large "
        "sheets) is not supported; use IntegralLoss(operator='dense') within the dense limit.")


class IntegralShapeOperator(ChainOperator):
    """The steady operator of a :class:`~simulator.thermal.steady.ThermalModel` ``tm`` with
    the integral loss at positions ``x`` (n, 3) [m], rebuilt there at its accurate levels,
    with its shape derivative (the interface of
    :class:`~simulator.sensitivity.chain.ChainOperator`).

    Attributes
    ----------
    L : (n_sheet, n_sheet) the loss conductance [W/K] on ``tm.integral.nodes``
    nonsmooth : list of str
    """

    def __init__(self, tm, x):
        self.tm, self.x = tm, np.asarray(x, float)
        self.nonsmooth = []
        self._conduction()
        self.nodes = tm.integral.nodes
        self.levels = [_Level(op, w, self.x) for op, w in loss_levels(tm.integral)]
        self.L = sum(lv.weight * lv.L for lv in self.levels)
        touch = np.flatnonzero(tm.integral.touching(self.x))
        touch = np.setdiff1d(touch, tm.fixed_nodes)
        if len(touch):
            self.nonsmooth.append(f"node(s) {touch.tolist()} touch the substrate plane (held "
                                  "at room temperature: the held set switches there)")
        if any(lv.pressed for lv in self.levels):
            self.nonsmooth.append("node(s) below the substrate plane (pressed onto it for "
                                  "the heat loss)")

    def matrix(self, nodes) -> sp.csr_matrix:
        """``A`` [W/K] on ``nodes`` (rows and columns), sparse (the loss block dense)."""
        n = self.tm.mesh.n_nodes
        full = np.zeros((n, n))
        full[np.ix_(self.nodes, self.nodes)] = self.L
        A = self.conduction_matrix() + sp.csr_matrix(full)
        return A[nodes][:, nodes].tocsr()

    def conductivity_derivative(self, rise) -> np.ndarray:
        """``d (A dT) / d k_env``: ``L dT / k_env`` (``S`` is proportional to ``1 / k``)."""
        out = np.zeros(self.tm.mesh.n_nodes)
        out[self.nodes] = self.L @ rise[self.nodes] / self.k_env
        return out

    def shape_jacobian(self, rise) -> sp.csr_matrix:
        """``d (A(x) dT) / dx`` [W/(K m)] for the fixed rise ``dT`` = ``rise`` (n,) [K], (n, 3n)
        (rows: nodes, columns: node-major coordinates); the loss's rows dense."""
        n = self.tm.mesh.n_nodes
        rows, cols, vals = (np.concatenate(a) for a in zip(*self.conduction_parts(rise)))
        J = sp.coo_matrix((vals, (rows, cols)), shape=(n, 3 * n)).tocsr()
        loss = np.zeros((n, 3 * n))
        loss[self.nodes] = sum(lv.weight * lv.jacobian(rise[self.nodes]) for lv in self.levels)
        return (J + sp.csr_matrix(loss)).tocsr()


class _Level:
    """One :class:`~simulator.thermal.integral.IntegralOperator` ``op`` (weight ``weight``)
    built at ``x``: its live sub-triangles, the factor of ``S`` and ``L``."""

    def __init__(self, op, weight, x):
        from . import SensitivityNotSupported

        self.op, self.weight = op, float(weight)
        self.sub, self.M, edges, flat, self.pressed = op.live_sub_triangles(x)
        live = np.ones(op.n_sub, bool) if flat is None else ~flat
        self.live = live
        s = len(op._bary)
        self.parent = np.repeat(op.triangles, s, axis=0)[live]               # (n_live, 3)
        self.bary = np.tile(op._bary, (len(op.triangles), 1, 1))[live]       # (n_live, 3, 3)
        if not len(self.sub):
            self.L, self.factor = np.zeros((len(op.nodes),) * 2), None
            return
        S, _ = single_layer_operator(self.sub, op.conductivity, op.plane, edges=edges)
        # S = C C^T (C lower), W = C^-1 M, L = W^T W: one BLAS thread, as the loss's own build
        out = dense_lapack.cholesky_loss(S, self.M, overwrite=True)
        if out is None:
            try:
                C = sla.cholesky(S, lower=True)
            except np.linalg.LinAlgError:
                raise SensitivityNotSupported(
                    "differentiate: the integral loss's single-layer operator is not positive "
                    "definite at this shape (parts of the sheet closer than a sub-triangle or "
                    "passing through each other)") from None
            W = sla.solve_triangular(C, self.M, lower=True)
            out = C, W, W.T @ W
        self.factor, self.W, L = out
        self.L = 0.5 * (L + L.T)

    def jacobian(self, rise_sheet) -> np.ndarray:
        """``d (L dT) / dx`` (n_sheet, 3 n_nodes) [W/(K m)] of this level at the rise
        ``rise_sheet`` on the operator's nodes: ``-M^T S^-1 D = -W^T (C^-1 D)``."""
        op = self.op
        if self.factor is None:
            return np.zeros((len(op.nodes), 3 * op.n_nodes))
        with dense_lapack.one_blas_thread():
            p = sla.solve_triangular(self.factor, self.W @ rise_sheet, lower=True, trans="T",
                                     check_finite=False)
            D = pair_derivative(self.sub, self.parent, self.bary, p, op.conductivity,
                                op.plane, op.n_nodes)
            return -(self.W.T @ sla.solve_triangular(self.factor, D, lower=True,
                                                     check_finite=False))


def pair_derivative(tri, parent, bary, p, conductivity, plane=None, n_nodes=None,
                    near: float = NEAR_FACTOR, compiled=None) -> np.ndarray:
    """``D = d(S p)/dx`` [K/(W m) W] at fixed ``p``: the derivative of the product of the
    symmetrised single-layer operator ``S`` (:func:`~simulator.thermal._single_layer.
    single_layer_operator`) of the sub-triangles ``tri`` (n, 3, 3) [m] with ``p`` (n,) [W],
    in the positions of the mesh nodes, (n, 3 n_nodes) (node-major coordinates).

    ``parent`` (n, 3): the mesh nodes of each sub-triangle's triangle; ``bary`` (n, 3, 3): the
    barycentric weights (corner, parent node) of its corners. Compiled when ``compiled``
    (default: when compiled kernels are selected, :mod:`simulator.sensitivity._integral_jit`),
    else numpy in blocks of rows (the checked reference)."""
    tri = np.asarray(tri, float)
    n = len(tri)
    n_nodes = int(parent.max()) + 1 if n_nodes is None else int(n_nodes)
    kappa = 1 / (4 * math.pi * conductivity)
    if compiled is None:
        compiled = _integral_jit.use_compiled()
    if compiled and _integral_jit.use_compiled():
        return _integral_jit.pair_derivative(tri, parent, bary, p, kappa, plane, n_nodes,
                                             near * (1 + TIE), MID_FACTOR, CLOSED_FORM_STEP)
    cbar = bary.mean(axis=1)                                              # (n, 3)
    c = tri.mean(axis=1)
    diam = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
    # node-major columns of each sub-triangle's parent nodes, (n, 9): (parent node b, coord k)
    cols = (3 * parent[:, :, None] + np.arange(3)).reshape(n, 9)
    # (n 9, 3 n_nodes): a (sub-triangle, parent node, coordinate) row to its node's column
    P = sp.csr_matrix((np.ones(9 * n), (np.arange(9 * n), cols.ravel())),
                      shape=(9 * n, 3 * n_nodes))
    sources = [(tri, c, 1.0, None)]
    if plane is not None:
        origin, normal = (np.asarray(v, float) for v in plane)
        R = np.eye(3) - 2 * np.outer(normal, normal)
        sources.append((mirror(tri, (origin, normal)), mirror(c, (origin, normal)), -1.0, R))
    D = np.zeros((n, 3 * n_nodes))
    for start in range(0, n, _BLOCK):
        rows = np.arange(start, min(start + _BLOCK, n))
        gc = np.zeros((len(rows), n, 3))               # d S'_ij / d c_i
        gv = np.zeros((len(rows), n, 3, 3))            # d S'_ij / d (corner a of j)
        for src, cs, sign, R in sources:
            a, b = _pair_gradients(c[rows], src, cs, diam, near, rows if R is None else None)
            if R is not None:                          # the image's corners are R v + t
                b = b @ R
            gc += sign * a
            gv += sign * b
        gc *= kappa
        gv *= kappa
        # to the parent nodes: the centroid's weights for c_i, the corners' for j
        gi = gc[:, :, None, :] * cbar[rows][:, None, :, None]               # (B, n, 3, 3)
        gj = np.einsum("jab,ijak->ijbk", bary, gv)                         # (B, n, 3, 3)
        half_p = 0.5 * p
        # rows i of the block: sum_j p_j / 2 (gi_ij -> parent(i), gj_ij -> parent(j))
        local = np.einsum("j,ijbk->ibk", half_p, gi).reshape(len(rows), 9)
        np.add.at(D, (rows[:, None], cols[rows]), local)
        D[rows] += (gj * half_p[None, :, None, None]).reshape(len(rows), 9 * n) @ P
        # rows j (every sub-triangle): sum_{i in block} p_i / 2 (gi_ij -> parent(i), gj_ij ->
        # parent(j))
        hp = half_p[rows]
        local = np.einsum("i,ijbk->jbk", hp, gj).reshape(n, 9)
        np.add.at(D, (np.arange(n)[:, None], cols), local)
        D += (gi * hp[:, None, None, None]).transpose(1, 0, 2, 3).reshape(n, 9 * len(rows)) \
            @ P[9 * rows[0]:9 * (rows[-1] + 1)]
    return D


def _pair_gradients(points, tri, centroid, diam, near, own=None):
    """``(d f / d p_i, d f / d v_ja)`` of ``f_ij`` = the mean of ``1 / |p_i - y|`` over
    triangle j (``tri`` (n, 3, 3), its ``centroid`` and diameter ``diam``), for every point
    ``points`` (B, 3) and triangle, by the operator's rule: (B, n, 3) and (B, n, 3, 3).
    ``own`` (B,): the triangle whose centroid point b is (None: none); for that pair the
    total derivative in the corners, the point moving with them (the self-integral is
    smooth along the triangle, not in a point leaving its plane)."""
    B, n = len(points), len(tri)
    diff = points[:, None, :] - centroid[None, :, :]
    dist = np.sqrt(np.einsum("ijk,ijk->ij", diff, diff))
    near = near * (1 + TIE)
    close = dist < near * diam[None, :]
    mid = ~close & (dist < MID_FACTOR * near * diam[None, :])
    gc = np.zeros((B, n, 3))
    gv = np.zeros((B, n, 3, 3))
    far = ~close & ~mid
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.where(far[..., None], diff / dist[..., None] ** 3, 0.0)
    gc -= g
    gv += g[:, :, None, :] / 3
    i, j = np.nonzero(mid)
    if len(i):
        w = np.full((3, 3), 1 / 6) + np.eye(3) / 2                        # (q, a): 2/3, 1/6
        y = np.einsum("qa,pak->pqk", w, tri[j])                          # (P, 3, 3)
        d = points[i][:, None, :] - y
        r3 = np.linalg.norm(d, axis=2) ** 3
        e = d / r3[..., None] / 3                                          # (P, q, 3)
        gc[i, j] = -e.sum(axis=1)
        gv[i, j] = np.einsum("qa,pqk->pak", w, e)
    if own is not None:
        close[np.arange(B), own] = False
        gv[np.arange(B), own] = _self_gradients(tri[own], diam[own])
    i, j = np.nonzero(close)
    if len(i):
        a, b = _closed_form_gradients(points[i], tri[j], diam[j])
        gc[i, j], gv[i, j] = a, b
    return gc, gv


def _mean_potential(points, tri) -> np.ndarray:
    """``int_T 1 / |p - y| dS / A_T`` of points (P, 3) and triangles (P, 3, 3)."""
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    return triangle_potential(points, tri) / area


def _moved(coords, h):
    """``coords`` (P, K, 3) with each of its 3K coordinates moved by +-h (P,): (P, 2, 3K, K,
    3)."""
    P, K = coords.shape[:2]
    eye = np.eye(3 * K).reshape(3 * K, K, 3)
    return coords[:, None, None] + np.array([1.0, -1.0])[None, :, None, None, None] \
        * h[:, None, None, None, None] * eye[None, None]


def _self_gradients(tri, diam):
    """Central differences of the self term ``f(v) = int_T 1 / |c - y| dS / A_T``, ``c`` the
    centroid of ``T`` = ``tri`` (P, 3, 3), in the corners: (P, 3, 3)."""
    P = len(tri)
    h = CLOSED_FORM_STEP * diam
    t = _moved(tri, h).reshape(-1, 3, 3)
    f = _mean_potential(t.mean(axis=1), t).reshape(P, 2, 9)
    return ((f[:, 0] - f[:, 1]) / (2 * h[:, None])).reshape(P, 3, 3)


def _closed_form_gradients(points, tri, diam):
    """Central differences of ``int_T 1 / |p - y| dS / A_T`` (the closed form,
    :func:`~simulator.thermal._single_layer.triangle_potential`) in the point (P, 3) and the
    triangle's corners (P, 3, 3), step :data:`CLOSED_FORM_STEP` times ``diam`` (P,)."""
    P = len(points)
    h = CLOSED_FORM_STEP * diam                                           # (P,)
    coords = np.concatenate([points[:, None, :], tri], axis=1)           # (P, 4, 3)
    moved = _moved(coords, h).reshape(-1, 4, 3)
    f = _mean_potential(moved[:, 0], moved[:, 1:]).reshape(P, 2, 12)
    g = ((f[:, 0] - f[:, 1]) / (2 * h[:, None])).reshape(P, 4, 3)
    return g[:, 0], g[:, 1:]
