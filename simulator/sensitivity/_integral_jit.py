"""Compiled (numba) twin of :func:`simulator.sensitivity.integral.pair_derivative`.

The same rules pair by pair (theory 12.6): the centroid and 3-point rules differentiated
analytically, the closed form (Wilton et al.) by central differences of the pair's value in its
12 coordinates, the self term along its triangle; for the sheet and, with a substrate plane, its
mirror image; accumulated straight into ``D``. The numpy function is the checked reference
(``tests/unit/test_sensitivity_integral.py`` compares the two). Compiled on first use and cached
by numba where :func:`simulator._jit.numba_selected` says compiled kernels run, numpy otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import compile_kernel, numba_selected

__all__ = ["use_compiled", "pair_derivative"]

_compiled = None
_broken = False

#: corners (n, 3, 3), centroids (n, 3), diameters (n,), parent nodes (n, 3), corner weights
#: (n, 3, 3), centroid weights (n, 3), p (n,), kappa, plane?, origin (3,), normal (3,), near,
#: mid, step, output D (n, 3 n_nodes)
_SIGNATURE = ("void(f8[:, :, ::1], f8[:, ::1], f8[::1], i8[:, ::1], f8[:, :, ::1], f8[:, ::1], "
              "f8[::1], f8, b1, f8[::1], f8[::1], f8, f8, f8, f8[:, ::1])")


def _mean_potential(px, py, pz, t):
    """``int_T 1 / |p - y| dS / A_T`` of the triangle ``t`` (3, 3) at the point p: the closed
    form of :func:`simulator.thermal._single_layer.triangle_potential`, divided by the area."""
    ux, uy, uz = t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2]
    vx, vy, vz = t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    area = 0.5 * norm
    nx, ny, nz = nx / norm, ny / norm, nz / norm
    d = (px - t[0, 0]) * nx + (py - t[0, 1]) * ny + (pz - t[0, 2]) * nz
    rx, ry, rz = px - d * nx, py - d * ny, pz - d * nz
    ad = abs(d)
    total = 0.0
    for e in range(3):
        f = (e + 1) % 3
        ex, ey, ez = t[f, 0] - t[e, 0], t[f, 1] - t[e, 1], t[f, 2] - t[e, 2]
        length = math.sqrt(ex * ex + ey * ey + ez * ez)
        tx, ty, tz = ex / length, ey / length, ez / length
        # outward in-plane edge normal: t x n
        wx, wy, wz = ty * nz - tz * ny, tz * nx - tx * nz, tx * ny - ty * nx
        ax, ay, az = t[e, 0] - rx, t[e, 1] - ry, t[e, 2] - rz
        bx, by, bz = t[f, 0] - rx, t[f, 1] - ry, t[f, 2] - rz
        p0 = ax * wx + ay * wy + az * wz
        if abs(p0) <= 1e-12 * length:
            continue
        lm = ax * tx + ay * ty + az * tz
        lp = bx * tx + by * ty + bz * tz
        r0sq = p0 * p0 + ad * ad
        rm = math.sqrt(lm * lm + r0sq)
        rp = math.sqrt(lp * lp + r0sq)
        num = rp + lp if lp >= 0 else r0sq / (rp - lp)
        den = rm + lm if lm >= 0 else r0sq / (rm - lm)
        angle = math.atan2(p0 * lp, r0sq + ad * rp) - math.atan2(p0 * lm, r0sq + ad * rm)
        total += p0 * math.log(num / den) - ad * angle
    return total / area


def _corner_difference(cx, cy, cz, v, w, a, k, hs, own):
    """Central difference of :func:`_mean_potential` at the point c of the triangle ``v`` in
    coordinate k of its corner a (step ``hs``; ``w`` scratch (3, 3)); ``own``: the point is
    the triangle's centroid and moves with it."""
    out = 0.0
    for s in range(2):
        for b in range(3):
            for m in range(3):
                w[b, m] = v[b, m]
        w[a, k] += hs if s == 0 else -hs
        if own:
            cx = (w[0, 0] + w[1, 0] + w[2, 0]) / 3
            cy = (w[0, 1] + w[1, 1] + w[2, 1]) / 3
            cz = (w[0, 2] + w[1, 2] + w[2, 2]) / 3
        f = _mean_potential(cx, cy, cz, w)
        out += f if s == 0 else -f
    return out / (2 * hs)


