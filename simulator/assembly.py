"""Generic sparse assembly of element gradients and Hessians.

Element families give node connectivities ``(n_el, k)``; their kernels return
gradients ``(n_el, 3k)`` and Hessians ``(n_el, 3k, 3k)`` in node-major DOF
order. Vectors are assembled with ``np.bincount``; matrices on the free DOFs
with a CSR pattern computed once per topology (:class:`StiffnessPattern`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["element_dofs", "assemble_vector", "StiffnessPattern", "assemble_matrix"]


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
    """

    def __init__(self, dofs: list[np.ndarray], free_index: np.ndarray, diagonal=None):
        self.n_free = int(free_index.max()) + 1 if free_index.size else 0
        rows, cols = [], []
        for d in dofs:
            m = d.shape[1]
            rows.append(np.repeat(d, m, axis=1).ravel())
            cols.append(np.tile(d, (1, m)).ravel())
        if diagonal is not None:
            rows.append(np.asarray(diagonal))
            cols.append(np.asarray(diagonal))
        r = free_index[np.concatenate(rows)] if rows else np.zeros(0, int)
        c = free_index[np.concatenate(cols)] if cols else np.zeros(0, int)
        self.keep = (r >= 0) & (c >= 0)
        key = r[self.keep].astype(np.int64) * self.n_free + c[self.keep]
        uniq, self.scatter = np.unique(key, return_inverse=True)
        self.indices = (uniq % self.n_free).astype(np.int32)
        self.indptr = np.searchsorted(uniq // self.n_free, np.arange(self.n_free + 1)).astype(np.int32)
        self.nnz = len(uniq)
        # position in the CSR data of every Hessian entry (-1: fixed DOF), per family
        pos = np.full(len(self.keep), -1, dtype=np.int64)
        pos[self.keep] = self.scatter
        sizes = [d.size * d.shape[1] for d in dofs] + ([len(rows[-1])] if diagonal is not None
                                                      else [])
        split = np.split(pos, np.cumsum(sizes)[:-1]) if sizes else []
        self._family_pos = [p.reshape(len(d), -1) for p, d in zip(split, dofs)] + split[len(dofs):]
        self._rows = None                    # row of every stored entry (from_dense), lazily

    def from_dense(self, D: np.ndarray) -> sp.csr_matrix:
        """CSR matrix in this pattern with the entries of the dense (n_free, n_free) ``D``
        (which must be zero outside the pattern)."""
        if self._rows is None:
            self._rows = np.repeat(np.arange(self.n_free), np.diff(self.indptr))
        return sp.csr_matrix((D[self._rows, self.indices], self.indices, self.indptr),
                             shape=(self.n_free, self.n_free))

    def matrix(self, values: list[np.ndarray], subsets: dict | None = None) -> sp.csr_matrix:
        """CSR matrix from element Hessians (same order as the families) and diagonal terms.

        ``subsets[i]``, if given, lists the elements of family ``i`` that ``values[i]`` holds
        (the others are zero), e.g. the active pairs of a contact family.
        """
        if not subsets:
            flat = np.concatenate([v.ravel() for v in values])[self.keep]
            data = np.bincount(self.scatter, flat, minlength=self.nnz)
        else:
            pos = [self._family_pos[i][subsets[i]] if i in subsets else self._family_pos[i]
                   for i in range(len(values))]
            p = np.concatenate([q.ravel() for q in pos])
            v = np.concatenate([np.ravel(x) for x in values])
            k = p >= 0
            data = np.bincount(p[k], v[k], minlength=self.nnz)
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n_free, self.n_free))


def assemble_matrix(dofs: np.ndarray, hess: np.ndarray, free_index: np.ndarray,
                    n_free: int) -> sp.csr_matrix:
    """Free-DOF CSR matrix of one element family with a changing topology (e.g. contact)."""
    m = dofs.shape[1]
    r = free_index[np.repeat(dofs, m, axis=1).ravel()]
    c = free_index[np.tile(dofs, (1, m)).ravel()]
    keep = (r >= 0) & (c >= 0)
    return sp.csr_matrix((hess.ravel()[keep], (r[keep], c[keep])), shape=(n_free, n_free))
