"""Compiled (numba) element data of the steady thermal model: same formulas as
:mod:`simulator.thermal.steady`.

One call computes, for every triangle, the T3 conduction matrix and area (reference edge
lengths, current angle at the first node), the cap of t_env (mean distance of its vertices to
the nearest thermal-boundary triangle), t_air, the environment conductance of every node's
layers, and condenses each node's chain into one series conductance ``g_eff`` to room
temperature. The numpy path (:meth:`simulator.thermal.steady.ThermalModel.solve` with the
``"numpy"`` backend) is the checked reference: tests compare the two.

A small gripper (42 nodes) takes about 1 ms per solve on numpy (some 60 array calls of a few
microseconds each, and SuperLU's set-up) and tens of microseconds here. It runs where
:mod:`simulator._jit` selects compiled kernels (the ahead-of-time copy in tier "aot"):
compiled on first use, cached by numba, numpy if numba is missing or fails to compile.
"""

from __future__ import annotations

import logging
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from .._jit import aot_kernel, compile_kernel, numba_selected

__all__ = ["use_compiled", "thermal_element_data", "compile_in_background"]

logger = logging.getLogger(__name__)

#: x (n, 3), tri (m, 3), edge lengths (m, 3), k t (m,), is_boundary (m,), cap nodes (c,),
#: t_env, tan(beta), k_env, layers, min air fraction, cap of boundary triangles, cap without
#: boundary, then outputs Ke (m, 3, 3), g_eff (n,), then zeroed work arrays dmin
#: (n,), g (n, layers), bt (3, 3); returns the number of triangles whose t_air was floored.
_SIGNATURE = ("i8(f8[:, ::1], i8[:, ::1], f8[:, ::1], f8[::1], b1[::1], i8[::1], f8, f8, f8, "
              "i8, f8, f8, f8, f8[:, :, ::1], f8[::1], f8[::1], f8[:, ::1], f8[:, ::1])")

_compiled = None
_broken = False
#: A process compiling the kernel into numba's cache (:func:`compile_in_background`), or None.
_background = None
#: Longest wait for that process before compiling here instead [s].
_BACKGROUND_WAIT = 60.0


def _point_triangle_distance(px, py, pz, t):
    """Distance from the point (px, py, pz) to the closed triangle ``t`` (3, 3) [m]
    (closest-point regions of Ericson, Real-Time Collision Detection, 5.1.5)."""
    ax, ay, az = t[0, 0], t[0, 1], t[0, 2]
    abx, aby, abz = t[1, 0] - ax, t[1, 1] - ay, t[1, 2] - az
    acx, acy, acz = t[2, 0] - ax, t[2, 1] - ay, t[2, 2] - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:                                   # vertex A
        return math.sqrt(apx * apx + apy * apy + apz * apz)
    bpx, bpy, bpz = px - t[1, 0], py - t[1, 1], pz - t[1, 2]
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:                                    # vertex B
        return math.sqrt(bpx * bpx + bpy * bpy + bpz * bpz)
    cpx, cpy, cpz = px - t[2, 0], py - t[2, 1], pz - t[2, 2]
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:                                    # vertex C
        return math.sqrt(cpx * cpx + cpy * cpy + cpz * cpz)
    vc = d1 * d4 - d3 * d2
    vb = d5 * d2 - d1 * d6
    va = d3 * d6 - d5 * d4
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:                     # edge AB
        s = d1 / (d1 - d3)
        qx, qy, qz = ax + s * abx, ay + s * aby, az + s * abz
    elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:                   # edge AC
        s = d2 / (d2 - d6)
        qx, qy, qz = ax + s * acx, ay + s * acy, az + s * acz
    elif va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:     # edge BC
        s = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        qx = t[1, 0] + s * (t[2, 0] - t[1, 0])
        qy = t[1, 1] + s * (t[2, 1] - t[1, 1])
        qz = t[1, 2] + s * (t[2, 2] - t[1, 2])
    else:                                                         # face
        den = va + vb + vc
        if den <= 0.0:                        # degenerate triangle: nearest of its vertices
            return min(math.sqrt(apx * apx + apy * apy + apz * apz),
                       math.sqrt(bpx * bpx + bpy * bpy + bpz * bpz),
                       math.sqrt(cpx * cpx + cpy * cpy + cpz * cpz))
        v, w = vb / den, vc / den
        qx = ax + v * abx + w * acx
        qy = ay + v * aby + w * acy
        qz = az + v * abz + w * acz
    dx, dy, dz = px - qx, py - qy, pz - qz
    return math.sqrt(dx * dx + dy * dy + dz * dz)


