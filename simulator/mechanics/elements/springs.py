"""Four-node rotational spring (theory 3.3; Liu & Paulino 2017).

Nodes (i, j, k, l), axis j-k. The fold angle theta lies in [0, 2 pi) with pi =
flat; with the mesher's polarity convention theta > pi means folded towards +z.
Energy ``k (theta - theta0)^2 / 2`` (linear law; the reference's locking
penalty is inactive for compliant creases), with ``theta - theta0`` taken modulo 2 pi into
[-pi, pi): the energy is a function of the geometry, so a crease line that folds flat
(theta passing 0 = 2 pi) keeps a continuous energy instead of jumping by ``2 pi k (...)``
(the jump stopped heated Miura sheets at ~11 mW). The only kink left is at theta0 +- pi, half a
turn away from the rest angle.
"""

from __future__ import annotations

import contextlib

import numpy as np

from ... import _jit as _kernels
from ...errors import ParameterError
from . import _springs_jit as _jit
from ._vec import cross, dot as _dot, outer as _outer

__all__ = ["fold_angle", "fold_angle_derivatives", "spring_kernel", "spring_kernel_numpy",
           "spring_kernel_backend"]


def fold_angle(x: np.ndarray) -> np.ndarray:
    """Fold angle theta in [0, 2 pi) of springs with coordinates x (n, 4, 3)."""
    r_ij, r_kj, r_kl = x[:, 0] - x[:, 1], x[:, 2] - x[:, 1], x[:, 2] - x[:, 3]
    m, n = cross(r_ij, r_kj), cross(r_kj, r_kl)
    return _angle(m, n, r_kl, r_kj)


def _angle(m, n, r_kl, r_kj):
    """theta = mod(eta arccos(m.n / |m||n|), 2 pi) with eta = sign(m . r_kl), computed with atan2.

    Since m x n = r_kj (m . r_kl), the sine of the angle is |r_kj| (m . r_kl) / (|m||n|); atan2
    keeps full precision near flat (theta = pi), where arccos loses half the digits.
    """
    y = np.sqrt(_dot(r_kj, r_kj)) * _dot(m, r_kl)
    return np.mod(np.arctan2(y, _dot(m, n)), 2 * np.pi)


def fold_angle_derivatives(x: np.ndarray, hessian: bool = True):
    """Fold angle, its gradient (n, 12) and Hessian (n, 12, 12) [rad/m, rad/m^2].

    Gradient and Hessian are the closed forms of Liu & Paulino (theory 3.3).
    """
    r_ij, r_kj, r_kl = x[:, 0] - x[:, 1], x[:, 2] - x[:, 1], x[:, 2] - x[:, 3]
    m, n = cross(r_ij, r_kj), cross(r_kj, r_kl)
    theta = _angle(m, n, r_kl, r_kj)
    mm, nn, rr = _dot(m, m), _dot(n, n), _dot(r_kj, r_kj)
    r = np.sqrt(rr)
    g_i = (r / mm)[:, None] * m
    g_l = -(r / nn)[:, None] * n
    A = _dot(r_ij, r_kj) / rr
    B = _dot(r_kl, r_kj) / rr
    g_j = (A - 1)[:, None] * g_i - B[:, None] * g_l
    g_k = (B - 1)[:, None] * g_l - A[:, None] * g_i
    grad = np.concatenate([g_i, g_j, g_k, g_l], axis=1)
    if not hessian:
        return theta, grad, None

    # six "sym" terms of theory 3.3 in two batched operations
    cm = cross(np.stack([r_kj, r_ij, r_kj - r_ij], axis=1), m[:, None, :])      # (n, 3, 3)
    cn = cross(np.stack([r_kj, r_kl, r_kj - r_kl], axis=1), n[:, None, :])
    om = _outer(m[:, None, :], cm)
    on = _outer(n[:, None, :], cn)
    sm = (r / mm**2)[:, None, None, None] * (om + np.swapaxes(om, 2, 3))
    sn = (r / nn**2)[:, None, None, None] * (on + np.swapaxes(on, 2, 3))
    mr = _outer(m, r_kj) / (mm * r)[:, None, None]
    nr = _outer(n, r_kj) / (nn * r)[:, None, None]
    H_ii, H_ik, H_ij = -sm[:, 0], mr + sm[:, 1], -mr + sm[:, 2]
    H_ll, H_lj, H_lk = sn[:, 0], nr - sn[:, 1], -nr - sn[:, 2]
    rr3 = rr[:, None]
    dA_j = ((2 * A - 1)[:, None] * r_kj - r_ij) / rr3
    dA_k = (r_ij - (2 * A)[:, None] * r_kj) / rr3
    dB_j = ((2 * B)[:, None] * r_kj - r_kl) / rr3
    dB_k = ((1 - 2 * B)[:, None] * r_kj + r_kl) / rr3
    # g_i dA_j^T, g_i dA_k^T, g_l dB_j^T, g_l dB_k^T in one operation
    o = _outer(np.stack([g_i, g_i, g_l, g_l], axis=1), np.stack([dA_j, dA_k, dB_j, dB_k], axis=1))
    A3, B3 = A[:, None, None], B[:, None, None]
    H_jj = o[:, 0] + (A3 - 1) * H_ij - o[:, 2] - B3 * H_lj
    H_jk = o[:, 1] + (A3 - 1) * H_ik - o[:, 3] - B3 * H_lk
    H_kk = o[:, 3] + (B3 - 1) * H_lk - o[:, 1] - A3 * H_ik
    hess = np.zeros((len(x), 4, 3, 4, 3))
    for (p, q), blk in (((0, 0), H_ii), ((0, 1), H_ij), ((0, 2), H_ik), ((1, 1), H_jj),
                        ((1, 2), H_jk), ((2, 2), H_kk), ((3, 1), H_lj), ((3, 2), H_lk),
                        ((3, 3), H_ll)):
        hess[:, p, :, q] = blk
        if p != q:
            hess[:, q, :, p] = np.swapaxes(blk, 1, 2)
    hess = hess.reshape(-1, 12, 12)
    return theta, grad, hess


