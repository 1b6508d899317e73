"""Generic sparse assembly of element gradients and Hessians.

Element families give node connectivities ``(n_el, k)``; their kernels return
gradients ``(n_el, 3k)`` and Hessians ``(n_el, 3k, 3k)`` in node-major DOF
order. Vectors are assembled with ``np.bincount``; matrices on the free DOFs
with a CSR pattern computed once per topology (:class:`StiffnessPattern`).
:class:`FamilyAssembly` does both for a list of element families
(:mod:`simulator.mechanics.families`, docs/theory.md#310-element-families-and-assembly).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .._jit import compile_kernel, numba_selected

__all__ = ["element_dofs", "assemble_vector", "StiffnessPattern", "assemble_matrix",
           "FamilyAssembly", "scatter_numpy", "JIT_ENTRIES"]


#: Patterns with at least this many Hessian entries sum them with a compiled loop (numba): no
#: concatenated copy of the values, ~0.4 s less per evaluation of a 1e5-node sheet.
JIT_ENTRIES = 2_000_000

_loop = None                       # the compiled loop; False: not available


def element_dofs(conn: np.ndarray) -> np.ndarray:
    """Global DOF indices (n_el, 3k) of elements with node connectivity (n_el, k)."""
    conn = np.asarray(conn)
    return (3 * conn[:, :, None] + np.arange(3)).reshape(len(conn), -1)


def assemble_vector(n_dof: int, dofs: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Sum element vectors (n_el, m) into a global vector of length ``n_dof``."""
    return np.bincount(dofs.ravel(), values.ravel(), minlength=n_dof)


class StiffnessPattern:
    """Cached CSR structure of the free-DOF stiffness matrix for fixed element families.

    Parameters
    ----------
    dofs : list of (n_el, m) int arrays
        Global DOFs of each element family, in the order the Hessians will be given.
    free_index : (n_dof,) int array
        Reduced index of every DOF, -1 for fixed (eliminated) DOFs.
    diagonal : (n_diag,) int array, optional
        Extra global DOFs receiving diagonal terms (elastic supports), given last.

    Element DOFs in node blocks (:func:`element_dofs`) with free DOFs numbered in order are
    assembled by node pairs (:func:`_block_positions`: 9x fewer keys to sort than DOF pairs,
    ~1/3 of the memory on a 1e5-node sheet); any other input takes the DOF-pair reference
    (:func:`_reference_positions`). Both give the same matrix.
    """

    def __init__(self, dofs: list[np.ndarray], free_index: np.ndarray, diagonal=None):
        self.n_free = int(free_index.max()) + 1 if free_index.size else 0
        dofs = [np.asarray(d) for d in dofs]
        diagonal = None if diagonal is None else np.asarray(diagonal, dtype=np.int64)
        found = _block_positions(dofs, free_index, diagonal, self.n_free)
        if found is None:
            found = _reference_positions(dofs, free_index, diagonal, self.n_free)
        self.indptr, self.indices, flat = found
        self.nnz = len(self.indices)
        #: position in the CSR data of every Hessian entry, families then diagonal terms, in
        #: the order of the values given to :meth:`matrix`; ``nnz`` (one bin past the data)
        #: for entries on fixed DOFs
        self.positions = flat
        sizes = [d.size * d.shape[1] for d in dofs] + ([len(diagonal)] if diagonal is not None
                                                      else [])
        split = np.split(flat, np.cumsum(sizes)[:-1]) if sizes else []
        self._family_pos = [p.reshape(len(d), -1) for p, d in zip(split, dofs)] + split[len(dofs):]
        self._flat = None              # position of every stored entry in a dense matrix

    def from_dense(self, D: np.ndarray) -> sp.csr_matrix:
        """CSR matrix in this pattern with the entries of the dense (n_free, n_free) ``D``
        (which must be zero outside the pattern)."""
        return sp.csr_matrix((D.reshape(-1)[self.dense_positions()], self.indices, self.indptr),
                             shape=(self.n_free, self.n_free))

    def dense_positions(self) -> np.ndarray:
        """Flat position ``row * n_free + column`` of every stored entry in a dense
        (n_free, n_free) matrix, in CSR order (computed once)."""
        if self._flat is None:
            rows = np.repeat(np.arange(self.n_free), np.diff(self.indptr))
            self._flat = rows * self.n_free + self.indices
        return self._flat

    def matrix(self, values: list[np.ndarray], subsets: dict | None = None) -> sp.csr_matrix:
        """CSR matrix from element Hessians (same order as the families) and diagonal terms.

        ``subsets[i]``, if given, lists the elements of family ``i`` that ``values[i]`` holds
        (the others are zero), e.g. the active pairs of a contact family.
        """
        if not subsets:
            scatter = _scatter_compiled() if len(self.positions) >= JIT_ENTRIES else None
            data = (scatter_numpy(self.positions, values, self.nnz) if scatter is None
                    else scatter(self.positions, values, self.nnz))
        else:
            pos = [self._family_pos[i][subsets[i]] if i in subsets else self._family_pos[i]
                   for i in range(len(values))]
            data = scatter_numpy(np.concatenate([q.ravel() for q in pos]), values, self.nnz)
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n_free, self.n_free))