def _kernel(x, tri, edge, kt, is_boundary, cap_nodes, t_env, tan_beta, k_env, layers,
            min_air, cap_boundary, cap_none, Ke, g_eff, dmin, g, bt):
    n, m = x.shape[0], tri.shape[0]
    # distance of every cap node to the nearest boundary triangle
    n_boundary = 0
    for t in range(m):
        if is_boundary[t]:
            n_boundary += 1
    if n_boundary:
        for c in range(cap_nodes.shape[0]):
            p = cap_nodes[c]
            best = math.inf
            for t in range(m):
                if not is_boundary[t]:
                    continue
                for i in range(3):
                    for j in range(3):
                        bt[i, j] = x[tri[t, i], j]
                d = _point_triangle_distance(x[p, 0], x[p, 1], x[p, 2], bt)
                if d < best:
                    best = d
            dmin[p] = best
    floored = 0
    for t in range(m):
        i0, i1, i2 = tri[t, 0], tri[t, 1], tri[t, 2]
        ux, uy, uz = x[i1, 0] - x[i0, 0], x[i1, 1] - x[i0, 1], x[i1, 2] - x[i0, 2]
        vx, vy, vz = x[i2, 0] - x[i0, 0], x[i2, 1] - x[i0, 1], x[i2, 2] - x[i0, 2]
        cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        alpha = math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ux * vx + uy * vy + uz * vz)
        l1, l2 = edge[t, 0], edge[t, 1]
        x3, y3 = l2 * math.cos(alpha), l2 * math.sin(alpha)
        a = 0.5 * l1 * y3
        b0, b1, b2 = -y3, y3, 0.0
        c0, c1, c2 = x3 - l1, -x3, l1
        s = kt[t] / (4 * a)
        Ke[t, 0, 0] = s * (b0 * b0 + c0 * c0)
        Ke[t, 0, 1] = Ke[t, 1, 0] = s * (b0 * b1 + c0 * c1)
        Ke[t, 0, 2] = Ke[t, 2, 0] = s * (b0 * b2 + c0 * c2)
        Ke[t, 1, 1] = s * (b1 * b1 + c1 * c1)
        Ke[t, 1, 2] = Ke[t, 2, 1] = s * (b1 * b2 + c1 * c2)
        Ke[t, 2, 2] = s * (b2 * b2 + c2 * c2)
        if is_boundary[t]:
            cap = cap_boundary
        elif n_boundary:
            cap = (dmin[i0] + dmin[i1] + dmin[i2]) / 3
        else:
            cap = cap_none
        t_air = t_env if t_env < cap else cap
        if t_air < min_air * t_env:
            t_air = min_air * t_env
            floored += 1
        spread = (edge[t, 0] + edge[t, 1] + edge[t, 2]) * t_air * tan_beta
        for q in range(layers):
            a_q = (2 / 3) * a + (2 / 3) * spread * ((q + 1 - 0.5) / layers)
            gq = k_env * a_q * layers / t_air
            g[i0, q] += gq
            g[i1, q] += gq
            g[i2, q] += gq
    for i in range(n):
        inv, positive = 0.0, True
        for q in range(layers):
            if g[i, q] > 0:
                inv += 1 / g[i, q]
            else:
                positive = False
        g_eff[i] = 1 / inv if positive else 0.0
    return floored


def _build():
    from numba import njit

    g = globals()
    if not hasattr(g["_point_triangle_distance"], "py_func"):
        g["_point_triangle_distance"] = njit(cache=True)(_point_triangle_distance)
    return njit(_SIGNATURE, cache=True)(_kernel)


def _compile():
    """Compile (or load from numba's cache) the kernel; None if that fails (numpy from then
    on)."""
    global _compiled, _broken, _background
    if _background is not None:                    # let it finish: then this loads its cache
        try:
            _background.wait(timeout=_BACKGROUND_WAIT)
        except subprocess.TimeoutExpired:
            _background.kill()
            _background.wait()
        _background = None
    _compiled = compile_kernel("thermal kernel", _build, "using numpy")
    _broken = _compiled is None
    return _compiled


def compile_in_background() -> bool:
    """Compile the kernel into numba's cache in a separate process, on the other core, if it
    is neither loaded here nor cached yet; returns whether such a process was started.

    The first run after install compiles the fused mechanics kernel (about 4 s of CPU) and
    this one (about 1 s) one after the other; the CLI's short commands on a cold cache call
    this first (no simulation does: a library call starts no process), so that both compile
    side by side and :func:`use_compiled` later only loads this kernel from the cache (it
    waits for the process first). Any failure here is ignored: the kernel is then compiled in
    this process as usual.
    """
    global _background
    if _compiled is not None or _broken or _background is not None:
        return False
    try:
        from numba.core.caching import FunctionCache

        if Path(FunctionCache(_kernel)._cache_file._index_path).exists():
            return False                                # cached: loading it is quick
        package_root = str(Path(__file__).resolve().parents[2])
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            [package_root] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
        _background = subprocess.Popen(
            [sys.executable, "-c", "from simulator.thermal import _thermal_jit; _thermal_jit._compile()"],
            env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL)
        logger.info("compiling the thermal kernel in a background process")
        return True
    except Exception as exc:  # noqa: BLE001 - an optimisation of the first run only
        logger.debug("no background compilation of the thermal kernel (%s)", exc)
        return False


def use_compiled() -> bool:
    """Whether the thermal model uses this kernel (:func:`simulator._jit.numba_selected`):
    the ahead-of-time compiled one in tier "aot" when it loads (:mod:`simulator._aot`), else
    numba's, compiled or loaded on the first call."""
    if _broken or not numba_selected():
        return False
    return (aot_kernel("thermal") or _compiled or _compile()) is not None


def thermal_element_data(args, x):
    """Conduction matrices (m, 3, 3) [W/K] and condensed environment conductances g_eff (n,)
    [W/K] at positions ``x`` (n, 3) [m], and the number of triangles whose t_air was floored;
    ``args`` are the model's arguments of the kernel (``ThermalModel._kernel_args``). Compiles
    the kernel on first use (see :func:`use_compiled`)."""
    kernel = aot_kernel("thermal") or _compiled or _compile()
    n, m, layers = len(x), len(args[0]), args[8]
    Ke, g_eff = np.empty((m, 3, 3)), np.empty(n)
    floored = kernel(np.require(x, np.float64, ("C", "W")), *args, Ke, g_eff, np.zeros(n),
                     np.zeros((n, layers)), np.zeros((3, 3)))
    return Ke, g_eff, int(floored)
