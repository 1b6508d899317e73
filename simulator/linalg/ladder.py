"""The one factorisation ladder of the package: :func:`factorize` (kept factors) and
:func:`solve` (one solve, as Newton needs).

Every caller (Newton, arc length, dynamics, steady and transient heat, stability, natural
modes) goes through these two functions; the size thresholds are in
:mod:`simulator.linalg.thresholds` and the acceptance rule is the backward-error test of
:mod:`simulator.linalg.linsolve` (:func:`~simulator.linalg.linsolve.accurate`, with
:func:`~simulator.linalg.linsolve.refined`). The rungs, tried in order:

1. ``dense`` (up to the caller's dense limit, default
   :data:`~simulator.linalg.thresholds.DENSE_LIMIT`): LAPACK Cholesky, or LU with partial
   pivoting when the matrix is not positive definite
   (:class:`~simulator.linalg.small_solve.DenseFactor`);
   for the fused small models, the compiled sparse Cholesky of the element pattern
   (:class:`~simulator.linalg.small_solve.SparseCholesky`) when it is cheaper.
2. ``pardiso`` (from :data:`~simulator.linalg.thresholds.PARDISO_LIMIT` unknowns, when MKL is
   installed and ``ETORIGAMI_PARDISO`` is not 0): PARDISO's L D L^T, analysis cached per pattern.
3. ``superlu-nd`` (from :data:`~simulator.linalg.thresholds.ND_LIMIT` unknowns): SuperLU in the
   cached METIS nested-dissection order, diagonal pivots.
4. ``superlu-mmd`` (kind "symmetric"): SuperLU in symmetric mode, symmetric minimum degree
   (~3x less fill than COLAMD on bar-and-hinge tangents).
5. ``superlu``: SuperLU with partial pivoting in COLAMD order: the fallback, always accepted.

A rung's result is accepted when it is accurate: :func:`solve` tests the solution of the
right-hand side itself after up to three steps of iterative refinement with the same factors
(rtol 1e-6); :func:`factorize` tests the solution of a vector of ones (rtol 1e-8) before it
keeps the factors. ``kind`` selects the rungs that apply: "spd" (conduction matrices: no
minimum-degree rung, the results of earlier versions), "symmetric" (tangents, possibly
indefinite) or "general" (dense LU or SuperLU with partial pivoting only).

``backend`` forces one family ("dense", "pardiso", "superlu"; the partial-pivoting rung stays
the last resort of the sparse ones); "auto" is the ladder. It is the documented option
``NewtonOptions(linear_solver=...)`` and the ``linear_solver`` argument of the other solvers.
"""

from __future__ import annotations

import logging
import threading
import warnings

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from . import linsolve, pardiso, thresholds
from .small_solve import DenseFactor, as_dense, solve_dense
from .small_solve import positive_definite as _dense_positive_definite

__all__ = ["Factor", "factorize", "solve", "positive_definite", "BACKENDS", "KINDS",
           "check_backend", "last_backend"]

logger = logging.getLogger(__name__)

#: Values of ``backend`` (and of ``NewtonOptions.linear_solver``).
BACKENDS = ("auto", "dense", "pardiso", "superlu")
#: Values of ``kind``.
KINDS = ("symmetric", "spd", "general")
_LAPACK_BACKENDS = ("auto", "dense")       # the backends that solve a dense array densely
#: Tolerance of the vector-of-ones check of kept factors, and of a single solve.
_KEPT_RTOL, _SOLVE_RTOL = 1e-8, 1e-6

_last = threading.local()


class Factor:
    """Factors of one square matrix from :func:`factorize`.

    Attributes
    ----------
    backend : str
        The rung that produced them: "dense", "pardiso", "superlu-nd", "superlu-mmd" or
        "superlu".
    n : int
        Matrix size.
    raw : object
        The backend's own factors, with a ``solve(b)`` method:
        :class:`~simulator.linalg.small_solve.DenseFactor`,
        :class:`~simulator.linalg.pardiso.PardisoFactor`,
        :class:`~simulator.linalg.linsolve.PermutedLU` or ``scipy.sparse.linalg.SuperLU``.
    """

    def __init__(self, raw, backend: str, n: int, inertia=None):
        self.raw, self.backend, self.n, self._inertia = raw, backend, n, inertia
        self.solve = raw.solve              # (the method below, one call less per solve)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``A^-1 b`` for b (n,) or (n, k)."""
        return self.raw.solve(b)

    @property
    def inertia(self) -> tuple[int, int, int] | None:
        """(positive, negative, zero) eigenvalue counts of the matrix where the backend gives
        them (dense, PARDISO), else None."""
        return self._inertia() if callable(self._inertia) else self._inertia

    def __repr__(self) -> str:
        return f"Factor(backend={self.backend!r}, n={self.n})"


