"""Compiled (numba) sparse Cholesky solve of a small dense-stored SPD matrix.

The structure (fill-reducing order, pattern of the factor L) comes from
:class:`simulator.linalg.small_solve.SparseCholesky`; one call of :func:`cholesky_solve` factors
``B = K[order][:, order]`` (entries gathered from the dense K, lower triangle, so any entry
outside the pattern is ignored: the pattern must hold every non-zero of K), estimates the
reciprocal condition number in the 1-norm as LAPACK's ``dpocon`` does (Hager-Higham, the
algorithm of ``dlacn2``, on K in its own ordering) and solves ``K du = r``.

Left-looking column factorisation: for column j, the columns k < j with ``L[j, k] != 0`` are
listed in ``rk[rp[j]:rp[j+1]]`` with the position of ``L[j, k]`` in ``Lx`` in ``rpos``;
their entries from that position down are the rows >= j, all in the pattern of column j.

numba is imported, and the function compiled (one signature, cached), on first use.
"""

from __future__ import annotations

import math

from .. import _jit
from .._jit import HELPER_OPTIONS, compile_kernel

__all__ = ["cholesky_solve", "SIGNATURE", "broken"]


#: f(K, r, order, Lp, Li, Lx, rp, rk, rpos, du, work) -> rcond (NaN if du is not finite), or
#: -(j + 1) if the j-th pivot is not positive (K not positive definite: nothing solved);
#: work: 4 n floats
SIGNATURE = ("f8(f8[:, ::1], f8[::1], i8[::1], i8[::1], i8[::1], f8[::1], i8[::1], i8[::1], "
             "i8[::1], f8[::1], f8[::1])")


def _apply_inverse(y, Lp, Li, Lx):
    """y <- B^-1 y for B = L L^T (y in the factor's order)."""
    n = Lp.shape[0] - 1
    for j in range(n):                                  # L z = y
        yj = y[j] / Lx[Lp[j]]
        y[j] = yj
        for p in range(Lp[j] + 1, Lp[j + 1]):
            y[Li[p]] -= Lx[p] * yj
    for j in range(n - 1, -1, -1):                      # L^T v = z
        s = y[j]
        for p in range(Lp[j] + 1, Lp[j + 1]):
            s -= Lx[p] * y[Li[p]]
        y[j] = s / Lx[Lp[j]]


def _sum_abs(x):
    s = 0.0
    for i in range(x.shape[0]):
        s += abs(x[i])
    return s


def _argmax_abs(x, order):
    """Position of the largest |x| (x in the factor's order), the first in K's numbering on
    ties, as LAPACK's idamax on K."""
    j = 0
    for i in range(1, x.shape[0]):
        if abs(x[i]) > abs(x[j]) or (abs(x[i]) == abs(x[j]) and order[i] < order[j]):
            j = i
    return j


def _kernel(K, r, order, Lp, Li, Lx, rp, rk, rpos, du, work):
    n = order.shape[0]
    w, y, x, sgn = work[:n], work[n:2 * n], work[2 * n:3 * n], work[3 * n:4 * n]
    for j in range(n):
        sgn[j] = 0.0                                    # column sums of |K| (in the order,
    for j in range(n):                                  # from the lower triangle: K symmetric
        oj = order[j]                                   # and zero outside the pattern)
        for p in range(Lp[j], Lp[j + 1]):               # factor, column by column
            i = Li[p]
            w[i] = K[order[i], oj]
            sgn[j] += abs(w[i])
            if i > j:
                sgn[i] += abs(w[i])
        for q in range(rp[j], rp[j + 1]):
            p0 = rpos[q]
            ljk = Lx[p0]
            for p in range(p0, Lp[rk[q] + 1]):
                w[Li[p]] -= Lx[p] * ljk
        d = w[j]
        if not d > 0:
            return -(j + 1.0)
        d = math.sqrt(d)
        Lx[Lp[j]] = d
        for p in range(Lp[j] + 1, Lp[j + 1]):
            Lx[p] = w[Li[p]] / d
    anorm = 0.0                                         # ||K||_1
    for j in range(n):
        anorm = max(anorm, sgn[j])
    # ||K^-1||_1 estimate: LAPACK's dlacn2 on K (symmetric: K^T x = K x), with the vectors
    # kept in the factor's order (position i is K's unknown order[i])
    for i in range(n):
        x[i] = 1.0 / n
    _apply_inverse(x, Lp, Li, Lx)
    if n == 1:
        est = abs(x[0])
    else:
        est = _sum_abs(x)
        for i in range(n):
            sgn[i] = 1.0 if x[i] >= 0 else -1.0
            x[i] = sgn[i]
        _apply_inverse(x, Lp, Li, Lx)
        j = _argmax_abs(x, order)
        it = 2
        while True:
            for i in range(n):
                x[i] = 0.0
            x[j] = 1.0
            _apply_inverse(x, Lp, Li, Lx)
            est_old, est = est, _sum_abs(x)
            repeated = True
            for i in range(n):
                if (1.0 if x[i] >= 0 else -1.0) != sgn[i]:
                    repeated = False
            if repeated or est <= est_old:
                break
            for i in range(n):
                sgn[i] = 1.0 if x[i] >= 0 else -1.0
                x[i] = sgn[i]
            _apply_inverse(x, Lp, Li, Lx)
            j_last, j = j, _argmax_abs(x, order)
            if x[j_last] == abs(x[j]) or it >= 5:
                break
            it += 1
        for i in range(n):
            x[i] = (1.0 if order[i] % 2 == 0 else -1.0) * (1.0 + order[i] / (n - 1.0))
        _apply_inverse(x, Lp, Li, Lx)
        est = max(est, 2.0 * (_sum_abs(x) / (3.0 * n)))
    for i in range(n):
        y[i] = r[order[i]]
    _apply_inverse(y, Lp, Li, Lx)
    for i in range(n):
        du[order[i]] = y[i]
    for i in range(n):
        if not math.isfinite(du[i]):
            return math.nan
    if anorm == 0.0 or est == 0.0:
        return 0.0
    return (1.0 / est) / anorm


_compiled = None
#: Compilation failed once (logged): callers solve densely from then on.
broken = False
_HELPERS = {"_apply_inverse": "void(f8[::1], i8[::1], i8[::1], f8[::1])",
            "_sum_abs": "f8(f8[::1])", "_argmax_abs": "i8(f8[::1], i8[::1])"}


def cholesky_solve():
    """The compiled function, or None if numba cannot compile it (logged once): the
    ahead-of-time compiled one when enabled and loaded (:mod:`simulator._aot`, no numba
    imported), else numba's, compiled or loaded from its cache on first use."""
    global _compiled, broken
    aot = _jit.aot_kernel("cholesky")                  # tier "aot": short CLI commands
    if aot is not None:
        return aot
    if _compiled is None and not broken:
        _compiled = compile_kernel("sparse Cholesky", _build, "solving densely")
        broken = _compiled is None
    return _compiled


def _build():
    from numba import njit

    g = globals()
    for name, sig in _HELPERS.items():
        if not hasattr(g[name], "py_func"):
            g[name] = njit(sig, cache=True, **HELPER_OPTIONS)(g[name])
    return njit(SIGNATURE, cache=True)(_kernel)
