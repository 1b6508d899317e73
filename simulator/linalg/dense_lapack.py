"""Single-threaded LAPACK Cholesky of the integral heat-loss operator (theory 4.7).

``S = C C^T`` (``dpotrf``), ``W = C^-1 M`` and ``L = W^T W`` (BLAS, by row blocks that skip
``M``'s leading zeros) for a symmetric
positive definite ``S``: blocked BLAS-3 code, 3-4 times the speed of the compiled row-oriented
kernel of :mod:`.dense_jit` from a few hundred rows on (measured: n = 584, 2.9 ms against
9.6 ms). BLAS's threads are limited to one for the call (``threadpoolctl``): at these sizes two
threads are slower than one (n = 396: 2.4 ms against 1.1 ms) and would compete with a
process pool's workers. The limit is scoped: each call enters ``threadpoolctl``'s limit and
leaves it when the call returns, restoring the number of threads BLAS had (the tests check
it); while the call runs it holds for the whole process (BLAS has one setting), so calls from
several threads take turns (:data:`_lock`). Nothing is changed at import or left changed
after a call. :func:`cholesky_loss` returns None where ``S`` is not positive
definite; :func:`lu_loss` then factorises it by LU with partial pivoting (``dgetrf``, blocked:
2-3 times the speed of the compiled kernels' indefinite path at n = 1314), and the compiled
kernel stays for a singular ``S``.
"""

from __future__ import annotations

import contextlib
import threading

import numpy as np
from scipy.linalg import blas, lapack

from .thresholds import DENSE_ONE_THREAD_MIN

__all__ = ["available", "cholesky_loss", "back_substitute", "lu_loss", "one_blas_thread",
           "rescan"]

_controller = None
#: threadpoolctl's limit is process-wide: calls from several threads take turns (re-entrant:
#: a limited call may call another)
_lock = threading.RLock()


def available() -> bool:
    """Whether BLAS's threads can be limited (``threadpoolctl`` importable)."""
    global _controller
    if _controller is None:
        try:
            from threadpoolctl import ThreadpoolController
            _controller = ThreadpoolController()
        except Exception:  # noqa: BLE001 - an accelerator: the compiled kernel stays
            _controller = False
    return bool(_controller)


def rescan() -> None:
    """Look for BLAS libraries again at the next :func:`available`: threadpoolctl limits the
    libraries loaded when its controller was made, so a loader of another BLAS (PARDISO's MKL,
    :mod:`~simulator.linalg.pardiso`) calls this once it has loaded it."""
    global _controller
    if _controller:
        _controller = None


@contextlib.contextmanager
def one_blas_thread(rows: int | None = None):
    """BLAS limited to one thread while the block runs (a no-op without ``threadpoolctl``, and
    for a matrix of fewer ``rows`` than :data:`~.thresholds.DENSE_ONE_THREAD_MIN`, where the
    limit would cost more than threads can):
    for the dense factorisations and eigen-decompositions of a few hundred rows, where two
    threads gain little on an idle machine and lose much on a loaded one or beside a process
    pool's workers (measured, n = 400 at load 3.4: dpotrf 25 ms with OpenBLAS's threads, 4.0
    ms with one; idle, 2.0 against 2.3 ms at n = 300; the crane with the integral loss 179 s
    against 7 s at load 3-4). Entering and leaving costs about 12 us."""
    if (rows is not None and rows < DENSE_ONE_THREAD_MIN) or not available():
        yield
        return
    with _lock, _controller.limit(limits=1, user_api="blas"):
        yield