def check_backend(value, owner: str = "linear_solver") -> str:
    """``value`` if it names a backend, else a :class:`~simulator.errors.ParameterError`
    naming ``owner``."""
    if value not in BACKENDS:
        from ..errors import ParameterError
        raise ParameterError(f"{owner} = {value!r}; use one of {', '.join(map(repr, BACKENDS))} "
                             "('auto': dense for small systems, PARDISO when installed, else "
                             "SuperLU).")
    return value


def last_backend() -> str | None:
    """The rung of this thread's last :func:`solve` / :func:`factorize` (diagnostics), or None
    if it failed."""
    return getattr(_last, "backend", None)


def _is_dense(A, backend: str, dense_limit: int | None) -> bool:
    if backend != "auto":
        return backend == "dense"
    limit = thresholds.DENSE_LIMIT if dense_limit is None else dense_limit
    return isinstance(A, np.ndarray) or A.shape[0] <= limit


def _sparse_rungs(n: int, kind: str, backend: str) -> list[str]:
    """The sparse rungs for an n x n matrix, in order (the last one is always accepted)."""
    rungs = []
    if kind != "general" and (backend == "pardiso" or (
            backend == "auto" and n >= thresholds.PARDISO_LIMIT)):
        if pardiso.available():
            rungs.append("pardiso")
        elif backend == "pardiso":
            from ..errors import ParameterError
            raise ParameterError("linear_solver = 'pardiso' but PARDISO is not available "
                                 "(pip install 'etorigami[mkl]', and ETORIGAMI_PARDISO not 0); "
                                 "use 'auto' or 'superlu'.")
    if kind != "general" and backend in ("auto", "superlu"):
        if n >= thresholds.ND_LIMIT:
            rungs.append("superlu-nd")
        if kind == "symmetric":
            rungs.append("superlu-mmd")
    return rungs + ["superlu"]


def _check(kind, backend):
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r}; use one of {KINDS}")
    check_backend(backend)


def factorize(A, kind: str = "symmetric", backend: str = "auto", *,
              dense_limit: int | None = None) -> Factor:
    """Factors of a square matrix ``A`` (sparse or dense) for repeated solves.

    Parameters
    ----------
    A : (n, n) sparse matrix or array
    kind : {"symmetric", "spd", "general"}
    backend : {"auto", "dense", "pardiso", "superlu"}
    dense_limit : int, optional
        Largest size factorised densely by "auto" (default
        :data:`~simulator.linalg.thresholds.DENSE_LIMIT`).

    Each rung but the last is kept only if its solution of a vector of ones is accurate
    (see the module docstring). Raises RuntimeError if SuperLU finds ``A`` exactly singular.
    """
    if kind not in KINDS or backend not in BACKENDS:
        _check(kind, backend)
    n = A.shape[0]
    if (backend == "auto" and type(A) is np.ndarray) or _is_dense(A, backend, dense_limit):
        factor = _dense_factor(A if type(A) is np.ndarray else as_dense(A), kind)
        if factor is not None:
            return _chosen(factor)
        if backend == "dense":
            raise np.linalg.LinAlgError("dense factorisation: the matrix is singular")
    A = _canonical(A)
    for rung in _sparse_rungs(n, kind, backend):
        factor = _KEPT[rung](A)
        if factor is not None and (rung == "superlu" or linsolve.solves_ones(
                A, factor.solve, _KEPT_RTOL)):
            return _chosen(factor)
    raise AssertionError("unreachable: the last rung is always kept")


def positive_definite(A, backend: str = "auto", *, dense_limit: int | None = None) -> bool:
    """Whether the symmetric ``A`` (sparse or dense) is positive definite, from the pivots of
    one symmetric factorisation of the ladder: the rungs of :func:`factorize` (kind
    "symmetric"), without the solve of a vector of ones with which it tests factors it keeps.

    True when every pivot of the first rung that gives them is positive: an L D L^T
    factorisation with D > 0 is a Cholesky factorisation, backward stable, so ``A`` is
    numerically positive definite in the sense of LAPACK's Cholesky of a dense matrix (the
    dense rung is that). False when a pivot is not positive (by Sylvester's law ``A`` has an
    eigenvalue <= 0) and where the factors cannot tell: PARDISO perturbed a pivot, SuperLU
    left the diagonal or hit an exactly zero pivot, or only the partial-pivoting rung is left.
    The test a stability check makes of every accepted state
    (:func:`~simulator.solvers.stability.quick_stability`): one factorisation, no solve.
    """
    if type(A) is np.ndarray:                     # a dense tangent: LAPACK, as Newton's
        return A.shape[0] == 0 or _dense_positive_definite(A)
    check_backend(backend)
    n = A.shape[0]
    if n == 0:
        return True
    if _is_dense(A, backend, dense_limit):
        return _dense_positive_definite(as_dense(A))
    A = _canonical(A)
    for rung in _sparse_rungs(n, "symmetric", backend):
        inertia = _pivot_signs(rung, A)
        if inertia is not None:
            return inertia[0] == n
    return False


