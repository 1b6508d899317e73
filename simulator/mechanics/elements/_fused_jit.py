"""Fused compiled (numba) evaluation of a small model: bars, springs, contact, elastic supports.

One call computes what :meth:`simulator.mechanics.equilibrium.EquilibriumSystem.evaluate` assembles from
the numpy kernels on small meshes: the internal force ``f`` (n_dof,), the energy per kind and
the active contact pairs, and the tangent stiffness on the free DOFs written straight into a
DENSE (n_free, n_free) matrix: no per-element Hessian arrays, no CSR, no candidate arrays. The
numpy kernels (:mod:`.bars`, :mod:`.springs`, :mod:`.contact`,
:mod:`simulator.mechanics.contact_search`) stay the reference: the formulas below are theirs, written
with scalar arithmetic, and the tests compare the two paths. It is an accelerator, not the
structure: the system chooses it only when the model's element families are exactly the four
it knows (:data:`simulator.mechanics.families.FUSED_FAMILIES`); any other family sends the
model through the generic assembly of :mod:`simulator.mechanics.assembly`.

* bars: :func:`simulator.mechanics.elements.bars.bar_kernel`, same operations in the same order (the
  strain of a stiff bar cancels strongly, so it is worth the same floats);
* springs: the per-spring function of :mod:`._springs_jit` (shared with the compiled spring
  kernel);
* contact: the bounding-sphere filter of :meth:`simulator.mechanics.contact_search.ContactSearch.
  candidates` over all admissible pairs (``static`` mode), then per pair the plane-distance
  pre-filter, Ericson's Voronoi regions, the distance derivatives per zone (face, vertex, edge)
  and the penalty of :mod:`.contact`; a pair is active (counted and assembled) when its energy
  is positive, as in the numpy path;
* summation order of the numpy path: ``f = (bars + springs) + supports + contact``, each family
  element by element, ``K`` entry by entry over bars, springs, contact, supports; so without
  active contact the results are those of the numpy path with the compiled spring kernel,
  bit for bit.

Numba's compile time grows with the number of array accesses written in the source (not with
loop trip counts), so the code keeps vectors in small 1-D work arrays handled in loops.
Numba is imported, and the kernel compiled (one signature, ``cache=True``), on the first call
of :func:`fused_kernel`; the backend switch of :mod:`._springs_jit` (``ETORIGAMI_JIT``,
:func:`simulator.mechanics.elements.springs.spring_kernel_backend`) decides whether the fused path is
used at all. numba's cache does not notice edits of :mod:`._springs_jit` (a callee in another
file): after changing the spring element there, delete the cached ``_fused_jit*`` files in
``__pycache__`` (the tests comparing with numpy would show the stale kernel).
"""

from __future__ import annotations

import math

import numpy as np

from ... import _jit
from ..._jit import compile_kernel
from . import _springs_jit
from ._springs_jit import HELPER_OPTIONS, cross, dot  # noqa: F401 - compiled ones at _compile

__all__ = ["fused_kernel", "SIGNATURE", "broken"]


_EPS = 1e-12                       # as in .contact: relative floors
_TINY = 1e-100
_HALF_PI = 0.5 * np.pi
_SPRING_WORK = _springs_jit.WORK
# Maclaurin coefficients (.contact._TAN): (tan x - x)/x = sum T_m x^(2m), m = 1..7
_T1, _T2, _T3, _T4, _T5, _T6, _T7 = (1 / 3, 2 / 15, 17 / 315, 62 / 2835, 1382 / 155925,
                                     21844 / 6081075, 929569 / 638512875)
# contact work array offsets: slot vectors, then 9-vectors
AP, AB, AC, NRM, R, E, C, RHO = range(0, 24, 3)
GV, GA, GS, FU = range(24, 60, 9)
_CONTACT_WORK = 60

