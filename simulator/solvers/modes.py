"""Natural frequencies and mode shapes about any state (theory 9).

The structure is linearised about a state (flat, self-folded, heated, under gravity, in
contact): ``K`` is the tangent stiffness at its displacements and spring rest angles (stress
stiffness of any prestress and active contact included), reduced to the free DOFs (supports
eliminated, not zeroed as in the reference), and ``M`` the lumped mass of
:mod:`simulator.model.mass`. The generalized eigenproblem ``K phi = omega^2 M phi`` is solved densely
for small models and with a sparse shift-invert Lanczos solver (``eigsh``, shift just below
zero) for large ones. Mode shapes are M-orthonormal (``phi.M phi = 1`` [kg]).

Accuracy: bar-and-hinge models of micro-scale sheets span 10-15 orders of magnitude between
the fold modes and the stiff crease-bar modes, so a dense solver's absolute round-off in omega^2
(about machine epsilon times the largest omega^2) can reach 1e-6 of the lowest eigenvalues; the
shift-invert solver, refined by Rayleigh quotients, is more precise at the low end.

Zero modes (rigid-body motions of an under-supported model, mechanisms) are kept and flagged;
a negative eigenvalue means the state is unstable, and its "frequency" is reported as
``-sqrt(-omega^2) / (2 pi)`` so that it stands out in tables.

The state must be an equilibrium (:mod:`simulator.solvers.equilibrium_check`): one that is not
(a loosely converged self-fold, a state in the middle of a motion) is analysed with a WARNING
and status "not in equilibrium" (its residual in the message and in ``equilibrium``), refused,
or re-converged first (``equilibrium=``).
"""

from __future__ import annotations

import logging
import pathlib
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .._result import ResultFiles
from .._validate import integer
from ..errors import ParameterError
from ..linalg.ladder import check_backend, factorize
from ..linalg.thresholds import EIGEN_DENSE_LIMIT as DENSE_LIMIT  # dense eigen-analysis
from ..model.mass import check_masses, lumped_masses
from ..model.model import Model
from ..mechanics.equilibrium import equilibrium_system
from ..state import SimulationState
from .equilibrium_check import EquilibriumCheck, analysis_state, checked_state

__all__ = ["ModesResult", "natural_modes"]

logger = logging.getLogger(__name__)

#: A mode whose eigenvalue magnitude is below this fraction of the stiffness scale
#: max(K_ii / M_ii) is at the round-off level and counts as a zero (mechanism) mode; rigid-body
#: modes are recognised by their shape. (Soft but real modes can lie only a few machine epsilons
#: of that scale above zero in micro-scale sheets, so the tolerance is one epsilon.)
ZERO_TOL = float(np.finfo(float).eps)