def _pivot_signs(rung: str, A) -> tuple[int, int, int] | None:
    """(positive, negative, zero) pivot counts of ``A`` (canonical CSR) by a symmetric
    factorisation of the ``rung``, or None where it cannot tell (see
    :func:`positive_definite`)."""
    if rung == "pardiso":
        handle = linsolve.pardiso_handle(A)
        if handle is None:
            return None
        try:
            handle.factorize(A)
        except pardiso.PardisoError as exc:
            logger.debug("PARDISO failed (%s)", str(exc))
            return None
        if handle.perturbed_pivots:
            return None
        pos, neg = handle.positive_eigenvalues, handle.negative_eigenvalues
        return pos, neg, A.shape[0] - pos - neg
    try:
        if rung == "superlu-nd":
            lu = linsolve.nd_factors(A)
            return None if lu is None else _superlu_inertia(lu.lu)
        if rung == "superlu-mmd":
            return _superlu_inertia(_mmd(A.tocsc()))
    except RuntimeError:                                  # an exactly zero pivot
        return None
    return None                                           # partial pivoting: no inertia


def _canonical(A) -> sp.csr_matrix:
    """``A`` as CSR with sorted indices and no duplicates (PARDISO's and the cached orderings'
    input; a copy only if it is not so already)."""
    A = A if sp.issparse(A) and A.format == "csr" else sp.csr_matrix(A)
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
    return A


def _chosen(factor: Factor) -> Factor:
    _last.backend = factor.backend
    if logger.isEnabledFor(logging.DEBUG):
        logger.debug("factorised %d x %d by %s", factor.n, factor.n, factor.backend)
    return factor


def _dense_factor(A: np.ndarray, kind: str) -> Factor | None:
    """The dense rung's factors, or None if LU finds an exactly zero pivot (kind "spd": if
    Cholesky fails, the caller goes on to the sparse rungs)."""
    factor = DenseFactor(A, cholesky_first=kind != "general", condition=False,
                         lu_fallback=kind != "spd")   # spd: Cholesky, else the sparse rungs
    if factor.info != 0:
        return None
    n = A.shape[0]
    if factor.method == "cholesky":
        inertia = (n, 0, 0)
    else:
        def inertia():
            return _signs(np.linalg.eigvalsh(scipy.linalg.ldl(A)[1]))
    return Factor(factor, "dense", n, inertia)


def _kept_pardiso(A) -> Factor | None:
    handle = linsolve.pardiso_handle(A)
    if handle is None:
        return None
    try:
        f = handle.factorize(A)
    except pardiso.PardisoError as exc:
        logger.debug("PARDISO failed (%s)", str(exc))
        return None
    n = A.shape[0]
    pos, neg = handle.positive_eigenvalues, handle.negative_eigenvalues
    return Factor(f, "pardiso", n, (pos, neg, n - pos - neg))


def _kept_nd(A) -> Factor | None:
    lu = linsolve.nd_factors(A)
    return None if lu is None else Factor(lu, "superlu-nd", A.shape[0],
                                          lambda: _superlu_inertia(lu.lu))


def _superlu_inertia(lu) -> tuple[int, int, int] | None:
    """Inertia of a symmetric matrix from SuperLU factors with diagonal pivots (the same
    permutation of rows and columns): ``P A P^T = L U`` with ``U = D L^T``, so by Sylvester's
    law the signs of U's diagonal count the eigenvalues. None where a pivot left the diagonal
    (the factors then say nothing of the inertia)."""
    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None
    return _signs(lu.U.diagonal())


def _signs(d: np.ndarray) -> tuple[int, int, int]:
    """(positive, negative, zero) counts of the pivots or eigenvalues ``d`` of a factorised
    symmetric matrix, zero meaning within ``n eps max |d|``."""
    tol = len(d) * np.finfo(float).eps * max(float(np.abs(d).max(initial=0.0)), 1e-300)
    return int(np.sum(d > tol)), int(np.sum(d < -tol)), int(np.sum(np.abs(d) <= tol))


