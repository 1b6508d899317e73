"""The integral heat loss at any size: the single-layer operator never formed (theory 4.7).

:class:`~simulator.thermal.integral.IntegralOperator` forms the dense collocation matrix ``S``
(``n_s x n_s``, ``n_s = m^2 n_tri``) and the dense loss conductance ``L = M^T S^-1 M``: memory
``O(n_s^2)``, factorisation ``O(n_s^3)``. Above a size the
same discrete model is solved without forming either (above the dense limit
``MAX_SUB_TRIANGLES`` with ``IntegralLoss(operator="auto")``, the default):

* :class:`FastSingleLayer` applies the symmetrised ``S`` to a vector: the centroid rule
  ``A_j G(c_i, c_j)`` of every pair (the far field: a sum of point charges at the centroids,
  their mirror images with the opposite sign above a substrate plane) by the fast multipole
  method (``fmm3dpy``, the Flatiron FMM; a direct sum below :data:`DIRECT_MAX`), plus a
  sparse correction ``(V_ij - A_j / |c_i - c_j|) / A_j`` on the pairs closer than
  :data:`NEAR_RADIUS` source diameters, where the dense matrix uses the closed form or the
  3-point rule (:func:`~simulator.thermal._single_layer.pair_values`: the same entries).
  Beyond that radius the dense matrix *is* the centroid rule, so the two operators differ by
  the FMM's tolerance only.
* :func:`coupled_solver` solves ``(K + sum_l w_l M_l^T S_l^-1 M_l) T = q`` (one term per level
  of the operator: the plain operator, or the Richardson pair ``3 L_3 - 2 L_2``) level by
  level, each as the symmetric saddle system ``[[K, M^T], [M, -S]] [T; p] = [q; 0]`` by MINRES
  with a two-level preconditioner (:mod:`simulator.thermal.integral_schwarz`: zero-sum patch
  blocks of ``S`` and the patches' constants as a coarse space, and the Schur complement of
  that approximation by the Woodbury identity): some 50 iterations per level whatever the
  size. The Richardson pair's rises are extrapolated from the levels' solutions and corrected
  once towards the operators' extrapolation.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..linalg.ladder import factorize
from ._single_layer import mirror, pair_values

__all__ = ["FastSingleLayer", "FastIntegralOperator", "coupled_solver", "NEAR_RADIUS",
           "PRECONDITIONER_RADIUS", "FMM_EPS", "DIRECT_MAX", "SOLVE_RTOL", "GRID_MIN",
           "FAR_FIELDS"]

logger = logging.getLogger(__name__)

#: Pairs closer than this many diameters (the larger of the two) get the exact entry of the
#: dense matrix: the dense matrix uses the closed form up to 1.5 and the 3-point rule up to 3
#: source diameters, the centroid rule (the FMM's kernel) beyond.
NEAR_RADIUS = 3.0
#: Pairs of the preconditioner's sparse ``S`` (the larger of the two diameters).
PRECONDITIONER_RADIUS = 1.0
#: Relative tolerance of the FMM's far field (FMM3D over-delivers: 1e-8 of the largest potential
#: measured on flat sheets of 16,000-60,000 points, at half the time of 1e-7).
FMM_EPS = 1e-5
#: Up to this many sub-triangles (with their images) the far field is summed directly (the
#: compiled sum beats the FMM up to about 16,000 points, measured on the shared 2-core machine).
DIRECT_MAX = 15000
#: Above this many sub-triangles the far field is summed on a grid (``far_field="auto"``;
#: :mod:`simulator.thermal.integral_grid`): below, the compiled direct sum is exact and about
#: as fast.
GRID_MIN = 6000
#: The far-field methods of :class:`FastSingleLayer` (``far_field``).
FAR_FIELDS = ("auto", "direct", "grid", "fmm")
#: Above this many sub-triangles (all levels) the fast path warns of its cost (minutes per
#: solve: the near field, the grid's pairs and the preconditioners grow with the
#: sub-triangles; the 36 x 36-cell Miura sheet has 101,520 at its large-sheet levels).
SLOW_SUB_TRIANGLES = 150000
#: :meth:`FastIntegralOperator.unchanged` checks every node pair closer than this many
#: sub-triangle diameters ...
CHECK_RADIUS = 4.0
#: ... and every pair of a subset of about this many nodes spread over the sheet.
CHECK_NODES = 1500
#: Relative residual of the MINRES solve (in the preconditioned norm).
SOLVE_RTOL = 1e-10


_direct = None
_no_fmm_warned = False


def _build_direct():
    """The compiled direct sum (numba, parallel over the targets; coordinates as three
    contiguous arrays and the self term skipped by splitting the loop, so that the inner loops
    vectorise; fastmath: within 1e-14 of numpy, 2.6 times faster than one loop with a test)."""
    from numba import njit, prange

    def kernel(xs, ys, zs, charges, out):
        n = xs.shape[0]
        for i in prange(out.shape[0]):
            px, py, pz = xs[i], ys[i], zs[i]
            acc = 0.0
            for j in range(i):
                dx, dy, dz = px - xs[j], py - ys[j], pz - zs[j]
                acc += charges[j] / math.sqrt(dx * dx + dy * dy + dz * dz)
            for j in range(i + 1, n):
                dx, dy, dz = px - xs[j], py - ys[j], pz - zs[j]
                acc += charges[j] / math.sqrt(dx * dx + dy * dy + dz * dz)
            out[i] = acc
    return njit("void(f8[::1], f8[::1], f8[::1], f8[::1], f8[::1])", parallel=True,
                fastmath=True)(kernel)


def direct_potential(points, charges, compiled=None, n_targets=None) -> np.ndarray:
    """``sum_{j != i} charges_j / |points_i - points_j|`` at the first ``n_targets`` points
    (default all), (n_targets,), summed directly: compiled when ``compiled`` (default: when
    the numba backend is selected), numpy otherwise (the checked reference)."""
    global _direct
    from . import _single_layer_jit

    points = np.asarray(points, float)
    charges = np.ascontiguousarray(charges, float)
    n_t = len(points) if n_targets is None else int(n_targets)
    if compiled is None:
        compiled = _single_layer_jit.use_compiled()
    if compiled:
        if _direct is None:
            from .._jit import compile_kernel

            _direct = compile_kernel("direct potential sum", _build_direct, "using numpy") \
                or False
        if _direct is not False:
            out = np.empty(n_t)
            _direct(*(np.ascontiguousarray(points[:, k]) for k in range(3)), charges, out)
            return out
    from scipy.spatial.distance import cdist

    out = np.empty(n_t)
    for a in range(0, n_t, 1024):
        d = cdist(points[a:min(a + 1024, n_t)], points)
        idx = np.arange(a, min(a + 1024, n_t))
        d[idx - a, idx] = np.inf
        out[a:a + 1024] = (1.0 / d) @ charges
    return out


def _far_method(far_field: str, c, area, plane) -> str:
    """The far-field method "direct", "grid" or "fmm" of :class:`FastSingleLayer`'s
    ``far_field`` option for the centroids ``c`` (n, 3) of sub-triangles of areas ``area``."""
    if far_field not in FAR_FIELDS:
        raise ValueError(f"far_field = {far_field!r}: use one of {', '.join(FAR_FIELDS)}")
    if far_field != "auto":
        return far_field
    if len(c) <= GRID_MIN:
        return "fmm"
    from .integral_grid import MAX_GRID, SPLIT, grid_size

    nodes = grid_size(c, SPLIT * math.sqrt(area.mean()), plane)
    if nodes <= MAX_GRID:
        return "grid"
    logger.info("integral loss (fast): the far field's grid would have %d nodes (more than "
                "MAX_GRID = %d: a folded sheet's bounding box); the FMM sums it", nodes, MAX_GRID)
    return "fmm"


def _fmm_potential(points, charges, eps, n_targets=None, direct=False):
    """``sum_{j != i} charges_j / |points_i - points_j|`` at the first ``n_targets`` points
    (default all), (n_targets,): directly with ``direct`` or up to :data:`DIRECT_MAX` points,
    else by the FMM (``fmm3dpy``) at tolerance ``eps``."""
    global _no_fmm_warned
    if direct or len(points) <= DIRECT_MAX:
        return direct_potential(points, charges, n_targets=n_targets)
    try:
        import fmm3dpy
    except ImportError:
        if not _no_fmm_warned:
            _no_fmm_warned = True
            logger.warning("the integral loss's fast path: fmm3dpy is not installed (pip install "
                           "'etorigami[fast]'); the far field of %d points is summed directly "
                           "(quadratic in the size)", len(points))
        return direct_potential(points, charges, n_targets=n_targets)

    sources = np.ascontiguousarray(points.T)
    if n_targets is None or n_targets == len(points):
        res = fmm3dpy.lfmm3d(eps=eps, sources=sources, charges=charges, pg=1)
        return 4 * math.pi * res.pot                # FMM3D's kernel is 1 / (4 pi r)
    # the targets coincide with the first sources: FMM3D drops coincident pairs
    res = fmm3dpy.lfmm3d(eps=eps, sources=sources, charges=charges,
                         targets=np.ascontiguousarray(sources[:, :n_targets]), pgt=1)
    return 4 * math.pi * res.pottarg


class FastSingleLayer:
    """The symmetrised collocation matrix ``S = (S_d + S_d^T) / 2`` [K/W] of
    :func:`~simulator.thermal._single_layer.collocation_matrix` (``S_d = V / A``), applied
    without being formed.

    Parameters
    ----------
    sub : (n, 3, 3) array
        Sub-triangle corners [m].
    conductivity : float
        Medium conductivity [W/(m K)].
    plane : (origin (3,), unit normal (3,)), optional
        Isothermal substrate plane (image method).
    eps : float
        Relative tolerance of the far field (FMM).
    far_field : {"auto", "direct", "grid", "fmm"}
        How the centroid rule's far field is summed: directly (compiled), on a grid
        (:class:`~simulator.thermal.integral_grid.GridFarField`, about 1e-4 of the potential)
        or by the FMM (``fmm3dpy`` at ``eps``; directly up to :data:`DIRECT_MAX` points).
        "auto": "fmm" up to :data:`GRID_MIN` sub-triangles (that is, directly), "grid" above
        ("fmm" where the grid would exceed :data:`~simulator.thermal.integral_grid.MAX_GRID`
        nodes).
    """

    def __init__(self, sub, conductivity: float, plane=None, eps: float = FMM_EPS,
                 far_field: str = "auto"):
        from scipy.spatial import cKDTree

        sub = np.ascontiguousarray(sub, float)
        self.n = n = len(sub)
        self.eps, self.scale = float(eps), 1.0 / (4 * math.pi * float(conductivity))
        c = sub.mean(axis=1)
        area = 0.5 * np.linalg.norm(np.cross(sub[:, 1] - sub[:, 0], sub[:, 2] - sub[:, 0]),
                                    axis=1)
        diam = np.linalg.norm(sub - np.roll(sub, 1, axis=1), axis=2).max(axis=1)
        self.centroids, self.area, self.diameter = c, area, diam
        self.plane = None if plane is None else (np.asarray(plane[0], float),
                                                 np.asarray(plane[1], float))
        tree = cKDTree(c)
        rows, cols, d = _pairs(tree, c, diam, NEAR_RADIUS)     # the self pairs first
        V = pair_values(c, sub, c, area, diam, rows, cols)
        inverse, point = np.zeros(len(d)), np.zeros(len(d))    # 0 for the self pairs
        with np.errstate(divide="ignore"):
            inverse[n:] = 1.0 / d[n:]
            point[n:] = area[cols[n:]] / d[n:]
        corr = (V - point) / area[cols]
        pre_rows, pre_cols = rows, cols
        pre = inverse + corr
        keep = d < PRECONDITIONER_RADIUS * np.maximum(diam[rows], diam[cols])
        if self.plane is not None:
            cm, subm = mirror(c, self.plane), mirror(sub, self.plane)
            self.images = cm
            ir, ic = _pairs_to(tree, cm, c, diam, NEAR_RADIUS)
            di = np.linalg.norm(c[ir] - cm[ic], axis=1)
            Vi = pair_values(c, subm, cm, area, diam, ir, ic)
            icorr = -(Vi - area[ic] / di) / area[ic]
            rows, cols = np.concatenate([rows, ir]), np.concatenate([cols, ic])
            corr = np.concatenate([corr, icorr])
            # the preconditioner's entries: the point images of its pairs, and the corrections
            pre = pre - 1.0 / np.linalg.norm(c[pre_rows] - cm[pre_cols], axis=1)
            pre = _add_pairs(pre_rows, pre_cols, pre, ir, ic, icorr, n)
        N = sp.csr_matrix((corr, (rows, cols)), shape=(n, n))
        #: symmetrised near-field correction [K/W] (sparse)
        self.near = (0.5 * (N + N.T)).tocsr() * self.scale
        P = sp.csr_matrix((pre[keep], (pre_rows[keep], pre_cols[keep])), shape=(n, n))
        #: ``S`` on the preconditioner's pairs [K/W] (sparse, symmetric)
        self.near_block = (0.5 * (P + P.T)).tocsr() * self.scale
        #: the diagonal of ``S`` [K/W]
        self.diagonal = self.near_block.diagonal()
        #: how the far field is summed ("direct", "grid" or "fmm"; :meth:`far`)
        self.far_field = _far_method(far_field, c, area, self.plane)
        self._grid = None
        if self.far_field == "grid":
            from .integral_grid import SPLIT, GridFarField

            self._grid = GridFarField(c, SPLIT * math.sqrt(area.mean()), self.plane)

    def far(self, p) -> np.ndarray:
        """The centroid-rule part ``sum_{j != i} p_j G(c_i, c_j)`` [K] (images included) of
        heats ``p`` (n,) [W]."""
        p = np.asarray(p, float)
        if self._grid is not None:
            return self.scale * self._grid.potential(p)
        direct = self.far_field == "direct"
        if self.plane is None:
            return self.scale * _fmm_potential(self.centroids, p, self.eps, direct=direct)
        both = np.concatenate([self.centroids, self.images])
        return self.scale * _fmm_potential(both, np.concatenate([p, -p]), self.eps, self.n,
                                           direct=direct)

    def matvec(self, p) -> np.ndarray:
        """``S p`` [K] for heats ``p`` (n,) [W]."""
        return self.far(p) + self.near @ np.asarray(p, float)

    def block(self, rows, cols=None) -> np.ndarray:
        """``S`` [K/W] on the sub-triangles ``rows`` x ``cols`` (default ``rows``), dense."""
        rows = np.asarray(rows, np.int64)
        cols = rows if cols is None else np.asarray(cols, np.int64)
        return self.point_block(rows, cols) + self.near[rows][:, cols].toarray()

    def point_block(self, rows, cols) -> np.ndarray:
        """The centroid rule of ``S`` [K/W] on ``rows`` x ``cols`` (images included, no self
        term): ``S`` without its sparse near-field part, dense."""
        c = self.centroids
        d = np.linalg.norm(c[rows][:, None] - c[cols][None], axis=2)
        with np.errstate(divide="ignore"):
            out = np.where(rows[:, None] == cols[None], 0.0, 1.0 / d)
        if self.plane is not None:
            out -= 1.0 / np.linalg.norm(c[rows][:, None] - self.images[cols][None], axis=2)
        return self.scale * out

    def point_blocks(self, rows, cols=None) -> np.ndarray:
        """:meth:`point_block` of each row of ``rows`` (b, k) with the same row of ``cols``
        (b, l) (default ``rows``), (b, k, l) [K/W]: the blocks of many patches at once."""
        rows = np.asarray(rows, np.int64)
        cols = rows if cols is None else np.asarray(cols, np.int64)
        c = self.centroids
        d = np.linalg.norm(c[rows][:, :, None] - c[cols][:, None], axis=3)
        with np.errstate(divide="ignore"):
            out = np.where(rows[:, :, None] == cols[:, None], 0.0, 1.0 / d)
        if self.plane is not None:
            out -= 1.0 / np.linalg.norm(c[rows][:, :, None] - self.images[cols][:, None],
                                        axis=3)
        return self.scale * out

    def dense(self) -> np.ndarray:
        """``S`` as a dense array (columns by :meth:`matvec`; for checks on small sets)."""
        return np.column_stack([self.matvec(e) for e in np.eye(self.n)])


def _pairs(tree, c, diam, radius):
    """Index pairs (rows, cols), the ``n`` self pairs ``i == j`` first, then both orders, of
    centroids closer than ``radius`` times the larger of their diameters, and their
    distances."""
    pairs = tree.query_pairs(radius * diam.max(), output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    d = np.linalg.norm(c[i] - c[j], axis=1)
    k = d < radius * np.maximum(diam[i], diam[j])
    i, j, d = i[k], j[k], d[k]
    own = np.arange(len(c))
    return np.concatenate([own, i, j]), np.concatenate([own, j, i]), \
        np.concatenate([np.zeros(len(c)), d, d])


def _pairs_to(tree, images, c, diam, radius):
    """Pairs (rows i, cols j) with the image of ``j`` closer to centroid ``i`` than
    ``radius`` times the larger diameter (the image part is symmetric in i, j)."""
    from scipy.spatial import cKDTree

    hits = cKDTree(images).query_ball_tree(tree, radius * diam.max())
    cols = np.repeat(np.arange(len(images)), [len(h) for h in hits])
    rows = np.fromiter((i for h in hits for i in h), np.int64, len(cols))
    d = np.linalg.norm(c[rows] - images[cols], axis=1)
    k = d < radius * np.maximum(diam[rows], diam[cols])
    return rows[k], cols[k]


def _add_pairs(rows, cols, values, ar, ac, av, n):
    """``values`` on the pairs (rows, cols) plus ``av`` where (ar, ac) is one of them."""
    key = rows * n + cols
    order = np.argsort(key)
    extra = ar * n + ac
    pos = np.searchsorted(key, extra, sorter=order)
    pos = np.minimum(pos, len(key) - 1)
    hit = key[order[pos]] == extra
    out = values.copy()
    np.add.at(out, order[pos[hit]], av[hit])
    return out


def coupled_solver(K, terms, rtol: float | None = None, maxiter: int = 2000,
                   preconditioners=None):
    """Solver of ``(K + L) T = q``, ``L = sum_l w_l M_l^T S_l^-1 M_l``, without forming ``L``.

    One level (``w = 1``): the symmetric saddle system ``[[K, M^T], [M, -S]] [T; p] = [q; 0]``
    by MINRES with the two-level preconditioner
    (:class:`~simulator.thermal.integral_schwarz.TwoLevelPreconditioner`). Several levels
    (the Richardson pair, ``sum_l w_l = 1``): each level's system solved so, the rises
    extrapolated, ``T_se = sum_l w_l T_l`` (the solutions' extrapolation: within 0.19-0.50 %
    of the largest rise of the operators' on 5 x 5-cell Miura sheets, free and over a
    plane), and corrected once towards the operators' extrapolation (its inner
    ``corrected``: two more single-layer solves by CG and one saddle solve); a saddle system of
    both levels, of opposite weights, needs some 200-240 iterations even with these blocks.

    Parameters
    ----------
    K : (n, n) sparse matrix
        Symmetric positive semi-definite conduction [W/K] of the unknown nodes.
    terms : list of (w, M, S)
        Weight ``w`` (float), interpolation ``M`` (n_l, n) sparse [-] of the live
        sub-triangles at the unknown nodes, and ``S`` (:class:`FastSingleLayer`, n_l).
    rtol : float
        Relative residual of MINRES (preconditioned norm).
    preconditioners : list of TwoLevelPreconditioner, optional
        One per level, built before (with a nearby ``K``: a kept operator at a new shape);
        default: built here.

    Returns
    -------
    solver : callable
        ``q (n,), start -> (T (n,), [(T_l, p_l)], [h_l])``: the rises [K], each level's own
        rises and heats [W] (``S_l p_l = M_l T_l``; ``start``, optional: guesses of them) and
        each level's heats at the rises ``T`` (``S_l h_l = M_l T``); its attribute
        ``preconditioners`` the levels' preconditioners.
    """
    from .integral_schwarz import TwoLevelPreconditioner

    rtol = SOLVE_RTOL if rtol is None else float(rtol)
    K = K.tocsr()
    n = K.shape[0]
    if preconditioners is None:
        preconditioners = [TwoLevelPreconditioner(S, K, M) for _, M, S in terms]
    levels = [(w, M, S, pre) for (w, M, S), pre in zip(terms, preconditioners)]

    def level_solve(M, S, pre, q, start):
        total = n + S.n

        def matvec(y):
            T, p = y[:n], y[n:]
            return np.concatenate([K @ T + M.T @ p, M @ T - S.matvec(p)])

        def precondition(y):
            return np.concatenate([pre.rise(y[:n]), pre.heat(y[n:])])

        A = spla.LinearOperator((total, total), matvec=matvec, dtype=float)
        P = spla.LinearOperator((total, total), matvec=precondition, dtype=float)
        rhs = np.concatenate([q, np.zeros(S.n)])
        y0 = None if start is None else np.concatenate(start)
        if y0 is not None:               # kept only if it cuts the residual (MINRES's norm)
            r = rhs - matvec(y0)
            if r @ precondition(r) >= rhs @ precondition(rhs):
                y0 = None
        count = [0]

        def cb(_):
            count[0] += 1
        y, info = spla.minres(A, rhs, x0=y0, M=P, rtol=rtol, maxiter=maxiter, callback=cb)
        if info != 0:
            logger.warning("integral loss (fast): MINRES stopped after %d iterations without "
                           "reaching rtol %.1e", count[0], rtol)
        logger.debug("integral loss (fast): %d unknowns, %d MINRES iterations%s", total,
                     count[0], "" if y0 is None else " (from the last solution)")
        return y[:n], y[n:]

    def heat_solve(S, pre, u, rtol=1e-8):
        """``S^-1 u`` [W] of potentials ``u`` [K] by conjugate gradients (``P_S``)."""
        A = spla.LinearOperator((S.n, S.n), matvec=S.matvec, dtype=float)
        P = spla.LinearOperator((S.n, S.n), matvec=pre.heat, dtype=float)
        p, info = spla.cg(A, u, M=P, rtol=rtol, maxiter=maxiter)
        if info != 0:
            logger.warning("integral loss (fast): CG on the single layer did not converge")
        return p

    def corrected(q, out):
        """The operators' extrapolation from the solutions' (two levels, ``d = T_1 - T_2``):
        the residual of ``T_se = w_1 T_1 + w_2 T_2`` is ``r = w_1 w_2 (L_1 - L_2) d``; one
        correction ``(K + L_1)^-1 r`` leaves a second-order error. The levels' heats at the
        corrected rises, ``S_l^-1 M_l T``, follow from ``h_l = S_l^-1 M_l d`` and the
        correction's."""
        (w1, M1, S1, pre1), (w2, M2, S2, pre2) = levels
        (T1, p1), (T2, p2) = out
        d = T1 - T2
        h1, h2 = heat_solve(S1, pre1, M1 @ d), heat_solve(S2, pre2, M2 @ d)
        r = w1 * w2 * (M1.T @ h1 - M2.T @ h2)
        delta, g1 = level_solve(M1, S1, pre1, r, None)
        g2 = heat_solve(S2, pre2, M2 @ delta)
        T = w1 * T1 + w2 * T2 + delta
        return T, [p1 - w2 * h1 + g1, p2 + w1 * h2 + g2]

    def solver(q, start=None):
        q = np.asarray(q, float)
        if not np.any(q):
            zero = [(np.zeros(n), np.zeros(S.n)) for _, _, S, _ in levels]
            return np.zeros(n), zero, [p for _, p in zero]
        out = [level_solve(M, S, pre, q, None if start is None else start[k])
               for k, (_, M, S, pre) in enumerate(levels)]
        if len(levels) == 1:
            return out[0][0], out, [out[0][1]]
        if len(levels) == 2:
            T, heats = corrected(q, out)
            return T, out, heats
        T = sum(w * T_l for (w, _, _, _), (T_l, _) in zip(levels, out))
        return T, out, [p for _, p in out]
    solver.preconditioners = preconditioners
    return solver