@dataclass(frozen=True, eq=False)
class ModesResult(ResultFiles):
    """Natural modes of a model about a state (``k`` modes, ascending eigenvalue).

    Attributes
    ----------
    success, status, message
        status "converged", "not in equilibrium" (the modes were computed, about a state
        that is not an equilibrium: see ``equilibrium`` and the message), or "failed" when the
        eigensolver did not converge.
    eigenvalue : (k,) omega^2 [(rad/s)^2]
    frequency : (k,) omega / (2 pi) [Hz]; negative for unstable (negative-eigenvalue) modes
    shapes : (k, n_nodes, 3) M-orthonormal mode shapes [m / sqrt(kg)], zero on fixed DOFs
    zero_mode : (k,) bool, rigid-body mode (by its shape) or mechanism (|omega^2| at round-off
        level, see :data:`ZERO_TOL`); its frequency is reported as 0
    masses : (n_nodes,) lumped nodal masses [kg]
    solver : "dense" or "shift-invert"
    wall_time : float [s]
    state : SimulationState
        The state linearised about (the re-converged one with ``equilibrium="reconverge"``).
    equilibrium : EquilibriumCheck
        Its force residual (``residual_norm`` [N], ``relative``, ``in_equilibrium``).
    """

    success: bool
    status: str
    message: str
    eigenvalue: np.ndarray
    frequency: np.ndarray
    shapes: np.ndarray
    zero_mode: np.ndarray
    masses: np.ndarray
    solver: str
    wall_time: float
    model: Model = field(repr=False, default=None)
    state: SimulationState = field(repr=False, default=None)
    equilibrium: EquilibriumCheck | None = field(repr=False, default=None)

    @property
    def count(self) -> int:
        return len(self.eigenvalue)

    @property
    def residual_norm(self) -> float | None:
        """Force residual of the state [N] (None if not checked)."""
        return None if self.equilibrium is None else self.equilibrium.residual_norm

    def to_frame(self):
        """One row per mode: ``mode`` (1-based), ``frequency [Hz]``,
        ``eigenvalue [rad^2/s^2]``, ``zero_mode``."""
        import pandas as pd

        return pd.DataFrame({"mode": np.arange(1, self.count + 1),
                             "frequency [Hz]": self.frequency,
                             "eigenvalue [rad^2/s^2]": self.eigenvalue,
                             "zero_mode": self.zero_mode})

    _csv_name = "modes.csv"

    def _meta(self) -> dict:
        return {"solver": self.solver, "count": self.count, "wall_time [s]": self.wall_time,
                "total_mass [kg]": float(self.masses.sum()), "model": self.model.to_dict(),
                "equilibrium": None if self.equilibrium is None else self.equilibrium.to_dict()}

    def save(self, directory, metadata: dict | None = None) -> pathlib.Path:
        """Write ``modes.csv``, ``modes.npz`` (shapes, reference nodes, displacements of the
        state, triangles) and ``meta.json`` into ``directory``."""
        out = super().save(directory, metadata)
        mesh = self.model.mesh
        np.savez_compressed(out / "modes.npz", shapes=self.shapes, frequency=self.frequency,
                            reference_positions=mesh.nodes, displacements=self.state.u,
                            triangles=mesh.triangles, masses=self.masses)
        return out


def natural_modes(model: Model, state: SimulationState | None = None, count: int = 10,
                  method: str = "auto", masses=None, linear_solver: str = "auto",
                  equilibrium: str = "warn") -> ModesResult:
    """The ``count`` lowest natural modes of ``model`` linearised about ``state``.

    Parameters
    ----------
    model : Model
    state : SimulationState, optional
        State to linearise about (e.g. ``simulate(...).state``); default the flat initial state.
    count : int
        Number of modes (at most the number of free DOFs).
    method : {"auto", "dense", "sparse"}
        "dense": ``scipy.linalg.eigh`` of the full reduced matrices; "sparse": ``eigsh`` in
        shift-invert mode about a small negative shift; "auto": dense up to
        :data:`DENSE_LIMIT` free DOFs.
    masses : (n_nodes,) nodal masses [kg], optional
        Default :func:`~simulator.model.mass.lumped_masses` (needs material densities).
    linear_solver : {"auto", "dense", "pardiso", "superlu"}
        Backend of the shift-invert factorisation (:func:`~simulator.linalg.ladder.factorize`).
    equilibrium : {"warn", "raise", "reconverge"}
        When the state is not an equilibrium (force residual above
        :data:`~simulator.solvers.equilibrium_check.EQUILIBRIUM_RTOL` of max K_ii times the
        model size): "warn" analyses it with a logged WARNING and status "not in
        equilibrium"; "raise" refuses it (ParameterError); "reconverge" first solves for the
        equilibrium at the state's rest angles and dead loads (Newton, default options) and
        analyses that.

    Returns
    -------
    ModesResult
    """
    t0 = time.perf_counter()
    state = checked_state(model, state, "natural_modes")
    if method not in ("auto", "dense", "sparse"):
        raise ParameterError(f"natural_modes: method = {method!r}; use 'auto', 'dense' or "
                             "'sparse'.")
    check_backend(linear_solver, "natural_modes: linear_solver")
    system = equilibrium_system(model)
    n_free = system.n_free
    integer("natural_modes: count", count, 1, n_free, hint="at most the number of free DOFs")
    m = lumped_masses(model.mesh) if masses is None else np.asarray(masses, float)
    check_masses(model, m)
    state, check, ev = analysis_state(model, state, equilibrium, "natural_modes")
    K = ev.K
    mf = np.repeat(m, 3)[system.free]
    dense = method == "dense" or (method == "auto" and n_free <= DENSE_LIMIT)
    scale = float(np.max(K.diagonal() / mf))
    if dense:
        lam, phi = scipy.linalg.eigh(K.toarray(), np.diag(mf), subset_by_index=(0, count - 1))
        status, message = "converged", "converged"
    else:
        lam, phi, status, message = _shift_invert(K, mf, count, scale, linear_solver)
    shapes = np.zeros((len(lam), model.mesh.n_dof))
    shapes[:, system.free] = phi.T
    zero = (np.abs(lam) <= ZERO_TOL * scale) | _rigid_modes(model, state, shapes.reshape(
        len(lam), -1, 3), m)
    freq = np.sign(lam) * np.sqrt(np.abs(lam)) / (2 * np.pi)
    freq[zero] = 0.0
    if zero.any():
        message += f"; {int(zero.sum())} zero-frequency (rigid-body or mechanism) mode(s)"
    if (lam < 0).any() and not zero[lam < 0].all():
        message += "; negative eigenvalues: the state is unstable"
    if not check.in_equilibrium and status == "converged":
        status = "not in equilibrium"
    if not check.in_equilibrium or check.reconverged_from is not None:
        message += f"; state {check.message}"
    wall = time.perf_counter() - t0
    logger.info("natural_modes: %d modes, %s solver, %d free DOFs, %.3g s", len(lam),
                "dense" if dense else "shift-invert", n_free, wall)
    return ModesResult(status != "failed", status, message, lam, freq,
                       shapes.reshape(len(lam), -1, 3), zero, m,
                       "dense" if dense else "shift-invert", wall, model, state, check)


