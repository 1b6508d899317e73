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
from .solvers import NewtonOptions, PathResult, follow_path

__all__ = ["SimulationState", "initial_state", "SelfFold", "Load", "Gravity", "StepResult",
           "SimulationResult", "simulate", "equilibrium_system", "ROOM_TEMPERATURE"]

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
    """

    u: np.ndarray
    applied_load: np.ndarray
    crease_rest: np.ndarray
    spring_rest: np.ndarray
    temperature: np.ndarray

    @property
    def rest_fold(self) -> np.ndarray:
        """Crease rest fold angles [rad], 0 = flat, positive towards +z."""
        return self.crease_rest - np.pi


def initial_state(model: Model, room_temperature: float = ROOM_TEMPERATURE) -> SimulationState:
    """Unloaded state: zero displacement, flat crease rest angles, spring rest angles equal to
    the spring angles of the initial geometry (digest 7.1), uniform room temperature."""
    mesh = model.mesh
    return SimulationState(
        u=np.zeros((mesh.n_nodes, 3)), applied_load=np.zeros((mesh.n_nodes, 3)),
        crease_rest=np.full(mesh.n_creases, np.pi),
        spring_rest=fold_angle(mesh.nodes[mesh.springs]),
        temperature=np.full(mesh.n_nodes, float(room_temperature)))


_SYSTEMS: "weakref.WeakKeyDictionary[Model, EquilibriumSystem]" = weakref.WeakKeyDictionary()


def equilibrium_system(model: Model) -> EquilibriumSystem:
    """The cached :class:`EquilibriumSystem` of a model (built on first use)."""
    sys = _SYSTEMS.get(model)
    if sys is None:
        sys = _SYSTEMS[model] = EquilibriumSystem(model)
    return sys


@dataclass(frozen=True, eq=False)
class StepResult:
    """Result of one loading step.

    Attributes
    ----------
    name : str
    converged : bool
    status : str
        "converged", "failed" or "stopped".
    message : str
    state : SimulationState
        State at the end of the step (the last converged one if it failed).
    iterations, cuts : int
        Total Newton iterations and increment halvings.
    load_factor : (m,) path parameter of every accepted increment, in (0, 1]
    u_history : (m, n_nodes, 3) displacements after every accepted increment [m]
    residual_norms : list of (k,) arrays, Newton residual norms of each accepted increment [N]
    reactions : (n_nodes, 3) support reactions on the structure at the end [N]
    energies : dict of energy components at the end [J]
    wall_time : float [s]
    """

    name: str
    converged: bool
    status: str
    message: str
    state: SimulationState
    iterations: int
    cuts: int
    load_factor: np.ndarray
    u_history: np.ndarray
    residual_norms: list
    reactions: np.ndarray
    energies: dict
    wall_time: float

    @property
    def increments(self) -> int:
        return len(self.load_factor)


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Results of all steps of :func:`simulate` and the final state."""

    steps: list
    state: SimulationState
    model: Model = field(repr=False, default=None)

    @property
    def converged(self) -> bool:
        return all(s.converged for s in self.steps)

    @property
    def status(self) -> str:
        bad = [s for s in self.steps if not s.converged]
        return "converged" if not bad else bad[0].status

    @property
    def message(self) -> str:
        bad = [s for s in self.steps if not s.converged]
        return "all steps converged" if not bad else f"step {bad[0].name!r}: {bad[0].message}"


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
        return path, new, f


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
        return path, new, new.applied_load.ravel()


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
        return load.run(model, system, state, options)


# ---------------------------------------------------------------------------- facade
def simulate(model: Model, steps, state: SimulationState | None = None,
             options: NewtonOptions = NewtonOptions()) -> SimulationResult:
    """Run loading steps in order, each starting from the state the previous one left.

    Stops after the first step that fails (its result says why); raises
    :class:`~simulator.errors.ConvergenceError` then only if ``options.raise_on_failure``.
    """
    if not isinstance(model, Model):
        raise ParameterError(f"simulate expects a Model, got {type(model).__name__}.")
    steps = list(steps)
    for s in steps:
        if not hasattr(s, "run"):
            raise ParameterError(f"{s!r} is not a loading step (SelfFold, Load, Gravity, ...).")
    system = equilibrium_system(model)
    state = initial_state(model) if state is None else state
    results = []
    for step in steps:
        t0 = time.perf_counter()
        path, new_state, f_ext = step.run(model, system, state, options)
        results.append(_step_result(step, path, new_state, f_ext, system, time.perf_counter() - t0))
        state = new_state
        logger.info("step %s: %s, %d increments, %d Newton iterations, %d cuts",
                    step.name, path.status, len(path.history), path.iterations, path.cuts)
        if not path.converged:
            result = SimulationResult(results, state, model)
            if options.raise_on_failure:
                raise ConvergenceError(result.message, result)
            return result
    return SimulationResult(results, state, model)


def _step_result(step, path: PathResult, state, f_ext, system, wall) -> StepResult:
    ev = path.evaluation or system.evaluate(state.u, state.spring_rest, hessian=False)
    fixed = system.free_index < 0
    reactions = np.where(fixed, ev.f_int - f_ext, 0.0).reshape(-1, 3)
    n = state.u.shape
    return StepResult(
        name=step.name, converged=path.converged, status=path.status, message=path.message,
        state=state, iterations=path.iterations, cuts=path.cuts,
        load_factor=np.array([h[0] for h in path.history]),
        u_history=np.array([h[1] for h in path.history]).reshape(-1, *n),
        residual_norms=path.residual_norms, reactions=reactions, energies=ev.energies,
        wall_time=wall)
