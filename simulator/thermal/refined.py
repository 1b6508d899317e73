"""The sheet's temperature resolved within the mesh triangles (theory 4.11).

The mechanics' mesh is coarse where a panel is rigid: a gripper panel is two fan triangles of
500 um, a crease strip one triangle across. The sheet's temperature, linear on those triangles,
cannot follow the few tens of micrometres over which a polymer panel hands its heat to the air
(``k t / (2 k_air)``), so the coarse model runs the heated creases 10-30 % hot and, with the
integral loss, puts nodes below room temperature (theory 4.9). ``ThermalParameters(
sheet_refinement=r)`` solves the heat balance on every mesh triangle split uniformly into
``r^2`` (:class:`RefinedSheet`): the same materials, loss model and substrate, with

* the mesh nodes kept as the first fine nodes (the temperatures the mechanics reads are the
  fine field's at the mesh nodes, injected);
* fine positions interpolated linearly from the mesh nodes' (``RefinedSheet.P``): a fine
  node stays on its (flat) mesh triangle at any shape;
* the heat input (:meth:`RefinedSheet.heat`): a crease's power, which the mesh nodes receive
  by the paper's nodal split (theory 4.6), heats the crease's fine triangles uniformly (the
  thin-film heater covers the crease); any other nodal heat is spread as a density
  proportional to the node's hat function over its triangles. The nodal heat ``q`` is split
  into the two by least squares, ``p = (W^T W)^-1 W^T q`` with ``W`` the nodal split (n, C):
  exact for the heat of crease powers, ``q = W p``, and the total always kept.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import ParameterError
from ..model.thermal_parameters import MAX_SHEET_REFINEMENT
from ._single_layer import subdivision

__all__ = ["RefinedSheet", "FineMesh"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class FineMesh:
    """The refined sheet as the thermal model reads a mesh: nodes, triangles with their
    panel or crease, bars (every fine triangle edge) with their reference lengths, and the
    pattern (materials, thicknesses) and crease ids of the mesh it refines."""

    nodes: np.ndarray
    triangles: np.ndarray
    triangle_panel: np.ndarray
    triangle_crease: np.ndarray
    bars: np.ndarray
    bar_length: np.ndarray
    crease_ids: np.ndarray
    pattern: object
    #: the refinement r of the mesh triangles (the integral loss's levels count per fine
    #: triangle edge, :func:`~simulator.thermal.integral_levels.sheet_levels`)
    r: int = 1

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def n_creases(self) -> int:
        return len(self.crease_ids)


class RefinedSheet:
    """Uniform refinement of a mesh's triangles into ``r^2`` each, for the thermal solve.

    Parameters
    ----------
    mesh : BarHingeMesh
        The mesh (its triangles, panels and creases, reference positions).
    r : int
        Fine triangles per mesh triangle edge, 1 to :data:`MAX_SHEET_REFINEMENT`.

    Attributes
    ----------
    P : (n_fine, n) sparse
        Fine node positions from the mesh nodes' (linear on each mesh triangle); its first
        ``n`` rows are the identity (the mesh nodes are the first fine nodes).
    hats : (n_fine, n) sparse
        Each mesh node's heat spread as a density proportional to its hat function (module
        notes); every column sums to 1.
    mesh : FineMesh
        The fine sheet for :class:`~simulator.thermal.steady.ThermalModel`.
    parent : (n_fine_tri,) int
        The mesh triangle of every fine triangle.
    """

    def __init__(self, mesh, r: int):
        if isinstance(r, bool) or not isinstance(r, (int, np.integer)) \
                or not 1 <= r <= MAX_SHEET_REFINEMENT:
            raise ParameterError(f"ThermalParameters.sheet_refinement = {r!r} must be an integer "
                                 f"from 1 (the mesh triangles) to {MAX_SHEET_REFINEMENT}.")
        self.r, self.n = int(r), int(mesh.n_nodes)
        tri = np.asarray(mesh.triangles, np.int64)
        bary = subdivision(self.r)[0]                                   # (s, 3 corners, 3)
        weights = np.rint(bary * self.r).astype(np.int64)
        s = len(bary)
        ftri, self.P = self._nodes(tri, weights)
        self.parent = np.repeat(np.arange(len(tri)), s)
        sub = np.tile(np.arange(s), len(tri))
        x0 = self.P @ np.asarray(mesh.nodes, float)
        self.hats = self._hats(mesh, ftri, bary[sub], x0)
        self._creases = (self._crease_heating(mesh, ftri, x0)
                         if getattr(mesh, "n_creases", 0) and hasattr(mesh, "crease_nodes")
                         else None)
        edges = np.unique(np.sort(ftri[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
        self.mesh = FineMesh(
            nodes=x0, triangles=ftri,
            triangle_panel=np.asarray(mesh.triangle_panel)[self.parent],
            triangle_crease=np.asarray(mesh.triangle_crease)[self.parent],
            bars=edges, bar_length=np.linalg.norm(x0[edges[:, 1]] - x0[edges[:, 0]], axis=1),
            crease_ids=np.asarray(mesh.crease_ids), pattern=mesh.pattern, r=self.r)
        logger.debug("sheet refined r = %d: %d nodes, %d triangles (mesh: %d, %d)", self.r,
                     len(x0), len(ftri), self.n, len(tri))

    @property
    def n_fine(self) -> int:
        """Number of fine nodes."""
        return self.P.shape[0]

    def _nodes(self, tri, weights):
        """Fine triangles (n_tri s, 3) and the sparse interpolation ``P`` of their nodes: the
        mesh nodes first, then ``r - 1`` nodes per mesh edge (from its lower node id), then the
        ``(r - 1)(r - 2) / 2`` inner nodes of every mesh triangle."""
        r, n = self.r, self.n
        t, s = len(tri), len(weights)
        nodes = np.broadcast_to(tri[:, None, None, :], (t, s, 3, 3))
        w = np.broadcast_to(weights, nodes.shape)
        n_pos = (w > 0).sum(axis=-1)                                      # (t, s, 3)
        edges, edge_of = np.unique(np.sort(tri[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1),
                                   axis=0, return_inverse=True)
        edge_of = edge_of.reshape(t, 3)                  # edge (0,1), (1,2), (2,0) of each
        ids = np.empty((t, s, 3), np.int64)
        # corners: the mesh node with weight r
        vert = n_pos == 1
        ids[vert] = np.take_along_axis(nodes, np.argmax(w, axis=-1)[..., None], -1)[..., 0][vert]
        # on a mesh edge: the zero weight names the edge (opposite corner)
        on_edge = n_pos == 2
        zero = np.argmin(w, axis=-1)                                      # (t, s, 3)
        local = (zero + 1) % 3                            # edge (local, local + 1) of the parent
        e = np.take_along_axis(np.broadcast_to(edge_of[:, None, None, :], (t, s, 3, 3)),
                               local[..., None], -1)[..., 0]
        low = edges[e, 0]                                 # the edge's lower node id
        # the weight of the edge's higher node: that of the corner whose id is not `low`
        w_high = np.where((nodes != low[..., None]) & (w > 0), w, 0).sum(axis=-1)
        ids[on_edge] = (n + e * (r - 1) + w_high - 1)[on_edge]
        # inside: the (w1, w2) pair indexes the inner points of the triangle
        inner = n_pos == 3
        if inner.any():
            n_in = (r - 1) * (r - 2) // 2
            grid = -np.ones((r + 1, r + 1), np.int64)
            k = 0
            for i in range(1, r):
                for j in range(1, r - i):
                    grid[i, j] = k
                    k += 1
            loc = grid[w[..., 1], w[..., 2]]
            base = n + len(edges) * (r - 1)
            ids[inner] = (base + np.arange(t)[:, None, None] * n_in + loc)[inner]
        n_fine = n + len(edges) * (r - 1) + t * ((r - 1) * (r - 2) // 2)
        rows = np.repeat(ids.reshape(-1), 3)
        cols = nodes.reshape(-1)
        vals = (w / r).reshape(-1)
        keep = vals > 0
        P = sp.coo_matrix((vals[keep], (rows[keep], cols[keep])), shape=(n_fine, n)).tocsr()
        P.sum_duplicates()
        # a fine node met from several fine triangles was added several times: divide back
        count = np.bincount(ids.reshape(-1), minlength=n_fine).astype(float)
        P = sp.diags(1.0 / count) @ P
        return ids.reshape(-1, 3), P.tocsr()

    def _hats(self, mesh, ftri, phi, x0):
        """The (n_fine, n) spread of each mesh node's heat (module notes): column c is
        ``int phi_c phi_f`` over the fine triangles of the node's region, normalised to sum
        to 1; ``phi`` (n_fine_tri, 3 corners, 3 parents) the parents' hat functions at the
        fine triangles' corners."""
        tri = np.asarray(mesh.triangles, np.int64)
        crease_tri = np.asarray(mesh.triangle_crease) >= 0
        heater = np.zeros(self.n, bool)
        heater[tri[crease_tri].ravel()] = True
        d1, d2 = x0[ftri[:, 1]] - x0[ftri[:, 0]], x0[ftri[:, 2]] - x0[ftri[:, 0]]
        area = 0.5 * np.linalg.norm(np.cross(d1, d2), axis=1)
        parents = tri[self.parent]                                       # (f, 3)
        # int over a fine triangle of phi_c phi_v = A / 12 (phi_c(v) + sum_g phi_c(g))
        val = area[:, None, None] / 12 * (phi + phi.sum(axis=1, keepdims=True))  # (f, v, c)
        ok = ~heater[parents] | crease_tri[self.parent][:, None]         # (f, c)
        val = val * ok[:, None, :]
        rows = np.repeat(ftri, 3, axis=1).reshape(-1)                   # v-major, then c
        cols = np.tile(parents, (1, 3)).reshape(-1)
        Q = sp.coo_matrix((val.reshape(-1), (rows, cols)), shape=(self.n_fine, self.n)).tocsc()
        Q.sum_duplicates()
        total = np.asarray(Q.sum(axis=0)).ravel()
        return (Q @ sp.diags(np.where(total > 0, 1.0 / np.where(total > 0, total, 1), 0.0))
                ).tocsr()

    def _crease_heating(self, mesh, ftri, x0):
        """The crease powers' part of :meth:`heat`: the nodal split ``W`` (n, C) (theory 4.6),
        the factorised ``W^T W`` and the uniform heating ``F`` (n_fine, C) of each crease's
        fine triangles."""
        from ..linalg.ladder import factorize
        from .steady import heat_weights

        n, C = self.n, mesh.n_creases
        W = sp.coo_matrix((np.tile(heat_weights(), C), (np.asarray(mesh.crease_nodes).ravel(),
                                                         np.repeat(np.arange(C), 7))),
                          shape=(n, C)).tocsr()
        d1, d2 = x0[ftri[:, 1]] - x0[ftri[:, 0]], x0[ftri[:, 2]] - x0[ftri[:, 0]]
        third = np.linalg.norm(np.cross(d1, d2), axis=1) / 6
        row = np.asarray(mesh.triangle_crease)[self.parent]
        on = row >= 0
        F = sp.coo_matrix((np.repeat(third[on], 3), (ftri[on].ravel(), np.repeat(row[on], 3))),
                          shape=(self.n_fine, C)).tocsc()
        total = np.asarray(F.sum(axis=0)).ravel()
        F = (F @ sp.diags(np.where(total > 0, 1.0 / np.where(total > 0, total, 1), 0.0))).tocsr()
        return W, factorize((W.T @ W).tocsc(), kind="spd").solve, F

    @property
    def load(self) -> np.ndarray:
        """The dense (n_fine, n) matrix of :meth:`heat` (every column sums to 1)."""
        return self.heat(np.eye(self.n))

    def positions(self, x) -> np.ndarray:
        """Fine node positions (n_fine, 3) [m] at mesh node positions ``x`` (n, 3) [m]."""
        return self.P @ np.asarray(x, float)

    def heat(self, q) -> np.ndarray:
        """Fine nodal heat [W] of the mesh nodal heat ``q`` (n,) or (n, k) [W] (module notes:
        the crease powers ``p = (W^T W)^-1 W^T q`` heat their creases' fine triangles
        uniformly, the rest ``q - W p`` spreads by the hat functions)."""
        q = np.asarray(q, float)
        if self._creases is None:
            return self.hats @ q
        W, solve, F = self._creases
        p = solve(W.T @ q)
        return F @ p + self.hats @ (q - W @ p)

    def restrict(self, v) -> np.ndarray:
        """A fine nodal heat flow (n_fine,) [W] gathered onto the mesh nodes (``P^T``: the
        total is kept)."""
        return self.P.T @ np.asarray(v, float)
