"""Compiled (numba) bar kernel: the operations of :func:`.bars.bar_kernel` in the same order.

On large sheets the numpy kernel's time goes into its (n, 6, 6) array temporaries (five of
them, about 74 MB each at 1e5 nodes, allocated and freed at every Newton iteration): 60-210
ms per call at 256,128 bars against about 10 ms for this loop. It computes the same floats
(the tests compare bit for bit): the strain sums ``x0 y0 + x2 y2`` first, as numpy's einsum
does, and every Hessian entry is ``c (g_i g_j) + s B_ij``.

Used by :meth:`simulator.mechanics.equilibrium.EquilibriumSystem.evaluate` on models outside the fused
small-model kernel, with the ``"numba"`` backend (the switch of
:func:`simulator._jit.numba_selected`); compiled on first use (about 1 s of
CPU once per install, then loaded from numba's cache).
"""

from __future__ import annotations

import numpy as np

from ..._jit import compile_kernel, numba_selected

__all__ = ["bar_kernel_jit", "use_compiled"]

_compiled = None
_broken = False


def _kernel(dX, du, L0, EA, want_hess, energy, grad, hess):
    g = np.empty(6)
    for e in range(dX.shape[0]):
        v0, v1, v2 = du[e, 0], du[e, 1], du[e, 2]
        d0, d1, d2 = dX[e, 0], dX[e, 1], dX[e, 2]
        L2 = L0[e] * L0[e]
        eps = (2 * ((d0 * v0 + d2 * v2) + d1 * v1) + ((v0 * v0 + v2 * v2) + v1 * v1)) / (2 * L2)
        c = EA[e] * L0[e]
        ce = c * eps
        g[3], g[4], g[5] = (d0 + v0) / L2, (d1 + v1) / L2, (d2 + v2) / L2
        g[0], g[1], g[2] = -(d0 + v0) / L2, -(d1 + v1) / L2, -(d2 + v2) / L2
        energy[e] = 0.5 * c * eps**2
        for p in range(6):
            grad[e, p] = ce * g[p]
        if want_hess:
            sb = ce / L2
            for i in range(6):
                for j in range(6):
                    hess[e, i, j] = c * (g[i] * g[j]) + (sb if j == i else
                                                         (-sb if j == (i + 3) % 6 else 0.0))


def _build():
    from numba import njit, types

    def array(ndim, readonly=False):
        return types.Array(types.float64, ndim, "C", readonly=readonly)

    # dX (n, 3), du (n, 3), L0 (n,), EA (n,): read-only allowed (the system's arrays are), no
    # copies; want_hess; energy (n,), grad (n, 6), hess (n or 0, 6, 6) written
    signature = types.void(array(2, True), array(2, True), array(1, True), array(1, True),
                           types.boolean, array(1), array(2), array(3))
    return njit(signature, cache=True)(_kernel)


def use_compiled() -> bool:
    """Whether the compiled kernel is used (the "numba" backend is in force and compiling, or
    loading, it has not failed; it is compiled on the first call that says yes)."""
    global _compiled, _broken
    if _broken or not numba_selected():
        return False
    if _compiled is None:
        _compiled = compile_kernel("bar kernel", _build, "using numpy")
        _broken = _compiled is None
    return _compiled is not None


def bar_kernel_jit(dX, du, L0, EA, hessian: bool = True):
    """Energy [J] (n,), gradient [N] (n, 6) and Hessian [N/m] (n, 6, 6) or None: see
    :func:`simulator.mechanics.elements.bars.bar_kernel`. Requires :func:`use_compiled` to be True."""
    if _compiled is None:
        raise RuntimeError("the compiled bar kernel is not available; call use_compiled() "
                           "first, or use simulator.mechanics.elements.bars.bar_kernel")
    n = len(dX)
    energy, grad = np.empty(n), np.empty((n, 6))
    hess = np.empty((n, 6, 6)) if hessian else np.empty((0, 6, 6))
    dX, du, L0, EA = (np.ascontiguousarray(a, dtype=np.float64) for a in (dX, du, L0, EA))
    _compiled(dX, du, L0, EA, hessian, energy, grad, hess)
    return energy, grad, (hess if hessian else None)
