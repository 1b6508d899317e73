"""A two-level preconditioner of the integral heat loss's coupled system (theory 4.7).

The fast path (:mod:`simulator.thermal.integral_fast`) solves, per level of the operator, the
symmetric saddle system ``[[K, M^T], [M, -S]] [T; p] = [q; 0]`` by MINRES with a block-diagonal
preconditioner ``diag(P_T, P_S)``. The iteration count is bounded with the size when ``P_S``
is spectrally equivalent to the single-layer matrix ``S`` and ``P_T`` to the Schur complement
``K + M^T S^-1 M``. Here:

* ``P_S^-1 = B + R0^T S0^-1 R0`` (two-level additive Schwarz): the sub-triangles are split
  into patches of about :data:`PATCH_SIZE` by recursive coordinate bisection; ``R0`` sums
  a patch's heats (the coarse space: a constant heat density per patch) and ``S0 = R0 S
  R0^T`` is the coarse single-layer matrix (dense, one row per patch); ``B`` is block
  diagonal, per patch the inverse of ``S`` on the patch restricted to heats of zero sum
  (``S_ii^-1 - u u^T / 1^T u``, ``u = S_ii^-1 1``). Without that restriction the patches'
  constants, which interact over the whole sheet through ``1/r``, make the local blocks far
  from orthogonal and the condition number grows with the number of patches (measured on
  Miura sheets, m = 1: 20 -> 37 from 500 to 1500 sub-triangles with plain block inverses;
  7.5 -> 8.5 from 500 to 3000 with zero-sum blocks);
* ``P_T = K + M^T P_S^-1 M``: the Schur complement of the preconditioner's own saddle system,
  the sparse ``K + M^T B M`` plus the rank-``n0`` coarse term ``U S0^-1 U^T`` (``U = M^T
  R0^T``), inverted by the Woodbury identity around a sparse factorisation (``K + M^T B M``
  is singular on constant rises: a multiple of ``U diag(S0)^-1 U^T`` is moved into the sparse
  part).

``S0`` is formed from the patches' monopoles (``n_I n_J G(c_I, c_J)``) for patch pairs
farther apart than :data:`COARSE_NEAR` times the sum of their radii, and exactly (all
sub-triangle pairs of the two patches, with the near-field entries) otherwise.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import scipy.sparse as sp

from ..linalg.ladder import factorize
from ._single_layer import mirror

__all__ = ["TwoLevelPreconditioner", "patches", "PATCH_SIZE", "MAX_PATCHES", "COARSE_NEAR"]

logger = logging.getLogger(__name__)

#: Sub-triangles per patch (at least; more when the sheet would have more than
#: :data:`MAX_PATCHES` patches).
PATCH_SIZE = 32
#: Largest number of patches (the coarse matrix is dense, and the Woodbury identity needs one
#: sparse solve per patch).
MAX_PATCHES = 1000
#: Patch pairs closer than this many times the sum of their radii get the exact coarse entry.
COARSE_NEAR = 2.0
#: Multiple of ``U diag(S0)^-1 U^T`` moved into the sparse part of ``P_T``.
_SHIFT = 0.5
#: Patches (or patch pairs) whose dense blocks are formed at once (about 50 MB at 80
#: sub-triangles per patch).
_BATCH = 128


def patches(points, size: int) -> np.ndarray:
    """Labels (n,) of ``points`` (n, 3) split by recursive coordinate bisection (along the
    longest extent, at the median) into groups of at most ``size`` points, 0..n_groups-1."""
    points = np.asarray(points, float)
    labels = np.zeros(len(points), np.int64)
    todo, count = [np.arange(len(points))], 0
    while todo:
        g = todo.pop()
        if len(g) <= size:
            labels[g] = count
            count += 1
            continue
        axis = int(np.argmax(np.ptp(points[g], axis=0)))
        order = np.argsort(points[g, axis], kind="stable")
        half = len(g) // 2
        todo += [g[order[half:]], g[order[:half]]]
    return labels


class TwoLevelPreconditioner:
    """``P_S^-1`` and ``P_T^-1`` of one level (see the module notes).

    Parameters
    ----------
    S : FastSingleLayer
        The level's single-layer matrix (centroids, near field, plane).
    K : (n, n) sparse matrix
        Conduction [W/K] of the unknown nodes.
    M : (n_s, n) sparse matrix
        Interpolation of the unknown nodes' rises at the sub-triangle centroids.
    size : int, optional
        Sub-triangles per patch (default :data:`PATCH_SIZE`, more above
        :data:`MAX_PATCHES` patches).
    """

    def __init__(self, S, K, M, size: int | None = None):
        ns = S.n
        size = max(PATCH_SIZE, math.ceil(ns / MAX_PATCHES)) if size is None else int(size)
        self.labels = labels = patches(S.centroids, size)
        self.n0 = n0 = int(labels.max()) + 1
        groups = np.split(np.argsort(labels, kind="stable"),
                          np.cumsum(np.bincount(labels, minlength=n0))[:-1])
        R0 = sp.csr_matrix((np.ones(ns), (labels, np.arange(ns))), shape=(n0, ns))
        self.B = _zero_sum_blocks(S, groups, labels)
        self.S0 = coarse_matrix(S, groups, labels)
        self._S0 = factorize(self.S0, kind="spd", backend="dense").solve
        self.R0 = R0
        U = (M.T @ R0.T).tocsc()
        W = _SHIFT / np.diag(self.S0)
        A = (K + M.T @ self.B @ M + U @ sp.diags(W) @ U.T).tocsr()
        self._A = factorize(A, kind="spd", dense_limit=400).solve
        self._AU = self._A(U.toarray())
        X = np.linalg.inv(self._S0(np.eye(n0)) - np.diag(W))
        self._core = np.linalg.inv(X + U.T @ self._AU)
        self._U = U

    def heat(self, r) -> np.ndarray:
        """``P_S^-1 r`` [W] of potentials ``r`` (n_s,) [K]."""
        return self.B @ r + self.R0.T @ self._S0(self.R0 @ r)

    def rise(self, r) -> np.ndarray:
        """``P_T^-1 r`` [K] of heats ``r`` (n,) [W] (Woodbury)."""
        y = self._A(r)
        return y - self._AU @ (self._core @ (self._U.T @ y))


def _zero_sum_blocks(S, groups, labels) -> sp.csr_matrix:
    """Block-diagonal ``B`` (n_s, n_s): per patch the inverse of ``S`` on it restricted to heats
    of zero sum."""
    near = S.near.tocoo()
    inside = labels[near.row] == labels[near.col]
    row, col, data = near.row[inside], near.col[inside], near.data[inside]
    # each sub-triangle's place in its patch: the near entries (one per pair) added to the
    # dense blocks, found by patch in the entries sorted by it
    place = np.empty(S.n, np.int64)
    for g in groups:
        place[g] = np.arange(len(g))
    order = np.argsort(labels[row], kind="stable")
    row, col, data = row[order], col[order], data[order]
    start = np.searchsorted(labels[row], np.arange(len(groups) + 1))
    rows, cols, vals = [], [], []
    for ids, members in _batches(groups):
        k = members.shape[1]
        block = S.point_blocks(members)
        at = np.concatenate([np.arange(start[i], start[i + 1]) for i in ids])
        which = np.repeat(np.arange(len(ids)), start[ids + 1] - start[ids])
        block[which, place[row[at]], place[col[at]]] += data[at]
        inv = np.linalg.inv(block)
        u = inv.sum(axis=2)
        vals.append((inv - u[:, :, None] * u[:, None, :] / u.sum(axis=1)[:, None, None])
                    .ravel())
        rows.append(np.repeat(members, k, axis=1).ravel())
        cols.append(np.tile(members, (1, k)).ravel())
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(S.n, S.n))


def _batches(groups, limit: int = _BATCH):
    """The patches of one size together, at most ``limit`` at a time: ``(ids (b,), members
    (b, k))`` (patches by recursive bisection have at most two sizes)."""
    sizes = np.array([len(g) for g in groups])
    for k in np.unique(sizes):
        ids = np.flatnonzero(sizes == k)
        for part in np.array_split(ids, -(-len(ids) // limit)):
            yield part, np.array([groups[i] for i in part], np.int64).reshape(len(part), k)


def coarse_matrix(S, groups, labels=None) -> np.ndarray:
    """``R0 S R0^T`` (n0, n0) [K/W]: the sum over patch I's centroids of the potential of one
    watt on each of patch J's sub-triangles; the near-field part exact (sparse), the centroid
    rule's by monopoles between far patch pairs and exact sums between near ones (see the
    module notes)."""
    n0 = len(groups)
    if labels is None:
        labels = np.empty(S.n, np.int64)
        for k, g in enumerate(groups):
            labels[g] = k
    c = S.centroids
    count = np.array([len(g) for g in groups], float)
    centre = np.array([c[g].mean(axis=0) for g in groups])
    radius = np.array([np.linalg.norm(c[g] - m, axis=1).max() for g, m in zip(groups, centre)])
    d = np.linalg.norm(centre[:, None] - centre[None], axis=2)
    with np.errstate(divide="ignore"):
        out = S.scale * np.outer(count, count) / d
    if S.plane is not None:
        img = mirror(centre, S.plane)
        out -= S.scale * np.outer(count, count) / np.linalg.norm(
            centre[:, None] - img[None], axis=2)
    near = d < COARSE_NEAR * (radius[:, None] + radius[None])
    I, J = np.nonzero(np.triu(near))
    size = np.array([len(g) for g in groups])
    for k, l in {(int(size[i]), int(size[j])) for i, j in zip(I, J)}:   # pairs by sizes
        which = np.flatnonzero((size[I] == k) & (size[J] == l))
        for part in np.array_split(which, -(-len(which) // _BATCH)):
            a = np.array([groups[i] for i in I[part]], np.int64).reshape(len(part), k)
            b = np.array([groups[j] for j in J[part]], np.int64).reshape(len(part), l)
            total = S.point_blocks(a, b).sum(axis=(1, 2))
            out[I[part], J[part]] = total
            out[J[part], I[part]] = total
    R0 = sp.csr_matrix((np.ones(S.n), (labels, np.arange(S.n))), shape=(n0, S.n))
    out += (R0 @ S.near @ R0.T).toarray()
    return 0.5 * (out + out.T)

