"""The sparse rungs of the factorisation ladder and its acceptance rule: PARDISO, SuperLU in
nested-dissection order, and the backward-error test (:func:`accurate`, :func:`refined`).

Which rung solves which system is decided in one place, :mod:`simulator.linalg.ladder`
(thresholds in :mod:`simulator.linalg.thresholds`). When MKL is installed, sparse symmetric
systems are solved by PARDISO (:func:`pardiso_solve`, :mod:`simulator.linalg.pardiso`), whose
analysis is kept per sparsity pattern like the METIS ordering below; it is 3-6x faster than
SuperLU at every size measured. The rest of this module is the SuperLU path, without MKL or if
PARDISO fails.

SuperLU's minimum-degree orderings make a fill that grows fast on large 2-D sheet meshes
(1e5 nodes: 34e6 entries in L, 19 GFlop). METIS nested dissection on the graph of the
mesh nodes cuts that to 28e6 entries and 12 GFlop, and the factorisation time by 1.5-2x;
the ordering depends on the sparsity pattern only, so it is computed once per pattern
(:func:`ordering_for` keeps the last few) and every later matrix of that pattern is permuted
by a cached index map. The free DOFs of one node have identical rows; they are grouped into
one graph vertex (weighted by their count), which keeps them together in the ordering
(an ordering of the DOF graph itself is 20x worse).

A direct factorisation of a 2-D mesh still costs O(n^1.5) flops: the ordering lowers the
constant, not the exponent. Smoothed-aggregation AMG with Krylov iterations was measured
and rejected: on bar-and-hinge tangents (stiff bars, soft hinges, indefinite at the
benchmark states) it needs ~200 GMRES iterations at 3e3 DOFs (50x the direct solve) and
over 1100 (minutes) at 3e4.

A solution is accepted when its residual is small, ``|K x - r| <= rtol |r|``, or, for
ill-conditioned tangents where no double-precision solution can reach that, when its
componentwise backward error is at round-off level (:func:`accurate`). On a partly folded
1e5-node sheet |K| |x| is 5e10 |r|: a residual of 1e-6 |r| is below the round-off of the
product ``K x`` itself, and rejecting the (backward-stable, error 1e-14) solution sent one
Newton iteration in ten to a partial-pivoting factorisation 15x slower and no more exact.

Kept factors as preconditioners for the *next* Newton iterations (GMRES, refactorising when
it needs a factorisation's worth of iterations) were measured and rejected: on a folding
Miura sheet the tangent changes so much between iterations (soft hinges, geometric
stiffness) that the old factors need 13-40 GMRES iterations, about the cost of a new
factorisation, at 3e4 and 3e5 unknowns alike; inexact solves (Eisenstat-Walker forcing)
doubled the Newton iterations.

Without ``pymetis`` (or for a matrix it cannot order) :func:`ordering_for` returns None
and callers keep SuperLU's own ordering.
"""

from __future__ import annotations

import logging
import math
import threading
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from . import pardiso

__all__ = ["NestedDissection", "ordering_for", "nested_dissection_ordering",
           "nested_dissection_solve", "nd_factors", "PermutedLU", "supervariables", "accurate",
           "backward_error", "refined", "BACKWARD_ERROR_TOL", "pardiso_solve", "pardiso_handle",
           "solves_ones"]

logger = logging.getLogger(__name__)

#: How many sparsity patterns keep their ordering (one per model in use, typically).
_CACHE_SIZE = 4

#: Componentwise backward error up to which :func:`accurate` accepts a solution whose
#: residual is not small (a backward-stable solve gives ~1e-16 to 1e-14).
BACKWARD_ERROR_TOL = 1e-12