def _source(tri, centroid, j, image, origin, normal, v):
    """Triangle ``j``'s corners into ``v`` and its centroid returned, mirrored in the plane
    ``(origin, normal)`` for the ``image``."""
    for a in range(3):
        for k in range(3):
            v[a, k] = tri[j, a, k]
    sx, sy, sz = centroid[j, 0], centroid[j, 1], centroid[j, 2]
    if image == 1:
        for a in range(3):
            h = ((v[a, 0] - origin[0]) * normal[0] + (v[a, 1] - origin[1]) * normal[1]
                 + (v[a, 2] - origin[2]) * normal[2])
            for k in range(3):
                v[a, k] -= 2.0 * h * normal[k]
        h = (sx - origin[0]) * normal[0] + (sy - origin[1]) * normal[1] \
            + (sz - origin[2]) * normal[2]
        sx, sy, sz = sx - 2 * h * normal[0], sy - 2 * h * normal[1], sz - 2 * h * normal[2]
    return sx, sy, sz


def _rule_gradient(cx, cy, cz, v, dx, dy, dz, own, near_dist, mid_dist, hs, w, tc, tg):
    """The gradient of the mean of ``1 / |c - y|`` over the triangle ``v`` in the point c
    (into ``tc``) and the corners (into ``tg``), by the operator's rule at the distance
    ``(dx, dy, dz)`` from its centroid: the self term (``own``) along the triangle, the closed
    form's central differences (step ``hs``) within ``near_dist``, the 3-point rule within
    ``mid_dist``, the centroid rule beyond."""
    dist = math.sqrt(dx * dx + dy * dy + dz * dz)
    for k in range(3):
        tc[k] = 0.0
        for a in range(3):
            tg[a, k] = 0.0
    if own:                                      # the self term, along its triangle
        for a in range(3):
            for k in range(3):
                tg[a, k] = _corner_difference(cx, cy, cz, v, w, a, k, hs, True)
    elif dist < near_dist:                       # the closed form: central differences
        for k in range(3):
            for s in range(2):
                e = hs if s == 0 else -hs
                f = _mean_potential(cx + (e if k == 0 else 0.0), cy + (e if k == 1 else 0.0),
                                    cz + (e if k == 2 else 0.0), v)
                tc[k] += f if s == 0 else -f
            tc[k] /= 2 * hs
        for a in range(3):
            for k in range(3):
                tg[a, k] = _corner_difference(cx, cy, cz, v, w, a, k, hs, False)
    elif dist < mid_dist:                        # the 3-point rule
        for q in range(3):
            yx = yy = yz = 0.0
            for a in range(3):
                c = 2.0 / 3.0 if a == q else 1.0 / 6.0
                yx += c * v[a, 0]
                yy += c * v[a, 1]
                yz += c * v[a, 2]
            ex, ey, ez = cx - yx, cy - yy, cz - yz
            r = math.sqrt(ex * ex + ey * ey + ez * ez)
            r3 = 3.0 * r * r * r
            tc[0] -= ex / r3
            tc[1] -= ey / r3
            tc[2] -= ez / r3
            for a in range(3):
                c = 2.0 / 3.0 if a == q else 1.0 / 6.0
                tg[a, 0] += c * ex / r3
                tg[a, 1] += c * ey / r3
                tg[a, 2] += c * ez / r3
    else:                                        # the centroid rule
        r3 = dist * dist * dist
        tc[0], tc[1], tc[2] = -dx / r3, -dy / r3, -dz / r3
        for a in range(3):
            tg[a, 0], tg[a, 1], tg[a, 2] = dx / (3 * r3), dy / (3 * r3), dz / (3 * r3)