def scatter_numpy(positions: np.ndarray, values: list, nnz: int) -> np.ndarray:
    """CSR data (nnz,): the sum of every value at its position (``nnz``: dropped), in the order
    given. The reference of the compiled loop."""
    v = np.concatenate([np.ravel(x) for x in values])
    return np.bincount(positions, v, minlength=nnz + 1)[:nnz]


def _scatter_loop(data, positions, values):
    for i in range(values.size):
        data[positions[i]] += values[i]


def _build_scatter():
    from numba import njit

    return njit("void(float64[::1], int64[::1], float64[::1])", cache=True)(_scatter_loop)


def _scatter_compiled():
    """The compiled :func:`scatter_numpy` (the same sums in the same order, without the
    concatenated copy of the values), or None unless the "numba" backend is in force
    (:func:`~simulator.mechanics.elements.springs.spring_kernel_backend`, ``ETORIGAMI_JIT``)."""
    global _loop
    if not numba_selected():
        return None
    if _loop is None:
        _loop = compile_kernel("scatter loop", _build_scatter, "using numpy") or False
    if not _loop:
        return None

    def scatter(positions, values, nnz):
        data, at = np.zeros(nnz + 1), 0
        for x in values:
            x = np.ascontiguousarray(np.ravel(x), dtype=float)
            _loop(data, positions[at:at + x.size], x)
            at += x.size
        return data[:nnz]
    return scatter


