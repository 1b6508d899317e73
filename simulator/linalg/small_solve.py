"""Solves of small tangent systems ``K du = r`` (at most
:data:`~simulator.linalg.thresholds.DENSE_LIMIT` unknowns): the dense
rung of the factorisation ladder (:mod:`simulator.linalg.ladder`).

* :class:`DenseFactor`: LAPACK directly (no ``scipy.linalg`` wrappers): Cholesky when K is
  positive definite, else LU with partial pivoting, with LAPACK's reciprocal condition
  estimate; :func:`solve_dense` factors and solves once.
* :class:`SparseCholesky`: the structure of a small tangent (fill-reducing order and pattern of
  the Cholesky factor, from the element connectivity) for the compiled factorisation of
  :mod:`simulator.linalg._cholesky_jit`, which reads the dense matrix of the fused kernel; bar-and-hinge
  tangents are sparse enough (96 free DOFs of the gripper: ~1,100 non-zeros in L, ~11,000
  multiply-adds against ~300,000 for dense Cholesky) for it to beat LAPACK's dense routines.

Both solves return None where ``scipy.linalg.solve`` under warnings-as-errors would have failed:
K singular (a zero pivot), ill-conditioned (1-norm reciprocal condition estimate below machine
epsilon: LAPACK's ``gecon`` / ``pocon``, or the same estimator compiled) or a result that is
not finite; Newton then reports a singular tangent.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg.lapack as lapack
import scipy.sparse as sp

from ..errors import SolverError
from ._cholesky_jit import cholesky_solve
from .dense_lapack import one_blas_thread

__all__ = ["as_dense", "solve_dense", "positive_definite", "schur_complements", "DenseFactor",
           "SparseCholesky", "pattern_of"]

_EPS = float(np.finfo(float).eps)
#: ``np.logical_and.reduce`` (with ``axis=None``): what ``ndarray.all()`` calls, without its
#: Python wrapper (one call fewer per solve on the hot path of small models; the same result).
_all = np.logical_and.reduce
_dlange, _dpotrf, _dpocon, _dpotrs = lapack.dlange, lapack.dpotrf, lapack.dpocon, lapack.dpotrs
_dgetrf, _dgecon, _dgetrs = lapack.dgetrf, lapack.dgecon, lapack.dgetrs


def as_dense(K) -> np.ndarray:
    """``K`` as a dense array: a sparse matrix densified, an array as it is (not copied)."""
    return K.toarray() if sp.issparse(K) else np.asarray(K)


def positive_definite(K: np.ndarray) -> bool:
    """True if LAPACK's Cholesky factorisation of the dense symmetric ``K`` (upper triangle)
    succeeds: K is numerically positive definite. (``K.T`` with the lower triangle: the same
    entries, in the Fortran order LAPACK reads without a transposing copy of a C-ordered K.)"""
    return _dpotrf(K.T, lower=1, clean=0)[1] == 0


def schur_complements(F: np.ndarray, k: int) -> np.ndarray:
    """Schur complements ``F_oo - F_os F_ss^-1 F_so`` of a batch of small matrices ``F``
    (p, m, m) onto their first ``k`` rows and columns, (p, k, k): the elimination of the last
    ``m - k`` unknowns of each (``F_ss`` non-singular; numpy's batched LU)."""
    F = np.asarray(F, float)
    if F.shape[1] == k:
        return F.copy()
    return F[:, :k, :k] - F[:, :k, k:] @ np.linalg.solve(F[:, k:, k:], F[:, k:, :k])


def solve_dense(K: np.ndarray, r: np.ndarray, cholesky_first: bool = True):
    """Solve the dense symmetric K du = r: Cholesky (upper triangle) when K is positive
    definite (and ``cholesky_first``), else LU with partial pivoting (``scipy.linalg.solve``'s
    general path). None when K is singular, ill-conditioned (reciprocal condition estimate
    below machine epsilon) or the result is not finite.

    The LAPACK calls of :class:`DenseFactor` (in the same order) and its solve, written out
    without the object: this is the one-shot solve of Newton's loop on small models, where
    Python overhead per iteration is the cost that counts."""
    anorm = _dlange("1", K)
    if cholesky_first:
        c, info = _dpotrf(K, lower=0, clean=0)
        if info == 0:
            if not _dpocon(c, anorm)[0] >= _EPS:
                return None
            du, info = _dpotrs(c, r)
            return du if info == 0 and _all(np.isfinite(du), axis=None) else None
    lu, piv, info = _dgetrf(K)
    if info != 0 or not _dgecon(lu, anorm)[0] >= _EPS:
        return None
    du, info = _dgetrs(lu, piv, r)
    return du if info == 0 and _all(np.isfinite(du), axis=None) else None


def _factor(K: np.ndarray, cholesky_first: bool, condition: bool, lu_fallback: bool) -> tuple:
    """``(method, info, factors, pivots, rcond)`` of a dense square K (see
    :class:`DenseFactor`): pivots None for Cholesky, rcond None without ``condition``; BLAS on
    one thread from :data:`~simulator.linalg.thresholds.DENSE_ONE_THREAD_MIN` rows on
    (:func:`~simulator.linalg.dense_lapack.one_blas_thread`)."""
    with one_blas_thread(K.shape[0]):
        return _factor_here(K, cholesky_first, condition, lu_fallback)


def _factor_here(K, cholesky_first, condition, lu_fallback) -> tuple:
    anorm = _dlange("1", K) if condition else None
    if cholesky_first:
        c, info = _dpotrf(K, lower=0, clean=0)
        if info == 0:
            return "cholesky", 0, c, None, _dpocon(c, anorm)[0] if condition else None
        if not lu_fallback:                     # not positive definite, and no LU wanted
            return "cholesky", info, None, None, 0.0
    lu, piv, info = _dgetrf(K)
    rcond = (_dgecon(lu, anorm)[0] if info == 0 else 0.0) if condition else None
    return "lu", info, lu, piv, rcond


class DenseFactor:
    """LAPACK factors of a dense square ``K``: Cholesky (upper triangle) if ``cholesky_first``
    and K is positive definite, else LU with partial pivoting.

    Attributes
    ----------
    method : "cholesky" or "lu"
    info : int
        LAPACK's ``info`` of the factorisation (> 0: an exactly zero pivot of LU).
    rcond : float or None
        1-norm reciprocal condition estimate (``pocon`` / ``gecon``); 0 when ``info != 0``;
        None without ``condition``.

    With ``lu_fallback`` False a matrix that is not positive definite is not factorised (``info`` is
    Cholesky's, > 0).
    """

    def __init__(self, K: np.ndarray, cholesky_first: bool = True, condition: bool = True,
                 lu_fallback: bool = True):
        self.n = K.shape[0]
        self.method, self.info, self._c, self._piv, self.rcond = _factor(
            K, cholesky_first, condition, lu_fallback)

    def solve_info(self, b: np.ndarray):
        """(``K^-1 b``, LAPACK's ``info``) for b (n,) or (n, k)."""
        if self.method == "cholesky":
            return _dpotrs(self._c, b)
        return _dgetrs(self._c, self._piv, b)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``K^-1 b`` for b (n,) or (n, k) (not finite where K is singular); raises
        :class:`~simulator.errors.SolverError` if LAPACK's solve fails."""
        if self.info != 0:
            return np.full(np.shape(b), np.nan)
        x, info = self.solve_info(b)
        if info != 0:
            routine = "dpotrs" if self.method == "cholesky" else "dgetrs"
            raise SolverError(f"dense {self.method} solve failed (LAPACK {routine} info {info})")
        return x


class SparseCholesky:
    """Structure of the Cholesky factor of a symmetric matrix with a given non-zero pattern.

    Parameters
    ----------
    rows, cols : int arrays
        Positions (0 .. n-1) of the structural non-zeros (either triangle or both).
    n : int
        Matrix size.

    The order is SuperLU's symmetric minimum degree (``MMD_AT_PLUS_A``); the pattern of L
    (column j: rows >= j, diagonal first) follows from the elimination tree. :meth:`solve`
    factors and solves a dense matrix that is zero outside the pattern.
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, n: int):
        self.n = n
        A = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n)).tocsc()
        A = (abs(A) + abs(A.T) + sp.identity(n, format="csc") * (2.0 * n)).tocsc()
        import scipy.sparse.linalg as spla

        lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
        self.order = np.argsort(lu.perm_c).astype(np.int64)
        B = A[self.order][:, self.order].tocsc()
        columns, children = [], [[] for _ in range(n)]
        for j in range(n):                          # symbolic factorisation (etree)
            below = B.indices[B.indptr[j]:B.indptr[j + 1]]
            s = set(below[below > j].tolist())
            for c in children[j]:
                s.update(columns[c])
            s.discard(j)
            columns.append(s)
            if s:
                children[min(s)].append(j)
        counts = np.array([1 + len(s) for s in columns], dtype=np.int64)
        self.Lp = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        self.Li = np.concatenate([[j] + sorted(s) for j, s in enumerate(columns)]).astype(np.int64)
        # for each row j: the columns k < j with L[j, k] != 0 and the position of L[j, k]
        below = np.ones(len(self.Li), bool)
        below[self.Lp[:-1]] = False
        pos = np.flatnonzero(below)
        col = np.repeat(np.arange(n), counts)[pos]
        row = self.Li[pos]
        by_row = np.lexsort((col, row))
        self.rk, self.rpos = col[by_row].astype(np.int64), pos[by_row].astype(np.int64)
        self.rp = np.searchsorted(row[by_row], np.arange(n + 1)).astype(np.int64)
        self.flops = int(np.sum((counts - 1) ** 2))
        #: whether its factorisation needs at most a twentieth of dense Cholesky's ~n^3/3
        #: multiply-adds (the ladder's dense rung then uses it, from SPARSE_MIN rows)
        self.beats_dense = 20 * self.flops <= n ** 3

    @property
    def nnz(self) -> int:
        """Stored entries of L."""
        return len(self.Li)

    def solve(self, K: np.ndarray, r: np.ndarray):
        """du with K du = r (K dense C-ordered, zero outside the pattern), or None as
        :func:`solve_dense` would; K not positive definite: :func:`solve_dense`'s LU."""
        kernel = cholesky_solve()
        if kernel is None:                              # numba failed (logged)
            return solve_dense(K, r)
        n, nnz = self.n, len(self.Li)
        buf = np.empty(nnz + 5 * n)                     # L values, du, work
        du = buf[nnz:nnz + n]
        rcond = kernel(K, np.ascontiguousarray(r, dtype=float), self.order, self.Lp, self.Li,
                       buf[:nnz], self.rp, self.rk, self.rpos, du, buf[nnz + n:])
        if rcond >= _EPS:                               # (NaN: du not finite)
            return du
        if rcond < 0:                                   # not positive definite
            return solve_dense(K, r, cholesky_first=False)
        return None


def pattern_of(dof_sets, free_index: np.ndarray, diagonal=()) -> tuple:
    """(rows, cols) of the free-DOF entries coupled by elements with global DOFs ``dof_sets``
    (a list of (n_el, m) arrays) and by the ``diagonal`` DOFs."""
    rows, cols = [], []
    for d in dof_sets:
        if len(d):
            f = free_index[d]
            m = f.shape[1]
            rows.append(np.repeat(f, m, axis=1).ravel())
            cols.append(np.tile(f, (1, m)).ravel())
    f = free_index[np.asarray(diagonal, dtype=int)]
    rows.append(f)
    cols.append(f)
    r, c = np.concatenate(rows), np.concatenate(cols)
    keep = (r >= 0) & (c >= 0)
    return r[keep], c[keep]
