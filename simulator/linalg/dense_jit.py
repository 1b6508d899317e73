"""Compiled (numba) dense factorisations of the integral heat-loss operator (theory 4.7).

``S = C diag(sign) C^T`` of a symmetric matrix (Cholesky where it is positive definite) with the
forward substitution of the right sides and their Gram matrix ``M^T S^-1 M``
(:func:`loss_factor`), the back substitution (:func:`back_substitute`) and LU with partial
pivoting where a pivot vanishes (:func:`lu_response`). Row-oriented and single-threaded on
purpose: LAPACK's threads, next to the solver's, cost a hundred times the arithmetic of these
small (n < ~4000) systems on a loaded machine. Compiled on first use (cached by numba); callers
check :func:`available` and keep the factorisation ladder
(:func:`~simulator.linalg.ladder.factorize`) otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import compile_kernel

__all__ = ["available", "loss_factor", "lu_response", "back_substitute", "cholesky_solve"]

_compiled = None
_broken = False


def _loss_factor(S, W, sign):
    """Overwrite the lower triangle of the symmetric ``S`` (n, n) with C of ``S = C diag(sign)
    C^T`` (positive diagonal, ``sign`` (n,) of +-1: Cholesky where ``S`` is positive definite)
    and ``W`` (n, k) with ``C^-1 W``; returns False (S, W partly overwritten) if a pivot is
    below 1e-12 of its diagonal entry (then LU with pivoting is needed).

    Row by row (left-looking): the dot products run over contiguous row prefixes and the
    forward substitution over contiguous rows of ``W``, so both vectorise (compiled with
    fastmath: sums in any order, round-off level differences only).
    """
    n = S.shape[0]
    G = np.empty((n, n))                                       # G[i, m] = C[i, m] sign[m]
    for i in range(n):
        for j in range(i + 1):
            v = S[i, j]
            for m in range(j):
                v -= S[i, m] * G[j, m]
            if i == j:
                if not abs(v) > 1e-12 * abs(S[i, i]):
                    return False
                sign[i] = 1.0 if v > 0.0 else -1.0
                S[i, i] = math.sqrt(abs(v))
                G[i, i] = S[i, i] * sign[i]
            else:
                S[i, j] = v / G[j, j]
                G[i, j] = S[i, j] * sign[j]
        for m in range(i):                                     # row i of C^-1 W
            _row_update(W, i, m, S[i, m])
        _row_scale(W, i, 1.0 / S[i, i])
    return True


def _row_update(B, i, m, f):
    """``B[i] -= f B[m]`` (contiguous rows: vectorised)."""
    for q in range(B.shape[1]):
        B[i, q] -= f * B[m, q]


def _row_scale(B, i, f):
    """``B[i] *= f``."""
    for q in range(B.shape[1]):
        B[i, q] *= f


def _lu_solve(A, B):
    """Overwrite ``B`` (n, k) with ``A^-1 B`` by LU with partial pivoting (``A`` (n, n)
    overwritten by its factors), row-oriented like :func:`_loss_factor`; returns False if a
    pivot is exactly zero."""
    n, k = A.shape[0], B.shape[1]
    for j in range(n):
        p = j
        for i in range(j + 1, n):
            if abs(A[i, j]) > abs(A[p, j]):
                p = i
        if A[p, j] == 0.0:
            return False
        if p != j:
            for c in range(n):
                A[j, c], A[p, c] = A[p, c], A[j, c]
            for q in range(k):
                B[j, q], B[p, q] = B[p, q], B[j, q]
        inv = 1.0 / A[j, j]
        for i in range(j + 1, n):
            f = A[i, j] * inv
            if f != 0.0:
                for c in range(j + 1, n):
                    A[i, c] -= f * A[j, c]
                _row_update(B, i, j, f)
    for i in range(n - 1, -1, -1):
        for m in range(i + 1, n):
            _row_update(B, i, m, A[i, m])
        _row_scale(B, i, 1.0 / A[i, i])
    return True


def _back_substitute(C, B):
    """Overwrite the rows of ``B`` (k, n) with ``C^-T`` times them (C (n, n) lower)."""
    n = C.shape[0]
    for c in range(B.shape[0]):
        for i in range(n - 1, -1, -1):
            B[c, i] /= C[i, i]
            v = B[c, i]
            for m in range(i):
                B[c, m] -= C[i, m] * v


def _gram(U, W, out):
    """``out = (U^T W + W^T U) / 2`` (k, k) for ``U``, ``W`` (n, k), through their transposes
    (contiguous rows); ``W^T W`` when ``U`` is ``W``."""
    Ut, Wt = U.T.copy(), W.T.copy()
    k, n = Wt.shape
    for a in range(k):
        for b in range(a, k):
            v = 0.0
            for r in range(n):
                v += Ut[a, r] * Wt[b, r] + Wt[a, r] * Ut[b, r]
            out[a, b] = 0.5 * v
            out[b, a] = 0.5 * v


def _build():
    from numba import njit

    g = globals()
    for name in ("_row_update", "_row_scale"):
        if not hasattr(g[name], "py_func"):
            g[name] = njit(cache=True, inline="always")(g[name])
    for name, sig in (("_loss_factor", "b1(f8[:, ::1], f8[:, ::1], f8[::1])"),
                      ("_lu_solve", "b1(f8[:, ::1], f8[:, ::1])"),
                      ("_back_substitute", "void(f8[:, ::1], f8[:, ::1])"),
                      ("_gram", "void(f8[:, ::1], f8[:, ::1], f8[:, ::1])")):
        if not hasattr(g[name], "py_func"):
            g[name] = njit(sig, cache=True, fastmath=True)(g[name])
    return True


def available() -> bool:
    """Whether the compiled factorisations can be used (compiles or loads them on the first
    call; False, after one warning, if numba fails)."""
    global _compiled, _broken
    if _compiled is None and not _broken:
        _compiled = compile_kernel("dense operator factorisation", _build, "using the ladder")
        _broken = _compiled is None
    return bool(_compiled)


def loss_factor(S, M):
    """``C``, ``sign`` of the symmetric ``S = C diag(sign) C^T`` (n, n) (Cholesky when ``S`` is
    positive definite: ``sign`` all +1), ``W = C^-1 M`` for ``M`` (n, k) and ``M^T S^-1 M =
    W^T diag(sign) W`` (k, k), by the compiled single-threaded kernel; None if a pivot
    vanishes (inputs not changed: use :func:`lu_response`)."""
    available()
    C, W = np.array(S, np.float64, order="C"), np.array(M, np.float64, order="C")
    sign = np.empty(len(C))
    if W.ndim != 2 or not _loss_factor(C, W, sign):
        return None
    G = np.empty((W.shape[1],) * 2)
    _gram(np.ascontiguousarray(sign[:, None] * W), W, G)
    return C, sign, W, G


def lu_response(S, M):
    """``P = S^-1 M`` and ``(M^T P + P^T M) / 2`` for a square ``S`` (n, n) that is not
    positive definite and ``M`` (n, k), by the compiled single-threaded LU with partial
    pivoting; None if ``S`` is singular (inputs not changed)."""
    available()
    A, P = np.array(S, np.float64, order="C"), np.array(M, np.float64, order="C")
    if P.ndim != 2 or not _lu_solve(A, P):
        return None
    G = np.empty((P.shape[1],) * 2)
    _gram(np.ascontiguousarray(M, np.float64), P, G)
    return P, G


def back_substitute(C, B, sign=None):
    """``C^-T B`` for the factor ``C`` (n, n) of :func:`loss_factor` and ``B`` (n,) or (n, k);
    ``C^-T diag(sign) B`` with its ``sign``."""
    available()
    B = np.asarray(B, np.float64)
    X = B.reshape(len(B), -1)
    X = np.array((X if sign is None else sign[:, None] * X).T, order="C")
    _back_substitute(C, X)
    return X.T.reshape(B.shape)


def cholesky_solve(S, B):
    """``S^-1 B`` for a symmetric positive definite ``S`` (n, n) and ``B`` (n,) or (n, k) by the
    compiled single-threaded Cholesky, or None if ``S`` is not positive definite (inputs not
    changed)."""
    available()
    B = np.asarray(B, np.float64)
    out = loss_factor(S, B.reshape(len(B), -1))
    if out is None or not np.all(out[1] > 0):
        return None
    return back_substitute(out[0], out[2]).reshape(B.shape)
