"""Stability of an equilibrium: inertia of the reduced tangent stiffness.

An equilibrium is stable when the tangent stiffness on the free DOFs is positive definite. The
number of negative eigenvalues (the Morse index) changes by one at a limit point or at a simple
bifurcation; the two are told apart by the eigenvector of the vanishing eigenvalue: at a limit
point it has a component along the load derivative ``q = dr/dlambda``, at a bifurcation it is
orthogonal to it.

Small systems (up to :data:`DENSE_LIMIT` free DOFs) are analysed densely (all eigenvalues, so
the count is exact); large ones by shift-invert Lanczos (``eigsh`` near zero), which finds the
``k`` eigenvalues closest to zero, so a count of ``k`` is a lower bound.

:func:`state_stability` analyses a given state (its tangent at its displacements and rest
angles) after checking that it is an equilibrium (:mod:`simulator.solvers.equilibrium_check`):
the inertia of the tangent about a state out of equilibrium says nothing about a physical
state.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
import scipy.sparse as sp

from .._result import ResultFiles
from ..linalg.dense_lapack import one_blas_thread
from ..linalg.ladder import factorize, positive_definite
from ..linalg.small_solve import as_dense
from ..linalg.thresholds import EIGEN_DENSE_LIMIT as DENSE_LIMIT  # dense eigen-analysis

__all__ = ["Stability", "tangent_stability", "state_stability", "quick_stability",
           "NEGATIVE_RTOL", "negative_tolerance"]

#: An eigenvalue counts as negative below ``-NEGATIVE_RTOL * n * eps * |K|`` (|K| the largest
#: diagonal entry): a few hundred times the error bound of a symmetric eigensolver, so the
#: round-off around the zero eigenvalue of a mechanism (a sheet held only by its own
#: stiffness along a rigid-body or folding motion) never reads as a loss of stability, while
#: the negative eigenvalues of the heated flat waterbomb (-1e-4 N/m against diagonal entries
#: of ~1e3 N/m) are 1e6 times above it.
NEGATIVE_RTOL = 100.0



@dataclass(frozen=True, eq=False)
class Stability(ResultFiles):
    """Inertia of a reduced tangent stiffness.

    Like every result it has ``success`` (True: the eigenvalues were computed; a failing
    eigensolver raises instead), ``status`` ("stable" or "unstable"), ``message``,
    ``to_frame()`` (one row) and ``save(directory)``.

    Attributes
    ----------
    negative : int
        Number of negative eigenvalues (a lower bound when ``exact`` is False).
    lowest : float
        Lowest eigenvalue [N/m].
    mode : (n_free,) unit eigenvector of the lowest eigenvalue
    exact : bool
        True if all eigenvalues were computed (dense), False for the ``k`` nearest to zero.
    equilibrium : EquilibriumCheck or None
        The force residual of the state (:func:`state_stability`; None for a bare tangent).
        About a state out of equilibrium the status is "not in equilibrium" and the message
        gives the residual.
    """

    negative: int
    lowest: float | None
    mode: np.ndarray | None
    exact: bool = True
    equilibrium: object = None

    @property
    def stable(self) -> bool:
        """True if no eigenvalue is negative."""
        return self.negative == 0

    @property
    def success(self) -> bool:
        return True

    @property
    def in_equilibrium(self) -> bool | None:
        """Whether the state was an equilibrium (None for a bare tangent)."""
        return None if self.equilibrium is None else self.equilibrium.in_equilibrium

    @property
    def status(self) -> str:
        if self.in_equilibrium is False:
            return "not in equilibrium"
        return "stable" if self.stable else "unstable"

    @property
    def message(self) -> str:
        bound = "" if self.exact else "at least "
        if self.lowest is None:
            return "positive definite (Cholesky); lowest eigenvalue not computed"
        text = (f"{bound}{self.negative} negative eigenvalue(s); lowest eigenvalue "
                f"{self.lowest:.6g} N/m")
        eq = self.equilibrium
        if eq is not None and (not eq.in_equilibrium or eq.reconverged_from is not None):
            text += f"; state {eq.message}"
        return text

    _csv_name = "stability.csv"

    def _row(self) -> dict:
        eq = self.equilibrium
        return {"stable": self.stable, "negative_eigenvalues": self.negative,
                "lowest_eigenvalue [N/m]": self.lowest, "exact": self.exact,
                "in_equilibrium": self.in_equilibrium,
                "residual_norm [N]": None if eq is None else eq.residual_norm}

    def load_alignment(self, q: np.ndarray) -> float:
        """|cos| of the angle between the critical mode and the load derivative ``q``
        (1: a limit-point mode, 0: a bifurcation mode); nan if ``q`` is zero."""
        nq = float(np.linalg.norm(q))
        if self.mode is None:
            return float("nan")
        return abs(float(self.mode @ q)) / nq if nq > 0 else float("nan")


def tangent_stability(K, k: int = 6, linear_solver: str = "auto",
                      rtol: float = 0.0) -> Stability:
    """Inertia and lowest eigenpair of the symmetric reduced tangent ``K`` (n_free, n_free).

    Parameters
    ----------
    K : sparse or dense (n, n) symmetric matrix [N/m]
    k : int
        Eigenvalues computed near zero for large systems.
    linear_solver : {"auto", "dense", "pardiso", "superlu"}
        Backend of the shift-invert factorisation of large systems
        (:func:`~simulator.linalg.ladder.factorize`).
    rtol : float
        An eigenvalue counts as negative below ``-rtol * n * eps * max |K_ii|`` (0: below 0,
        exactly, as the continuation's bisection to a critical point needs;
        :func:`quick_stability` uses :data:`NEGATIVE_RTOL`).
    """
    n = K.shape[0]
    if n == 0:
        return Stability(0, float("inf"), np.zeros(0))
    tol = rtol * negative_tolerance(K)
    if n <= DENSE_LIMIT:
        A = as_dense(K)
        with one_blas_thread(n):
            w, V = scipy.linalg.eigh(0.5 * (A + A.T), check_finite=False)
        return Stability(int(np.sum(w < -tol)), float(w[0]), _critical_mode(w, V), True)
    import scipy.sparse.linalg as spla

    diag = np.abs(K.diagonal())
    shift = -1e-8 * float(np.median(diag[diag > 0])) if np.any(diag > 0) else -1e-12
    K = sp.csr_matrix(K)
    lu = factorize((K - shift * sp.identity(n, format="csr")).tocsr(), kind="symmetric",
                   backend=linear_solver)
    op = spla.LinearOperator(K.shape, matvec=lambda y: lu.solve(np.ravel(y)), dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        w, V = spla.eigsh(K, k=min(k, n - 1), sigma=shift, which="LM", OPinv=op)
    order = np.argsort(w)
    w, V = w[order], V[:, order]
    return Stability(int(np.sum(w < -tol)), float(w[0]), V[:, 0], False)


#: Eigenvalues within this (relative) of the lowest share its eigenspace (a symmetric
#: structure's repeated eigenvalue).
DEGENERATE_RTOL = 1e-6


def _critical_mode(w, V) -> np.ndarray:
    """The lowest eigenvector, made independent of the eigensolver's choice of basis where the
    lowest eigenvalue is repeated (a symmetric pattern): the projection onto that eigenspace of
    the unit vector of the DOF it moves most (the first such DOF), normalised."""
    k = int(np.sum(w - w[0] <= DEGENERATE_RTOL * max(abs(w[0]), 1e-300)))
    if k < 2:
        return V[:, 0]
    B = V[:, :k]
    reach = np.einsum("ij,ij->i", B, B)
    j = int(np.flatnonzero(reach >= (1 - 1e-8) * reach.max())[0])
    m = B @ B[j]
    return m / np.linalg.norm(m)


def negative_tolerance(K) -> float:
    """``n * eps * max |K_ii|`` [N/m]: the unit of the tolerance on negative eigenvalues."""
    d = np.abs(K.diagonal()) if sp.issparse(K) else np.abs(np.diagonal(np.asarray(K)))
    return K.shape[0] * np.finfo(float).eps * float(d.max(initial=0.0))


def quick_stability(K, linear_solver: str = "auto") -> Stability:
    """Stability of an equilibrium from its reduced tangent ``K`` (n_free, n_free) [N/m],
    cheaply where it is stable.

    One factorisation first, as Newton's for the same tangent, and no solve
    (:func:`~simulator.linalg.ladder.positive_definite`: LAPACK's Cholesky for the dense
    tangent of a small model; for a sparse one the signs of the pivots of PARDISO's or
    SuperLU's L D L^T with diagonal pivots): a positive definite
    tangent is stable (``lowest`` and ``mode`` None: not computed). Otherwise, or where the
    factorisation gives no inertia, :func:`tangent_stability` (the eigenvalues, with the
    critical mode). This is the check every quasi-static step makes of each accepted state.
    """
    if K.shape[0] == 0:
        return Stability(0, float("inf"), np.zeros(0))
    if positive_definite(K, linear_solver):
        return _STABLE
    return tangent_stability(K, linear_solver=linear_solver, rtol=NEGATIVE_RTOL)


#: The outcome of a positive definite tangent (immutable, shared).
_STABLE = Stability(0, None, None, True)


def state_stability(model, state=None, k: int = 6, linear_solver: str = "auto",
                    equilibrium: str = "warn") -> Stability:
    """Stability of ``state`` (default the initial state): :func:`tangent_stability` of the
    reduced tangent at its displacements and spring rest angles, after checking that it is an
    equilibrium.

    Parameters
    ----------
    model : Model
    state : SimulationState, optional
    k, linear_solver
        As :func:`tangent_stability`.
    equilibrium : {"warn", "raise", "reconverge"}
        When the state is not an equilibrium: analyse it with a logged WARNING (status "not in
        equilibrium"), refuse it (ParameterError) or re-converge it first (Newton at its rest
        angles and dead loads), as :func:`~simulator.solvers.modes.natural_modes`.

    Returns
    -------
    Stability
        With ``equilibrium`` (the state's force residual) set.
    """
    from .equilibrium_check import analysis_state, checked_state

    state = checked_state(model, state, "state_stability")
    state, check, ev = analysis_state(model, state, equilibrium, "state_stability")
    return replace(tangent_stability(ev.K, k, linear_solver), equilibrium=check)
