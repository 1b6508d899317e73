"""Compiled (numba) fold angles of the crossing watch: the operations of
:meth:`simulator.events._CreaseAngles.__call__` in the same order, and the watch's
per-increment test (:func:`_quiet`) in one call.

Every quasi-static step checks each accepted state for panels passing through each other
(:class:`simulator.events.CrossingWatch`). On a small model the numpy path, some twenty array
calls, costs more than its arithmetic (18 us per state on the single crease, 24-31 us on the
gripper and the 3 x 3 Miura lifter); one call here costs a few microseconds. The numpy path
stays the reference (the tests compare the two) and is used where numba is not selected
(``ETORIGAMI_JIT=0``: the switch of :func:`simulator._jit.numba_selected`) or fails to
compile.

The same formulas, with the components taken in the order the numpy path gathers them; the
angles agree to round-off, a few ulps (the tests check 1e-14 rad), not bit for bit: numpy's
``vecdot`` goes through BLAS, whose dot products fuse multiply-adds on CPUs that have them, and
``np.add.reduceat`` adds a panel's first fan term to the sum of the others. The watch's
decisions compare these angles with thresholds (:data:`simulator.events.NEAR_FLAT`,
:data:`~simulator.events.LARGE_TURN`, the wrap at +-180 deg) that a state meets by round-off
only by coincidence, as the numpy path's own agreement with
:func:`~simulator.mechanics.kinematics.fold_angles` is to round-off.
"""

from __future__ import annotations

import math

from ._jit import aot_kernel, compile_kernel, numba_selected

__all__ = ["fold_angles_kernel", "quiet_kernel", "SIGNATURE", "QUIET_SIGNATURE"]

#: f(x (n_nodes, 3), fan (3, F), start (P + 1,), crease (4, C), normals (P, 3) work,
#: a (C,) out): see :func:`_kernel`.
SIGNATURE = "void(f8[:, ::1], i8[:, ::1], i8[::1], i8[:, ::1], f8[:, ::1], f8[::1])"
#: f(a (C,), b (C,), turn, flat) -> bool: see :func:`_quiet`.
QUIET_SIGNATURE = "b1(f8[::1], f8[::1], f8, f8)"


def _kernel(x, fan, start, crease, normals, a):
    """Fold angles ``a`` (C,) [rad] at node positions ``x`` (n_nodes, 3) [m].

    ``fan`` (3, F): corner node, centre node and next corner node (in the top side's turning
    sense) of the fan triangles of the creases' panels, panel after panel; ``start`` (P + 1,):
    where each panel's triangles start in ``fan`` (and F); ``crease`` (4, C): the two panels of
    each crease (0 .. P-1) and the nodes of its axis, head then tail. ``normals`` (P, 3) is
    overwritten with the panels' unnormalised top-side normals (fan sums of cross products)."""
    for p in range(start.shape[0] - 1):
        for i in range(start[p], start[p + 1]):
            c, o, q = fan[0, i], fan[1, i], fan[2, i]
            for j in range(3):
                j1, j2 = (j + 1) % 3, (j + 2) % 3
                v = (x[c, j1] - x[o, j1]) * (x[q, j2] - x[o, j2]) \
                    - (x[c, j2] - x[o, j2]) * (x[q, j1] - x[o, j1])
                normals[p, j] = v if i == start[p] else normals[p, j] + v
    for k in range(a.shape[0]):
        p1, p2, h, t = crease[0, k], crease[1, k], crease[2, k], crease[3, k]
        y, d, s = 0.0, 0.0, 0.0
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            axis = x[h, j] - x[t, j]
            y += (normals[p1, j1] * normals[p2, j2] - normals[p1, j2] * normals[p2, j1]) * axis
            d += normals[p1, j1] * normals[p2, j1]
            s += axis * axis
        a[k] = math.atan2(y, d * math.sqrt(s))


def _quiet(a, b, turn, flat):
    """Whether ``max |a - b| <= turn`` and ``max |a| <= flat`` (C >= 1), the maxima taken
    as ``np.fmax.reduce`` takes them: NaN entries skipped, NaN if all are (then False)."""
    m_turn, m_flat = math.nan, math.nan
    for k in range(a.shape[0]):
        v, w = abs(a[k] - b[k]), abs(a[k])
        if v > m_turn or m_turn != m_turn:
            m_turn = v
        if w > m_flat or m_flat != m_flat:
            m_flat = w
    return m_turn <= turn and m_flat <= flat


_compiled = None
_compiled_quiet = None
#: Compilation failed once (logged): the numpy path from then on.
broken = False


def _build():
    from numba import njit

    return njit(SIGNATURE, cache=True)(_kernel), njit(QUIET_SIGNATURE, cache=True)(_quiet)


def _compile() -> bool:
    """Compile (or load from numba's cache) both kernels; False if that fails (logged once)."""
    global _compiled, _compiled_quiet, broken
    built = compile_kernel("fold-angle kernel", _build, "using numpy")
    broken = built is None
    if not broken:
        _compiled, _compiled_quiet = built
    return not broken


def fold_angles_kernel():
    """The compiled :func:`_kernel`, or None (use numpy): the ahead-of-time compiled one when
    enabled and loaded (:mod:`simulator._aot`, no numba imported), else numba's where numba
    is selected, compiled or loaded from its cache on first use."""
    aot = aot_kernel("fold_angles")                    # tier "aot": short CLI commands
    if aot is not None:
        return aot
    if broken or not numba_selected():
        return None
    return _compiled if _compiled is not None or _compile() else None


def quiet_kernel():
    """The compiled :func:`_quiet`, or None, as :func:`fold_angles_kernel`."""
    aot = aot_kernel("quiet")
    if aot is not None:
        return aot
    if broken or not numba_selected():
        return None
    return _compiled_quiet if _compiled_quiet is not None or _compile() else None
