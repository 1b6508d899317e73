"""Compiled (numba) twin of :func:`simulator.thermal._single_layer._kernel_matrix`.

The same formulas pair by pair: the closed form of ``int_T 1 / |p - y| dS_y`` (Wilton et al.)
for pairs closer than ``near`` source diameters, the centroid rule otherwise. The numpy path is
the checked reference (tests compare the two). It follows the spring kernel's backend
(:func:`simulator.mechanics.elements.springs.spring_kernel_backend`, environment variable
``ETORIGAMI_JIT``): compiled on first use, cached by numba, numpy if numba is missing or fails.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import compile_kernel
from ..mechanics.elements import _springs_jit

__all__ = ["use_compiled", "kernel_matrix", "pair_values"]

#: points (n, 3), triangles (m, 3, 3), centroids (m, 3), areas (m,), diameters (m,), near,
#: output (n, m)
_SIGNATURE = "void(f8[:, ::1], f8[:, :, ::1], f8[:, ::1], f8[::1], f8[::1], f8, f8[:, ::1])"

_compiled = None
_broken = False
_compiled_pairs = None
#: The 3-point rule is used up to this many times ``near`` source diameters (numpy's twin:
#: :data:`simulator.thermal._single_layer.MID_FACTOR`).
_MID_FACTOR = 2.0


def _frame(t, f):
    """The point-independent part of :func:`_potential` for the triangle ``t`` (3, 3), into
    ``f`` (4, 7): row 0 the unit normal (columns 0-2); row e + 1 (edge e, from vertex e to
    e + 1) its unit tangent (0-2), outward in-plane normal (3-5) and length (6)."""
    e1 = (t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2])
    e2 = (t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2])
    nx, ny, nz = e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], \
        e1[0] * e2[1] - e1[1] * e2[0]
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    nx, ny, nz = nx / nn, ny / nn, nz / nn
    f[0, 0], f[0, 1], f[0, 2] = nx, ny, nz
    for i in range(3):
        j = (i + 1) % 3
        ex, ey, ez = t[j, 0] - t[i, 0], t[j, 1] - t[i, 1], t[j, 2] - t[i, 2]
        length = math.sqrt(ex * ex + ey * ey + ez * ez)
        tx, ty, tz = ex / length, ey / length, ez / length
        f[i + 1, 0], f[i + 1, 1], f[i + 1, 2] = tx, ty, tz
        f[i + 1, 3] = ty * nz - tz * ny
        f[i + 1, 4] = tz * nx - tx * nz
        f[i + 1, 5] = tx * ny - ty * nx
        f[i + 1, 6] = length


def _potential(px, py, pz, t, f):
    """``int_t 1 / |p - y| dS_y`` [m] of the triangle ``t`` (3, 3) with its :func:`_frame`
    ``f`` (4, 7) at the point p."""
    nx, ny, nz = f[0, 0], f[0, 1], f[0, 2]
    d = (px - t[0, 0]) * nx + (py - t[0, 1]) * ny + (pz - t[0, 2]) * nz
    rx, ry, rz = px - d * nx, py - d * ny, pz - d * nz
    ad = abs(d)
    total = 0.0
    for i in range(3):
        j = (i + 1) % 3
        tx, ty, tz = f[i + 1, 0], f[i + 1, 1], f[i + 1, 2]
        ux, uy, uz, length = f[i + 1, 3], f[i + 1, 4], f[i + 1, 5], f[i + 1, 6]
        ax, ay, az = t[i, 0] - rx, t[i, 1] - ry, t[i, 2] - rz
        bx, by, bz = t[j, 0] - rx, t[j, 1] - ry, t[j, 2] - rz
        p0 = ax * ux + ay * uy + az * uz
        if abs(p0) <= 1e-12 * length:
            continue
        lm = ax * tx + ay * ty + az * tz
        lp = bx * tx + by * ty + bz * tz
        r0sq = p0 * p0 + ad * ad
        rm = math.sqrt(lm * lm + r0sq)
        rp = math.sqrt(lp * lp + r0sq)
        # r + l without cancellation where l < 0 (r + l = r0^2 / (r - l))
        num = rp + lp if lp >= 0.0 else r0sq / (rp - lp)
        den = rm + lm if lm >= 0.0 else r0sq / (rm - lm)
        total += p0 * math.log(num / den)
        if ad > 0.0:
            # atan2(y1, x1) - atan2(y2, x2) in one atan2: both x > 0, so both angles lie in
            # (-pi/2, pi/2) and their difference in (-pi, pi), atan2's own range
            y1, x1 = p0 * lp, r0sq + ad * rp
            y2, x2 = p0 * lm, r0sq + ad * rm
            total -= ad * math.atan2(y1 * x2 - y2 * x1, x1 * x2 + y1 * y2)
    return total


def _value(px, py, pz, j, tri, centroid, area, diam, near, mid, frame):
    """``int_j 1 / |p - y| dS_y`` [m] of triangle ``j`` at the point p by the rule of its
    distance: closed form, 3-point rule or centroid rule."""
    dx, dy, dz = px - centroid[j, 0], py - centroid[j, 1], pz - centroid[j, 2]
    dist = math.sqrt(dx * dx + dy * dy + dz * dz)
    if dist < near * diam[j]:
        return _potential(px, py, pz, tri[j], frame)
    if dist < mid * diam[j]:                                 # 3-point rule (degree 2)
        acc = 0.0
        for a in range(3):
            b, c = (a + 1) % 3, (a + 2) % 3
            qx = (4.0 * tri[j, a, 0] + tri[j, b, 0] + tri[j, c, 0]) / 6.0 - px
            qy = (4.0 * tri[j, a, 1] + tri[j, b, 1] + tri[j, c, 1]) / 6.0 - py
            qz = (4.0 * tri[j, a, 2] + tri[j, b, 2] + tri[j, c, 2]) / 6.0 - pz
            acc += 1.0 / math.sqrt(qx * qx + qy * qy + qz * qz)
        return area[j] * acc / 3.0
    return area[j] / dist


def _kernel(points, tri, centroid, area, diam, near, out):
    mid = _MID_FACTOR * near
    frames = np.empty((tri.shape[0], 4, 7))             # point-independent, once per triangle
    for j in range(tri.shape[0]):
        _frame(tri[j], frames[j])
    for i in range(points.shape[0]):
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        for j in range(tri.shape[0]):
            out[i, j] = _value(px, py, pz, j, tri, centroid, area, diam, near, mid, frames[j])


def _pair_kernel(points, tri, centroid, area, diam, near, rows, cols, out):
    mid = _MID_FACTOR * near
    frame = np.empty((4, 7))
    for k in range(rows.shape[0]):
        i, j = rows[k], cols[k]
        _frame(tri[j], frame)
        out[k] = _value(points[i, 0], points[i, 1], points[i, 2], j, tri, centroid, area, diam,
                        near, mid, frame)


def _build():
    from numba import njit

    g = globals()
    for name in ("_potential", "_frame", "_value"):
        if not hasattr(g[name], "py_func"):
            g[name] = njit(cache=True, inline="always")(g[name])
    return njit(_SIGNATURE, cache=True, fastmath=False)(_kernel)


def _build_pairs():
    from numba import njit

    _build()                                           # the helpers, compiled
    return njit(_PAIR_SIGNATURE, cache=True, fastmath=False)(_pair_kernel)


#: points (n, 3), triangles (m, 3, 3), centroids (m, 3), areas (m,), diameters (m,), near,
#: rows (p,), columns (p,), output (p,)
_PAIR_SIGNATURE = ("void(f8[:, ::1], f8[:, :, ::1], f8[:, ::1], f8[::1], f8[::1], f8, i8[::1], "
                   "i8[::1], f8[::1])")


def use_compiled() -> bool:
    """Whether the compiled kernel is used (the spring kernel's backend is "numba"); compiles
    or loads it on the first call."""
    global _compiled, _broken
    if _broken or not _springs_jit.numba_selected():
        return False
    if _compiled is None:
        _compiled = compile_kernel("single-layer kernel", _build, "using numpy")
        _broken = _compiled is None
    return _compiled is not None


def kernel_matrix(points, tri, centroid, area, diam, near) -> np.ndarray:
    """``int_j 1 / |p_i - y| dS_y`` [m], (n, m), by the compiled kernel (see module notes)."""
    out = np.empty((len(points), len(tri)))
    c = np.ascontiguousarray
    _compiled(c(points, np.float64), c(tri, np.float64), c(centroid, np.float64),
              c(area, np.float64), c(diam, np.float64), float(near), out)
    return out


def pair_values(points, tri, centroid, area, diam, near, rows, cols) -> np.ndarray:
    """``int_j 1 / |p_i - y| dS_y`` [m] of the pairs ``(rows[k], cols[k])``, (p,), by the
    compiled kernel (the entries of :func:`kernel_matrix` at those pairs); ``None`` if it
    cannot be compiled."""
    global _compiled_pairs
    if _compiled_pairs is None:
        _compiled_pairs = compile_kernel("single-layer pair kernel", _build_pairs,
                                         "using numpy") or False
    if _compiled_pairs is False:
        return None
    out = np.empty(len(rows))
    c = np.ascontiguousarray
    _compiled_pairs(c(points, np.float64), c(tri, np.float64), c(centroid, np.float64),
                    c(area, np.float64), c(diam, np.float64), float(near),
                    c(rows, np.int64), c(cols, np.int64), out)
    return out
