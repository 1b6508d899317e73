"""Intel MKL PARDISO for large symmetric tangents: an optional, faster direct solver.

PARDISO factorises a symmetric indefinite matrix as L D L^T (supernodal, BLAS-3, threaded,
Bunch-Kaufman pivoting inside supernodes, METIS nested-dissection ordering). On Miura
sheet tangents it is 5-6x faster than SuperLU in nested-dissection order: 0.55-0.7 s
instead of 3.4 s at 3e5 unknowns (1e5 nodes), 0.045 s instead of 0.14 s at 3e4.

The ordering and symbolic factorisation (PARDISO's phase 11) depend on the sparsity pattern
only: :class:`PardisoLDLT` does them once per pattern; every matrix of the pattern then
costs a numeric factorisation (phase 22) and a solve (phase 33). PARDISO keeps its factors
inside its handle, so one handle serves one factorise-and-solve at a time (a lock), and the
factors are not kept for later solves (callers that need that use SuperLU's).

MKL comes with ``pip install etorigami[mkl]`` (the ``mkl`` wheel: Linux and Windows on
x86-64); its runtime library is loaded by ctypes on the first large solve (~0.1 s), found
next to this Python (see :func:`_mkl_candidates`; ``ETORIGAMI_MKL_RT`` names it
explicitly). Without it, or with ``ETORIGAMI_PARDISO=0`` in the environment,
:func:`available` is False and large systems use SuperLU (:mod:`simulator.linalg.linsolve`).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import glob
import logging
import os
import site
import sys
import threading
import weakref

import numpy as np
import scipy.sparse as sp

from .. import _jit
from . import dense_lapack

__all__ = ["available", "PardisoLDLT", "PardisoFactor", "PardisoError"]

logger = logging.getLogger(__name__)

_REAL_SYMMETRIC_INDEFINITE = -2
_library = None                       # (pardiso function,) once looked up; () if unavailable
_library_lock = threading.Lock()


class PardisoError(RuntimeError):
    """PARDISO returned an error code (the caller falls back to SuperLU)."""


def _pardiso():
    """The ctypes ``pardiso`` function of MKL, or None (not installed, or disabled)."""
    global _library
    with _library_lock:
        if _library is None:
            _library = _load()
        return _library[0] if _library else None


def _load() -> tuple:
    if not _jit.environment().pardiso:
        logger.info("PARDISO disabled by ETORIGAMI_PARDISO")
        return ()
    lib = None
    for path in _mkl_candidates():
        try:
            lib = ctypes.CDLL(path)
            break
        except OSError as exc:
            logger.debug("cannot load %s: %s", path, exc)
    if lib is None or not hasattr(lib, "pardiso"):
        logger.info("no MKL PARDISO found; large systems use SuperLU. "
                    "pip install 'etorigami[mkl]' for 5x faster solves of large models")
        return ()
    f = lib.pardiso
    i32, p = ctypes.c_int32, ctypes.POINTER
    f.argtypes = [p(ctypes.c_int64), p(i32), p(i32), p(i32), p(i32), p(i32), ctypes.c_void_p,
                  p(i32), p(i32), p(i32), p(i32), p(i32), p(i32), ctypes.c_void_p,
                  ctypes.c_void_p, p(i32)]
    f.restype = None
    logger.debug("PARDISO from %s", path)
    dense_lapack.rescan()                  # MKL is a BLAS too: limit it with the others
    return (f,)


def _mkl_candidates() -> list[str]:
    """Paths of MKL's runtime library to try, most likely first: ``ETORIGAMI_MKL_RT``, then
    the ``lib`` (``Library/bin`` on Windows) folders of this Python and of the user site,
    where the ``mkl`` wheel puts it, then the system's library search."""
    override = _jit.environment().mkl_rt
    if override:
        return [override]
    names = ("mkl_rt*.dll",) if sys.platform == "win32" else ("libmkl_rt.so*", "libmkl_rt*.dylib")
    found = []
    for base in dict.fromkeys([sys.prefix, sys.base_prefix, site.USER_BASE or ""]):
        for folder in ("lib", os.path.join("Library", "bin")):
            for name in names:
                found += sorted(glob.glob(os.path.join(base, folder, name)), key=len)
    system = ctypes.util.find_library("mkl_rt")
    return found + ([system] if system else [])


