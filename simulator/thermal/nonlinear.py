"""The nonlinear heat losses: a medium whose conductivity depends on temperature, and radiation
(theory 4.12).

The heat balance on ``m`` unknown rises ``u`` [K] above room temperature ``T0`` [deg C] is

    F(u) = A u + B Phi(u) + diag(g) Phi(u) + sigma e ((T0 + u + KELVIN)^4 - (T0 + KELVIN)^4) = q,

with ``A`` the sheet's conduction (and anything else linear), ``B`` the medium's loss
conductance at its reference conductivity k0 (the integral model's ``L``, or the chains' layer
conductances in the time domain), ``g`` the chains condensed to one conductance per node, ``e``
the emissivity-weighted radiating area of each unknown (both faces) and ``Phi`` the Kirchhoff
transformation of the medium's conductivity law (:meth:`~simulator.geometry.materials.Fluid.
kirchhoff`; ``Phi(u) = u`` for a constant conductivity). Its Jacobian is ``A + B diag(Phi') +
diag(g Phi' + 4 sigma e T^3)``; with a conductivity law and ``B`` it is not symmetric.

:class:`NonlinearLoss` holds ``B``, ``g``, ``e`` and the law; :func:`solve_heat_balance` solves
``F(u) = q`` by Newton's method (:func:`~simulator.solvers.nonlinear.iterate`, the package's one
Newton iteration) and returns a :class:`HeatBalance` (``success``, ``status``, ``message``).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..geometry.materials import KELVIN
from ..linalg.ladder import factorize
from ..solvers.nonlinear import iterate

__all__ = ["STEFAN_BOLTZMANN", "NonlinearLoss", "HeatBalance", "solve_heat_balance",
           "HEAT_BALANCE_RTOL"]

logger = logging.getLogger(__name__)

#: The Stefan-Boltzmann constant sigma [W/(m^2 K^4)] (CODATA 2018, exact in the 2019 SI).
STEFAN_BOLTZMANN = 5.670374419e-8
#: The Newton solve of the heat balance stops when the 2-norm of its residual [W] is at most
#: this fraction of the heat input's.
HEAT_BALANCE_RTOL = 1e-12
#: Newton corrections at most.
_MAX_ITER = 50
#: Largest entry of one Newton correction [K] (a damping that only a far start needs).
_MAX_STEP = 500.0


@dataclass(frozen=True, eq=False)
class NonlinearLoss:
    """The nonlinear losses of ``m`` unknowns (module notes).

    Attributes
    ----------
    medium : Fluid
        The medium and its conductivity law.
    room : float
        Room temperature [deg C] (of the medium far away, the surroundings and the held nodes).
    B : (m, m) array or sparse, or None
        The medium's loss conductance at its reference conductivity [W/K], applied to
        ``Phi(u)``.
    g : (m,) array or None
        Conductance of each unknown to room temperature through the medium [W/K] (condensed
        chains), applied to ``Phi(u)``.
    emissive : (m,) array
        Emissivity times the radiating area of each unknown, both faces [m^2].
    """

    medium: object
    room: float
    B: object = None
    g: np.ndarray | None = None
    emissive: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def flux(self, u) -> np.ndarray:
        """Heat [W] each unknown loses at rises ``u`` (m,) [K], through the medium and by
        radiation."""
        phi, _ = self.medium.kirchhoff(u, self.room)
        out = radiation(self.emissive, u, self.room)
        if self.B is not None:
            out = out + self.B @ phi
        if self.g is not None:
            out = out + self.g * phi
        return out

    def jacobian(self, u):
        """``(B diag(Phi'(u)) or None, d)``: the derivative of :meth:`flux` at ``u`` [W/K], its
        full part (the medium's ``B`` with its columns scaled) and its diagonal ``d`` (m,)."""
        _, dphi = self.medium.kirchhoff(u, self.room)
        T = self.room + KELVIN + np.asarray(u, float)
        d = 4 * STEFAN_BOLTZMANN * self.emissive * T ** 3
        if self.g is not None:
            d = d + self.g * dphi
        if self.B is None:
            return None, d
        if sp.issparse(self.B):
            return (self.B @ sp.diags(dphi)).tocsc(), d
        return self.B * dphi[None, :], d


def radiation(emissive, u, room: float) -> np.ndarray:
    """Heat [W] radiated by unknowns of emissive area ``emissive`` (m,) [m^2] at rises ``u``
    (m,) [K] over room temperature ``room`` [deg C] to surroundings at room temperature:
    ``sigma e (T^4 - T0^4)`` in kelvin, factored as ``sigma e u (T + T0) (T^2 + T0^2)`` (no
    cancellation at small rises)."""
    T0 = room + KELVIN
    u = np.asarray(u, float)
    T = T0 + u
    return STEFAN_BOLTZMANN * np.asarray(emissive, float) * u * (T + T0) * (T * T + T0 * T0)


@dataclass
class HeatBalance:
    """Outcome of :func:`solve_heat_balance`.

    Attributes
    ----------
    success : bool
    status : str
        "converged" or "failed".
    message : str
    rise : (m,) array
        The rises [K] of the last iterate (the solution where converged).
    iterations : int
        Newton corrections applied.
    residual_norms : list of float
        2-norm of the residual [W] at every iterate.
    """

    success: bool
    status: str
    message: str
    rise: np.ndarray
    iterations: int
    residual_norms: list


class _Problem:
    """The heat balance for :func:`~simulator.solvers.nonlinear.iterate`: residual, Newton
    correction and update of the rises."""

    def __init__(self, A, loss: NonlinearLoss, q, u0):
        self.A, self.loss, self.q = A, loss, q
        self.u = np.array(u0, float)
        self.dense = isinstance(A, np.ndarray)

    def evaluate(self):
        return self.A @ self.u + self.loss.flux(self.u) - self.q, None

    def correct(self, point, r):
        full, d = self.loss.jacobian(self.u)
        if self.dense:
            J = self.A + (0.0 if full is None else full)
            J[np.diag_indices_from(J)] += d
            kind = "spd" if full is None else "general"
        else:
            J = self.A + sp.diags(d) + (0 if full is None else full)
            kind = "spd" if full is None else "general"
        try:
            return -factorize(J, kind=kind, dense_limit=len(d)).solve(r)
        except (np.linalg.LinAlgError, RuntimeError) as error:
            return f"the Jacobian of the heat balance is singular ({error})"

    def apply(self, dx, scale):
        self.u += dx


def solve_heat_balance(A, loss: NonlinearLoss, q, u0=None) -> HeatBalance:
    """Solve ``A u + loss.flux(u) = q`` for the rises ``u`` (m,) [K] by Newton's method.

    Parameters
    ----------
    A : (m, m) array or sparse
        The linear conductance [W/K] (the sheet's conduction), symmetric.
    loss : NonlinearLoss
    q : (m,) array
        Heat input [W].
    u0 : (m,) array, optional
        Start (default zero: the first correction is then the linear solve at the medium's
        conductivity at room temperature).

    The residual's 2-norm must fall to :data:`HEAT_BALANCE_RTOL` times the heat input's (or
    the correction to round-off, 1e-13 K); failures are returned as data (status "failed").
    """
    q = np.asarray(q, float)
    m = len(q)
    problem = _Problem(A, loss, q, np.zeros(m) if u0 is None else u0)
    if m == 0:
        return HeatBalance(True, "converged", "converged (no unknowns)", problem.u, 0, [])
    atol = HEAT_BALANCE_RTOL * max(math.sqrt(q @ q), 1e-300)
    it = iterate(problem, max_iter=_MAX_ITER, atol=atol, rtol=0.0, size=1.0,
                 criterion="residual", max_step=_MAX_STEP)
    if it.success:
        message = (f"converged in {it.iterations} Newton iterations (residual "
                   f"{it.residual_norms[-1]:.3g} W)")
    else:
        message = (f"the nonlinear heat balance did not converge: {it.message.replace(' N)', ' W)')}"
                   f" (residual {it.residual_norms[-1]:.3g} W of a heat input {math.sqrt(q @ q):.3g}"
                   " W)")
    logger.debug("heat balance: %s", message)
    return HeatBalance(it.success, "converged" if it.success else "failed", message, problem.u,
                       it.iterations, list(it.residual_norms))