def _kernel(tri, centroid, diam, parent, bary, cbar, p, kappa, has_plane, origin, normal,
            near, mid, step, D):
    n = tri.shape[0]
    v = np.empty((3, 3))
    w = np.empty((3, 3))
    gc = np.empty(3)
    gv = np.empty((3, 3))
    tc = np.empty(3)
    tg = np.empty((3, 3))
    R = np.eye(3)
    for a in range(3):
        for b in range(3):
            R[a, b] -= 2.0 * normal[a] * normal[b]
    for i in range(n):
        cx, cy, cz = centroid[i, 0], centroid[i, 1], centroid[i, 2]
        for j in range(n):
            for k in range(3):
                gc[k] = 0.0
                for a in range(3):
                    gv[a, k] = 0.0
            for image in range(2 if has_plane else 1):
                sign = 1.0 if image == 0 else -1.0
                sx, sy, sz = _source(tri, centroid, j, image, origin, normal, v)
                _rule_gradient(cx, cy, cz, v, cx - sx, cy - sy, cz - sz, image == 0 and i == j,
                               near * diam[j], mid * near * diam[j], step * diam[j], w, tc, tg)
                for k in range(3):
                    gc[k] += sign * kappa * tc[k]
                for a in range(3):
                    for k in range(3):
                        g = tg[a, k]
                        if image == 1:               # the image's corners are R v + t
                            g = tg[a, 0] * R[0, k] + tg[a, 1] * R[1, k] + tg[a, 2] * R[2, k]
                        gv[a, k] += sign * kappa * g
            hi, hj = 0.5 * p[i], 0.5 * p[j]
            for b in range(3):
                ci, cj = 3 * parent[i, b], 3 * parent[j, b]
                for k in range(3):
                    gi = cbar[i, b] * gc[k]
                    gj = bary[j, 0, b] * gv[0, k] + bary[j, 1, b] * gv[1, k] \
                        + bary[j, 2, b] * gv[2, k]
                    D[i, ci + k] += hj * gi
                    D[i, cj + k] += hj * gj
                    D[j, ci + k] += hi * gi
                    D[j, cj + k] += hi * gj


def _build():
    from numba import njit

    g = globals()
    for name in ("_mean_potential", "_corner_difference", "_source", "_rule_gradient"):
        if not hasattr(g[name], "py_func"):
            g[name] = njit(cache=True, inline="always")(g[name])
    return njit(_SIGNATURE, cache=True, fastmath=False)(_kernel)


def use_compiled() -> bool:
    """Whether the compiled kernel is used (compiled kernels selected); compiles or loads it
    on the first call."""
    global _compiled, _broken
    if _broken or not numba_selected():
        return False
    if _compiled is None:
        _compiled = compile_kernel("single-layer derivative kernel", _build, "using numpy")
        _broken = _compiled is None
    return _compiled is not None


def pair_derivative(tri, parent, bary, p, kappa, plane, n_nodes, near, mid, step):
    """``D`` (n, 3 n_nodes) by the compiled kernel (see
    :func:`simulator.sensitivity.integral.pair_derivative`)."""
    tri = np.ascontiguousarray(tri, float)
    centroid = np.ascontiguousarray(tri.mean(axis=1))
    diam = np.ascontiguousarray(
        np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1))
    bary = np.ascontiguousarray(bary, float)
    origin, normal = (np.zeros(3), np.zeros(3)) if plane is None else \
        (np.ascontiguousarray(plane[0], float), np.ascontiguousarray(plane[1], float))
    D = np.zeros((len(tri), 3 * int(n_nodes)))
    _compiled(tri, centroid, diam, np.ascontiguousarray(parent, np.int64), bary,
              np.ascontiguousarray(bary.mean(axis=1)), np.ascontiguousarray(p, float),
              float(kappa), plane is not None, origin, normal, float(near), float(mid),
              float(step), D)
    return D