#: f(x, u, bars, bar_dX, bar_L0, bar_EA, bar_kind, springs, spr_k, spr_rest, spr_kind,
#: free_index, elastic_dofs, elastic_k, pair_point, pair_tri, pair_d0, tri, ke, want_K,
#: f, K, energies, active) -> number of active contact pairs (their indices in active[:n])
SIGNATURE = ("i8(f8[:, ::1], f8[:, ::1], i8[:, ::1], f8[:, ::1], f8[::1], f8[::1], i8[::1], "
             "i8[:, ::1], f8[::1], f8[::1], i8[::1], i8[::1], i8[::1], f8[::1], i8[::1], i8[::1], "
             "f8[::1], i8[:, ::1], f8, b1, f8[::1], f8[:, ::1], f8[::1], i8[::1])")


def _face(w, V, inv, Hs):
    """Slot gradient w[GS:GS+9] and Hessian Hs[:9, :9] of d = |V| / |N| on the slots
    y = (a, b, c) = w[R:R+9] (see .contact._face)."""
    cross(w, E, C, GV)            # dV/dy = (b x c, c x a, a x b)
    cross(w, C, R, GV + 3)
    cross(w, R, E, GV + 6)
    cross(w, C, GV, GA + 3)       # dA2/dy = (0, 2 c x N, 2 N x b), N = b x c
    cross(w, GV, E, GA + 6)
    for p in range(9):
        w[GA + p] = 0.0 if p < 3 else 2 * w[GA + p]
    iv2 = inv * inv
    cV = math.copysign(inv, V)
    cVA = -0.5 * iv2 * cV
    cA = cVA * V
    hAA = -0.75 * iv2 * cA
    for p in range(9):
        w[GS + p] = cV * w[GV + p] + cA * w[GA + p]
        w[FU + p] = cVA * w[GV + p] + hAA * w[GA + p]
    bb, cc, bc = dot(w, E, E), dot(w, C, C), dot(w, E, C)
    for p in range(9):
        for q in range(9):     # f_VA (gV gA + gA gV) + f_AA gA gA, then f_A d2A2/dy2
            hpq = w[FU + p] * w[GA + q] + w[GA + p] * w[FU + q]
            i, j = p % 3, q % 3
            dij = 1.0 if i == j else 0.0
            if p >= 3 and q >= 3:
                if p < 6 and q < 6:
                    hpq += cA * (2 * dij * cc - 2 * w[C + i] * w[C + j])
                elif p >= 6 and q >= 6:
                    hpq += cA * (2 * dij * bb - 2 * w[E + i] * w[E + j])
                else:
                    ib, jc = (i, j) if p < 6 else (j, i)
                    hpq += cA * (4 * w[E + ib] * w[C + jc] - 2 * w[E + jc] * w[C + ib] - 2 * dij * bc)
            Hs[p, q] = hpq
    for i in range(3):             # f_V d2V/dy2: eps_ijk on the (a, b), (a, c), (b, c) blocks
        j, k = (i + 1) % 3, (i + 2) % 3
        for sgn in (1.0, -1.0):
            s = cV * sgn
            Hs[i, 3 + j] += s * w[C + k]
            Hs[3 + j, i] += s * w[C + k]
            Hs[i, 6 + k] += s * w[E + j]
            Hs[6 + k, i] += s * w[E + j]
            Hs[3 + j, 6 + k] += s * w[R + i]
            Hs[6 + k, 3 + j] += s * w[R + i]
            j, k = k, j


def _vertex_edge(w, d, t, kinv, dmin, Hs):
    """Slot gradient w[GS:GS+6] and Hessian Hs[:6, :6] of d = |rho| on the slots (r, e)
    (see .contact._vertex_edge); rho = w[RHO:RHO+3]."""
    dc = max(d, dmin)
    sk = math.sqrt(kinv)
    for p in range(6):
        a = p % 3
        w[GS + p] = (1.0 if p < 3 else -t) * (w[RHO + a] / dc)
        w[FU + p] = (w[E + a] if p < 3 else -t * w[E + a] + w[RHO + a]) * sk
    for p in range(6):
        for q in range(6):
            lam = (1.0 if p < 3 else -t) * (1.0 if q < 3 else -t) if p % 3 == q % 3 else 0.0
            Hs[p, q] = (lam - (w[FU + p] * w[FU + q] + w[GS + p] * w[GS + q])) / dc