def _splu(A, **options):
    """SuperLU factors of a CSC matrix (``scipy.sparse.linalg`` is imported on first use: a
    small model never needs it)."""
    import scipy.sparse.linalg as spla

    return spla.splu(A, **options)


def _mmd_factor(lu, n: int) -> Factor:
    return Factor(lu, "superlu-mmd", n, lambda: _superlu_inertia(lu))


def _mmd(Ac):
    return _splu(Ac, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                 options={"SymmetricMode": True})


_KEPT = {
    "pardiso": _kept_pardiso,
    "superlu-nd": _kept_nd,
    "superlu-mmd": lambda A: _mmd_factor(_mmd(A.tocsc()), A.shape[0]),
    "superlu": lambda A: Factor(_splu(A.tocsc()), "superlu", A.shape[0]),
}


def solve(A, b: np.ndarray, kind: str = "symmetric", backend: str = "auto", *,
          rtol: float = _SOLVE_RTOL, dense_limit: int | None = None, cholesky=None,
          reject_ill_conditioned: bool = True) -> np.ndarray | None:
    """``A^-1 b`` by the ladder (one factorisation, not kept); None if ``A`` is singular
    or the result is not finite.

    Parameters
    ----------
    A : (n, n) sparse matrix or array
    b : (n,) or (n, k) right-hand side
    kind, backend, dense_limit : as :func:`factorize`
    rtol : float
        Residual tolerance of the acceptance test (:func:`~simulator.linalg.linsolve.accurate`).
    cholesky : SparseCholesky, optional
        The structure of a small dense-stored tangent (fused kernel); its compiled
        factorisation replaces LAPACK's when it needs under a twentieth of dense Cholesky's
        ~n^3/3 multiply-adds (and the matrix has at least
        :data:`~simulator.linalg.thresholds.SPARSE_MIN` rows).
    reject_ill_conditioned : bool
        Dense rung: None also when the reciprocal condition estimate is below machine
        epsilon (Newton). False for bordered systems, whose tangent is nearly singular at a
        limit point by design (arc length).
    """
    if type(A) is not np.ndarray or backend not in _LAPACK_BACKENDS or kind not in KINDS:
        # (a small dense array, as in Newton's loop on small models, skips these tests)
        if kind not in KINDS or backend not in BACKENDS:
            _check(kind, backend)
        if not _is_dense(A, backend, dense_limit):
            return _sparse_solve(A, b, kind, backend, rtol)
        A = as_dense(A)
    if (cholesky is not None and kind != "general" and cholesky.beats_dense
            and A.shape[0] >= thresholds.SPARSE_MIN):
        x = cholesky.solve(A, b)
    elif reject_ill_conditioned:
        x = solve_dense(A, b, kind != "general")
    else:
        factor = DenseFactor(A, cholesky_first=kind != "general")
        x = factor.solve(b) if factor.info == 0 else None
        x = x if x is not None and np.all(np.isfinite(x)) else None
    _last.backend = "dense" if x is not None else None
    return x


def _sparse_solve(A, b, kind, backend, rtol):
    """The sparse rungs of :func:`solve`: the solution, or None if every rung fails
    (singular) or it is not finite."""
    _last.backend = None
    A = _canonical(A)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            x, rung = _sparse_rungs_solve(A, b, kind, backend, rtol)
        except (np.linalg.LinAlgError, scipy.linalg.LinAlgError, RuntimeError, Warning):
            return None
    if not np.all(np.isfinite(x)):
        return None
    _last.backend = rung
    return x


def _sparse_rungs_solve(A, b, kind, backend, rtol):
    """(x, rung) from the first sparse rung whose solution is accurate after refinement."""
    Ac = None
    for rung in _sparse_rungs(A.shape[0], kind, backend):
        if rung == "pardiso":
            x = linsolve.pardiso_solve(A, b, rtol)
        elif rung == "superlu-nd":
            x = linsolve.nested_dissection_solve(A, b, rtol)
        elif rung == "superlu-mmd":
            Ac = A.tocsc()
            lu = _mmd(Ac)
            x, ok = linsolve.refined(A, lu.solve, b, lu.solve(b), rtol)
            x = x if ok else None
        else:
            x = _splu(A.tocsc() if Ac is None else Ac).solve(b)
        if x is not None:
            return x, rung
    raise AssertionError("unreachable: the last rung always solves")
