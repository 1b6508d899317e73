"""Simulation state, loading steps and the :func:`simulate` facade.

A simulation is an ordered list of loading steps (self-folding, dead loads,
gravity, and in later versions heating) applied to a :class:`SimulationState`
that each step hands to the next: displacements, accumulated loads, crease and
spring rest angles and temperatures persist (the reference's controller list,
digest 7.1).
"""

from __future__ import annotations

import logging
import time
import weakref
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from .elements.springs import fold_angle
from .equilibrium import EquilibriumSystem
from .errors import ConvergenceError, ParameterError
from .model import STANDARD_GRAVITY, Model, gravity_loads
from .properties import spring_rest_angles
from .results import SimulationResult, StepResult
from .solvers import NewtonOptions, PathResult, follow_path

__all__ = ["SimulationState", "initial_state", "SelfFold", "Load", "Gravity", "StepResult",
           "SimulationResult", "StepRun", "simulate", "equilibrium_system", "ROOM_TEMPERATURE"]

logger = logging.getLogger(__name__)

#: Default room temperature [deg C].
ROOM_TEMPERATURE = 21.0


@dataclass(frozen=True, eq=False)
class SimulationState:
    """State handed from one loading step to the next.

    Attributes
    ----------
    u : (n_nodes, 3) displacements from the mesh nodes [m]
    applied_load : (n_nodes, 3) accumulated dead loads (incl. gravity) [N]
    crease_rest : (C,) crease rest angles [rad], pi = flat (crease-row order)
    spring_rest : (n_springs,) spring rest angles [rad]
    temperature : (n_nodes,) node temperatures [deg C]
    crease_power : (C,) heating power applied to each crease [W]
    room_temperature : float
        Ambient (room) temperature of the thermal boundary conditions [deg C].
    """

    u: np.ndarray
    applied_load: np.ndarray
    crease_rest: np.ndarray
    spring_rest: np.ndarray
    temperature: np.ndarray
    crease_power: np.ndarray
    room_temperature: float = ROOM_TEMPERATURE

    @property
    def rest_fold(self) -> np.ndarray:
        """Crease rest fold angles [rad], 0 = flat, positive towards +z."""
        return self.crease_rest - np.pi


def initial_state(model: Model, room_temperature: float | None = None) -> SimulationState:
    """Unloaded state: zero displacement, flat crease rest angles, spring rest angles equal to
    the spring angles of the initial geometry (digest 7.1), uniform room temperature (from the
    model's thermal parameters, else 21 deg C), no heating."""
    mesh = model.mesh
    if room_temperature is None:
        room_temperature = ROOM_TEMPERATURE if model.thermal is None \
            else model.thermal.room_temperature
    return SimulationState(
        u=np.zeros((mesh.n_nodes, 3)), applied_load=np.zeros((mesh.n_nodes, 3)),
        crease_rest=np.full(mesh.n_creases, np.pi),
        spring_rest=fold_angle(mesh.nodes[mesh.springs]),
        temperature=np.full(mesh.n_nodes, float(room_temperature)),
        crease_power=np.zeros(mesh.n_creases), room_temperature=float(room_temperature))


_SYSTEMS: "weakref.WeakKeyDictionary[Model, EquilibriumSystem]" = weakref.WeakKeyDictionary()


def equilibrium_system(model: Model) -> EquilibriumSystem:
    """The cached :class:`EquilibriumSystem` of a model (built on first use)."""
    sys = _SYSTEMS.get(model)
    if sys is None:
        sys = _SYSTEMS[model] = EquilibriumSystem(model)
    return sys


@dataclass
class StepRun:
    """What a loading step returns to :func:`simulate` (internal)."""

    converged: bool
    status: str
    message: str
    state: SimulationState
    f_ext: np.ndarray
    iterations: int = 0
    cuts: int = 0
    load_factor: list = field(default_factory=list)
    u: list = field(default_factory=list)
    temperature: list = field(default_factory=list)
    power: list = field(default_factory=list)
    increment_iterations: list = field(default_factory=list)
    residual_norms: list = field(default_factory=list)
    evaluation: object = None
    settings: dict = field(default_factory=dict)