@contextlib.contextmanager
def spring_kernel_backend(name: str):
    """Use the ``"numba"`` or ``"numpy"`` kernels inside the ``with`` block.

    The backend selects the compiled kernels as a whole: the spring kernel and, on models of
    at most :data:`~simulator.linalg.thresholds.DENSE_LIMIT` free DOFs, the fused evaluation of
    :mod:`._fused_jit` (bars, springs, contact and supports in one call, dense tangent) with
    the sparse Cholesky solve of :mod:`simulator.linalg._cholesky_jit`. The default is ``"numba"``
    when numba is installed (compiled on first use, once per install: a few seconds of CPU;
    loaded from numba's cache in well under a second per process) unless ``ETORIGAMI_JIT=0``.
    ``"numpy"`` suits short runs (one case or one gripper evaluation), where compiling costs
    more than it saves. Both give the same values to rounding; keep one backend for runs whose
    floats are compared bit for bit. A block of :func:`simulator._jit.use` with the same name
    (the one place that chooses the kernels).
    """
    if name not in _kernels.BACKENDS:
        raise ParameterError(f"spring kernel backend {name!r}; use one of "
                             f"{', '.join(map(repr, _kernels.BACKENDS))}.")
    if name == "numba" and not _kernels.AVAILABLE:
        raise ParameterError("spring kernel backend 'numba' needs numba; install it or use "
                             "'numpy'.")
    with _kernels.use(name):
        yield


def spring_kernel(x: np.ndarray, k: np.ndarray, theta0: np.ndarray, hessian: bool = True):
    """Energy [J], gradient [N] (n, 12) and Hessian [N/m] (n, 12, 12) of all springs.

    Uses the compiled kernel of :mod:`._springs_jit` (same formulas, one call instead of ~60
    array operations) with the ``"numba"`` backend, else :func:`spring_kernel_numpy`; see
    :func:`spring_kernel_backend`.
    """
    if _jit.use_compiled():
        return _jit.spring_kernel_jit(x, k, theta0, hessian)
    return spring_kernel_numpy(x, k, theta0, hessian)


def spring_kernel_numpy(x: np.ndarray, k: np.ndarray, theta0: np.ndarray, hessian: bool = True):
    """Energy [J], gradient [N] (n, 12) and Hessian [N/m] (n, 12, 12) of all springs.

    Parameters
    ----------
    x : (n, 4, 3) node coordinates (i, j, k, l) [m]
    k : (n,) rotational stiffness [N m / rad]
    theta0 : (n,) rest angle [rad]
    """
    theta, g, H = fold_angle_derivatives(x, hessian)
    dev = theta - theta0
    dev = dev - 2 * np.pi * np.floor(dev / (2 * np.pi) + 0.5)
    moment = k * dev
    energy = 0.5 * moment * dev
    grad = moment[:, None] * g
    if not hessian:
        return energy, grad, None
    hess = k[:, None, None] * _outer(g, g) + moment[:, None, None] * H
    return energy, grad, hess
