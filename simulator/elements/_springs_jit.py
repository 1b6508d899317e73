"""Compiled (numba) rotational-spring kernel: same formulas as :mod:`.springs`.

On small meshes (tens of springs) the numpy kernel spends its time in ~60 array calls of a
few microseconds each; this loop-based version does one call (about 10 us instead of
150-500 us for 20 springs). It is written with scalar arithmetic on a small work array (no
``np.cross``, ``@`` or array temporaries), which cuts numba's compilation to 40 %, and it is
checked against the numpy kernel by the tests.

Compiling costs about 2.9 s of CPU once per install (0.5 s importing numba, 2.4 s compiling;
the previous array-style kernel took 5.4-6.7 s); loading it from numba's cache (next to this
file or in ``NUMBA_CACHE_DIR``) costs 0.7 s per process. A run of one of the paper's cases
calls the kernel 1,200-2,500 times and one gripper evaluation 870-1,650 times, too few to win
that back; an optimisation does (15 coordinate-descent evaluations: 12.7 s of CPU compiled,
compilation included, against 15.1 s on numpy).

So numba is imported, and the kernel compiled, only when the kernel is first called with the
``"numba"`` backend. The backend is fixed per process, never switched by how much has been
computed, so that the same computation gives the same floats in every process (serial and
process-pool sweeps are compared bit for bit): ``"numba"`` when numba is installed, unless the
environment variable ``ETORIGAMI_JIT`` is ``0`` (``off``, ``numpy``); short commands select
``"numpy"`` with :func:`simulator.elements.springs.spring_kernel_backend`.
"""

from __future__ import annotations

import importlib.util
import logging
import math
import os

import numpy as np

__all__ = ["AVAILABLE", "BACKENDS", "default_backend", "spring_kernel_jit", "use_compiled"]

logger = logging.getLogger(__name__)

#: numba is installed (checked without importing it).
AVAILABLE = importlib.util.find_spec("numba") is not None
BACKENDS = ("numba", "numpy")
#: The one specialisation compiled: x (n, 4, 3), k (n,), theta0 (n,), want_hess, energy (n,),
#: grad (n, 12), hess (n or 0, 12, 12); all C-contiguous float64.
_SIGNATURE = "void(f8[:, :, ::1], f8[::1], f8[::1], b1, f8[::1], f8[:, ::1], f8[:, :, ::1])"
_OFF = ("0", "off", "no", "false", "never", "numpy")

#: (row node, column node) of the stored Hessian blocks ii, ij, ik, jj, jk, kk, lj, lk, ll.
_BLOCK_POS = np.array([[0, 0], [0, 1], [0, 2], [1, 1], [1, 2], [2, 2], [3, 1], [3, 2], [3, 3]])
# rows of the work array
RIJ, RKJ, RKL, M, N, GI, GJ, GK, GL, D1, D2 = range(11)
V = 11                             # V + 0 ... V + 9: the vectors v0 ... v9 below


def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _kernel(x, k, theta0, want_hess, energy, grad, hess):
    w = np.empty((V + 10, 3))
    blk = np.empty((9, 3, 3))
    g = np.empty(12)
    for e in range(x.shape[0]):
        for a in range(3):
            w[RIJ, a] = x[e, 0, a] - x[e, 1, a]
            w[RKJ, a] = x[e, 2, a] - x[e, 1, a]
            w[RKL, a] = x[e, 2, a] - x[e, 3, a]
        _cross(w[RIJ], w[RKJ], w[M])
        _cross(w[RKJ], w[RKL], w[N])
        mm = _dot(w[M], w[M])
        nn = _dot(w[N], w[N])
        rr = _dot(w[RKJ], w[RKJ])
        r = math.sqrt(rr)
        theta = math.atan2(r * _dot(w[M], w[RKL]), _dot(w[M], w[N])) % (2 * math.pi)
        A = _dot(w[RIJ], w[RKJ]) / rr
        B = _dot(w[RKL], w[RKJ]) / rr
        d = theta - theta0[e]
        d -= 2 * math.pi * math.floor(d / (2 * math.pi) + 0.5)      # periodic: see springs.py
        moment = k[e] * d
        energy[e] = 0.5 * moment * d
        for a in range(3):
            w[GI, a] = (r / mm) * w[M, a]
            w[GL, a] = -(r / nn) * w[N, a]
        for a in range(3):
            w[GJ, a] = (A - 1) * w[GI, a] - B * w[GL, a]
            w[GK, a] = (B - 1) * w[GL, a] - A * w[GI, a]
            for node in range(4):
                g[3 * node + a] = w[GI + node, a]
        for p in range(12):
            grad[e, p] = moment * g[p]
        if want_hess:
            _hessian(w, blk, g, A, B, r, rr, mm, nn, k[e], moment, hess[e])


