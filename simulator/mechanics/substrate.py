"""Nodes below a substrate: a state no accepted increment may have (theory 6.11, issue 29).

A *substrate panel* is a panel whose corners are all fixed in x, y and z and whose plane has every
other node of the mesh strictly on one side in the reference configuration (by more than
:data:`SIDE_RTOL` of the model size): the chip under a released sheet (``with_substrate``), not
a clamped panel of the sheet itself (the sheet starts in its plane). A substrate does not move,
and it is a solid (the chip is hundreds of um thick), so a node on its far side within its
outline has passed through it, whatever the path: the test is on one state, not on two.

Panel contact (theory 3.5) keeps the panel corner and centre nodes above the substrate: its
barrier is infinite at zero distance. The crease nodes (A, B and the centre of each crease of
finite width) are not contact points, and a Newton or descent step can carry a node further
than its contact distance; :func:`substrate_breaches` finds what got through, for the steps to
refuse the state (halve the increment) or, where they cannot, end without success.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from ..model.mesh import BarHingeMesh

__all__ = ["Substrate", "substrate_of", "substrate_breaches", "breach_message", "substrate_refusal",
           "not_physical", "BELOW_RTOL", "NOT_PHYSICAL"]

#: A node counts as below a substrate where it is more than this fraction of the model size
#: under the substrate's plane (1 nm on a 1 mm sheet). The substrate's nodes are fixed, so its
#: plane is exact; a node's height is computed to about 1e-16 of the model size; the contact
#: distance (40 um on the Miura lifter) is 4e-2 of it. Any penetration a physical model could
#: resolve is therefore far above this, and round-off far below.
BELOW_RTOL = 1e-9
#: How a refusal of a converged state begins (:func:`substrate_refusal`,
#: :func:`~simulator.mechanics.crossing.wrap_refusal`); :func:`not_physical` finds it in a message.
NOT_PHYSICAL = "the converged state is not physical: "
#: Every other node must lie on one side of a fixed panel's plane by more than this fraction of
#: the model size for the panel to be a substrate (a clamped panel of a flat sheet is not).
SIDE_RTOL = 1e-6
#: Barycentric slack of the outline test: a node above a fan triangle's edge (to round-off) is
#: inside (the fan triangles of a panel share their edges).
_EDGE = 1e-9


@dataclass(frozen=True, eq=False)
class Substrate:
    """The substrate panels of a model and what the test needs of them (SI units).

    Attributes
    ----------
    panels : (k,) substrate panel of each fan triangle
    origin : (k, 3) first corner of each fan triangle [m]
    normal : (k, 3) unit normal of each fan triangle, towards the structure
    edges : (k, 2, 3) the triangle's edge vectors from ``origin`` [m]
    nodes : (m,) the nodes tested (not of a substrate panel)
    tol : depth below the plane that counts [m] (:data:`BELOW_RTOL` of the model size)
    """

    panels: np.ndarray
    origin: np.ndarray
    normal: np.ndarray
    edges: np.ndarray
    nodes: np.ndarray
    tol: float

    def heights(self, x: np.ndarray) -> np.ndarray:
        """(m, k) signed height [m] of the tested nodes over each fan triangle's plane (positive
        on the structure's side) at positions ``x`` (n_nodes, 3), NaN where the node's
        projection is outside the triangle."""
        d = x[self.nodes][:, None, :] - self.origin[None]                   # (m, k, 3)
        h = np.einsum("mki,ki->mk", d, self.normal)
        e1, e2 = self.edges[:, 0], self.edges[:, 1]
        d11, d12, d22 = (np.einsum("ki,ki->k", a, b) for a, b in ((e1, e1), (e1, e2), (e2, e2)))
        b1, b2 = np.einsum("mki,ki->mk", d, e1), np.einsum("mki,ki->mk", d, e2)
        det = d11 * d22 - d12 * d12
        v, w = (d22 * b1 - d12 * b2) / det, (d11 * b2 - d12 * b1) / det
        inside = (v >= -_EDGE) & (w >= -_EDGE) & (1 - v - w >= -_EDGE)
        return np.where(inside, h, np.nan)


_SUBSTRATES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def substrate_of(mesh: BarHingeMesh, supports) -> Substrate | None:
    """The :class:`Substrate` of a mesh with its supports (``Supports``), None if it has no
    substrate panel (cached per mesh and set of fixed nodes)."""
    kept = _SUBSTRATES.get(mesh)
    if kept is not None and kept[0] is supports:
        return kept[2]
    fixed = frozenset(int(n) for n, d in supports.fixed.items() if d == "xyz")
    out = kept[2] if kept is not None and kept[1] == fixed else _build(mesh, fixed)
    _SUBSTRATES[mesh] = (supports, fixed, out)
    return out


def _build(mesh: BarHingeMesh, fixed: frozenset) -> Substrate | None:
    if getattr(mesh, "sharp", False) or not fixed or not len(mesh.nodes):
        return None
    X = mesh.nodes
    size = float(np.max(np.ptp(X, axis=0)))
    fan = mesh.fan_triangles
    tri_panel = mesh.triangle_panel[fan]
    panels, tris, sides, own = [], [], [], set()
    for p in range(mesh.pattern.n_panels):       # (once per model: a few panels)
        nodes = mesh.panel_nodes(p)
        if not fixed.issuperset(int(i) for i in nodes[:-1]):        # its corners
            continue
        t = mesh.triangles[fan[tri_panel == p]]
        n = np.cross(X[t[:, 1]] - X[t[:, 0]], X[t[:, 2]] - X[t[:, 0]])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        others = np.setdiff1d(np.arange(len(X)), nodes)
        if not len(others):
            continue
        h = np.einsum("mki,ki->mk", X[others][:, None] - X[t[:, 0]][None], n)    # (m, k)
        n *= np.sign(h[0])[:, None]          # (a fan's triangles need not turn alike)
        if not np.all(h * np.sign(h[0]) > SIDE_RTOL * size):
            continue
        panels.append(np.full(len(t), p))
        tris.append(t)
        sides.append(n)
        own.update(int(i) for i in nodes)
    if not panels:
        return None
    t = np.concatenate(tris)
    origin = X[t[:, 0]]
    edges = np.stack([X[t[:, 1]] - origin, X[t[:, 2]] - origin], axis=1)
    tested = np.setdiff1d(np.arange(len(X)), np.fromiter(own, int))
    return Substrate(np.concatenate(panels), origin, np.concatenate(sides), edges, tested,
                     BELOW_RTOL * size)


def substrate_breaches(substrate: Substrate | None, x: np.ndarray) -> np.ndarray:
    """Nodes below a substrate at positions ``x`` (n_nodes, 3) [m].

    Returns
    -------
    (j, 3) float array of rows (node, substrate panel, depth below its plane [m]), deepest
    first; empty (0, 3) if none (or no substrate).
    """
    if substrate is None:
        return np.zeros((0, 3))
    h = substrate.heights(np.asarray(x, float))
    with np.errstate(invalid="ignore"):
        hit = h < -substrate.tol
    m, k = np.nonzero(hit)
    if not len(m):
        return np.zeros((0, 3))
    rows = np.column_stack([substrate.nodes[m], substrate.panels[k], -h[m, k]])
    rows = rows[np.argsort(-rows[:, 2], kind="stable")]
    _, first = np.unique(rows[:, 0], return_index=True)       # one row per node (deepest)
    return rows[np.sort(first)]


def breach_message(mesh: BarHingeMesh, rows: np.ndarray, limit: int = 3) -> str:
    """Rows of :func:`substrate_breaches` in words: which nodes (crease nodes are not contact
    points), how deep [um], below which substrate panel."""
    parts = []
    for node, panel, depth in rows[:limit]:
        node = int(node)
        kind = "crease node" if mesh.node_panel[node] < 0 else \
            f"panel {int(mesh.node_panel[node])} node"
        parts.append(f"{kind} {node} {1e6 * depth:.3g} um below substrate panel {int(panel)}")
    more = f" and {len(rows) - limit} more" if len(rows) > limit else ""
    return ", ".join(parts) + more


def substrate_refusal(system, u) -> str:
    """Why a converged state ``u`` (n_nodes, 3) [m] of ``system`` (an EquilibriumSystem: its
    ``model``) must be refused: its nodes below a substrate in words, "" if none are (or the
    system has no model)."""
    model = getattr(system, "model", None)
    if model is None:
        return ""
    substrate = substrate_of(model.mesh, model.supports)
    if substrate is None:
        return ""
    rows = substrate_breaches(substrate, model.mesh.nodes + np.asarray(u, float).reshape(-1, 3))
    if not len(rows):
        return ""
    return NOT_PHYSICAL + breach_message(model.mesh, rows)


def not_physical(message: str) -> str:
    """The refusal of a converged state in a failure ``message`` (what was not physical, up
    to ": halving it"), "" if there is none."""
    k = message.find(NOT_PHYSICAL)
    if k < 0:
        return ""
    text = message[k + len(NOT_PHYSICAL):]
    return text.split(": halving it")[0]