def _contact_pair(xc, d0, ke, want_K, w, Hs, G, H):
    """Penalty energy of one (point, triangle) pair with nodes xc (4, 3) = (P, T1, T2, T3)
    (0 when out of range); if positive, its gradient into G (12,) and, if want_K, Hessian
    into H (12, 12), node-major; w (_CONTACT_WORK,), Hs (9, 9) work."""
    for a in range(3):
        w[AP + a] = xc[0, a] - xc[1, a]
        w[AB + a] = xc[2, a] - xc[1, a]
        w[AC + a] = xc[3, a] - xc[1, a]
    cross(w, AB, AC, NRM)
    q0, q1, q2, q3 = dot(w, AP, NRM), dot(w, NRM, NRM), dot(w, AB, AB), dot(w, AC, AC)
    q4, q5, q6 = dot(w, AB, AP), dot(w, AC, AP), dot(w, AB, AC)
    fl = _EPS * (q2 + q3)
    inv = max(q1, fl * fl + _TINY) ** -0.5
    hgt = abs(q0) * inv
    if not hgt <= d0:                                   # exact pre-filter: h <= d
        return 0.0
    # Ericson's regions in his order: V1, V2, E12, V3, E31, E23, face -> zone, anchor
    d1, d2, d3, d4, d5, d6 = q4, q5, q4 - q2, q5 - q6, q4 - q6, q5 - q3
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    if d1 <= 0 and d2 <= 0:
        zone, anchor = 1, 0
    elif -d3 <= 0 and d4 - d3 <= 0:
        zone, anchor = 1, 1
    elif vc <= 0 and -d1 <= 0 and d3 <= 0:
        zone, anchor = 2, 0
    elif -d6 <= 0 and d5 - d6 <= 0:
        zone, anchor = 1, 2
    elif vb <= 0 and -d2 <= 0 and d6 <= 0:
        zone, anchor = 2, 2
    elif va <= 0 and d3 - d4 <= 0 and d6 - d5 <= 0:
        zone, anchor = 2, 1
    else:
        zone, anchor = 0, 0
    ta, tn, tn2 = 1 + anchor, 1 + (anchor + 1) % 3, 1 + (anchor + 2) % 3
    for a in range(3):             # slots (P - Ta, Tn - Ta, Tn2 - Ta)
        w[R + a] = xc[0, a] - xc[ta, a]
        w[E + a] = xc[tn, a] - xc[ta, a]
        w[C + a] = xc[tn2, a] - xc[ta, a]
    ee = dot(w, E, E)
    if zone == 2 and ee <= _EPS**2 * (q2 + q3):          # zero-length edge: a vertex
        zone = 1
    kinv = 1.0 / ee if zone == 2 else 0.0
    t = dot(w, R, E) * kinv
    for a in range(3):
        w[RHO + a] = w[R + a] - t * w[E + a]
    d = hgt if zone == 0 else math.sqrt(dot(w, RHO, RHO))
    if not d <= d0:
        return 0.0
    # penalty U(d) = ke [ln sec(phi) - phi^2 / 2], phi = pi/2 (1 - d/d0), and U', U''
    phi = _HALF_PI * (1.0 - min(max(d / d0, _EPS), 1.0))
    p2 = phi * phi
    if phi <= 0.1:                 # series (the closed forms cancel)
        s0 = p2 * (_T1 + p2 * (_T2 + p2 * (_T3 + p2 * (_T4 + p2 * (_T5 + p2 * (_T6 + p2 * _T7))))))
        lnsec = p2 * p2 * (_T1 / 4 + p2 * (_T2 / 6 + p2 * (_T3 / 8 + p2 * (
            _T4 / 10 + p2 * (_T5 / 12 + p2 * (_T6 / 14 + p2 * _T7 / 16))))))
        tan_m = phi * s0
        tan = phi + tan_m
    else:
        tan = math.tan(phi)
        lnsec, tan_m = 0.5 * (math.log1p(tan * tan) - p2), tan - phi
    dphi = -_HALF_PI / d0
    kd = ke * dphi
    U, dU, d2U = ke * lnsec, kd * tan_m, kd * dphi * tan * tan
    if not U > 0:
        return 0.0
    if zone == 0:
        ns = 3
        _face(w, q0, inv, Hs)
    else:
        ns = 2
        _vertex_edge(w, d, t, kinv, _EPS * d0, Hs)
    m = 3 * ns
    for p in range(m):
        if want_K:
            for q in range(m):
                Hs[p, q] = Hs[p, q] * dU + d2U * (w[GS + p] * w[GS + q])
    for p in range(m):
        w[GS + p] *= dU
    # slots -> nodes (P, T1, T2, T3): slot s = node plus(s) - node ta
    for p in range(12):
        G[p] = 0.0
        if want_K:
            for q in range(12):
                H[p, q] = 0.0
    for p in range(m):
        s, a = p // 3, p % 3
        ps = 3 * (0 if s == 0 else (tn if s == 1 else tn2)) + a
        G[ps] += w[GS + p]
        G[3 * ta + a] -= w[GS + p]
        if want_K:
            for q in range(m):
                t2, b = q // 3, q % 3
                pt = 3 * (0 if t2 == 0 else (tn if t2 == 1 else tn2)) + b
                v = Hs[p, q]
                H[ps, pt] += v
                H[ps, 3 * ta + b] -= v
                H[3 * ta + a, pt] -= v
                H[3 * ta + a, 3 * ta + b] += v
    return U