def available() -> bool:
    """Whether PARDISO can be used (MKL installed and found, not disabled)."""
    return _pardiso() is not None


class PardisoLDLT:
    """PARDISO's analysis of one symmetric sparsity pattern, and factorise-and-solve of its
    matrices.

    Parameters
    ----------
    indptr, indices : a canonical CSR pattern (sorted, no duplicates) of a symmetric matrix
    """

    def __init__(self, indptr: np.ndarray, indices: np.ndarray):
        f = _pardiso()
        if f is None:
            raise PardisoError("PARDISO is not available")
        n = len(indptr) - 1
        rows = np.repeat(np.arange(n), np.diff(indptr))
        upper = np.flatnonzero(indices >= rows)          # the upper triangle, row by row
        if len(np.unique(rows[indices == rows])) != n:
            raise PardisoError("a diagonal entry is missing from the pattern")
        self.n, self.nnz = n, len(indices)
        self.upper = upper
        self.ia = np.concatenate([[0], np.cumsum(np.bincount(rows[upper], minlength=n))]
                                 ).astype(np.int32)
        self.ja = indices[upper].astype(np.int32)
        self.pt = np.zeros(64, dtype=np.int64)          # PARDISO's handle
        self.iparm = np.zeros(64, dtype=np.int32)
        self.iparm[0] = 1      # these settings, not the defaults
        self.iparm[1] = 2      # METIS nested dissection
        self.iparm[7] = 0      # no iterative refinement inside (the caller refines if needed)
        self.iparm[9] = 8      # perturb pivots below 1e-8 |A| (the default for this type)
        self.iparm[20] = 1     # Bunch-Kaufman 1x1 and 2x2 pivots
        self.iparm[34] = 1     # zero-based indices
        self._lock = threading.Lock()
        self._owner = None                # the PardisoFactor whose matrix is factorised now
        self._f = f
        self._fixed = _fixed_arguments(self.pt, self.iparm, n, self.ia, self.ja)
        # PARDISO's memory is freed with this object (and if the analysis fails)
        weakref.finalize(self, _release, f, self.pt, self.iparm, n, self.ia, self.ja)
        self._call(11, np.zeros(len(upper)))              # ordering + symbolic factorisation

    def _call(self, phase: int, data: np.ndarray, b: np.ndarray | None = None,
              x: np.ndarray | None = None) -> None:
        error = _invoke(self._f, self.pt, self.iparm, phase, self.n, data, self.ia, self.ja, b, x,
                        self._fixed)
        if error != 0:
            raise PardisoError(f"PARDISO phase {phase} returned error {error}")

    def factor_solve(self, K: sp.csr_matrix, r: np.ndarray, refine=None) -> np.ndarray:
        """Factorise ``K`` (of this pattern, CSR) and return ``K^-1 r`` (r (n,) or (n, k)).

        ``refine(solve, x)``, if given, runs while the factors are held (``solve(v)`` applies
        them) and its result is returned instead of x. Raises :class:`PardisoError`.
        """
        data = self._data_of(K)
        with self._lock:
            self._call(22, data)                           # numeric factorisation
            self._owner = None                             # no factor object holds these

            def solve(v):
                return self._solve_locked(data, v)
            x = solve(r)
            return x if refine is None else refine(solve, x)

    def factorize(self, K: sp.csr_matrix) -> PardisoFactor:
        """Factors of ``K`` (of this pattern, CSR) for repeated solves. They live in the
        handle: a later factorisation of another matrix of the pattern replaces them, and a
        solve with this object then factorises ``K`` again (correct, but slower)."""
        factor = PardisoFactor(self, self._data_of(K))
        with self._lock:
            self._call(22, factor.data)
            self._owner = factor
        return factor

    def _data_of(self, K) -> np.ndarray:
        """The upper-triangle values of ``K`` in PARDISO's order."""
        if K.shape != (self.n, self.n) or K.nnz != self.nnz:
            raise ValueError(f"matrix {K.shape} with {K.nnz} entries is not of this pattern")
        return np.ascontiguousarray(K.data[self.upper], dtype=float)

    def _solve_locked(self, data: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Apply the factors held now (the caller holds the lock and has factorised data)."""
        b = np.asfortranarray(v, dtype=float)
        x = np.zeros_like(b)
        self._call(33, data, b, x)
        return np.ascontiguousarray(x)

    @property
    def perturbed_pivots(self) -> int:
        """Pivots PARDISO perturbed in the last factorisation (small or zero pivots)."""
        return int(self.iparm[13])

    @property
    def positive_eigenvalues(self) -> int:
        """Positive eigenvalues of the last factorised matrix (its inertia)."""
        return int(self.iparm[21])

    @property
    def negative_eigenvalues(self) -> int:
        """Negative eigenvalues of the last factorised matrix (its inertia)."""
        return int(self.iparm[22])


class PardisoFactor:
    """Factors of one matrix, from :meth:`PardisoLDLT.factorize`: ``solve(b)`` gives
    ``K^-1 b`` for b (n,) or (n, k), factorising again first if the handle has factorised
    another matrix since."""

    def __init__(self, handle: PardisoLDLT, data: np.ndarray):
        self.handle, self.data = handle, data

    def solve(self, b: np.ndarray) -> np.ndarray:
        h = self.handle
        with h._lock:
            if h._owner is not self:
                h._call(22, self.data)
                h._owner = self
            return h._solve_locked(self.data, b)


def _fixed_arguments(pt, iparm, n, ia, ja) -> tuple:
    """The arguments of ``pardiso`` that stay the same for a handle, as ctypes objects (they
    keep the arrays alive): pointers to ``pt``, ``ia``, ``ja``, ``iparm`` and references to
    maxfct = mnum = 1, mtype, n and msglvl = 0. Made once per handle: numpy's ``data_as``
    costs about 2 us a call."""
    i32, p, ref = ctypes.c_int32, ctypes.POINTER, ctypes.byref
    return (pt.ctypes.data_as(p(ctypes.c_int64)), ref(i32(1)), ref(i32(1)),
            ref(i32(_REAL_SYMMETRIC_INDEFINITE)), ref(i32(n)), ia.ctypes.data_as(p(i32)),
            ja.ctypes.data_as(p(i32)), iparm.ctypes.data_as(p(i32)), ref(i32(0)))


def _invoke(f, pt, iparm, phase, n, data, ia, ja, b=None, x=None, fixed=None) -> int:
    """One call of ``pardiso`` (one factor in the handle, real symmetric indefinite, no
    messages); its error code. ``fixed``: the handle's :func:`_fixed_arguments` (made here if
    not given)."""
    i32, ref = ctypes.c_int32, ctypes.byref
    pt, maxfct, mnum, mtype, n, ia, ja, iparm, msglvl = \
        _fixed_arguments(pt, iparm, n, ia, ja) if fixed is None else fixed
    nrhs = 1 if b is None or b.ndim == 1 else b.shape[1]
    dummy = np.zeros(1)
    error = i32(0)
    f(pt, maxfct, mnum, mtype, ref(i32(phase)), n, data.ctypes.data, ia, ja, None,
      ref(i32(nrhs)), iparm, msglvl, (dummy if b is None else b).ctypes.data,
      (dummy if x is None else x).ctypes.data, ref(error))
    return error.value


def _release(f, pt, iparm, n, ia, ja) -> None:
    """Free PARDISO's memory of a handle (phase -1)."""
    try:
        _invoke(f, pt, iparm, -1, n, np.zeros(1), ia, ja)
    except Exception:  # noqa: BLE001 - at interpreter exit the library may be gone
        pass
