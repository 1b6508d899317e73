"""Compiled (numba) rotational-spring kernel: same formulas as :mod:`.springs`.

On small meshes (tens of springs) the numpy kernel spends its time in ~60 array calls of a
few microseconds each; this loop-based version does one call (about 10 us instead of
150-500 us for 20 springs). It is written with scalar arithmetic on a small 1-D work array (no
``np.cross``, ``@``, array temporaries or array-to-array assignments, and few array accesses in
the source: numba's compile time grows with them, not with the loop trip counts), and it is
checked against the numpy kernel by the tests.

Compiling costs about 2 s of CPU once per install (0.5 s importing numba, 0.4 s numba's own
start-up, 1.2 s compiling; 1.6 s with the 2-D work array and nine Hessian blocks written out,
5.4-6.7 s for the earlier array-style kernel); loading it from numba's cache (next to this file
or in ``NUMBA_CACHE_DIR``) costs 0.7 s per process. On small models the fused kernel of
:mod:`._fused_jit` calls the per-spring function :func:`element` instead of this kernel. A run of one of the paper's cases
calls the kernel 1,200-2,500 times and one gripper evaluation 870-1,650 times, too few to win
that back; an optimisation does (15 coordinate-descent evaluations: 12.7 s of CPU compiled,
compilation included, against 15.1 s on numpy).

So numba is imported, and the kernel compiled, only when the kernel is first called with
compiled kernels selected. :mod:`simulator._jit` decides that for every kernel of the package
(:func:`simulator._jit.numba_selected`: numba installed and ``ETORIGAMI_JIT`` not off, unless a
block of :func:`simulator.mechanics.elements.springs.spring_kernel_backend` says otherwise),
never by how much has been computed or by the state of numba's cache, so that the same
computation gives the same floats in every process (serial and process-pool sweeps are
compared bit for bit).
"""

from __future__ import annotations

import math

import numpy as np

from ... import _jit
from ..._jit import HELPER_OPTIONS, compile_kernel, numba_selected

__all__ = ["compiled_backend", "default_backend", "spring_kernel_jit", "use_compiled", "element", "cross", "dot", "jit_helpers"]

#: The one specialisation compiled: x (n, 4, 3), k (n,), theta0 (n,), want_hess, energy (n,),
#: grad (n, 12), hess (n or 0, 12, 12); all C-contiguous float64.
_SIGNATURE = "void(f8[:, :, ::1], f8[::1], f8[::1], b1, f8[::1], f8[:, ::1], f8[:, :, ::1])"
#: Helpers called with constant offsets get a signature: without one numba would compile a
#: version per distinct set of literal arguments.
_HELPER_SIGNATURES = {"cross": "void(f8[::1], i8, i8, i8)", "dot": "f8(f8[::1], i8, i8)"}

# offsets in the 1-D work array: 3-vectors, then 12-vectors (node blocks i, j, k, l)
RIJ, RKJ, RKL, M, N, C0, C1, C3, C4 = range(0, 27, 3)
U, S, U2, S2, DA, DB = range(27, 99, 12)
#: Size of the work array of :func:`element`.
WORK = 99


def cross(w, i, j, k):
    """w[k:k+3] = w[i:i+3] x w[j:j+3]."""
    w[k] = w[i + 1] * w[j + 2] - w[i + 2] * w[j + 1]
    w[k + 1] = w[i + 2] * w[j] - w[i] * w[j + 2]
    w[k + 2] = w[i] * w[j + 1] - w[i + 1] * w[j]


def dot(w, i, j):
    return w[i] * w[j] + w[i + 1] * w[j + 1] + w[i + 2] * w[j + 2]


def _kernel(x, k, theta0, want_hess, energy, grad, hess):
    w = np.empty(WORK)
    g = np.empty(12)
    h = np.empty((12, 12))
    for e in range(x.shape[0]):
        energy[e] = element(x[e], k[e], theta0[e], want_hess, w, g, grad[e],
                             hess[e] if want_hess else h)