def run_from_path(path: PathResult, state: SimulationState, f_ext: np.ndarray,
                  settings: dict) -> StepRun:
    """A :class:`StepRun` of a purely mechanical step (temperatures and powers unchanged)."""
    return StepRun(
        converged=path.converged, status=path.status, message=path.message, state=state,
        f_ext=f_ext, iterations=path.iterations, cuts=path.cuts,
        load_factor=[h[0] for h in path.history], u=[h[1] for h in path.history],
        temperature=[state.temperature] * len(path.history),
        power=[state.crease_power] * len(path.history),
        increment_iterations=[h[2] for h in path.history], residual_norms=path.residual_norms,
        evaluation=path.evaluation, settings=settings)


# ---------------------------------------------------------------------------- steps
def _check_increments(step) -> None:
    n = step.increments
    if not (isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 1):
        raise ParameterError(f"{type(step).__name__}.increments = {n!r} must be a positive integer.")


@dataclass(frozen=True)
class SelfFold:
    """Drive crease rest angles linearly to target fold angles (digest 7.3).

    Parameters
    ----------
    folds : mapping {crease id: fold angle [rad]}
        Target rest fold angle (0 = flat, > 0 towards +z) of the listed creases.
    increments : int
    reset_others : bool
        Unlisted creases go to flat (True, the reference behaviour) or keep their rest angle.
    """

    folds: Mapping = field(default_factory=dict)
    increments: int = 50
    reset_others: bool = True
    name: str = "self_fold"

    def __post_init__(self):
        _check_increments(self)
        for c, v in dict(self.folds).items():
            if not np.isfinite(v):
                raise ParameterError(f"SelfFold: fold angle of crease {c} is {v!r}; give radians.")

    def run(self, model, system, state, options):
        mesh = model.mesh
        target = np.full(mesh.n_creases, np.pi) if self.reset_others else state.crease_rest.copy()
        for c, v in dict(self.folds).items():
            target[mesh.crease_row_of(c)] = np.pi + float(v)
        rest_end = spring_rest_angles(mesh, target, model.params)
        f = state.applied_load.ravel()
        path = follow_path(system, state.u, f, f, state.spring_rest, rest_end, self.increments,
                           options)
        t = path.t
        new = replace(state, u=path.u, crease_rest=state.crease_rest + t * (target - state.crease_rest),
                      spring_rest=state.spring_rest + t * (rest_end - state.spring_rest))
        return run_from_path(path, new, f, {"folds [rad]": {str(k): float(v) for k, v in
                                                          dict(self.folds).items()},
                                            "increments": self.increments})


@dataclass(frozen=True)
class Load:
    """Add dead loads linearly over the step; they stay applied in later steps (digest 7.4).

    Parameters
    ----------
    forces : mapping {node: (fx, fy, fz)} or (n_nodes, 3) array
        TOTAL load added by this step [N] (the reference gives it per increment).
    increments : int
    """

    forces: object
    increments: int = 50
    name: str = "load"

    def __post_init__(self):
        _check_increments(self)

    def load_array(self, model: Model) -> np.ndarray:
        n = model.mesh.n_nodes
        if isinstance(self.forces, Mapping):
            out = np.zeros((n, 3))
            for node, fvec in self.forces.items():
                if not (isinstance(node, (int, np.integer)) and 0 <= node < n):
                    raise ParameterError(f"Load: node {node!r} does not exist (0..{n - 1}).")
                out[node] += np.asarray(fvec, float)
        else:
            out = np.asarray(self.forces, float)
            if out.shape != (n, 3):
                raise ParameterError(f"Load: forces must be a mapping or an ({n}, 3) array, got "
                                     f"shape {out.shape}.")
        if not np.isfinite(out).all():
            raise ParameterError("Load: forces contain NaN or inf.")
        return out

    def run(self, model, system, state, options):
        dF = self.load_array(model)
        f0 = state.applied_load.ravel()
        path = follow_path(system, state.u, f0, f0 + dF.ravel(), state.spring_rest,
                           state.spring_rest, self.increments, options)
        new = replace(state, u=path.u, applied_load=state.applied_load + path.t * dF)
        return run_from_path(path, new, new.applied_load.ravel(),
                             {"total_load [N]": dF.sum(axis=0).tolist(),
                              "increments": self.increments})


