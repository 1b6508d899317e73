"""Implicit nonlinear time integration of the bar-and-hinge mechanics (theory 8.2).

:func:`integrate` runs a whole integration and returns its time history with the energy
bookkeeping (:class:`DynamicsResult`: kinetic, strain, dissipated energy, external work and the
scheme's numerical dissipation). One time step, the equation of motion, the damping and the
generalized-alpha family are in :mod:`simulator.solvers.generalized_alpha`
(:class:`~simulator.solvers.generalized_alpha.TimeIntegrator`,
:class:`~simulator.solvers.generalized_alpha.MotionState`,
:class:`~simulator.solvers.generalized_alpha.StepReport`), the settings in
:mod:`simulator.solvers.dynamics_options` (:class:`~simulator.solvers.dynamics_options.DynamicsOptions`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from .dynamics_options import DynamicsOptions
from .._result import ResultFiles
from .._validate import integer, positive
from ..mechanics.equilibrium import EquilibriumSystem
from .generalized_alpha import MotionState, TimeIntegrator

__all__ = ["DynamicsResult", "integrate"]

logger = logging.getLogger(__name__)


# ---------------------------------------------------------------------- whole integrations
ENERGY_COLUMNS = ("kinetic_energy [J]", "strain_energy [J]", "dissipated_energy [J]",
                  "external_work [J]", "numerical_dissipation [J]")


@dataclass(frozen=True, eq=False)
class DynamicsResult(ResultFiles):
    """Time history of :func:`integrate` (record 0 = the initial state).

    Attributes
    ----------
    success, status, message
        status "converged", "failed" (a step did not converge after ``max_cuts`` halvings) or
        "stopped" (by the callback).
    time : (m,) [s]
    u, v, a : (m, n_nodes, 3) displacements [m], velocities [m/s], accelerations [m/s^2]
    kinetic, strain : (m,) kinetic energy 1/2 v.M v and internal energy [J]
    dissipated : (m,) energy taken out by Rayleigh and air damping since t_0 [J] (the
        trapezoidal damping work of the scheme; exact for linear problems; when stiff modes ring
        in a strongly nonlinear motion only its sum with :attr:`numerical_dissipation` is
        meaningful)
    external_work : (m,) work of the external loads since t_0 [J]
    iterations : (m,) Newton iterations of the step ending at each record (0 for record 0)
    cuts : int
        Step halvings in all.
    state : MotionState
        The last accepted state.
    """

    success: bool
    status: str
    message: str
    time: np.ndarray
    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    kinetic: np.ndarray
    strain: np.ndarray
    dissipated: np.ndarray
    external_work: np.ndarray
    iterations: np.ndarray
    cuts: int
    state: MotionState = field(repr=False)

    @property
    def numerical_dissipation(self) -> np.ndarray:
        """(m,) energy lost to the scheme [J]: external work - damping - change of kinetic +
        strain energy. Zero for "newmark" on linear problems; positive for dissipative schemes
        (up to the error of the trapezoidal work estimate in nonlinear ones)."""
        total = self.kinetic + self.strain
        return self.external_work - self.dissipated - (total - total[0])

    @property
    def energies(self) -> dict:
        """{column name: (m,) array} for :data:`ENERGY_COLUMNS` [J]."""
        return dict(zip(ENERGY_COLUMNS, (self.kinetic, self.strain, self.dissipated,
                                         self.external_work, self.numerical_dissipation)))

    def to_frame(self):
        """One row per record: ``time [s]``, the energy columns [J], ``iterations``."""
        import pandas as pd

        return pd.DataFrame({"time [s]": self.time, **self.energies,
                             "iterations": self.iterations})

    _csv_name = "dynamics.csv"

    def _meta(self) -> dict:
        return {"records": len(self.time), "end_time [s]": float(self.time[-1]),
                "cuts": self.cuts}


def integrate(system: EquilibriumSystem, u0, v0, duration: float, dt: float, f_ext,
              spring_rest, options: DynamicsOptions = DynamicsOptions(), masses=None,
              record_every: int = 1, callback=None) -> DynamicsResult:
    """Integrate the motion from (u0, v0) over ``duration`` [s] with time step ``dt`` [s].

    Parameters
    ----------
    system : EquilibriumSystem
        E.g. :func:`~simulator.mechanics.equilibrium_system` of a model.
    u0, v0 : (n_nodes, 3) initial displacements [m] and velocities [m/s]
    f_ext : (n_dof,) or (n_nodes, 3) array, or callable ``t -> array``
        External load [N] (a constant array is applied suddenly at t = 0).
    spring_rest : (n_springs,) array or callable ``t -> array``
        Spring rest angles [rad].
    options : DynamicsOptions
    masses : (n_nodes,) nodal masses [kg], optional (default lumped from the densities)
    record_every : int
        Keep every this many steps (and the last) in the history.
    callback : callable, optional
        ``callback(state)`` after every step; returning True stops (status "stopped").

    Returns
    -------
    DynamicsResult
        Never raises on non-convergence (status "failed"); raises
        :class:`~simulator.errors.ParameterError` on bad input.
    """
    n_steps, last_dt = _step_count(duration, dt)
    integer("record_every", record_every)
    load = f_ext if callable(f_ext) else (lambda t, f=np.asarray(f_ext, float).ravel(): f)
    rest = spring_rest if callable(spring_rest) else \
        (lambda t, r=np.asarray(spring_rest, float): r)
    integ = TimeIntegrator(system, options, masses)
    state = integ.initial_state(u0, v0, np.ravel(load(0.0)), rest(0.0))
    records = [_row(integ, state, 0.0, 0.0, 0)]
    dissipated = work = 0.0
    status, message, cuts = "converged", f"integrated {n_steps} steps", 0
    for k in range(1, n_steps + 1):
        h = dt if k < n_steps else last_dt
        t = state.time + h
        rep = integ.step(state, h, np.ravel(load(t)), rest(t))
        cuts += rep.cuts
        if not rep.success:
            status, message = "failed", (f"time step {k} to t = {t:.6g} s failed after "
                                         f"{rep.cuts} halvings: {rep.message}")
            logger.info(message)  # data: the result says it failed, the caller reports it
            break
        state = rep.state
        dissipated += rep.dissipated
        work += rep.external_work
        stop = callback is not None and bool(callback(state))
        if k % record_every == 0 or k == n_steps or stop:
            records.append(_row(integ, state, dissipated, work, rep.iterations))
        if stop:
            status, message = "stopped", f"stopped by callback at t = {state.time:.6g} s"
            break
    cols = list(zip(*records))
    arr = [np.array(c) for c in cols]
    return DynamicsResult(status == "converged", status, message, *arr[:8],
                          iterations=arr[8].astype(int), cuts=cuts, state=state)


def _row(integ, s: MotionState, dissipated, work, iterations):
    vf = s.v.ravel()[integ.system.free]
    return (s.time, s.u, s.v, s.a, 0.5 * float(vf @ (integ.m * vf)), s.strain_energy,
            dissipated, work, iterations)


def _step_count(duration, dt) -> tuple[int, float]:
    """Number of steps and the length of the last one (shortened to end at ``duration``)."""
    positive("time step dt", dt, "s")
    positive("duration", duration, "s")
    n = max(1, math.ceil(duration / dt * (1 - 1e-12)))
    return n, duration - (n - 1) * dt
