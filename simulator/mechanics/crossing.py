"""Panels passing through each other between two accepted states (issue 28, item 3).

Two vectorised tests between positions ``x_prev`` and ``x`` (n_nodes, 3) [m] of consecutive
accepted increments, both assuming the motion between them is small (a fraction of a panel, as
an accepted increment's is):

* :func:`crease_crossings`: creases whose fold angle passes +-180 deg. :func:`fold_angles
  <simulator.mechanics.kinematics.fold_angles>` lies in (-pi, pi]; a crease that folds on past
  flat-folded jumps from near +pi to near -pi (or back). The shorter way round from the old angle
  to the new one then passes +-pi, i.e. ``|a - a_prev| > pi``.
* :func:`node_crossings`: contact points (panel corners and centres, theory 3.5) passing
  through a fan triangle of another panel, the pairs panel contact would have held apart: the
  point's signed distance to the triangle's plane changes sign, and where it is zero (both
  moving linearly between the states) the point lies inside the triangle.
"""

from __future__ import annotations

import weakref

import numpy as np

from ..model.mesh import BarHingeMesh
from ..model.model import ContactParameters
from .contact_search import STATIC_PAIR_LIMIT, ContactSearch
from .elements._vec import cross, dot
from .kinematics import fold_angles

__all__ = ["crease_crossings", "node_crossings", "spring_wraps", "wrap_refusal"]

#: Barycentric margin of :func:`node_crossings`: a point passing within this fraction of a
#: triangle's edge is not counted (grazing a shared edge or a T-junction of a flat sheet).
INSIDE_MARGIN = 1e-6
#: Bisection steps locating the plane crossing (the signed distance is cubic in time).
_BISECTIONS = 30
#: Barycentric slack of the first-order pre-selection of pairs that :func:`_plane_time` locates.
_NEAR = 0.5

_SEARCHES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def crease_crossings(mesh: BarHingeMesh, x_prev: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Crease rows (into ``mesh.crease_ids``) whose fold angle passed +-180 deg between two
    states.

    Parameters
    ----------
    mesh : BarHingeMesh (bar-and-hinge or concentrated hinges)
    x_prev, x : (n_nodes, 3) node positions [m] of consecutive accepted states

    Returns
    -------
    (k,) int array, ascending; empty if no crease crossed. A crease that folds back through
    +-180 deg counts again.
    """
    a0, a1 = fold_angles(mesh, np.asarray(x_prev, float)), fold_angles(mesh, np.asarray(x, float))
    return np.flatnonzero(np.abs(a1 - a0) > np.pi)


def node_crossings(mesh: BarHingeMesh, x_prev: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Contact points that passed through a panel between two states.

    Points and admissible (point, triangle) pairs are those of panel contact (theory 3.5): panel
    corner and centre nodes against the fan triangles of the other panels, a corner never
    against a triangle holding a copy of its pattern vertex.

    Parameters
    ----------
    mesh : BarHingeMesh
    x_prev, x : (n_nodes, 3) node positions [m] of consecutive accepted states

    Returns
    -------
    (k, 2) int array of (node, panel passed through), one row per pair, sorted; empty (0, 2)
    if none crossed.
    """
    if getattr(mesh, "sharp", False):
        return np.zeros((0, 2), int)
    search = _search(mesh)
    x0, x1 = np.asarray(x_prev, float), np.asarray(x, float)
    p, t = _swept_pairs(search, x0, x1)
    P0, P1 = x0[search.points[p]], x1[search.points[p]]
    T0, T1 = x0[search.tri[t]], x1[search.tri[t]]                       # (m, 3, 3)
    s0, s1 = _signed_volume(P0, T0), _signed_volume(P1, T1)
    with np.errstate(divide="ignore", invalid="ignore"):
        guess = s0 / (s0 - s1)                   # where the plane is crossed, to first order
    # near the plane crossing in time and space: the pairs worth locating exactly
    k = np.flatnonzero(s0 * s1 < 0)
    k = k[_inside(*_at(guess[k], P0[k], P1[k], T0[k], T1[k]), margin=-_NEAR)]
    if not len(k):
        return np.zeros((0, 2), int)
    tau = _plane_time(P0[k], P1[k], T0[k], T1[k], np.sign(s0[k]))
    k = k[_inside(*_at(tau, P0[k], P1[k], T0[k], T1[k]))]
    out = np.column_stack([search.points[p[k]], search.tri_panel[t[k]]])
    return np.unique(out, axis=0) if len(out) else np.zeros((0, 2), int)


def _search(mesh) -> ContactSearch:
    """The contact points, fan triangles and exclusion rules of ``mesh`` (cached per mesh)."""
    search = _SEARCHES.get(mesh)
    if search is None:
        search = _SEARCHES[mesh] = ContactSearch(mesh, ContactParameters())
    return search


def _swept_pairs(search: ContactSearch, x0, x1) -> tuple[np.ndarray, np.ndarray]:
    """Admissible (point, triangle) index pairs whose swept bounding spheres overlap."""
    xp0, xp1 = x0[search.points], x1[search.points]
    pc, pr = 0.5 * (xp0 + xp1), 0.5 * np.linalg.norm(xp1 - xp0, axis=1)
    corners = np.concatenate([x0[search.tri], x1[search.tri]], axis=1)     # (nt, 6, 3)
    tc = corners.mean(axis=1)
    tr = np.linalg.norm(corners - tc[:, None], axis=2).max(axis=1)
    n_p, n_t = len(pc), len(tc)
    if n_p * n_t <= STATIC_PAIR_LIMIT:                 # all pairs, as contact's search
        p, t = np.divmod(np.arange(n_p * n_t), n_t)
    else:
        from scipy.spatial import cKDTree  # large meshes only; slow to import

        lists = cKDTree(pc).query_ball_point(tc, tr + pr.max())
        t = np.repeat(np.arange(n_t), [len(v) for v in lists])
        p = np.fromiter((i for v in lists for i in v), int, len(t))
    near = np.linalg.norm(pc[p] - tc[t], axis=1) <= pr[p] + tr[t]
    p, t = p[near], t[near]
    ok = search.admissible(p, t)
    return p[ok], t[ok]


def _signed_volume(P, T) -> np.ndarray:
    """(P - T1) . ((T2 - T1) x (T3 - T1)) of points P (m, 3) and triangles T (m, 3, 3) [m^3]."""
    return dot(P - T[:, 0], cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]))