def supervariables(indptr: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Group index (n,) of each row: consecutive rows with the same columns share a group.

    For a stiffness matrix these are the free DOFs of one node. Rows are compared by
    length, first and last column and column sum, which is exact for the block patterns of
    element assembly; a wrong grouping would only worsen the ordering, never the solution.
    """
    n = len(indptr) - 1
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    lengths = np.diff(indptr)
    nonempty = lengths > 0
    start = np.minimum(indptr[:-1], max(len(indices) - 1, 0))
    first = np.where(nonempty, indices[start], -1) if len(indices) else np.full(n, -1)
    last = np.where(nonempty, indices[np.maximum(indptr[1:] - 1, 0)], -1) \
        if len(indices) else np.full(n, -1)
    csum = np.concatenate([[0], np.cumsum(indices, dtype=np.int64)])
    sums = csum[indptr[1:]] - csum[indptr[:-1]]
    same = ((lengths[1:] == lengths[:-1]) & (first[1:] == first[:-1])
            & (last[1:] == last[:-1]) & (sums[1:] == sums[:-1]) & nonempty[1:])
    return np.concatenate([[0], np.cumsum(~same)])


def nested_dissection_ordering(indptr: np.ndarray, indices: np.ndarray) -> np.ndarray | None:
    """METIS nested-dissection permutation (n,) of a symmetric CSR pattern, or None.

    Rows are grouped by :func:`supervariables`; the group graph (weighted by group size) is
    ordered and the rows of a group stay together in it. ``A[perm][:, perm]`` is the
    reordered matrix. None when ``pymetis`` is not installed.
    """
    try:
        import pymetis
    except ImportError:                       # optional at run time: keep SuperLU's ordering
        logger.info("pymetis is not installed: no nested-dissection ordering")
        return None
    n = len(indptr) - 1
    group = supervariables(indptr, indices)
    n_groups = int(group[-1]) + 1 if n else 0
    if n_groups < 2:
        return np.arange(n)
    first_row = np.flatnonzero(np.concatenate([[True], group[1:] != group[:-1]]))
    # the group graph from the first row of every group (the others have the same columns)
    lengths = np.diff(indptr)[first_row]
    src = np.repeat(np.arange(n_groups), lengths)
    dst = group[_gather_rows(indptr, indices, first_row, lengths)]
    off = src != dst
    G = sp.csr_matrix((np.ones(int(off.sum()), dtype=np.int32), (src[off], dst[off])),
                      shape=(n_groups, n_groups))
    G = (G + G.T).tocsr()                     # METIS needs a symmetric graph
    xadj, adjncy = G.indptr.astype(np.int32), G.indices.astype(np.int32)
    weights = np.bincount(group).astype(np.int32)
    perm = pymetis.nested_dissection(pymetis.CSRAdjacency(xadj, adjncy), vweights=weights)[0]
    rank = np.empty(n_groups, dtype=np.int64)
    rank[np.asarray(perm)] = np.arange(n_groups)
    return np.argsort(rank[group], kind="stable")


def _gather_rows(indptr, indices, rows, lengths):
    """The column indices of the given CSR rows, concatenated."""
    start = np.repeat(indptr[rows] - np.concatenate([[0], np.cumsum(lengths)[:-1]]), lengths)
    return indices[start + np.arange(int(lengths.sum()))]


@dataclass(frozen=True, eq=False)
class NestedDissection:
    """A fill-reducing permutation of one sparsity pattern and the index map that applies it.

    Attributes
    ----------
    perm : (n,) permutation: row ``i`` of the reordered matrix is row ``perm[i]``
    indptr, indices : CSC structure of the reordered matrix
    data_map : (nnz,) position in the original CSR data of every reordered entry
    """

    perm: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    data_map: np.ndarray

    @classmethod
    def of(cls, indptr, indices) -> NestedDissection | None:
        """The ordering of a canonical CSR pattern, or None (see
        :func:`nested_dissection_ordering`)."""
        perm = nested_dissection_ordering(indptr, indices)
        if perm is None:
            return None
        n = len(indptr) - 1
        position = sp.csr_matrix((np.arange(1, len(indices) + 1, dtype=np.int64), indices, indptr),
                                 shape=(n, n))
        reordered = position[perm][:, perm].tocsc()
        reordered.sort_indices()
        return cls(perm, reordered.indptr, reordered.indices, reordered.data - 1)

    def factorize(self, K) -> PermutedLU:
        """SuperLU factors of the reordered ``K`` (of this pattern) in symmetric mode: no
        column reordering, diagonal pivots (raises RuntimeError on an exactly zero pivot)."""
        if K.format != "csr":
            K = K.tocsr()
        if K.shape != (len(self.perm),) * 2 or K.nnz != len(self.data_map):
            raise ValueError(f"matrix {K.shape} with {K.nnz} entries is not of this pattern")
        A = sp.csc_matrix((K.data[self.data_map], self.indices, self.indptr), shape=K.shape)
        import scipy.sparse.linalg as spla

        return PermutedLU(spla.splu(A, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                                    options={"SymmetricMode": True}), self.perm)


@dataclass(frozen=True, eq=False)
class PermutedLU:
    """SuperLU factors ``lu`` of ``K[perm][:, perm]``, solving with ``K`` itself."""

    lu: object          # scipy.sparse.linalg.SuperLU (scipy imported lazily)
    perm: np.ndarray

    def solve(self, r: np.ndarray) -> np.ndarray:
        """``K^-1 r`` for r (n,) or (n, k)."""
        y = self.lu.solve(np.asarray(r)[self.perm])
        x = np.empty_like(y)
        x[self.perm] = y
        return x


_UNSET = object()


@dataclass(eq=False)
class _Pattern:
    """A cached sparsity pattern: its METIS ordering and its PARDISO analysis, each made on
    first use (None / False: not available for this pattern)."""

    indptr: np.ndarray
    indices: np.ndarray
    nd: object = _UNSET                  # NestedDissection | None
    pardiso: object = _UNSET             # PardisoLDLT | False


_cache: list[_Pattern] = []
_lock = threading.Lock()


def _same_array(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether ``a`` and ``b`` are one array, or both the whole of one array (scipy's CSR
    constructor keeps ``indices[:nnz]``, a new view each time): the same numbers, known
    without comparing them (as by identity: the array is taken not to change in place)."""
    if a is b:
        return True
    base = a if a.base is None else a.base
    return (base is (b if b.base is None else b.base) and isinstance(base, np.ndarray)
            and a.shape == b.shape == base.shape and a.strides == b.strides == base.strides
            and a.dtype == b.dtype == base.dtype)


def _pattern_of(K) -> _Pattern | None:
    """The cache entry of the pattern of a square sparse ``K`` (made on first use), or None
    for a matrix without canonical format. The last few patterns are kept, matched by their
    index arrays (one array or whole views of one, :func:`_same_array`; else equal ones:
    ~5 ms at 1e5 nodes)."""
    if not sp.issparse(K) or K.format != "csr":
        K = sp.csr_matrix(K)
    if not K.has_canonical_format:
        return None
    indptr, indices = K.indptr, K.indices
    with _lock:
        for i, entry in enumerate(_cache):
            ip, ind = entry.indptr, entry.indices
            if (_same_array(ip, indptr) and _same_array(ind, indices)) or (
                    len(ip) == len(indptr) and len(ind) == len(indices)
                    and np.array_equal(ip, indptr) and np.array_equal(ind, indices)):
                _cache.insert(0, _cache.pop(i))
                return entry
        entry = _Pattern(indptr, indices)
        _cache.insert(0, entry)
        del _cache[_CACHE_SIZE:]
        return entry


def ordering_for(K) -> NestedDissection | None:
    """The cached :class:`NestedDissection` of the pattern of a square sparse ``K``, or None.

    Computed once per pattern (see :func:`_pattern_of`), not at every Newton iteration.
    """
    entry = _pattern_of(K)
    if entry is None:
        return None
    if entry.nd is _UNSET:
        try:
            with warnings.catch_warnings():      # an ordering only changes the speed
                warnings.simplefilter("ignore")
                entry.nd = NestedDissection.of(entry.indptr, entry.indices)
        except Exception as exc:  # noqa: BLE001 - an accelerator: SuperLU's own ordering instead
            logger.warning("no nested-dissection ordering (%s: %s); using SuperLU's",
                           type(exc).__name__, exc)
            entry.nd = None
        logger.debug("nested-dissection ordering of a %d x %d pattern", *K.shape)
    return entry.nd


def pardiso_handle(K):
    """The PARDISO analysis of the pattern of ``K`` (made on first use, cached with the
    pattern), or None when PARDISO is not available or cannot take the pattern."""
    if not pardiso.available():
        return None
    entry = _pattern_of(K)
    if entry is None:
        return None
    if entry.pardiso is _UNSET:
        try:
            entry.pardiso = pardiso.PardisoLDLT(entry.indptr, entry.indices)
            logger.debug("PARDISO analysis of a %d-row pattern", len(entry.indptr) - 1)
        except pardiso.PardisoError as exc:
            logger.warning("no PARDISO analysis (%s); using SuperLU", str(exc))
            entry.pardiso = False
    return entry.pardiso or None


def pardiso_solve(K, r: np.ndarray, rtol: float = 1e-6) -> np.ndarray | None:
    """``K^-1 r`` for a symmetric sparse ``K`` by PARDISO (:mod:`simulator.linalg.pardiso`), its
    analysis cached per pattern; None when PARDISO is not available, fails, or the solution
    is not :func:`accurate` even after :func:`refined`. ``r`` is (n,) or (n, k)."""
    if K.format != "csr":
        K = K.tocsr()
    handle = pardiso_handle(K)
    if handle is None:
        return None
    try:
        x, ok = handle.factor_solve(K, r, lambda solve, x: refined(K, solve, r, x, rtol))
    except pardiso.PardisoError as exc:
        logger.debug("PARDISO failed (%s)", str(exc))
        return None
    if not ok:
        logger.debug("PARDISO solve inaccurate (%d perturbed pivots)", handle.perturbed_pivots)
        return None
    return x


def nd_factors(K) -> PermutedLU | None:
    """Factors of ``K`` in its cached nested-dissection order, or None (no ordering, or an
    exactly zero pivot)."""
    nd = ordering_for(K)
    if nd is None:
        return None
    try:
        return nd.factorize(K)
    except RuntimeError:
        logger.debug("nested-dissection factorisation hit a zero pivot")
        return None


def nested_dissection_solve(K, r: np.ndarray, rtol: float = 1e-6) -> np.ndarray | None:
    """``K^-1 r`` for a symmetric sparse ``K`` by SuperLU in its cached METIS nested-dissection
    order; None when there is no ordering, a pivot is exactly zero or the solution is not
    :func:`accurate` even after :func:`refined` (the caller then takes another path).
    ``r`` is (n,) or (n, k)."""
    lu = nd_factors(K)
    if lu is None:
        return None
    x, ok = refined(K, lu.solve, r, lu.solve(r), rtol)
    if not ok:
        logger.debug("nested-dissection solve inaccurate (indefinite matrix?)")
        return None
    return x


def backward_error(K, x: np.ndarray, r: np.ndarray, residual=None) -> float:
    """Componentwise relative backward error of ``x`` as a solution of ``K x = r``:
    ``max_i |K x - r|_i / (|K| |x| + |r|)_i`` (Oettli-Prager; LAPACK's ``berr``), the smallest
    relative change of the entries of K and r for which x is exact. ``x`` and ``r`` are (n,)
    or (n, k); the largest over columns. Infinite for a non-finite x. ``residual``, if given,
    is ``K x - r`` already computed."""
    x = np.asarray(x)
    if not np.all(np.isfinite(x)):
        return math.inf
    res = np.abs(K @ x - r if residual is None else residual)
    scale = abs(K) @ np.abs(x) + np.abs(r)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(scale > 0, res / scale, np.where(res > 0, math.inf, 0.0))
    return float(q.max()) if q.size else 0.0


def accurate(K, x: np.ndarray, r: np.ndarray, rtol: float = 1e-6, residual=None) -> bool:
    """Whether ``x`` solves ``K x = r`` as well as the data allow: a small residual,
    ``|K x - r| <= rtol |r|`` (2-norm, per column), or a :func:`backward_error` of at most
    :data:`BACKWARD_ERROR_TOL` (for an ill-conditioned K, whose residual cannot be small in
    double precision). False for a non-finite x. ``residual``, if given, is ``K x - r``
    already computed."""
    x = np.asarray(x)
    if not np.all(np.isfinite(x)):
        return False
    residual = K @ x - r if residual is None else residual
    if np.all(np.linalg.norm(residual, axis=0) <= rtol * np.linalg.norm(r, axis=0)):
        return True
    return backward_error(K, x, r, residual) <= BACKWARD_ERROR_TOL


def refined(K, solve, r: np.ndarray, x: np.ndarray, rtol: float = 1e-6,
            steps: int = 3) -> tuple[np.ndarray, bool]:
    """``(x, ok)``: ``x`` improved by up to ``steps`` of iterative refinement with the factors
    that produced it (``x += solve(r - K x)``) until it is :func:`accurate`; ok when it is.
    One product ``K x`` per step serves both the test and the correction."""
    with np.errstate(all="ignore"):             # broken factors may overflow: then not ok
        for _ in range(steps + 1):
            if not np.all(np.isfinite(x)):
                break
            residual = K @ x - r
            if accurate(K, x, r, rtol, residual):
                return x, True
            x = x - solve(residual)
    return x, False


def solves_ones(A, solve, rtol: float) -> bool:
    """Whether factors (``solve(v)`` ~ ``A^-1 v``) kept for repeated solves are
    :func:`accurate` on a vector of ones: the check of each one before it is kept."""
    b = np.ones(A.shape[0])
    return accurate(A, solve(b), b, rtol)