def _reference_positions(dofs, free_index, diagonal, n_free):
    """CSR ``indptr``, ``indices`` (int32) and the data position of every Hessian entry
    (``nnz`` on fixed DOFs) from the sorted unique DOF pairs of all entries."""
    rows, cols = [], []
    for d in dofs:
        m = d.shape[1]
        rows.append(np.repeat(d, m, axis=1).ravel())
        cols.append(np.tile(d, (1, m)).ravel())
    if diagonal is not None:
        rows.append(diagonal)
        cols.append(diagonal)
    r = free_index[np.concatenate(rows)] if rows else np.zeros(0, int)
    c = free_index[np.concatenate(cols)] if cols else np.zeros(0, int)
    keep = (r >= 0) & (c >= 0)
    key = r[keep].astype(np.int64) * n_free + c[keep]
    uniq, scatter = np.unique(key, return_inverse=True)
    indices = (uniq % n_free).astype(np.int32)
    indptr = np.searchsorted(uniq // n_free, np.arange(n_free + 1)).astype(np.int32)
    flat = np.full(len(keep), len(uniq), dtype=np.int64)
    flat[keep] = scatter
    return indptr, indices, flat


def _block_positions(dofs, free_index, diagonal, n_free, block=3, chunk=50_000):
    """:func:`_reference_positions` from node pairs, or None unless every family lists whole
    node blocks ``block * node + (0, 1, 2)``, every diagonal DOF lies in a node of some
    element and the free DOFs are numbered in order (then a node pair's entries are its
    ``block x block`` free DOF pairs)."""
    n_dof = len(free_index)
    fi = np.asarray(free_index, dtype=np.int64)
    free_dofs = np.flatnonzero(fi >= 0)
    if (n_dof % block or not dofs or not np.array_equal(fi[free_dofs], np.arange(len(free_dofs)))
            or any(d.ndim != 2 or d.shape[1] % block for d in dofs)):
        return None
    nodes = [d[:, ::block] // block for d in dofs]
    if any(not np.array_equal(d.reshape(len(d), -1, block),
                              block * nd[:, :, None] + np.arange(block)) for d, nd in zip(dofs, nodes)):
        return None
    n_blocks = n_dof // block
    if diagonal is not None and len(diagonal):
        used = np.zeros(n_blocks, bool)
        for nd in nodes:
            used[nd.ravel()] = True
        if not used[diagonal // block].all():
            return None
    keys = [(nd[:, :, None].astype(np.int64) * n_blocks + nd[:, None, :]).ravel() for nd in nodes]
    if diagonal is not None:
        keys.append((diagonal // block) * (n_blocks + 1))
    pairs, inverse = np.unique(np.concatenate(keys), return_inverse=True)
    a, b = pairs // n_blocks, pairs % n_blocks
    is_free = (fi >= 0).reshape(n_blocks, block)
    width = is_free.sum(axis=1)[b]                    # free DOFs of the column node of a pair
    before = np.cumsum(width) - width
    offset = before - before[np.searchsorted(a, a)]   # columns before the pair in its row
    row_len = np.bincount(a, width, minlength=n_blocks).astype(np.int64)
    indptr = np.concatenate([[0], np.cumsum(row_len[free_dofs // block])])
    # row of a node: the free DOFs of its column nodes, in order; every free DOF of the node
    # repeats that row
    columns = np.repeat(b * block, width) + np.flatnonzero(is_free[b].ravel()) % block
    segment = np.searchsorted(a, np.arange(n_blocks))
    seg_of_row = np.repeat(before[np.minimum(segment, len(before) - 1)][free_dofs // block]
                           - indptr[:-1], np.diff(indptr))
    indices = fi[columns[seg_of_row + np.arange(indptr[-1])]].astype(np.int32)
    nnz = len(indices)
    row_start = np.where(fi >= 0, indptr[np.maximum(fi, 0)], -1)
    col_off = np.where(is_free, np.cumsum(is_free, axis=1) - 1, -1).ravel()
    total = sum(d.size * d.shape[1] for d in dofs) + (0 if diagonal is None else len(diagonal))
    flat, at = np.empty(total, dtype=np.int64), 0
    cut = np.cumsum([0] + [len(k) for k in keys])
    for f, (d, nd) in enumerate(zip(dofs, nodes)):
        k = nd.shape[1]
        inv = inverse[cut[f]:cut[f + 1]].reshape(len(d), k, k)
        for lo in range(0, len(d), chunk):
            dd, c = d[lo:lo + chunk], inv[lo:lo + chunk]
            rs = row_start[dd].reshape(len(dd), k, block, 1, 1)
            co = col_off[dd].reshape(len(dd), 1, 1, k, block)
            pos = rs + offset[c].reshape(len(dd), k, 1, k, 1) + co
            pos[(rs < 0) | (co < 0)] = nnz
            flat[at:at + pos.size] = pos.ravel()
            at += pos.size
    if diagonal is not None:
        inv = inverse[cut[-2]:]
        ok = fi[diagonal] >= 0
        flat[at:] = np.where(ok, row_start[diagonal] + offset[inv] + col_off[diagonal], nnz)
    return indptr.astype(np.int32), indices, flat


def assemble_matrix(dofs: np.ndarray, hess: np.ndarray, free_index: np.ndarray,
                    n_free: int) -> sp.csr_matrix:
    """Free-DOF CSR matrix of one element family with a changing topology (e.g. contact)."""
    m = dofs.shape[1]
    r = free_index[np.repeat(dofs, m, axis=1).ravel()]
    c = free_index[np.tile(dofs, (1, m)).ravel()]
    keep = (r >= 0) & (c >= 0)
    return sp.csr_matrix((hess.ravel()[keep], (r[keep], c[keep])), shape=(n_free, n_free))


class FamilyAssembly:
    """One generic assembly for a list of element families
    (:class:`~simulator.mechanics.families.ElementFamily`).

    Parameters
    ----------
    families : sequence of element families, in summation order
    free_index : (n_dof,) int array
        Reduced index of every DOF, -1 for fixed DOFs.

    The cached :attr:`pattern` holds the DOFs of every family that gives them: families of
    node elements in their order, then the one-DOF families as its diagonal terms. Changing
    families without DOFs (contact on large meshes) are assembled apart at every evaluation
    and added. Forces are summed family by family in the given order.
    """

    def __init__(self, families, free_index: np.ndarray):
        self.families = tuple(families)
        self.free_index = free_index
        self.n_dof = len(free_index)
        self.n_free = int(free_index.max()) + 1 if free_index.size else 0

    @cached_property
    def _layout(self) -> tuple:
        """Indices of the families in the pattern (node elements), on its diagonal (one DOF
        per element) and assembled apart (no DOFs), found on first use."""
        dofs = [f.dofs for f in self.families]
        given = [i for i, d in enumerate(dofs) if d is not None]
        return ([i for i in given if dofs[i].shape[1] != 1],
                [i for i in given if dofs[i].shape[1] == 1],
                [i for i, d in enumerate(dofs) if d is None])

    @cached_property
    def pattern(self) -> StiffnessPattern:
        """CSR pattern of the free-DOF tangent (built on first use)."""
        blocks, diagonal, _ = self._layout
        diag = None
        if diagonal:
            diag = np.concatenate([self.families[i].dofs[:, 0] for i in diagonal])
        return StiffnessPattern([self.families[i].dofs for i in blocks], self.free_index,
                                diagonal=diag)

    def _dofs(self, i: int, v) -> np.ndarray:
        if v.dofs is not None:
            return v.dofs
        d = self.families[i].dofs
        return d if v.elements is None else d[v.elements]

    def vector(self, values: list) -> np.ndarray:
        """Internal force (n_dof,) [N]: the gradients of ``values`` (one
        :class:`~simulator.mechanics.families.FamilyValues` per family) summed family by family."""
        f = None
        for i, v in enumerate(values):
            if f is not None and not len(v.grad):
                continue
            g = assemble_vector(self.n_dof, self._dofs(i, v), v.grad)
            if f is None:
                f = g
            else:
                f += g
        return np.zeros(self.n_dof) if f is None else f

    def energies(self, values: list, kinds=()) -> dict:
        """Energy per kind [J]: ``kinds`` first (zero unless a family gives them), then any
        other kind of the families; families with several kinds split by their labels."""
        out = dict.fromkeys(kinds, 0.0)
        for fam, v in zip(self.families, values):
            names = fam.energy_kinds
            if len(names) == 1:
                parts = (v.energy.sum() if len(v.energy) else 0.0,)
            else:
                labels = fam.labels if v.elements is None else fam.labels[v.elements]
                parts = np.bincount(labels, v.energy, minlength=len(names))
            for name, e in zip(names, parts):
                out[name] = out.get(name, 0.0) + float(e)
        return out

    def matrix(self, values: list) -> sp.csr_matrix:
        """Free-DOF CSR tangent [N/m] from the Hessians of ``values`` (one FamilyValues per
        family, or None for a family that adds nothing this time)."""
        blocks, diagonal, apart = self._layout
        hess, subsets = [], {}
        for i in blocks:
            v = values[i]
            if v is None or v.hess is None:          # no element: an empty subset
                m = self.families[i].dofs.shape[1]
                subsets[len(hess)] = np.zeros(0, dtype=int)
                hess.append(np.zeros((0, m, m)))
                continue
            if v.elements is not None:
                subsets[len(hess)] = v.elements
            hess.append(v.hess)
        if diagonal:
            diag = [np.zeros(len(self.families[i].dofs)) if values[i] is None
                    or values[i].hess is None else values[i].hess for i in diagonal]
            hess.append(diag[0] if len(diag) == 1 else np.concatenate([np.ravel(d) for d in diag]))
        K = self.pattern.matrix(hess, subsets or None)
        for i in apart:
            v = values[i]
            if v is not None and v.hess is not None and len(v.hess):
                K = K + assemble_matrix(v.dofs, v.hess, self.free_index, self.n_free)
        return K

