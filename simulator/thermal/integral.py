"""Heat loss with nothing to fit: the single-layer potential of the sheet (theory 4.7).

The medium (conductivity ``k_env``) around the thin sheet is unbounded and homogeneous, or a
half space above an isothermal substrate plane (image method). Each conducting mesh triangle
(boundary panels excepted: they lie on the substrate and their nodes are held at room
temperature) is refined uniformly into ``m^2`` sub-triangles (``m =
IntegralLoss.refinement``); the sheet temperature rise on them is the linear
interpolation of the nodal rises, ``M T`` at the sub-triangle centroids. The heat ``p_i`` [W]
leaving sub-triangle ``i`` through both faces solves the collocated single-layer equation
``S p = M T`` with ``S_ij = V_ij / A_j`` (:func:`~simulator.thermal._single_layer.collocation_matrix`,
symmetrised: :func:`~simulator.thermal._single_layer.single_layer_operator`), and the nodes
lose ``M^T p``: the loss conductance added to the sheet's T3 conduction is the dense
``L = M^T S^-1 M`` [W/K], symmetric positive definite.

Cost: ``S`` is dense, ``n_s = m^2 n_tri`` sub-triangles; assembly ``O(n_s^2)`` (memory
``~3 x 8 n_s^2`` bytes during assembly), Cholesky ``n_s^3 / 3`` flops, once per shape. Models
above ``MAX_SUB_TRIANGLES`` (:mod:`simulator.model.heat_loss`) sub-triangles are refused (use the chain model,
``loss=ChainLoss(thickness=...)``, or the 3-D FE reference of :mod:`simulator.thermal.fe`).

Sheet on the substrate: the rule of the 3-D FE reference (``solve_fe3d`` holds sheet nodes on
the plane at room temperature and does not embed triangles lying in it). Nodes closer to the
plane than :data:`TOUCH_TOLERANCE` times the sheet's extent touch the substrate
(:meth:`IntegralOperator.touching`): the steady model holds them at room temperature, and the
sub-triangles lying in the plane are left out of ``S`` (there the layer and its image cancel:
their rows and columns of ``S`` vanish, they carry heat straight into the substrate and none
into the medium). Nodes below the plane are pressed onto it (a warning) for the operator.
Between two sheets of the plane the gap conducts ``~ k A / h`` through the image term, which
tends to the held temperature as ``h -> 0``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..linalg import dense_jit as _dense_jit, dense_lapack, thresholds
from ..linalg.ladder import factorize
from ..model import heat_loss
from . import _single_layer_jit
from ._single_layer import (single_layer_operator, sub_triangle_corners, subdivision,
                             subdivision_edges)

__all__ = ["IntegralOperator", "TOUCH_TOLERANCE", "lump_couplings"]

logger = logging.getLogger(__name__)

#: A node closer to the substrate plane than this fraction of the sheet's extent touches it
#: (held at room temperature): the tolerance of the 3-D FE reference's on-plane nodes.
TOUCH_TOLERANCE = 1e-9
#: How much more strictly a height over the substrate plane is kept than a distance between
#: two sheet nodes (:meth:`IntegralOperator._scale`): through a gap h thin against the panel
#: the loss is about k A / h, so a height's relative change moves it by as much, where a pair
#: distance moves only its mutual term, a small part of the loss. Measured on the double fold
#: over its boundary panels' plane (node 21 at 36-48 um): with 1 (the pairs' tolerance) the
#: kept operator drifted 1.7 % of the largest rise from one rebuilt at every shape; with 1/4
#: and the corrected operator's height test, 0.31 %.
HEIGHT_SCALE = 0.25


class IntegralOperator:
    """Dense single-layer loss operator of one mesh's sheet, for any shape.

    Parameters
    ----------
    triangles : (n_tri, 3) int array
        Node ids of the sheet triangles that lose heat to the medium.
    n_nodes : int
        Number of mesh nodes.
    conductivity : float
        Medium conductivity k_env [W/(m K)], > 0.
    refinement : int
        Sub-triangles per triangle edge m (m^2 sub-triangles per triangle).
    plane : (origin (3,), unit normal (3,)), optional
        Isothermal substrate plane; the medium lies on the normal's side.
    shape_tol : float
        Rebuild the operator when the distance between two sheet nodes has changed by more
        than ``shape_tol`` times the larger of that distance and the mean sub-triangle
        diameter since the last build (0: on every change of position).
    lumped : bool
        :meth:`loss_matrix` returns the conductance with its positive couplings lumped onto
        the diagonal (:func:`lump_couplings`; ``IntegralLoss.lumped``), else the consistent
        ``M^T S^-1 M``. :meth:`sub_triangle_heat` is the consistent operator's either way
        (the lumped conductance loses the same total heat, not the same heat per node).
    """

    def __init__(self, triangles, n_nodes: int, conductivity: float, refinement: int,
                 plane=None, shape_tol: float = 0.0, lumped: bool = False):
        self.triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
        self.n_nodes, self.conductivity, self.plane = int(n_nodes), float(conductivity), plane
        self.shape_tol = float(shape_tol)
        #: whether :meth:`loss_matrix` is lumped (:func:`lump_couplings`)
        self.lumped = bool(lumped)
        #: number of operator builds so far (a diagnostic)
        self.builds = 0
        bary_vertices, bary_centroids = subdivision(refinement)
        self.n_sub = len(self.triangles) * len(bary_centroids)
        limit = heat_loss.MAX_SUB_TRIANGLES
        if self.n_sub > limit:
            raise ParameterError(
                f"the integral heat loss: {len(self.triangles)} triangles x "
                f"{len(bary_centroids)} sub-triangles (IntegralLoss.refinement = {refinement}) = "
                f"{self.n_sub} sub-triangles exceeds the dense-operator limit MAX_SUB_TRIANGLES = "
                f"{limit}; use IntegralLoss(operator='fast') or 'auto' (the "
                "default: the fast path above the limit), lower the refinement, or the chain "
                "model (loss=ChainLoss(thickness=...), calibrated by "
                "simulator.thermal.calibrate_environment) or the 3-D FE reference "
                "(simulator.fe).")
        self._bary = bary_vertices                                  # (s, 3, 3)
        #: (n_sub, 3) ids of the sub-triangles' edges (shared edges share an id)
        self._edges = subdivision_edges(self.triangles, refinement)
        s = len(bary_centroids)
        #: (n_sub, n_nodes) interpolation of nodal values at the sub-triangle centroids
        M = np.zeros((self.n_sub, self.n_nodes))
        rows = np.repeat(np.arange(self.n_sub), 3)
        cols = np.repeat(self.triangles, s, axis=0).ravel()
        np.add.at(M, (rows, cols), np.tile(bary_centroids, (len(self.triangles), 1)).ravel())
        self.nodes = np.unique(self.triangles)
        self.M = M[:, self.nodes]                                    # only the sheet's nodes
        self._cache = None
        self._warned = False             # the warning of an operator not positive definite
        #: ``[positions, distances]`` of the last :meth:`_distances` call; operators of the
        #: same sheet and plane at other refinements may share the list (they need the same)
        self.distance_memo = [None, None]
        #: ``[positions, heights, tolerance]`` of the last :meth:`_heights` call (shared as
        #: :attr:`distance_memo` is)
        self.height_memo = [None, None, None]
        self._factors = None               # the per-distance factors of :meth:`_scale`

    def _heights(self, x):
        """Height of every node over the substrate plane [m], (n_nodes,), read-only, and the
        touch tolerance [m] (``None, 0`` without a plane): :func:`plane_heights`, kept for the
        last positions (a loss evaluation asks for them at the same positions several
        times)."""
        if self.plane is None:
            return None, 0.0
        memo = self.height_memo
        if memo[0] is not None and memo[0].shape == x.shape and np.array_equal(memo[0], x):
            return memo[1], memo[2]
        h, tol = plane_heights(x, self.plane, self.nodes)
        h.setflags(write=False)
        memo[:] = [np.array(x, float), h, tol]
        return h, tol

    def touching(self, x) -> np.ndarray:
        """Nodes on (or below) the substrate plane at positions ``x`` (n, 3) [m], (n_nodes,)
        bool: the steady model holds them at room temperature (all False without a plane)."""
        h, tol = self._heights(np.asarray(x, float))
        return np.zeros(self.n_nodes, bool) if h is None else h <= tol

    def _pressed(self, x):
        """``x`` with the nodes below the substrate plane moved onto it, and the mask of the
        sub-triangles lying in the plane (None if there is none)."""
        h, tol = self._heights(x)
        if h is None or not np.any(h <= tol):
            return x, None
        if np.any(below := h < -tol):
            logger.warning("%d node(s) up to %.3g m below the substrate plane: pressed onto it "
                           "for the heat loss", int(below.sum()), float(-h.min()))
            x = x - np.minimum(h, 0.0)[:, None] * np.asarray(self.plane[1], float)
            h = np.maximum(h, 0.0)
        if not np.any(h[self.nodes] <= tol):     # only nodes off the sheet touch (its
            return x, None                       # boundary panels): no sub-triangle in the plane
        corner = np.einsum("sab,tb->tsa", self._bary, h[self.triangles]).reshape(-1, 3)
        flat = np.all(corner <= tol, axis=1)
        return x, (flat if flat.any() else None)

    def live_sub_triangles(self, x, full=None):
        """``(sub, M, edges, flat, pressed)`` at positions ``x`` (n, 3) [m]: the corners
        (n_live, 3, 3) [m] of the sub-triangles that carry a potential (not lying in the
        substrate plane; nodes below it pressed onto it), their rows of :attr:`M` and edge ids,
        the mask of those in the plane (None: none) and whether a node was pressed.
        ``full``: :meth:`sub_triangles` at ``x`` if already computed."""
        xp, flat = self._pressed(x)
        sub = full if (xp is x and full is not None) else self.sub_triangles(xp)
        M, edges = self.M, self._edges
        if flat is not None:             # on the substrate: no potential, no unknown
            sub, M, edges = sub[~flat], M[~flat], edges[~flat]
        return sub, M, edges, flat, xp is not x

    def sub_triangles(self, x) -> np.ndarray:
        """Corners of the sub-triangles at node positions ``x`` (n, 3) [m], (n_sub, 3, 3)."""
        return sub_triangle_corners(x, self.triangles, self._bary)

    def _operator(self, x) -> "_Operator":
        """The operator at positions ``x`` (n, 3) [m]: the last build while the shape stays
        within ``shape_tol`` of it (:meth:`_unchanged`), else a new one."""
        x = np.asarray(x, float)
        if self._cache is None or not self._unchanged(x):
            self.rebuild(x)
        return self._cache

    def rebuild(self, x) -> np.ndarray:
        """Build the operator at positions ``x`` (n, 3) [m] whatever the last build, keep it,
        and return its loss conductance (see :meth:`loss_matrix`)."""
        self._cache = self._build(np.asarray(x, float))
        self.builds += 1
        return self._cache.L

    def exact_at(self, x) -> bool:
        """Rebuild at positions ``x`` (n, 3) [m] unless the last build was there (the end of a
        settled coupling, theory 6.6: the answer then does not depend on where the operator
        was last rebuilt); whether it rebuilt."""
        x = np.asarray(x, float)
        if self._cache is not None and np.array_equal(self._cache.x, x):
            return False
        self.rebuild(x)
        return True

    @property
    def last_definite(self) -> bool:
        """Whether the operator of the last build was positive definite (False where parts of
        the sheet come too close or pass through each other; True before the first build)."""
        return True if self._cache is None else self._cache.definite

    @property
    def last_positions(self):
        """Positions (n, 3) [m] of the last build (None before the first)."""
        return None if self._cache is None else self._cache.x

    def _unchanged(self, x) -> bool:
        """Whether none of :meth:`_distances` has changed since the last build by more than
        ``shape_tol`` times its :meth:`_scale` (a rigid motion changes none; 0: exactly the
        same positions only)."""
        last = self._cache
        if np.array_equal(last.x, x):
            return True
        if self.shape_tol == 0:
            return False
        change = np.abs(self._distances(x) - last.distances) / last.scale
        return bool(change.max(initial=0.0) <= self.shape_tol)

    def _distances(self, x) -> np.ndarray:
        """What the operator depends on, up to a rigid motion: the distances [m] between the
        sheet nodes (condensed, as ``scipy.spatial.distance.pdist``) and, with a substrate
        plane, between each node and its mirror image (twice its height)."""
        from scipy.spatial.distance import pdist    # not needed by a chain-model run

        memo = self.distance_memo
        if memo[0] is not None and memo[0].shape == x.shape and np.array_equal(memo[0], x):
            return memo[1]
        p = x[self.nodes]
        d = _single_layer_jit.pair_distances(p) if _single_layer_jit.use_compiled() else None
        if d is None:                               # numpy's twin
            d = pdist(p)
        if self.plane is not None:
            origin, normal = self.plane
            d = np.concatenate([d, 2 * np.abs((p - origin) @ normal)])
        memo[:] = [x.copy(), d]
        return d

    def _build(self, x) -> "_Operator":
        """Assemble ``S`` at positions ``x`` and factorise it: the loss conductance and the map
        from nodal rises to sub-triangle heats."""
        full = self.sub_triangles(x)
        sub, M, edges, flat, _ = self.live_sub_triangles(x, full)
        diam = None
        if len(sub):
            S, diam = single_layer_operator(sub, self.conductivity, self.plane, edges=edges)
            L, heat, definite = self._factorise(S, M)
        else:                            # the whole sheet lies on the substrate
            L, heat, definite = np.zeros((len(self.nodes),) * 2), None, True
        if flat is not None:
            heat = _padded(heat, ~flat, self.n_sub)
        if not definite and not self._warned:
            self._warned = True
            logger.warning(
                "the integral heat loss: the single-layer operator is not positive definite "
                "at this shape: parts of the sheet are closer to each other than about a "
                "sub-triangle diameter or pass through each other (a model without contact?); "
                "the temperatures there are not reliable. Raise IntegralLoss.refinement or add "
                "contact (said once per model).")
        if sub is not full:              # the diameters of all sub-triangles, unpressed
            diam = np.linalg.norm(full - np.roll(full, 1, axis=1), axis=2).max(axis=1)
        size = diam.mean()
        d = self._distances(x)
        if self.lumped:
            L = lump_couplings(L)
        L.setflags(write=False)
        return _Operator(x.copy(), L, heat, d, self._scale(d, size), definite)

    def _factorise(self, S, M):
        """``(L, heat, definite)`` of the symmetric ``S`` (n_live, n_live) with the
        interpolation ``M`` (n_live, n_sheet) of its live sub-triangles: the loss conductance
        (n_sheet, n_sheet) [W/K], ``heat(rise_sheet) -> (n_sub,)`` [W] and whether ``S`` is
        positive definite. Compiled: ``S = C diag(sign) C^T`` (Cholesky if definite), ``L =
        W^T diag(sign) W`` with ``W = C^-1 M``; LU if a pivot vanishes. Else by the ladder
        (dense Cholesky, a sparse LU if not definite)."""
        if len(S) >= thresholds.LOSS_DENSE_LAPACK_MIN:     # blocked LAPACK, single-threaded
            out = dense_lapack.cholesky_loss(S, M, overwrite=True)   # S is ours
            if out is not None:              # positive definite
                C, W, L = out
                return L, lambda rise: dense_lapack.back_substitute(C, W @ rise), True
            out = dense_lapack.lu_loss(S, M)
            if out is not None:              # not positive definite: LU
                solve, L = out
                return L, lambda rise: solve(M @ rise), False
        if _single_layer_jit.use_compiled() and _dense_jit.available():
            out = _dense_jit.loss_factor(S, M)
            if out is not None:
                C, sign, W, L = out
                return (L, lambda rise: _dense_jit.back_substitute(C, W @ rise, sign),
                        bool(np.all(sign > 0)))
            out = _dense_jit.lu_response(S, M)
            if out is not None:
                return out[1], out[0].__matmul__, False
        factor = factorize(S, kind="spd", dense_limit=len(S))
        P = factor.solve(M)
        L = M.T @ P
        return 0.5 * (L + L.T), P.__matmul__, factor.backend == "dense"

    def _scale(self, distances, size) -> np.ndarray:
        """How far each of :meth:`_distances` may change per unit of ``shape_tol`` [m]: the
        distance, at least the mean sub-triangle diameter ``size``; a height over the plane
        at least 1 % of it, times :data:`HEIGHT_SCALE` (the image's share of the loss changes
        with the height itself)."""
        if self._factors is None or len(self._factors[0]) != len(distances):
            n = len(self.nodes) * (len(self.nodes) - 1) // 2
            pair = np.arange(len(distances)) < n
            self._factors = np.where(pair, 1.0, 0.01), np.where(pair, 1.0, HEIGHT_SCALE)
        floor, scale = self._factors
        return np.maximum(distances, size * floor) * scale

    def loss_matrix(self, x) -> np.ndarray:
        """Loss conductance ``L = M^T S^-1 M`` [W/K] on :attr:`nodes`, (n_sheet, n_sheet)
        (lumped if :attr:`lumped`)."""
        return self._operator(x).L

    def sub_triangle_heat(self, x, rise) -> np.ndarray:
        """Heat [W] leaving each sub-triangle through both faces, (n_sub,), for nodal
        temperature rises ``rise`` (n_nodes,) [K] at positions ``x`` [m]."""
        return self._operator(x).heat(np.asarray(rise, float)[self.nodes])


def lump_couplings(L) -> np.ndarray:
    """The conductance ``L`` (n, n) [W/K] with its positive couplings lumped onto the diagonal
    (theory 4.9; ``IntegralLoss.lumped``): every positive off-diagonal entry ``L_ij`` is set
    to 0 and added to ``L_ii``. A symmetric ``L`` stays exactly symmetric (``L_ij`` and
    ``L_ji`` move onto the diagonals of both rows), its row sums (the heat each node loses at
    a uniform rise) are kept to round-off and so is the loss ``1^T L T`` of any rise ``T``;
    the negative couplings are kept. A new array."""
    L = np.array(L, float)
    positive = np.maximum(L, 0.0)
    np.fill_diagonal(positive, 0.0)
    L -= positive
    L[np.diag_indices_from(L)] += positive.sum(axis=1)
    return L


def plane_heights(x, plane, nodes):
    """Height of every node of ``x`` (n, 3) [m] over the substrate ``plane`` [m], (n,), and the
    touch tolerance [m]: :data:`TOUCH_TOLERANCE` times the extent of the sheet ``nodes``
    (``None, 0`` without a plane)."""
    if plane is None:
        return None, 0.0
    origin, normal = (np.asarray(v, float) for v in plane)
    h = (x - origin) @ normal
    return h, TOUCH_TOLERANCE * float(np.ptp(x[nodes], axis=0).max())


def _padded(heat, live, n_sub):
    """``heat(rise) -> (n_sub,)`` [W] from the heat of the ``live`` sub-triangles (None: none
    is live); the others, lying on the substrate, lose nothing to the medium."""
    def padded(rise):
        out = np.zeros(n_sub)
        if heat is not None:
            out[live] = heat(rise)
        return out
    return padded


@dataclass(frozen=True)
class _Operator:
    """One build of :class:`IntegralOperator`: the positions ``x`` (n, 3) [m] it was built at, the
    loss conductance ``L`` (n_sheet, n_sheet) [W/K], ``heat(rise_sheet) -> (n_sub,)`` [W] and
    :meth:`IntegralOperator._distances` [m] there with the scale of their allowed change
    (:meth:`IntegralOperator._scale`)."""

    x: np.ndarray
    L: np.ndarray
    heat: Callable
    distances: np.ndarray
    scale: np.ndarray
    definite: bool = True
