"""Compiled (numba) twin of :func:`simulator.thermal._single_layer.collocation_matrix` and
:func:`~simulator.thermal._single_layer.single_layer_operator`.

The same formulas pair by pair: the closed form of ``int_T 1 / |p - y| dS_y`` (Wilton et al.)
for pairs closer than ``near`` source diameters, the 3-point rule up to ``2 near``, the
centroid rule beyond, for the sheet and (with a substrate plane) its mirror image, in one pass
over the pairs. The numpy path is the checked reference (tests compare the two; the closed
form's arc tangents are summed in one atan2 here, see :func:`_potential`). It runs where
:func:`simulator._jit.numba_selected` says compiled kernels do (the one switch of every
kernel): compiled on first use, cached by numba, numpy if numba is missing or fails.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import compile_kernel, numba_selected

__all__ = ["use_compiled", "collocation", "pair_values", "corners", "pair_distances"]

#: triangles (n, 3, 3), their edges' ids (n, 3) and number, plane origin (3,), unit normal (3,),
#: image?, operator?, near, scale, outputs V (n, n), area (n,), centroid (n, 3), diameter (n,)
_SIGNATURE = ("void(f8[:, :, ::1], i8[:, ::1], i8, f8[::1], f8[::1], b1, b1, f8, f8, f8[:, ::1], "
              "f8[::1], "
              "f8[:, ::1], f8[::1])")

_compiled = None
_broken = False
_compiled_pairs = None
_compiled_corners = None
#: The 3-point rule is used up to this many times ``near`` source diameters (numpy's twin:
#: :data:`simulator.thermal._single_layer.MID_FACTOR`).
_MID_FACTOR = 2.0
#: Relative bias of the rule thresholds (numpy's twin :data:`simulator.thermal._single_layer.TIE`).
_TIE = 1e-9


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


def _potential(px, py, pz, t, f, edge, logs, stamp, key):
    """``int_t 1 / |p - y| dS_y`` [m] of the triangle ``t`` (3, 3) with its :func:`_frame`
    ``f`` (4, 7) at the point p: Wilton's closed form (numpy's twin
    :func:`simulator.thermal._single_layer.triangle_potential`) with the distances to the
    vertices computed once per triangle (an edge's ``R-`` and ``R+``) and the sum of the edges'
    arc tangents, the solid angle ``Omega`` the triangle subtends at p, in one atan2 (Van
    Oosterom & Strackee, IEEE Trans. Biomed. Eng. 30(2) 125, 1983):
    ``tan(Omega / 2) = |a . (b x c)| / (a b c + (a . b) c + (a . c) b + (b . c) a)``.

    An edge's logarithm ``ln((R+ + l+) / (R- + l-))`` depends on the point and the edge only
    (not on the triangle's plane, nor on the edge's direction): it is kept in ``logs`` under the
    edge's id ``edge[e]`` (n_edges,), marked in ``stamp`` with the point's ``key``, and reused by
    the other triangle of the edge."""
    nx, ny, nz = f[0, 0], f[0, 1], f[0, 2]
    ax, ay, az = t[0, 0] - px, t[0, 1] - py, t[0, 2] - pz
    bx, by, bz = t[1, 0] - px, t[1, 1] - py, t[1, 2] - pz
    cx, cy, cz = t[2, 0] - px, t[2, 1] - py, t[2, 2] - pz
    ra = math.sqrt(ax * ax + ay * ay + az * az)
    rb = math.sqrt(bx * bx + by * by + bz * bz)
    rc = math.sqrt(cx * cx + cy * cy + cz * cz)
    d = ax * nx + ay * ny + az * nz                  # height of the triangle's plane over p
    ad = abs(d)
    total = 0.0
    for i in range(3):
        if i == 0:
            vx, vy, vz, rv, r1 = ax, ay, az, ra, rb
        elif i == 1:
            vx, vy, vz, rv, r1 = bx, by, bz, rb, rc
        else:
            vx, vy, vz, rv, r1 = cx, cy, cz, rc, ra
        tx, ty, tz = f[i + 1, 0], f[i + 1, 1], f[i + 1, 2]
        ux, uy, uz, length = f[i + 1, 3], f[i + 1, 4], f[i + 1, 5], f[i + 1, 6]
        p0 = vx * ux + vy * uy + vz * uz
        if abs(p0) <= 1e-12 * length:
            continue
        lm = vx * tx + vy * ty + vz * tz
        lp = lm + length
        r0sq = p0 * p0 + ad * ad
        k = edge[i]
        if stamp[k] != key:
            num = r1 + lp if lp >= 0.0 else r0sq / (r1 - lp)
            den = rv + lm if lm >= 0.0 else r0sq / (rv - lm)
            logs[k] = math.log(num / den)
            stamp[k] = key
        total += p0 * logs[k]
    if ad > 0.0:
        triple = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        den = (ra * rb * rc + (ax * bx + ay * by + az * bz) * rc
               + (ax * cx + ay * cy + az * cz) * rb + (bx * cx + by * cy + bz * cz) * ra)
        total -= 2.0 * ad * math.atan2(abs(triple), den)
    return total


def _near_row(px, py, pz, key, dist, out, reach, near_dist, area, tri, frames, edges, rule,
              slot_of, stamp, picked, points, sums, close, work, slots, logs):
    """Overwrite ``out[j]`` (the centroid rule ``A_j / |p - c_j|``, ``dist`` (n,) the distances
    ``|p - c_j|``) for the triangles j closer to the point p than ``reach[j]``: the closed form
    (:func:`_closed_forms`, closer than ``near_dist[j]``), else ``A_j`` times the 3-point rule
    of degree 2 at the triangle's points ``rule[j]`` (3, 3) (barycentric (2/3, 1/6, 1/6) and
    permutations, :func:`_rule_points`). The rule's triangles are listed in ``picked`` (n,) and
    their points copied into ``points`` (9, n), so that the rule's loop over them is contiguous
    and vectorises (its square roots and divisions are correctly rounded either way: the same
    values as one triangle at a time); ``sums`` (n,) is work space, and ``close``, ``work``,
    ``slots``, ``logs``, ``slot_of``, ``stamp`` that of :func:`_closed_forms`."""
    n = dist.shape[0]
    count = 0
    n_close = 0
    for j in range(n):
        if dist[j] < reach[j]:
            if dist[j] < near_dist[j]:
                close[n_close] = j
                n_close += 1
            else:
                picked[count] = j
                count += 1
    _closed_forms(px, py, pz, key, close, n_close, out, tri, frames, edges, slot_of, stamp,
                  work, slots, logs)
    for k in range(count):
        j = picked[k]
        for c in range(9):
            points[c, k] = rule[j, c // 3, c % 3]
    for k in range(count):
        ax, ay, az = points[0, k] - px, points[1, k] - py, points[2, k] - pz
        bx, by, bz = points[3, k] - px, points[4, k] - py, points[5, k] - pz
        cx, cy, cz = points[6, k] - px, points[7, k] - py, points[8, k] - pz
        acc = 1.0 / math.sqrt(ax * ax + ay * ay + az * az)
        acc += 1.0 / math.sqrt(bx * bx + by * by + bz * bz)
        acc += 1.0 / math.sqrt(cx * cx + cy * cy + cz * cz)
        sums[k] = acc
    for k in range(count):
        j = picked[k]
        out[j] = area[j] * (sums[k] / 3.0)


def _closed_forms(px, py, pz, key, close, n_close, out, tri, frames, edges, slot_of, stamp,
                  work, slots, logs):
    """``out[j] = int_j 1 / |p - y| dS_y`` for the triangles ``close[:n_close]``: the formulas
    of :func:`_potential` (the same values, summed in the same order), in three passes so that
    the logarithms and arc tangents are evaluated back to back, not each at the end of its
    pair's chain of dependent operations: the geometry of every pair (per edge ``P0`` into
    ``work[0:3]`` and the slot of its logarithm's argument into ``slots`` (-1: the edge's line
    passes through the projection of p, no term), the solid angle's atan2 arguments and
    ``|d|`` into ``work[3:6]``), then the logarithms (``logs``: arguments, then values, one
    per edge: the edge's slot ``slot_of[edge]`` is this point's where ``stamp[edge] == key``,
    shared by the edge's two triangles), the arc tangents (``work[6]``), then the sums."""
    n_logs = 0
    for k in range(n_close):
        j = close[k]
        t, f, edge = tri[j], frames[j], edges[j]
        nx, ny, nz = f[0, 0], f[0, 1], f[0, 2]
        ax, ay, az = t[0, 0] - px, t[0, 1] - py, t[0, 2] - pz
        bx, by, bz = t[1, 0] - px, t[1, 1] - py, t[1, 2] - pz
        cx, cy, cz = t[2, 0] - px, t[2, 1] - py, t[2, 2] - pz
        ra = math.sqrt(ax * ax + ay * ay + az * az)
        rb = math.sqrt(bx * bx + by * by + bz * bz)
        rc = math.sqrt(cx * cx + cy * cy + cz * cz)
        d = ax * nx + ay * ny + az * nz
        ad = abs(d)
        for i in range(3):
            if i == 0:
                vx, vy, vz, rv, r1 = ax, ay, az, ra, rb
            elif i == 1:
                vx, vy, vz, rv, r1 = bx, by, bz, rb, rc
            else:
                vx, vy, vz, rv, r1 = cx, cy, cz, rc, ra
            tx, ty, tz = f[i + 1, 0], f[i + 1, 1], f[i + 1, 2]
            ux, uy, uz, length = f[i + 1, 3], f[i + 1, 4], f[i + 1, 5], f[i + 1, 6]
            p0 = vx * ux + vy * uy + vz * uz
            if abs(p0) <= 1e-12 * length:
                slots[k, i] = -1
                continue
            work[i, k] = p0
            e = edge[i]
            if stamp[e] != key:
                lm = vx * tx + vy * ty + vz * tz
                lp = lm + length
                r0sq = p0 * p0 + ad * ad
                num = r1 + lp if lp >= 0.0 else r0sq / (r1 - lp)
                den = rv + lm if lm >= 0.0 else r0sq / (rv - lm)
                logs[0, n_logs] = num / den
                slot_of[e] = n_logs
                stamp[e] = key
                n_logs += 1
            slots[k, i] = slot_of[e]
        work[5, k] = ad
        if ad > 0.0:
            triple = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
            work[3, k] = abs(triple)
            work[4, k] = (ra * rb * rc + (ax * bx + ay * by + az * bz) * rc
                          + (ax * cx + ay * cy + az * cz) * rb + (bx * cx + by * cy + bz * cz) * ra)
    for s in range(n_logs):
        logs[1, s] = math.log(logs[0, s])
    for k in range(n_close):
        if work[5, k] > 0.0:
            work[6, k] = math.atan2(work[3, k], work[4, k])
    for k in range(n_close):
        total = 0.0
        for i in range(3):
            s = slots[k, i]
            if s >= 0:
                total += work[i, k] * logs[1, s]
        ad = work[5, k]
        if ad > 0.0:
            total -= 2.0 * ad * work[6, k]
        out[close[k]] = total


def _rule_points(t, q):
    """The points of :func:`_near_row`'s 3-point rule of the triangle ``t`` (3, 3), into ``q``
    (3, 3)."""
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        for k in range(3):
            q[a, k] = (4.0 * t[a, k] + t[b, k] + t[c, k]) / 6.0


def _collocation(tri, edges, n_edges, origin, normal, image, operator, near, scale, V, area,
                 centroid, diam):
    """Into ``V`` (n, n): ``scale (int_j 1 / |c_i - y| dS_y - int_j 1 / |c_i* - y| dS_y)``
    (the second term with ``image`` only: ``c_i*`` the mirror image of the centroid ``c_i`` in
    the plane ``origin``, unit ``normal``; by the reflection's symmetry the same as numpy's
    integral over the mirrored triangle at ``c_i``), divided by ``A_j`` and symmetrised with
    ``operator``; into ``area``, ``centroid`` and ``diam`` the triangles' areas, centroids and
    diameters (longest edge). Per row the centroid rule first for all pairs (no branches: it
    vectorises), then the closed form and the 3-point rule for the closer ones
    (:func:`_near_row`)."""
    n = tri.shape[0]
    near = near * (1.0 + _TIE)
    mid = _MID_FACTOR * near
    frames, rule = np.empty((n, 4, 7)), np.empty((n, 3, 3))
    for j in range(n):
        t = tri[j]
        _frame(t, frames[j])
        _rule_points(t, rule[j])
        e1x, e1y, e1z = t[1, 0] - t[0, 0], t[1, 1] - t[0, 1], t[1, 2] - t[0, 2]
        e2x, e2y, e2z = t[2, 0] - t[0, 0], t[2, 1] - t[0, 1], t[2, 2] - t[0, 2]
        cx, cy, cz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
        area[j] = 0.5 * math.sqrt(cx * cx + cy * cy + cz * cz)
        dm = 0.0
        for a in range(3):
            b = (a + 2) % 3
            ex, ey, ez = t[a, 0] - t[b, 0], t[a, 1] - t[b, 1], t[a, 2] - t[b, 2]
            dm = max(dm, math.sqrt(ex * ex + ey * ey + ez * ez))
        diam[j] = dm
        for k in range(3):
            centroid[j, k] = (t[0, k] + t[1, k] + t[2, k]) / 3.0
    reach, near_dist = np.empty(n), np.empty(n)
    for j in range(n):
        reach[j] = mid * diam[j]
        near_dist[j] = near * diam[j]
    cx, cy, cz = centroid[:, 0].copy(), centroid[:, 1].copy(), centroid[:, 2].copy()
    dr, dv, qr, iv = np.empty(n), np.empty(n), np.zeros(n), np.zeros(n)
    picked, points, sums = np.empty(n, np.int64), np.empty((9, n)), np.empty(n)
    close, work = np.empty(n, np.int64), np.empty((7, n))
    slots, logs = np.empty((n, 3), np.int64), np.empty((2, 3 * n))
    slot_of, stamp = np.empty(n_edges, np.int64), np.full(n_edges, -1, np.int64)
    for i in range(n):
        px, py, pz = cx[i], cy[i], cz[i]
        # the far field (centroid rule) of all pairs, without branches (vectorised)
        for j in range(n):
            dx, dy, dz = px - cx[j], py - cy[j], pz - cz[j]
            dr[j] = math.sqrt(dx * dx + dy * dy + dz * dz)
        for j in range(n):
            dv[j] = area[j] / dr[j]
        _near_row(px, py, pz, 2 * i, dr, dv, reach, near_dist, area, tri, frames, edges, rule,
                  slot_of, stamp, picked, points, sums, close, work, slots,
                  logs)                                 # closer pairs: closed form, 3-point rule
        if image:                                # the mirror image of the point
            h = 2.0 * ((px - origin[0]) * normal[0] + (py - origin[1]) * normal[1]
                       + (pz - origin[2]) * normal[2])
            qx, qy, qz = px - h * normal[0], py - h * normal[1], pz - h * normal[2]
            for j in range(n):
                dx, dy, dz = qx - cx[j], qy - cy[j], qz - cz[j]
                qr[j] = math.sqrt(dx * dx + dy * dy + dz * dz)
            for j in range(n):
                iv[j] = area[j] / qr[j]
            _near_row(qx, qy, qz, 2 * i + 1, qr, iv, reach, near_dist, area, tri, frames, edges,
                      rule, slot_of, stamp, picked, points, sums, close, work, slots, logs)
        if operator:
            for j in range(n):
                V[i, j] = scale * (dv[j] - iv[j]) / area[j]
        else:
            for j in range(n):
                V[i, j] = scale * (dv[j] - iv[j])
    if operator:                                 # symmetrised
        for i in range(n):
            for j in range(i):
                s = 0.5 * (V[i, j] + V[j, i])
                V[i, j] = s
                V[j, i] = s


def _value(px, py, pz, j, tri, centroid, area, diam, near, mid, frame, edge, logs, stamp, key,
           rule):
    """``int_j 1 / |p - y| dS_y`` [m] of triangle ``j`` at the point p by the rule of its
    distance: closed form, 3-point rule (its points into the scratch ``rule`` (3, 3),
    :func:`_rule_points`) or centroid rule (the entry :func:`_collocation` gives the pair)."""
    dx, dy, dz = px - centroid[j, 0], py - centroid[j, 1], pz - centroid[j, 2]
    dist = math.sqrt(dx * dx + dy * dy + dz * dz)
    if dist < near * diam[j]:
        return _potential(px, py, pz, tri[j], frame, edge, logs, stamp, key)
    if dist < mid * diam[j]:                                 # 3-point rule (degree 2)
        _rule_points(tri[j], rule)
        acc = 0.0
        for a in range(3):
            qx, qy, qz = rule[a, 0] - px, rule[a, 1] - py, rule[a, 2] - pz
            acc += 1.0 / math.sqrt(qx * qx + qy * qy + qz * qz)
        return area[j] * acc / 3.0
    return area[j] / dist


def _pair_kernel(points, tri, centroid, area, diam, near, rows, cols, out):
    near = near * (1.0 + _TIE)
    mid = _MID_FACTOR * near
    frame = np.empty((4, 7))
    edge = np.arange(3)
    logs, stamp = np.empty(3), np.full(3, -1, np.int64)
    rule = np.empty((3, 3))
    for k in range(rows.shape[0]):
        i, j = rows[k], cols[k]
        _frame(tri[j], frame)
        out[k] = _value(points[i, 0], points[i, 1], points[i, 2], j, tri, centroid, area, diam,
                        near, mid, frame, edge, logs, stamp, k, rule)


def _corners_kernel(x, triangles, bary, out):
    """Into ``out`` (n_tri s, 3, 3): corner a of sub-triangle q of triangle t is
    ``sum_b bary[q, a, b] x[triangles[t, b]]``, summed in the order b = 0, 1, 2 (numpy's twin,
    ``einsum``, sums in that order: the same values)."""
    s = bary.shape[0]
    for t in range(triangles.shape[0]):
        v0, v1, v2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        for q in range(s):
            for a in range(3):
                w0, w1, w2 = bary[q, a, 0], bary[q, a, 1], bary[q, a, 2]
                for k in range(3):
                    out[t * s + q, a, k] = w0 * x[v0, k] + w1 * x[v1, k] + w2 * x[v2, k]


def _pair_distances_kernel(p, out):
    """Into ``out`` (n (n - 1) / 2,): ``|p_i - p_j|`` for i < j in the order of
    ``scipy.spatial.distance.pdist`` (numpy's twin; the same sums: the same values)."""
    n = p.shape[0]
    k = 0
    for i in range(n):
        for j in range(i + 1, n):
            dx, dy, dz = p[i, 0] - p[j, 0], p[i, 1] - p[j, 1], p[i, 2] - p[j, 2]
            out[k] = math.sqrt(dx * dx + dy * dy + dz * dz)
            k += 1


def _build():
    from numba import njit

    g = globals()
    for name in ("_potential", "_frame", "_near_row", "_closed_forms", "_rule_points",
                 "_value"):
        if not hasattr(g[name], "py_func"):
            g[name] = njit(cache=True, inline="always")(g[name])
    # error_model="numpy": the branch-free centroid rule divides by the zero distance of a
    # triangle to its own centroid (an inf, overwritten by the closed form)
    return njit(_SIGNATURE, cache=True, fastmath=False, error_model="numpy")(_collocation)


def _build_pairs():
    from numba import njit

    _build()                                           # the helpers, compiled
    return njit(_PAIR_SIGNATURE, cache=True, fastmath=False)(_pair_kernel)


def _build_corners():
    from numba import njit

    return (njit(_CORNERS_SIGNATURE, cache=True, fastmath=False)(_corners_kernel),
            njit("void(f8[:, ::1], f8[::1])", cache=True, fastmath=False)(
                _pair_distances_kernel))


#: node positions (n, 3), triangles (n_tri, 3), barycentric corners (s, 3, 3), output
#: (n_tri s, 3, 3)
_CORNERS_SIGNATURE = "void(f8[:, ::1], i8[:, ::1], f8[:, :, ::1], f8[:, :, ::1])"


#: points (n, 3), triangles (m, 3, 3), centroids (m, 3), areas (m,), diameters (m,), near,
#: rows (p,), columns (p,), output (p,)
_PAIR_SIGNATURE = ("void(f8[:, ::1], f8[:, :, ::1], f8[:, ::1], f8[::1], f8[::1], f8, i8[::1], "
                   "i8[::1], f8[::1])")


def use_compiled() -> bool:
    """Whether the compiled kernel is used (the spring kernel's backend is "numba"); compiles
    or loads it on the first call."""
    global _compiled, _broken
    if _broken or not numba_selected():
        return False
    if _compiled is None:
        _compiled = compile_kernel("single-layer kernel", _build, "using numpy")
        _broken = _compiled is None
    return _compiled is not None


def collocation(tri, plane, near, scale, operator=False, edges=None):
    """``(V, area, centroid, diam)`` of the triangles ``tri`` (n, 3, 3) [m] by the compiled
    kernel: ``V = scale (V_sheet - V_image)`` (n, n) (no image without a ``plane`` ``(origin,
    unit normal)``), divided by the source areas and symmetrised with ``operator``; the areas
    [m^2], centroids [m] and diameters [m] of the triangles (see :func:`_collocation`).
    ``edges`` (n, 3) int: an id per edge (edge e from corner e to e + 1), shared by the two
    triangles of an edge (their closed forms share its logarithm); None: none shared."""
    tri = np.ascontiguousarray(tri, np.float64)
    n = len(tri)
    if edges is None:
        edges = np.arange(3 * n, dtype=np.int64).reshape(n, 3)
    edges = np.ascontiguousarray(edges, np.int64)
    V, area, centroid, diam = np.empty((n, n)), np.empty(n), np.empty((n, 3)), np.empty(n)
    if plane is None:
        origin, normal = np.zeros(3), np.array([0.0, 0.0, 1.0])
    else:
        origin, normal = (np.ascontiguousarray(v, np.float64) for v in plane)
    _compiled(tri, edges, int(edges.max(initial=-1)) + 1, origin, normal, plane is not None,
              bool(operator), float(near), float(scale), V, area, centroid, diam)
    return V, area, centroid, diam


def pair_values(points, tri, centroid, area, diam, near, rows, cols) -> np.ndarray:
    """``int_j 1 / |p_i - y| dS_y`` [m] of the pairs ``(rows[k], cols[k])``, (p,), by the
    compiled kernel (the entries of :func:`collocation`'s ``V`` at those pairs, before the
    scale); ``None`` if it
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


def corners(x, triangles, bary):
    """Corners [m] of the sub-triangles (n_tri s, 3, 3) of the ``triangles`` (n_tri, 3) (node
    ids) at node positions ``x`` (n, 3) [m] by the barycentric corners ``bary`` (s, 3, 3)
    (:func:`simulator.thermal._single_layer.subdivision`), compiled: numpy's twin is
    :func:`simulator.thermal._single_layer.sub_triangle_corners` (the same values); ``None`` if
    it cannot be compiled."""
    kernels = _geometry_kernels()
    if kernels is None:
        return None
    out = np.empty((len(triangles) * len(bary), 3, 3))
    kernels[0](_writable(x, np.float64), _writable(triangles, np.int64),
               _writable(bary, np.float64), out)
    return out


def pair_distances(p):
    """``|p_i - p_j|`` [m] for i < j of the points ``p`` (n, 3) [m], (n (n - 1) / 2,), in the
    order of ``scipy.spatial.distance.pdist`` (numpy's twin, the same values), compiled;
    ``None`` if it cannot be compiled."""
    kernels = _geometry_kernels()
    if kernels is None:
        return None
    out = np.empty(len(p) * (len(p) - 1) // 2)
    kernels[1](_writable(p, np.float64), out)
    return out


def _geometry_kernels():
    """The compiled sub-triangle corner and pair distance kernels (compiled or loaded on the
    first call), None if they cannot be compiled."""
    global _compiled_corners
    if _compiled_corners is None:
        _compiled_corners = compile_kernel("sub-triangle geometry kernels", _build_corners,
                                           "using numpy") or False
    return _compiled_corners or None


def _writable(a, dtype):
    """``a`` as a C-contiguous array of ``dtype`` that the compiled signatures accept (numba
    types a read-only array apart: a copy then)."""
    a = np.ascontiguousarray(a, dtype)
    return a if a.flags.writeable else a.copy()
