"""Compiled (numba) rotational-spring kernel: same formulas as :mod:`.springs`.

On small meshes (tens of springs) the numpy kernel spends its time in ~60 array calls of a
few microseconds each; this loop-based version does one call. It is used when numba is
installed and checked against the numpy kernel by the tests.
"""

from __future__ import annotations

import math

import numpy as np

try:
    from numba import njit
except ImportError:  # pragma: no cover - numba is optional
    njit = None

__all__ = ["AVAILABLE", "spring_kernel_jit"]

AVAILABLE = njit is not None
#: (row node, column node) of the stored Hessian blocks ii, ij, ik, jj, jk, kk, lj, lk, ll.
_BLOCK_POS = np.array([[0, 0], [0, 1], [0, 2], [1, 1], [1, 2], [2, 2], [3, 1], [3, 2], [3, 3]])


def _kernel(x, k, theta0, want_hess, energy, grad, hess):
    n = x.shape[0]
    v = np.empty((16, 3))          # work vectors
    blk = np.empty((9, 3, 3))      # Hessian blocks ii, ij, ik, jj, jk, kk, lj, lk, ll
    for e in range(n):
        rij = x[e, 0] - x[e, 1]
        rkj = x[e, 2] - x[e, 1]
        rkl = x[e, 2] - x[e, 3]
        m = np.cross(rij, rkj)
        nv = np.cross(rkj, rkl)
        mm = m @ m
        nn = nv @ nv
        rr = rkj @ rkj
        r = math.sqrt(rr)
        theta = math.atan2(r * (m @ rkl), m @ nv) % (2 * math.pi)
        gi = (r / mm) * m
        gl = -(r / nn) * nv
        A = (rij @ rkj) / rr
        B = (rkl @ rkj) / rr
        gj = (A - 1) * gi - B * gl
        gk = (B - 1) * gl - A * gi
        d = theta - theta0[e]
        d -= 2 * math.pi * math.floor(d / (2 * math.pi) + 0.5)      # periodic: see springs.py
        moment = k[e] * d
        energy[e] = 0.5 * moment * d
        for a in range(3):
            grad[e, a] = moment * gi[a]
            grad[e, 3 + a] = moment * gj[a]
            grad[e, 6 + a] = moment * gk[a]
            grad[e, 9 + a] = moment * gl[a]
        if not want_hess:
            continue
        sm = r / mm**2
        sn = r / nn**2
        v[0] = np.cross(rkj, m)
        v[1] = np.cross(rij, m)
        v[2] = np.cross(rkj - rij, m)
        v[3] = np.cross(rkj, nv)
        v[4] = np.cross(rkl, nv)
        v[5] = np.cross(rkj - rkl, nv)
        v[6] = ((2 * A - 1) * rkj - rij) / rr          # dA/dx_j
        v[7] = (rij - 2 * A * rkj) / rr                # dA/dx_k
        v[8] = (2 * B * rkj - rkl) / rr                # dB/dx_j
        v[9] = ((1 - 2 * B) * rkj + rkl) / rr          # dB/dx_k
        for a in range(3):
            for b in range(3):
                mr = m[a] * rkj[b] / (mm * r)
                nr = nv[a] * rkj[b] / (nn * r)
                s0 = m[a] * v[0, b] + v[0, a] * m[b]
                s1 = m[a] * v[1, b] + v[1, a] * m[b]
                s2 = m[a] * v[2, b] + v[2, a] * m[b]
                t0 = nv[a] * v[3, b] + v[3, a] * nv[b]
                t1 = nv[a] * v[4, b] + v[4, a] * nv[b]
                t2 = nv[a] * v[5, b] + v[5, a] * nv[b]
                h_ii = -sm * s0
                h_ik = mr + sm * s1
                h_ij = -mr + sm * s2
                h_ll = sn * t0
                h_lj = nr - sn * t1
                h_lk = -nr - sn * t2
                blk[0, a, b] = h_ii
                blk[1, a, b] = h_ij
                blk[2, a, b] = h_ik
                blk[6, a, b] = h_lj
                blk[7, a, b] = h_lk
                blk[8, a, b] = h_ll
                blk[3, a, b] = (gi[a] * v[6, b] + (A - 1) * h_ij
                                - gl[a] * v[8, b] - B * h_lj)
                blk[4, a, b] = (gi[a] * v[7, b] + (A - 1) * h_ik
                                - gl[a] * v[9, b] - B * h_lk)
                blk[5, a, b] = (gl[a] * v[9, b] + (B - 1) * h_lk
                                - gi[a] * v[7, b] - A * h_ik)
        g = np.concatenate((gi, gj, gk, gl))
        for p in range(12):
            for q in range(12):
                hess[e, p, q] = k[e] * g[p] * g[q]
        for idx in range(9):
            p, q = _BLOCK_POS[idx, 0], _BLOCK_POS[idx, 1]
            for a in range(3):
                for b in range(3):
                    val = moment * blk[idx, a, b]
                    hess[e, 3 * p + a, 3 * q + b] += val
                    if p != q:
                        hess[e, 3 * q + b, 3 * p + a] += val


_compiled = njit(cache=True, fastmath=False)(_kernel) if AVAILABLE else None


def spring_kernel_jit(x, k, theta0, hessian=True):
    """Energy (n,), gradient (n, 12), Hessian (n, 12, 12) or None: see
    :func:`simulator.elements.springs.spring_kernel`."""
    n = len(x)
    energy = np.empty(n)
    grad = np.empty((n, 12))
    hess = np.empty((n, 12, 12)) if hessian else np.empty((0, 12, 12))
    _compiled(np.ascontiguousarray(x, dtype=np.float64), np.asarray(k, dtype=np.float64),
              np.asarray(theta0, dtype=np.float64), hessian, energy, grad, hess)
    return energy, grad, (hess if hessian else None)