def element(x, ke, theta0, want_hess, w, g, grad, h):
    """One spring with nodes ``x`` (4, 3): its energy; gradient into ``grad`` (12,) and, if
    ``want_hess``, Hessian into ``h`` (12, 12); ``w`` (:data:`WORK`,) and ``g`` (12,) are
    work arrays. Also used by the fused small-model kernel (:mod:`._fused_jit`)."""
    for a in range(3):
        w[RIJ + a] = x[0, a] - x[1, a]
        w[RKJ + a] = x[2, a] - x[1, a]
        w[RKL + a] = x[2, a] - x[3, a]
    cross(w, RIJ, RKJ, M)
    cross(w, RKJ, RKL, N)
    mm = dot(w, M, M)
    nn = dot(w, N, N)
    rr = dot(w, RKJ, RKJ)
    r = math.sqrt(rr)
    theta = math.atan2(r * dot(w, M, RKL), dot(w, M, N)) % (2 * math.pi)
    A = dot(w, RIJ, RKJ) / rr
    B = dot(w, RKL, RKJ) / rr
    d = theta - theta0
    d -= 2 * math.pi * math.floor(d / (2 * math.pi) + 0.5)          # periodic: see springs.py
    moment = ke * d
    cm, cn = r / mm, -(r / nn)
    for a in range(3):
        gi = cm * w[M + a]
        gl = cn * w[N + a]
        g[a] = gi
        g[3 + a] = (A - 1) * gi - B * gl
        g[6 + a] = (B - 1) * gl - A * gi
        g[9 + a] = gl
    for p in range(12):
        grad[p] = moment * g[p]
    if want_hess:                 # see _HESSIAN_NOTE
        sm = r / (mm * mm)
        sn = r / (nn * nn)
        mr = 1 / (mm * r)
        nr = 1 / (nn * r)
        cross(w, RKJ, M, C0)
        cross(w, RIJ, M, C1)
        cross(w, RKJ, N, C3)
        cross(w, RKL, N, C4)
        for a in range(3):
            kj, ij, kl = w[RKJ + a], w[RIJ + a], w[RKL + a]
            v0, v1, v3, v4 = w[C0 + a], w[C1 + a], w[C3 + a], w[C4 + a]
            w[U + a], w[U + 3 + a], w[U + 6 + a], w[U + 9 + a] = (
                -sm * v0, -kj * mr + sm * (v0 - v1), kj * mr + sm * v1, 0.0)
            w[S + a], w[S + 3 + a], w[S + 6 + a], w[S + 9 + a] = -v0, v0 - v1, v1, 0.0
            w[U2 + a], w[U2 + 3 + a], w[U2 + 6 + a], w[U2 + 9 + a] = (
                0.0, kj * nr - sn * v4, -kj * nr - sn * (v3 - v4), sn * v3)
            w[S2 + a], w[S2 + 3 + a], w[S2 + 6 + a], w[S2 + 9 + a] = 0.0, -v4, v4 - v3, v3
            w[DA + a], w[DA + 3 + a], w[DA + 6 + a], w[DA + 9 + a] = (
                kj / rr, ((2 * A - 1) * kj - ij) / rr, (ij - 2 * A * kj) / rr, 0.0)
            w[DB + a], w[DB + 3 + a], w[DB + 6 + a], w[DB + 9 + a] = (
                0.0, (2 * B * kj - kl) / rr, ((1 - 2 * B) * kj + kl) / rr, -kj / rr)
        for a in range(3):
            ma, na, gi, gl = w[M + a], w[N + a], g[a], g[9 + a]
            for q in range(12):
                b = q % 3
                Gi = ma * w[U + q] + sm * w[S + q - b + a] * w[M + b]
                Gl = na * w[U2 + q] + sn * w[S2 + q - b + a] * w[N + b]
                dA, dB = w[DA + q], w[DB + q]
                kg = ke * g[q]
                h[a, q] = kg * g[a] + moment * Gi
                h[3 + a, q] = kg * g[3 + a] + moment * ((A - 1) * Gi - B * Gl + gi * dA - gl * dB)
                h[6 + a, q] = kg * g[6 + a] + moment * ((B - 1) * Gl - A * Gi + gl * dB - gi * dA)
                h[9 + a, q] = kg * g[9 + a] + moment * Gl
    return 0.5 * moment * d


_compiled = None
_broken = False                    # compilation failed once: numpy from then on


def default_backend() -> str:
    """``"numba"`` if installed and not switched off by ``ETORIGAMI_JIT``, else ``"numpy"``
    (:func:`simulator._jit.default_backend`)."""
    return _jit.default_backend()


def jit_helpers():
    """Replace the per-spring helpers by their numba versions (compiled on first call, cached);
    the spring kernel and the fused kernel (:mod:`._fused_jit`) call them. Imports numba."""
    from numba import njit

    g = globals()
    for name in ("cross", "dot", "element"):
        if not hasattr(g[name], "py_func"):
            g[name] = njit(_HELPER_SIGNATURES.get(name), cache=True, **HELPER_OPTIONS)(g[name])


def _build():
    from numba import njit

    jit_helpers()
    return njit(_SIGNATURE, cache=True)(_kernel)       # compiles (or loads) now


def _compile():
    """Compile (or load from numba's cache) the kernel and its helpers; None if that fails
    (then the numpy kernel is used, and compilation is not tried again)."""
    global _compiled, _broken
    _compiled = compile_kernel("spring kernel", _build, "using numpy")
    _broken = _compiled is None
    return _compiled


def compiled_backend() -> bool:
    """Whether the compiled backend is in force (numba selected and the spring kernel's
    compilation not failed); nothing is imported or compiled."""
    return not _broken and numba_selected()


def use_compiled() -> bool:
    """Whether :func:`simulator.mechanics.elements.springs.spring_kernel` calls the compiled kernel
    (compiling or loading it on the first call)."""
    if _broken or not numba_selected():
        return False
    return (_compiled or _compile()) is not None


def spring_kernel_jit(x, k, theta0, hessian=True):
    """Energy (n,), gradient (n, 12), Hessian (n, 12, 12) or None: see
    :func:`simulator.mechanics.elements.springs.spring_kernel`. Compiles on first use."""
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