@dataclass(frozen=True)
class Gravity:
    """Apply panel self-weight (lumped by fan-triangle areas) as a persisting dead load.

    Parameters
    ----------
    g : float
        Gravitational acceleration [m/s^2] (the reference scripts use 9.8).
    scale : float
        Factor on the weight (the reference's Ex02 applies 0.9 of it).
    panels : sequence of int or None
        Panels that carry weight (default all; supported panels only add reactions).
    increments : int
    """

    g: float = STANDARD_GRAVITY
    scale: float = 1.0
    panels: tuple | None = None
    increments: int = 50
    name: str = "gravity"

    def __post_init__(self):
        _check_increments(self)
        if not np.isfinite(self.scale):
            raise ParameterError(f"Gravity.scale = {self.scale!r} must be finite.")

    def run(self, model, system, state, options):
        load = Load(self.scale * gravity_loads(model.mesh, self.g, panels=self.panels),
                    self.increments)
        run = load.run(model, system, state, options)
        run.settings = {"g [m/s^2]": self.g, "scale": self.scale, "increments": self.increments,
                        "panels": None if self.panels is None else list(self.panels)}
        return run


# ---------------------------------------------------------------------------- facade
def simulate(model: Model, steps, state: SimulationState | None = None,
             options: NewtonOptions = NewtonOptions(), progress=None) -> SimulationResult:
    """Run loading steps in order, each starting from the state the previous one left.

    Stops after the first step that fails (its result says why); raises
    :class:`~simulator.errors.ConvergenceError` then only if ``options.raise_on_failure``.
    ``progress(done, total)``, if given, is called after every increment of steps that
    report progress (heating).
    """
    if not isinstance(model, Model):
        raise ParameterError(f"simulate expects a Model, got {type(model).__name__}.")
    steps = list(steps)
    for s in steps:
        if not hasattr(s, "run"):
            raise ParameterError(f"{s!r} is not a loading step (SelfFold, Load, Gravity, Heat, "
                                 "...).")
    system = equilibrium_system(model)
    start = initial_state(model) if state is None else state
    state = start
    results = []
    t_start = time.perf_counter()
    for step in steps:
        t0 = time.perf_counter()
        run = step.run(model, system, state, options, progress) if getattr(
            step, "reports_progress", False) else step.run(model, system, state, options)
        results.append(_step_result(step, run, system, time.perf_counter() - t0))
        state = run.state
        logger.info("step %s: %s, %d increments, %d Newton iterations, %d cuts",
                    step.name, run.status, len(run.u), run.iterations, run.cuts)
        if not run.converged:
            break
    result = SimulationResult(results, state, model, start, options.to_dict(),
                              time.perf_counter() - t_start)
    if not result.converged and options.raise_on_failure:
        raise ConvergenceError(result.message, result)
    return result


def _step_result(step, run: StepRun, system, wall) -> StepResult:
    state = run.state
    ev = run.evaluation or system.evaluate(state.u, state.spring_rest, hessian=False)
    fixed = system.free_index < 0
    reactions = np.where(fixed, ev.f_int - run.f_ext, 0.0).reshape(-1, 3)
    n, C = state.u.shape, state.crease_power.shape
    return StepResult(
        name=step.name, converged=run.converged, status=run.status, message=run.message,
        state=state, iterations=run.iterations, cuts=run.cuts,
        load_factor=np.array(run.load_factor),
        u_history=np.array(run.u).reshape(-1, *n),
        temperature_history=np.array(run.temperature).reshape(-1, n[0]),
        power_history=np.array(run.power).reshape(-1, *C),
        increment_iterations=np.array(run.increment_iterations, dtype=int),
        residual_norms=run.residual_norms, reactions=reactions, energies=ev.energies,
        wall_time=wall, settings=run.settings)