def _multiple(q, last, tol: float = 1e-12):
    """``a`` with ``q = a q_last`` (``last[0]`` is ``q_last``) to ``tol`` of ``|q|`` (largest
    entry), else None; with ``tol = inf`` the least-squares ``a`` (None if it is 0)."""
    if last is None or last[0].shape != q.shape:
        return None
    q0 = last[0]
    den = float(q0 @ q0)
    if den == 0:
        return None
    a = float(q @ q0) / den
    if tol == np.inf:
        return a if a != 0 else None
    return a if np.abs(q - a * q0).max() <= tol * np.abs(q).max() else None


class FastIntegralOperator:
    """The integral loss operator of one mesh's sheet solved by :func:`coupled_solver`: one
    :class:`FastSingleLayer` per level, ``L = sum_l w_l M_l^T S_l^-1 M_l`` never formed.

    The levels are those of the dense model (:func:`~simulator.thermal.integral_levels.
    integral_operator`): ``[(1, m)]`` for the plain operator, ``[(m / (m - c), m),
    (-c / (m - c), c)]`` for the Richardson extrapolation. The operator is kept at a new
    shape within ``shape_tol`` (:meth:`unchanged`) and rebuilt otherwise; the substrate rule (touching nodes held, sub-triangles in the plane left out) is that of
    :class:`~simulator.thermal.integral.IntegralOperator`.

    Parameters
    ----------
    triangles : (n_tri, 3) int array
    n_nodes : int
    conductivity : float
        k_env [W/(m K)].
    levels : list of (weight, refinement)
    plane : (origin (3,), unit normal (3,)), optional
    eps : float
        FMM tolerance.
    shape_tol : float
        The operator (near field, far field, preconditioners) is kept at a new shape while no
        distance between sheet nodes has changed by more than this fraction of itself (at
        least of the mean sub-triangle diameter) and no height over the plane by more than a
        quarter of it (:meth:`unchanged`, the rule of
        :class:`~simulator.thermal.integral.IntegralOperator`); 0: rebuilt at every shape.
    """

    #: marks the fast path for :class:`~simulator.thermal.steady.ThermalModel`
    fast = True

    def __init__(self, triangles, n_nodes: int, conductivity: float, levels, plane=None,
                 eps: float = FMM_EPS, shape_tol: float = 0.0):
        from ._single_layer import subdivision

        self.triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
        self.n_nodes, self.conductivity, self.plane = int(n_nodes), float(conductivity), plane
        self.eps, self.shape_tol = float(eps), float(shape_tol)
        self.levels = [(float(w), int(m)) for w, m in levels]
        self.nodes = np.unique(self.triangles)
        #: number of operator builds so far (a diagnostic)
        self.builds = 0
        self._bary, self._M = [], []
        n_tri = len(self.triangles)
        for _, m in self.levels:
            bary, centroids = subdivision(m)
            s = len(centroids)
            rows = np.repeat(np.arange(n_tri * s), 3)
            cols = np.repeat(self.triangles, s, axis=0).ravel()
            vals = np.tile(centroids, (n_tri, 1)).ravel()
            self._bary.append(bary)
            self._M.append(sp.csr_matrix((vals, (rows, cols)), shape=(n_tri * s, self.n_nodes)))
        self.n_sub = sum(M.shape[0] for M in self._M)
        from .integral_levels import describe_levels

        level = logging.WARNING if self.n_sub > SLOW_SUB_TRIANGLES else logging.INFO
        logger.log(level, "the integral heat loss on %d triangles: %s, %d sub-triangles, above "
                   "the dense limit: the fast path (theory 4.7)%s", n_tri,
                   describe_levels(self.levels), self.n_sub,
                   "; slow at this size (minutes per solve): a lower IntegralLoss.refinement "
                   "or the chain model is much faster" if level == logging.WARNING else "")
        self._built = None                  # (positions, [(w, M_live, S)])
        self._last = None   # (unknown nodes, rise, [(T_l, p_l)], q, [h_l]) of the last solve
        self._pre = None    # (terms, unknown nodes, preconditioners) of the last solver

    def _heights(self, x):
        """Heights over the substrate plane [m] and the touch tolerance [m]."""
        from .integral import plane_heights

        return plane_heights(x, self.plane, self.nodes)

    def touching(self, x) -> np.ndarray:
        """Nodes on (or below) the substrate plane, (n_nodes,) bool (the rule of
        :meth:`~simulator.thermal.integral.IntegralOperator.touching`)."""
        h, tol = self._heights(np.asarray(x, float))
        return np.zeros(self.n_nodes, bool) if h is None else h <= tol

    def _build(self, x):
        """``[(w, M_live (n_live, n_nodes), S)]`` at positions ``x`` (and the mean
        sub-triangle diameter of the finest level, for :meth:`unchanged`)."""
        h, tol = self._heights(x)
        xp = x
        if h is not None and np.any(h < -tol):
            logger.warning("%d node(s) up to %.3g m below the substrate plane: pressed onto it "
                           "for the heat loss", int((h < -tol).sum()), float(-h.min()))
            xp = x - np.minimum(h, 0.0)[:, None] * np.asarray(self.plane[1], float)
            h = np.maximum(h, 0.0)
        corners = xp[self.triangles]
        terms = []
        for (w, _), bary, M in zip(self.levels, self._bary, self._M):
            sub = np.einsum("sab,tbk->tsak", bary, corners).reshape(-1, 3, 3)
            live = np.ones(len(sub), bool)
            if h is not None:
                corner_h = np.einsum("sab,tb->tsa", bary, h[self.triangles]).reshape(-1, 3)
                live = ~np.all(corner_h <= tol, axis=1)
            if live.any():
                terms.append((w, M[live], FastSingleLayer(sub[live], self.conductivity,
                                                          self.plane, self.eps)))
        self._size = float(min((S.diameter.mean() for _, _, S in terms), default=0.0))
        self.builds += 1
        logger.debug("integral loss (fast): operator built (%d so far)", self.builds)
        return terms

    def terms(self, x):
        """The levels at positions ``x`` (n, 3) [m], built once per shape (kept within
        ``shape_tol``, :meth:`unchanged`)."""
        x = np.asarray(x, float)
        if self._built is None or not self.unchanged(x):
            self._built = (x.copy(), self._build(x))
        return self._built[1]

    def unchanged(self, x) -> bool:
        """Whether the operator built at the last positions ``x0`` is kept at ``x`` (n, 3)
        [m]: the same positions, or, with ``shape_tol`` > 0, the distances between sheet
        nodes changed by at most ``shape_tol`` times the larger of the distance and the mean
        sub-triangle diameter, and twice the heights over the plane by at most a quarter of
        that (``HEIGHT_SCALE``; at least 1 % of the diameter). The pairs checked: all pairs
        closer than :data:`CHECK_RADIUS` diameters, and all pairs of a subset of
        :data:`CHECK_NODES` nodes spread over the sheet (a far distance changes smoothly
        with the shape; every pair of 14,000 nodes would be 100 million)."""
        x0 = self._built[0]
        if np.array_equal(x0, x):
            return True
        if self.shape_tol == 0:
            return False
        from scipy.spatial import cKDTree
        from .integral import HEIGHT_SCALE

        tol, size = self.shape_tol, self._size
        p0, p = x0[self.nodes], x[self.nodes]
        if self.plane is not None:
            o, nrm = (np.asarray(v, float) for v in self.plane)
            h0, h = 2 * np.abs((p0 - o) @ nrm), 2 * np.abs((p - o) @ nrm)
            if np.any(np.abs(h - h0) > tol * HEIGHT_SCALE * np.maximum(h0, 0.01 * size)):
                return False
        i, j = cKDTree(p0).query_pairs(CHECK_RADIUS * size, output_type="ndarray").T
        step = max(1, len(p0) // CHECK_NODES)
        a, b = np.triu_indices(len(p0[::step]), 1)
        i, j = np.concatenate([i, a * step]), np.concatenate([j, b * step])
        d0 = np.linalg.norm(p0[i] - p0[j], axis=1)
        d = np.linalg.norm(p[i] - p[j], axis=1)
        return bool(np.all(np.abs(d - d0) <= tol * np.maximum(d0, size)))

    def solver(self, x, K, unknown):
        """Solver ``q (n_unknown,) -> rise (n_unknown,)`` [W -> K] of ``(K + L) T = q`` on the
        ``unknown`` nodes (the free nodes not touching the substrate) at positions ``x``;
        ``K`` (n_unknown, n_unknown) sparse conduction [W/K]."""
        unknown = np.asarray(unknown, np.int64)
        terms = [(w, M[:, unknown].tocsr(), S) for w, M, S in self.terms(x)]
        if not terms:                      # the whole sheet lies on the substrate
            from ..linalg.ladder import factorize as _factorize

            return _factorize(K.tocsr(), kind="spd", dense_limit=400).solve
        pre = None
        if self._pre is not None and self._pre[0] is self._built[1] \
                and np.array_equal(self._pre[1], unknown):
            pre = self._pre[2]           # a kept operator: its preconditioners, K nearby
        solve = coupled_solver(K, terms, preconditioners=pre)
        self._pre = (self._built[1], unknown, solve.preconditioners)
        sizes = [M.shape[0] for _, M, _ in terms]
        shape = [None]                       # (q, rise, [p_l]) of the last solve at this shape

        def solver(q):
            q = np.asarray(q, float)
            if q.ndim == 2:
                return np.column_stack([solver(c) for c in q.T])
            scale, last = _multiple(q, shape[0]), self._last
            if scale is not None:            # the system is linear: a multiple of the last q
                rise = scale * shape[0][1]
                ps = [(scale * T, scale * p) for T, p in shape[0][2]]
                heats = [scale * h for h in shape[0][3]]
            else:
                start = None
                if last is not None and np.array_equal(last[0], unknown) \
                        and [len(p) for _, p in last[2]] == sizes and last[3] is not None:
                    a = _multiple(q, (last[3],), tol=np.inf)
                    start = [(a * T, a * p) for T, p in last[2]] if a else None
                rise, ps, heats = solve(q, start)
            shape[0] = (q.copy(), rise, ps, heats)
            self._last = (unknown, rise.copy(), ps, q.copy(), heats)
            return rise
        return solver

    def loss(self, x, rise) -> np.ndarray:
        """Heat [W] each node loses to the medium at nodal rises ``rise`` (n_nodes,) [K] and
        positions ``x``: ``sum_l w_l M_l^T p_l`` with ``S_l p_l = M_l rise`` (the last solve's
        heats when ``rise`` is its solution, else by conjugate gradients)."""
        rise = np.asarray(rise, float)
        terms = self.terms(x)
        last = self._last
        out = np.zeros(self.n_nodes)
        if last is not None and np.array_equal(rise[last[0]], last[1]) \
                and len(last[2]) == len(terms) and not np.any(np.delete(rise, last[0])):
            for (w, M, _), h in zip(terms, last[4]):
                out += w * (M.T @ h)
            return out
        for w, M, S in terms:
            pre = factorize(S.near_block.tocsr(), kind="spd", dense_limit=400).solve
            A = spla.LinearOperator((S.n, S.n), matvec=S.matvec, dtype=float)
            P = spla.LinearOperator((S.n, S.n), matvec=pre, dtype=float)
            p, info = spla.cg(A, M @ rise, M=P, rtol=1e-10, maxiter=5000)
            out += w * (M.T @ p)
        return out
