"""Time-integration step: the structure moves under inertia (theory 8.2).

:class:`Dynamics` integrates the equation of motion over a duration with
:func:`~simulator.solvers.dynamics.integrate` from the state the previous step left: free vibration from
initial velocities, the response to a suddenly applied (or removed) load, release from a
displaced state, or a sudden change of crease rest angles. Unlike the reference, dead loads of
earlier steps stay applied, supported DOFs keep their displacements (theory 8.6) and the
velocities carry over to a following dynamic step (``SimulationState.velocity``).

Choosing the scheme: the default (undamped average acceleration) is right for free vibration
and conserves energy. A sudden rest-angle change or an impact on a contact layer also excites
the very stiff modes of the crease nodes; use ``DynamicsOptions(method="generalized_alpha",
rho_inf=0.0, rayleigh_beta=1e-6)`` (or similar) there, which removes them within a few steps
while leaving the fold modes practically undamped (zeta = beta omega / 2).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from ..solvers.dynamics import integrate
from ..solvers.dynamics_options import DynamicsOptions
from ..errors import ParameterError
from ..model.properties import spring_rest_angles
from .base import Step, StepContext, StepOutcome, StepRecorder
from .mechanical import check_folds, crease_targets, node_vectors

__all__ = ["Dynamics"]


@dataclass(frozen=True)
class Dynamics(Step):
    """Integrate the motion for ``duration`` seconds with time step ``dt``.

    Parameters
    ----------
    duration : float
        Length of the step [s], > 0.
    dt : float
        Time step [s], > 0 (the last step is shortened to end at ``duration``).
    forces : mapping {node: (fx, fy, fz)} or (n_nodes, 3) array, optional
        Load [N] added suddenly at t = 0 to the dead loads of earlier steps; it stays applied
        afterwards (like :class:`~simulator.steps.Load`). The negative of an earlier load
        releases the structure from its displaced state.
    velocity : mapping {node: (vx, vy, vz)} or (n_nodes, 3) array, optional
        Initial velocities [m/s]; default the state's (zero after quasi-static steps). Fixed DOFs
        are set to zero.
    folds : mapping {crease id: fold angle [rad]}, optional
        Crease rest fold angles set suddenly at t = 0 (unlisted creases keep theirs).
    options : DynamicsOptions
        Scheme ("newmark", "hht", "generalized_alpha"), damping and Newton settings.
    record_every : int
        Record every this many time steps (and the last).

    Notes
    -----
    Every record carries the columns ``time [s]`` (time of the simulation, continuing from
    earlier dynamic steps), ``kinetic_energy [J]``, ``strain_energy [J]``,
    ``dissipated_energy [J]``, ``external_work [J]`` and ``numerical_dissipation [J]`` (energies
    and work counted from the start of the step).
    """

    duration: float
    dt: float
    forces: object = None
    velocity: object = None
    folds: Mapping = field(default_factory=dict)
    options: DynamicsOptions = DynamicsOptions()
    record_every: int = 1
    name: str = "dynamics"

    def __post_init__(self):
        for attr in ("duration", "dt"):
            v = getattr(self, attr)
            if not (isinstance(v, (int, float, np.integer, np.floating))
                    and not isinstance(v, bool) and np.isfinite(v) and v > 0):
                raise ParameterError(f"Dynamics.{attr} = {v!r} must be a positive number of "
                                     "seconds.")
        if not isinstance(self.options, DynamicsOptions):
            raise ParameterError(f"Dynamics.options is a {type(self.options).__name__}; give "
                                 "DynamicsOptions(...).")
        if not (isinstance(self.record_every, int) and self.record_every >= 1):
            raise ParameterError(f"Dynamics.record_every = {self.record_every!r} must be a "
                                 "positive integer.")
        check_folds(self.folds, "Dynamics")

    def run(self, context: StepContext, state) -> StepOutcome:
        model = context.model
        mesh, n = model.mesh, model.mesh.n_nodes
        load = state.applied_load
        if self.forces is not None:
            load = load + node_vectors(self.forces, n, "Dynamics", "forces")
        crease_rest, spring_rest = state.crease_rest, state.spring_rest
        if self.folds:
            crease_rest = crease_targets(mesh, self.folds, state.crease_rest)
            spring_rest = spring_rest_angles(mesh, crease_rest, model.params)
        v0 = state.node_velocity if self.velocity is None \
            else node_vectors(self.velocity, n, "Dynamics", "velocity")
        total = max(1, int(np.ceil(self.duration / self.dt * (1 - 1e-12))))
        done = [0]

        def callback(_):
            done[0] += 1
            context.report(done[0], total)
            return False

        res = integrate(context.system, state.u, v0, self.duration, self.dt, load.ravel(),
                        spring_rest, self.options, record_every=self.record_every,
                        callback=callback)
        rec = StepRecorder(state)
        rec.iterations, rec.cuts = int(res.iterations.sum()), res.cuts
        energies = res.energies
        for k in range(1, len(res.time)):
            columns = {"time [s]": state.time + res.time[k],
                       **{name: float(e[k]) for name, e in energies.items()}}
            rec.record(res.time[k] / self.duration, res.u[k], state.temperature,
                       state.crease_power, int(res.iterations[k]), velocity=res.v[k],
                       **columns)
        end = res.state
        new = replace(state, u=end.u, velocity=end.v, applied_load=load,
                      crease_rest=crease_rest, spring_rest=spring_rest,
                      time=state.time + end.time)
        return rec.finish(res.success, res.status, res.message, new, load.ravel(),
                          end.evaluation)

    def describe(self) -> dict:
        forces = None
        if isinstance(self.forces, Mapping):
            forces = {str(k): list(np.asarray(v, float)) for k, v in self.forces.items()}
        elif self.forces is not None:
            forces = np.asarray(self.forces, float).sum(axis=0).tolist()
        return {"duration [s]": self.duration, "dt [s]": self.dt, "forces [N]": forces,
                "initial_velocity": self.velocity is not None,
                "folds [rad]": {str(k): float(v) for k, v in dict(self.folds).items()},
                "record_every": self.record_every, **self.options.to_dict()}