def _shift_invert(K, mf, count, scale, linear_solver="auto"):
    """Lowest eigenpairs by shift-invert Lanczos about a small negative shift.

    With the diagonal mass, ``K phi = lam M phi`` is the standard symmetric problem of
    ``M^-1/2 K M^-1/2`` for ``y = M^1/2 phi``; its shift-invert operator
    ``M^1/2 (K - sigma M)^-1 M^1/2`` is applied with one sparse LU factorisation (symmetric
    minimum-degree ordering, as the Newton solver).
    """
    sigma = -1e-12 * scale     # just below the zero modes: K - sigma M is regular
    A = (K - sigma * sp.diags(mf)).tocsc()
    lu = _factorise(A, linear_solver)
    s = np.sqrt(mf)
    op = spla.LinearOperator(A.shape, matvec=lambda y: s * lu.solve(s * np.ravel(y)),
                             dtype=float)
    try:
        nu, y = spla.eigsh(op, k=count, which="LM")
        status, msg = "converged", "converged"
    except spla.ArpackNoConvergence as exc:
        nu, y = exc.eigenvalues, exc.eigenvectors
        status, msg = "failed", f"shift-invert Lanczos converged {len(nu)} of {count} modes"
    phi = y / s[:, None]
    # Rayleigh quotients (y is orthonormal, so phi.M phi = 1): error quadratic in the shape's
    lam = np.einsum("ij,ij->j", phi, K @ phi)
    order = np.argsort(lam)
    return lam[order], phi[:, order], status, msg


def _factorise(A, linear_solver="auto"):
    """Factors of a symmetric matrix by the ladder (:func:`~simulator.linalg.ladder.factorize`:
    PARDISO if installed; else SuperLU in symmetric mode, in nested-dissection order from
    :data:`~simulator.linalg.thresholds.ND_LIMIT` unknowns on, partial pivoting if inaccurate)."""
    return factorize(A, kind="symmetric", backend=linear_solver)


def _rigid_modes(model, state, shapes, m) -> np.ndarray:
    """(k,) True where a mode shape lies in the span of the six rigid-body motions of the
    deformed configuration (M-weighted projection of at least 1 - 1e-6)."""
    x = model.mesh.nodes + state.u
    r = x - (m[:, None] * x).sum(axis=0) / m.sum()
    basis = [np.tile(e, (len(x), 1)) for e in np.eye(3)] + [np.cross(e, r) for e in np.eye(3)]
    R = np.stack([b.ravel() for b in basis], axis=1) * np.sqrt(np.repeat(m, 3))[:, None]
    Q = np.linalg.qr(R)[0]
    Y = shapes.reshape(len(shapes), -1).T * np.sqrt(np.repeat(m, 3))[:, None]
    proj = np.linalg.norm(Q.T @ Y, axis=0) ** 2 / np.maximum(np.sum(Y**2, axis=0), 1e-300)
    return proj >= 1 - 1e-6