def cholesky_loss(S, M, overwrite=False):
    """``(C, W, L)`` for the symmetric ``S`` (n, n) and ``M`` (n, k): the lower Cholesky
    factor ``C`` of ``S``, ``W = C^-1 M`` and ``L = W^T W`` (k, k), exactly symmetric; None if
    ``S`` is not positive definite (or threads cannot be limited: :func:`available`). The
    strict upper triangle of ``C`` is left as LAPACK leaves it (not zeroed: only the lower
    triangle is read, by ``dtrtrs`` here and in :func:`back_substitute`).

    ``overwrite``: ``S`` (exactly symmetric, C- or Fortran-ordered float64) may be factorised
    in place, ``C`` is then a view of its memory (no copy of the n x n matrix); if it is not
    positive definite, ``S`` is restored (from the triangle LAPACK does not touch) before None
    is returned."""
    if not available():
        return None
    S = np.asarray(S, np.float64)
    # S^T == S: the transposed view of a C-ordered S is the Fortran-ordered matrix LAPACK reads
    A = S.T if S.flags.c_contiguous else S
    in_place = overwrite and A.flags.f_contiguous and A.flags.writeable
    if in_place:
        diagonal = np.diag(A).copy()
    with _lock, _controller.limit(limits=1, user_api="blas"):
        C, info = lapack.dpotrf(A, lower=1, clean=0, overwrite_a=int(in_place))
        if info != 0:
            if in_place:                   # the strict upper triangle is untouched
                A[...] = np.triu(A, 1) + np.triu(A, 1).T
                A[np.diag_indices_from(A)] = diagonal
            return None
        W, L = _solve_leading_zeros(C, np.asarray(M, np.float64))
    return C, W, 0.5 * (L + L.T)


def _solve_leading_zeros(C, M):
    """``(W, L)``: ``W = C^-1 M`` (n, k) and ``L = W^T W`` (k, k) for the lower factor ``C``,
    by row blocks that skip the zero rows above each column's first nonzero (``M`` an
    interpolation: 3 nonzeros per row, each column's rows spread over ``S``; ``W``'s column
    keeps ``M``'s leading zeros). The columns are taken in the order of their first nonzero,
    so the columns live in a row block are a prefix: per block a ``dtrsm`` with its diagonal
    block, a ``dgemm`` update of the rows below and the block's ``W^T W``, all on the live
    columns only. About 0.4 of the plain solve's flops on the gripper's operators (n = 704,
    k = 117: solve and product about 2.1 -> 1.4 ms; theory 4.7, "Where the gripper's time
    goes"). The same values to round-off (sums in another order)."""
    n, k = M.shape
    nonzero = M != 0
    first = np.where(nonzero.any(axis=0), nonzero.argmax(axis=0), n)
    order = np.argsort(first, kind="stable")
    first = first[order]
    W = np.asfortranarray(M[:, order])
    L = np.zeros((k, k))
    nb = max(64, -(-n // 6))                   # block rows (measured: 64 at n = 176, 6 blocks)
    for a in range(0, n, nb):
        b = min(a + nb, n)
        c = int(np.searchsorted(first, b))     # the columns with a nonzero above row b
        if c == 0:
            continue
        X = blas.dtrsm(1.0, C[a:b, a:b], W[a:b, :c], lower=1)
        W[a:b, :c] = X
        if b < n:
            W[b:, :c] -= C[b:, a:b] @ X
        L[:c, :c] += X.T @ X
    back = np.empty_like(order)
    back[order] = np.arange(k)
    return W[:, back], L[np.ix_(back, back)]


def back_substitute(C, b):
    """``C^-T b`` for the factor ``C`` of :func:`cholesky_loss` and ``b`` (n,) or (n, k)."""
    with _lock, _controller.limit(limits=1, user_api="blas"):
        x, _ = lapack.dtrtrs(C, np.asarray(b, np.float64), lower=1, trans=1)
    return x


def lu_loss(S, M):
    """``(solve, L)`` for a square ``S`` (n, n) that is not positive definite and ``M`` (n, k):
    ``solve(b) = S^-1 b`` for ``b`` (n,) or (n, k) by the LU factorisation with partial
    pivoting (``dgetrf``) and ``L = M^T S^-1 M`` (k, k), symmetrised; None if ``S`` is singular
    (or threads cannot be limited)."""
    if not available():
        return None
    with _lock, _controller.limit(limits=1, user_api="blas"):
        lu, piv, info = lapack.dgetrf(np.asarray(S, np.float64))
        if info != 0:
            return None
        X, info = lapack.dgetrs(lu, piv, np.asarray(M, np.float64))
        if info != 0:
            return None
        L = np.asarray(M, np.float64).T @ X

    def solve(b):
        with _lock, _controller.limit(limits=1, user_api="blas"):
            return lapack.dgetrs(lu, piv, np.asarray(b, np.float64))[0]
    return solve, 0.5 * (L + L.T)