def _kernel(x, u, bars, bar_dX, bar_L0, bar_EA, bar_kind, springs, spr_k, spr_rest, spr_kind,
            free_index, elastic_dofs, elastic_k, pair_point, pair_tri, pair_d0, tri, ke, want_K,
            f, K, energies, active):
    # One loop over bars, springs and contact pairs with one assembly site (numba compiles
    # each site of inlined code again). Summation order of the numpy path: the forces of the
    # families are summed separately (rows of F), then f = (bars + springs) + supports +
    # contact; K entry by entry over bars, springs, contact, then supports.
    n_dof = f.shape[0]
    F = np.empty((3, n_dof))
    for i in range(3 * n_dof):
        F[i // n_dof, i % n_dof] = 0.0
    for i in range(6):
        energies[i] = 0.0
    if want_K:
        for i in range(K.shape[0]):
            for j in range(K.shape[1]):
                K[i, j] = 0.0
    nt = tri.shape[0] if pair_point.shape[0] else 0
    sphere = np.empty(4 * nt)                          # bounding spheres of the triangles
    for t in range(nt):
        for a in range(3):
            sphere[4 * t + a] = (x[tri[t, 0], a] + x[tri[t, 1], a] + x[tri[t, 2], a]) / 3
        rad = 0.0
        for p in range(3):
            s = 0.0
            for a in range(3):
                s += (x[tri[t, p], a] - sphere[4 * t + a]) ** 2
            rad = max(rad, math.sqrt(s))
        sphere[4 * t + 3] = rad
    fl = np.empty(12, np.int64)
    nodes = np.empty(4, np.int64)
    g = np.empty(12)
    h = np.empty((12, 12))
    v = np.empty(_SPRING_WORK)
    gw = np.empty(12)
    xe = np.empty((4, 3))
    wc = np.empty(_CONTACT_WORK)
    Hs = np.empty((9, 9))
    nb, ns = bars.shape[0], springs.shape[0]
    n_active = 0
    for e in range(nb + ns + pair_point.shape[0]):
        if e < nb:                                      # bar: see .bars.bar_kernel; the same
            fam, k = 0, 2                               # operations in the same order (its
            nodes[0], nodes[1] = bars[e, 0], bars[e, 1]  # einsum sums x0 y0 + x2 y2 first)
            for a in range(3):
                v[a] = u[nodes[1], a] - u[nodes[0], a]
            dX, L0 = bar_dX[e], bar_L0[e]
            L2 = L0 * L0
            eps = (2 * ((dX[0] * v[0] + dX[2] * v[2]) + dX[1] * v[1])
                   + ((v[0] * v[0] + v[2] * v[2]) + v[1] * v[1])) / (2 * L2)
            c = bar_EA[e] * L0
            ce = c * eps
            for a in range(3):
                g[a + 3] = (dX[a] + v[a]) / L2
                g[a] = -(dX[a] + v[a]) / L2
            if want_K:
                sb = ce / L2
                for p in range(36):
                    i, j = p // 6, p % 6
                    h[i, j] = c * (g[i] * g[j]) + (sb if j == i else
                                                   (-sb if j == (i + 3) % 6 else 0.0))
            for p in range(6):
                g[p] = ce * g[p]
            energies[3 - bar_kind[e]] += 0.5 * c * eps**2
        elif e < nb + ns:                               # spring
            fam, k, i = 1, 4, e - nb
            for p in range(12):
                nodes[p // 3] = springs[i, p // 3]
                xe[p // 3, p % 3] = x[nodes[p // 3], p % 3]
            energies[spr_kind[i]] += _spring_element(xe, spr_k[i], spr_rest[i], want_K, v, gw,
                                                     g, h)
        else:                                           # contact pair, as ContactSearch and
            fam, k, i = 2, 4, e - nb - ns               # contact_kernel
            pt, t = pair_point[i], pair_tri[i]
            s = 0.0
            for a in range(3):
                s += (x[pt, a] - sphere[4 * t + a]) ** 2
            if not math.sqrt(s) <= sphere[4 * t + 3] + pair_d0[i]:
                continue
            for p in range(12):
                nodes[p // 3] = pt if p < 3 else tri[t, p // 3 - 1]
                xe[p // 3, p % 3] = x[nodes[p // 3], p % 3]
            U = _contact_pair(xe, pair_d0[i], ke, want_K, wc, Hs, g, h)
            if not U > 0:
                continue
            active[n_active] = i
            n_active += 1
            energies[4] += U
        m = 3 * k                                       # assembly
        for p in range(m):
            dof = 3 * nodes[p // 3] + p % 3
            F[fam, dof] += g[p]
            fl[p] = free_index[dof]
        if want_K:
            for p in range(m):
                if fl[p] >= 0:
                    for q in range(m):
                        if fl[q] >= 0:
                            K[fl[p], fl[q]] += h[p, q]
    e_support = 0.0
    for i in range(n_dof):
        f[i] = F[0, i] + F[1, i]
    for i in range(elastic_dofs.shape[0]):
        dof = elastic_dofs[i]
        ui = u[dof // 3, dof % 3]
        f[dof] += elastic_k[i] * ui
        e_support += elastic_k[i] * (ui * ui)
        if want_K and free_index[dof] >= 0:
            K[free_index[dof], free_index[dof]] += elastic_k[i]
    energies[5] = 0.5 * e_support
    if n_active:
        for i in range(n_dof):
            f[i] += F[2, i]
    return n_active


_compiled = None
#: Compilation failed once (logged): the numpy path from then on.
broken = False
_HELPERS = ("_face", "_vertex_edge", "_contact_pair")


def _compile():
    """Compile (or load from numba's cache) the fused kernel; raises if numba fails (see
    :func:`simulator._jit.compile_kernel`)."""
    global _compiled
    from numba import njit

    _springs_jit.jit_helpers()
    g = globals()
    for name in ("element", "cross", "dot"):        # the spring kernel's (compiled) helpers
        g[name if name != "element" else "_spring_element"] = getattr(_springs_jit, name)
    for name in _HELPERS:
        if not hasattr(g[name], "py_func"):
            g[name] = njit(cache=True, **HELPER_OPTIONS)(g[name])
    _compiled = njit(SIGNATURE, cache=True)(_kernel)
    return _compiled


def _spring_element(*args):                            # replaced by the compiled one
    return _springs_jit.element(*args)


def needs_compiling() -> bool:
    """Whether :func:`fused_kernel` has yet to compile (or load) the kernel in this process."""
    return _compiled is None and not broken and _jit.aot_kernel("fused") is None


def fused_kernel():
    """The compiled kernel, or None if compilation fails (logged once; :data:`broken` is then
    set): the ahead-of-time compiled one when this process enabled it and it loads
    (:mod:`simulator._aot`, no numba imported), else numba's, compiled or loaded from its cache
    on first use."""
    global broken
    aot = _jit.aot_kernel("fused")                     # tier "aot": short CLI commands
    if aot is not None:
        return aot
    if _compiled is not None:
        return _compiled
    if broken:
        return None
    kernel = compile_kernel("fused kernel", _compile, "using numpy")
    broken = kernel is None
    return kernel