def _at(tau, P0, P1, T0, T1) -> tuple:
    """Points (m, 3) and triangles (m, 3, 3) at fractions tau (m,) of a linear motion."""
    w = tau[:, None]
    return P0 + w * (P1 - P0), T0 + w[:, :, None] * (T1 - T0)


def _plane_time(P0, P1, T0, T1, sign0) -> np.ndarray:
    """Fraction tau in (0, 1) of the motion where the signed volume (sign ``sign0`` at 0,
    opposite at 1) vanishes, by bisection with every position moving linearly."""
    lo, hi = np.zeros(len(P0)), np.ones(len(P0))
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        same = _signed_volume(*_at(mid, P0, P1, T0, T1)) * sign0 > 0
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    return 0.5 * (lo + hi)


def _inside(P, T, margin: float = INSIDE_MARGIN) -> np.ndarray:
    """Whether the points P (m, 3) project inside triangles T (m, 3, 3), every barycentric
    coordinate above ``margin``."""
    e1, e2, d = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0], P - T[:, 0]
    d11, d12, d22, b1, b2 = dot(e1, e1), dot(e1, e2), dot(e2, e2), dot(d, e1), dot(d, e2)
    det = d11 * d22 - d12 * d12
    with np.errstate(divide="ignore", invalid="ignore"):
        v, w = (d22 * b1 - d12 * b2) / det, (d11 * b2 - d12 * b1) / det
    return (det > 0) & (v > margin) & (w > margin) & (1 - v - w > margin)


def spring_wraps(mesh: BarHingeMesh, x_prev: np.ndarray, rest_prev: np.ndarray, x: np.ndarray,
                 rest: np.ndarray) -> np.ndarray:
    """Rotational springs whose angle passed the spring law's wrap point, half a turn from the
    rest angle, between two states (theory 3.3).

    The law's deviation ``theta - theta0`` is taken modulo 2 pi into [-pi, pi): where it passes
    +-pi the spring's moment reverses (from about ``k pi`` to ``-k pi``), so a state past it is
    held by a moment that pushes the crease the other way round. A passing shows as the wrapped
    deviation changing by more than pi between the states (each moving less than half a turn).

    Parameters
    ----------
    mesh : BarHingeMesh
    x_prev, x : (n_nodes, 3) node positions [m] of consecutive states
    rest_prev, rest : (n_springs,) spring rest angles [rad] there

    Returns
    -------
    (k,) int array of spring indices (into ``mesh.springs``), ascending; empty if none.
    """
    from .elements.springs import fold_angle

    springs = np.asarray(mesh.springs)
    if not len(springs):
        return np.zeros(0, int)

    def deviation(xs, r):
        d = fold_angle(np.asarray(xs, float)[springs]) - np.asarray(r, float)
        return d - 2 * np.pi * np.floor(d / (2 * np.pi) + 0.5)
    return np.flatnonzero(np.abs(deviation(x, rest) - deviation(x_prev, rest_prev)) > np.pi)


def wrap_refusal(system, u_prev, rest_prev, u, rest) -> str:
    """Why a converged state ``u`` (rest angles ``rest``) reached from ``u_prev``
    (``rest_prev``) must be refused: the springs that passed the law's wrap point
    (:func:`spring_wraps`) in words, "" if none did (or ``system`` has no model)."""
    model = getattr(system, "model", None)
    if model is None or rest_prev is None or rest is None:
        return ""
    mesh = model.mesh
    rows = spring_wraps(mesh, mesh.nodes + np.asarray(u_prev, float).reshape(-1, 3), rest_prev,
                        mesh.nodes + np.asarray(u, float).reshape(-1, 3), rest)
    if not len(rows):
        return ""
    cs = np.asarray(mesh.crease_springs)                 # (C, 8) springs of each crease
    owner = dict(zip(cs.ravel().tolist(), np.repeat(mesh.crease_ids, cs.shape[1]).tolist())) \
        if cs.ndim == 2 else {}
    names = [f"spring {int(s)}" + (f" (crease {owner[int(s)]})" if int(s) in owner else "")
             for s in rows[:3]]
    more = f" and {len(rows) - 3} more" if len(rows) > 3 else ""
    from .substrate import NOT_PHYSICAL

    return (NOT_PHYSICAL + ", ".join(names) + more + " passed the spring law's wrap point, "
            "180 deg from the rest angle, where its moment reverses")