def _hessian(w, blk, g, A, B, r, rr, mm, nn, ke, moment, h):
    sm = r / mm**2
    sn = r / nn**2
    for a in range(3):
        w[D1, a] = w[RKJ, a] - w[RIJ, a]
        w[D2, a] = w[RKJ, a] - w[RKL, a]
    _cross(w[RKJ], w[M], w[V + 0])
    _cross(w[RIJ], w[M], w[V + 1])
    _cross(w[D1], w[M], w[V + 2])
    _cross(w[RKJ], w[N], w[V + 3])
    _cross(w[RKL], w[N], w[V + 4])
    _cross(w[D2], w[N], w[V + 5])
    for a in range(3):
        w[V + 6, a] = ((2 * A - 1) * w[RKJ, a] - w[RIJ, a]) / rr        # dA/dx_j
        w[V + 7, a] = (w[RIJ, a] - 2 * A * w[RKJ, a]) / rr              # dA/dx_k
        w[V + 8, a] = (2 * B * w[RKJ, a] - w[RKL, a]) / rr              # dB/dx_j
        w[V + 9, a] = ((1 - 2 * B) * w[RKJ, a] + w[RKL, a]) / rr        # dB/dx_k
    for a in range(3):
        for b in range(3):
            mr = w[M, a] * w[RKJ, b] / (mm * r)
            nr = w[N, a] * w[RKJ, b] / (nn * r)
            h_ii = -sm * (w[M, a] * w[V, b] + w[V, a] * w[M, b])
            h_ik = mr + sm * (w[M, a] * w[V + 1, b] + w[V + 1, a] * w[M, b])
            h_ij = -mr + sm * (w[M, a] * w[V + 2, b] + w[V + 2, a] * w[M, b])
            h_ll = sn * (w[N, a] * w[V + 3, b] + w[V + 3, a] * w[N, b])
            h_lj = nr - sn * (w[N, a] * w[V + 4, b] + w[V + 4, a] * w[N, b])
            h_lk = -nr - sn * (w[N, a] * w[V + 5, b] + w[V + 5, a] * w[N, b])
            blk[0, a, b] = h_ii
            blk[1, a, b] = h_ij
            blk[2, a, b] = h_ik
            blk[6, a, b] = h_lj
            blk[7, a, b] = h_lk
            blk[8, a, b] = h_ll
            blk[3, a, b] = (w[GI, a] * w[V + 6, b] + (A - 1) * h_ij
                            - w[GL, a] * w[V + 8, b] - B * h_lj)
            blk[4, a, b] = (w[GI, a] * w[V + 7, b] + (A - 1) * h_ik
                            - w[GL, a] * w[V + 9, b] - B * h_lk)
            blk[5, a, b] = (w[GL, a] * w[V + 9, b] + (B - 1) * h_lk
                            - w[GI, a] * w[V + 7, b] - A * h_ik)
    for p in range(12):
        for q in range(12):
            h[p, q] = ke * g[p] * g[q]
    for idx in range(9):
        p, q = _BLOCK_POS[idx, 0], _BLOCK_POS[idx, 1]
        for a in range(3):
            for b in range(3):
                val = moment * blk[idx, a, b]
                h[3 * p + a, 3 * q + b] += val
                if p != q:
                    h[3 * q + b, 3 * p + a] += val


_compiled = None
_broken = False                    # compilation failed once: numpy from then on
#: The backend in force: None = :func:`default_backend`, else one of BACKENDS.
backend = None


def default_backend() -> str:
    """``"numba"`` if installed and not switched off by ``ETORIGAMI_JIT``, else ``"numpy"``."""
    off = os.environ.get("ETORIGAMI_JIT", "").strip().lower() in _OFF
    return "numba" if AVAILABLE and not off else "numpy"


def _compile():
    """Compile (or load from numba's cache) the kernel and its helpers; None if that fails
    (then the numpy kernel is used, and compilation is not tried again)."""
    global _compiled, _broken
    try:
        from numba import njit

        g = globals()
        for name in ("_cross", "_dot", "_hessian"):
            if not hasattr(g[name], "py_func"):
                g[name] = njit(cache=True)(g[name])
        _compiled = njit(_SIGNATURE, cache=True)(_kernel)       # compiles (or loads) now
        return _compiled
    except Exception as exc:  # noqa: BLE001 - numba is an accelerator, never a requirement
        logger.warning("numba could not compile the spring kernel (%s: %s); using numpy",
                       type(exc).__name__, exc)
        _broken = True
        return None


def use_compiled() -> bool:
    """Whether :func:`simulator.elements.springs.spring_kernel` calls the compiled kernel
    (compiling or loading it on the first call)."""
    if _broken or (backend or default_backend()) != "numba":
        return False
    if _compiled is None:
        logger.info("compiling the spring kernel with numba (cached after the first time)")
    return (_compiled or _compile()) is not None


def spring_kernel_jit(x, k, theta0, hessian=True):
    """Energy (n,), gradient (n, 12), Hessian (n, 12, 12) or None: see
    :func:`simulator.elements.springs.spring_kernel`. Compiles on first use."""
    kernel = _compiled or _compile()
    if kernel is None:
        raise RuntimeError("the compiled spring kernel is not available (numba missing or "
                           "compilation failed); use spring_kernel_numpy")
    n = len(x)
    energy = np.empty(n)
    grad = np.empty((n, 12))
    hess = np.empty((n, 12, 12)) if hessian else np.empty((0, 12, 12))
    kernel(np.ascontiguousarray(x, dtype=np.float64), np.ascontiguousarray(k, dtype=np.float64),
           np.ascontiguousarray(theta0, dtype=np.float64), hessian, energy, grad, hess)
    return energy, grad, (hess if hessian else None)
