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
from .._validate import integer, positive
from ..errors import ParameterError
from ..events import CrossingWatch, renumbered, stops
from ..mechanics.rest_angles import spring_rest_angles
from .base import Step, StepContext, StepOutcome, StepRecorder
from .drives import MechanicalDrive, check_fold_drive, check_force_drive, describe_drive
from .mechanical import node_vectors

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
    forces : mapping {node: (fx, fy, fz) or ((fx, fy, fz), schedule)} or (n_nodes, 3) array
        Load [N] added to the dead loads of earlier steps: a constant vector suddenly at t = 0,
        or the vector times a :class:`~simulator.schedules.Schedule` of the step time
        (:mod:`simulator.steps.drives`); the value at the end stays applied afterwards (like
        :class:`~simulator.steps.Load`). The negative of an earlier load releases the
        structure from its displaced state.
    velocity : mapping {node: (vx, vy, vz)} or (n_nodes, 3) array, optional
        Initial velocities [m/s]; default the state's (zero after quasi-static steps). Fixed DOFs
        are set to zero.
    folds : mapping {crease id: fold angle [rad] or schedule}, optional
        Crease rest fold angles, set suddenly at t = 0 or driven in time by a schedule of the
        step time [rad] (e.g. ``SineSignal(amplitude, frequency, offset=fold0)``; unlisted
        creases keep theirs).
    options : DynamicsOptions
        Scheme ("newmark", "hht", "generalized_alpha"), damping and Newton settings.
    record_every : int
        Record every this many time steps (and the last).

    Notes
    -----
    The first record (increment 0) is the start state at the start time (its velocities those
    the step starts with). Every record carries the columns ``time [s]`` (time of the
    simulation, continuing from earlier time-domain steps), ``kinetic_energy [J]``,
    ``strain_energy [J]``, ``dissipated_energy [J]``, ``external_work [J]`` and
    ``numerical_dissipation [J]`` (energies and work counted from the start of the step).
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
        positive("Dynamics.duration", self.duration, "s")
        positive("Dynamics.dt", self.dt, "s", hint="give the time step in seconds")
        if not isinstance(self.options, DynamicsOptions):
            raise ParameterError(f"Dynamics.options is a {type(self.options).__name__}; give "
                                 "DynamicsOptions(...).")
        integer("Dynamics.record_every", self.record_every)
        check_fold_drive("Dynamics", self.folds)
        check_force_drive("Dynamics", self.forces)

    def run(self, context: StepContext, state) -> StepOutcome:
        model = context.model
        n = model.mesh.n_nodes
        drive = MechanicalDrive(model, state, self.forces, self.folds, "Dynamics")
        load, crease_rest, spring_rest = drive.load0, drive.crease0, state.spring_rest
        if drive.changed_rest:
            spring_rest = spring_rest_angles(model.mesh, crease_rest, model.params)
        # time schedules: functions of the step time
        f_ext = drive.load if drive.force_terms else load
        rest = drive.spring_rest if drive.fold_terms else spring_rest
        v0 = state.node_velocity if self.velocity is None \
            else node_vectors(self.velocity, n, "Dynamics", "velocity")
        total = max(1, int(np.ceil(self.duration / self.dt * (1 - 1e-12))))
        done, found = [0], []
        watch = CrossingWatch(model.mesh, state.u, model.supports)

        def callback(motion):
            done[0] += 1
            context.report(done[0], total)
            event = watch.check(motion.u, 0, motion.time / self.duration,
                                state.crease_power, state.temperature)
            if event is not None:          # panels through each other: stop (and record)
                found.append((event, motion.time))
            return stops(event)

        res = integrate(context.system, state.u, v0, self.duration, self.dt, f_ext, rest,
                        self.options, record_every=self.record_every, callback=callback)
        rec = StepRecorder(state)
        rec.iterations, rec.cuts = int(res.iterations.sum()), res.cuts
        energies = res.energies
        for k in range(len(res.time)):                 # record 0: the start, at its time
            columns = {"time [s]": state.time + res.time[k],
                       **{name: float(e[k]) for name, e in energies.items()}}
            if k == 0:
                rec.record_start(velocity=res.v[0], **columns)
                continue
            rec.record(res.time[k] / self.duration, res.u[k], state.temperature,
                       state.crease_power, int(res.iterations[k]), velocity=res.v[k],
                       **columns)
        status, message = res.status, res.message
        for event, time in found:          # at the first record at or after it
            k = min(int(np.searchsorted(res.time, time * (1 - 1e-12))), len(rec) - 1)
            event = renumbered(event, k)
            rec.events.append(event)
            if stops(event):               # the last record (the stop state)
                status = "panel_crossing"
                message = f"at t = {state.time + res.time[-1]:.6g} s: {event.message}"
        end = res.state
        if drive.force_terms:               # the drives' values at the end persist
            load = drive.load(end.time)
        if drive.fold_terms:
            crease_rest, spring_rest = drive.crease_rest(end.time), end.spring_rest
        new = replace(state, u=end.u, velocity=end.v, applied_load=load.reshape(n, 3),
                      crease_rest=crease_rest, spring_rest=spring_rest,
                      time=state.time + end.time)
        return rec.finish(res.success and status != "panel_crossing", status, message, new,
                          load.ravel(), end.evaluation)

    def describe(self) -> dict:
        return {"duration [s]": self.duration, "dt [s]": self.dt,
                **describe_drive(self.forces, self.folds),
                "initial_velocity": self.velocity is not None,
                "record_every": self.record_every, **self.options.to_dict()}
