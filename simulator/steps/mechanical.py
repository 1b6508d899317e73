"""Mechanical loading steps under load control: self-folding, dead loads, gravity.

Each step drives a linear path in (external load, spring rest angles) with
:func:`~simulator.solvers.newton.follow_path` (Newton with step cutting); loads and rest angles
persist into later steps (theory 6.4, 6.5).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from .._validate import array, finite
from ..errors import ParameterError
from ..events import CrossingWatch, stops
from ..solvers.load_path import LoadPath
from ..model.model import STANDARD_GRAVITY, Model, gravity_loads
from ..solvers.newton import follow_path
from ..mechanics.rest_angles import spring_rest_angles
from .base import Step, StepContext, StepOutcome, StepRecorder, check_increments
from ..state import at_rest
from .limit import check_on_limit_point, continue_past_limit

__all__ = ["SelfFold", "Load", "Gravity", "node_vectors", "check_folds", "crease_targets"]


def check_folds(folds, step: str) -> None:
    """Raise :class:`ParameterError` unless every fold angle [rad] is finite and in (-pi, pi]."""
    for c, v in dict(folds).items():
        if not (isinstance(v, (int, float, np.integer, np.floating)) and np.isfinite(v)):
            raise ParameterError(f"{step}: fold angle of crease {c} is {v!r}; give radians.")
        if not -np.pi < v <= np.pi:
            raise ParameterError(
                f"{step}: fold angle of crease {c} is {np.degrees(v):.6g} deg; fold "
                "angles must lie in (-180, 180] deg (give radians in Python).")


def crease_targets(mesh, folds, base: np.ndarray) -> np.ndarray:
    """(C,) crease rest angles [rad]: ``base`` with the listed creases set to pi + fold."""
    target = np.array(base, float)
    for c, v in dict(folds).items():
        target[mesh.crease_row_of(c)] = np.pi + float(v)
    return target


def node_vectors(value, n: int, step: str, name: str) -> np.ndarray:
    """(n, 3) array from a mapping {node: (x, y, z)} (summed per node) or an (n, 3) array.

    ``step`` and ``name`` (e.g. "Load", "forces") label the error messages.
    """
    if isinstance(value, Mapping):
        out = np.zeros((n, 3))
        for node, vec in value.items():
            if not (isinstance(node, (int, np.integer)) and 0 <= node < n):
                raise ParameterError(f"{step}: node {node!r} does not exist (0..{n - 1}).")
            out[node] += np.asarray(vec, float)
    else:
        out = np.asarray(value, float)
        if out.shape != (n, 3):
            raise ParameterError(f"{step}: {name} must be a mapping or an ({n}, 3) array, got "
                                 f"shape {out.shape}.")
    if not np.isfinite(out).all():
        raise ParameterError(f"{step}: {name} contain NaN or inf.")
    return out


def _follow(context: StepContext, state, f_start, f_end, rest_end, increments,
            load_factor=None):
    """Follow the load / rest-angle path; returns (path, recorder) with every increment
    recorded (temperatures and powers unchanged; ``load_factor(t)`` maps the path's parameter
    to the step's). A crease folding past +-180 deg stops the path with a "panel_crossing"
    event (:func:`~simulator.events.crossing_event`)."""
    total, watch = increments, CrossingWatch(context.model.mesh, state.u,
                                              context.model.supports)
    scale = (lambda t: t) if load_factor is None else load_factor
    crossings, accepted = [], [0]

    def callback(t, u):
        context.report(min(total, round(t * total)), total)
        event = watch.check(u, accepted[0], scale(t), state.crease_power, state.temperature)
        accepted[0] += 1
        if event is not None:
            crossings.append(event)
        return stops(event)

    path = follow_path(context.system, state.u, f_start, f_end, state.spring_rest, rest_end,
                       increments, context.options, callback=callback)
    rec = StepRecorder(state)
    rec.add_path(path, state.temperature, state.crease_power, load_factor)
    rec.events += crossings
    stopped = [e for e in crossings if stops(e)]
    if stopped:
        path = replace(path, status="panel_crossing", message=stopped[0].message)
    return path, rec


def _resume(context, mid, lam, f_end, rest_end, increments, end_state) -> StepOutcome:
    """Load control from a converged state ``mid`` at load factor ``lam`` to the end of the
    step (after a snap passed by arc length); records carry the step's load factor."""
    n = max(1, round((1 - lam) * increments))
    path, rec = _follow(context, mid, mid.applied_load.ravel(), f_end, rest_end, n,
                        lambda t: lam + (1 - lam) * t)
    new = end_state(path.u, lam + (1 - lam) * path.t)
    return rec.finish(path.success, path.status, path.message, new, new.applied_load.ravel(),
                      path.evaluation)


@dataclass(frozen=True)
class SelfFold(Step):
    """Drive crease rest angles linearly to target fold angles (theory 6.4).

    Parameters
    ----------
    folds : mapping {crease id: fold angle [rad]}
        Target rest fold angle (0 = flat, > 0 towards +z) of the listed creases, in
        (-pi, pi].
    increments : int
    reset_others : bool
        Unlisted creases go to flat (True, the reference behaviour) or keep their rest angle.
    on_limit_point : {"stop", "continue"}
        At a limit point of the rest-angle path: end with status "limit_point", or continue
        by arc length with the rest-angle parameter as the unknown (see :mod:`.limit`).
    """

    folds: Mapping = field(default_factory=dict)
    increments: int = 50
    reset_others: bool = True
    name: str = "self_fold"
    on_limit_point: str = "stop"

    def __post_init__(self):
        check_increments(self)
        check_on_limit_point(self)
        check_folds(self.folds, "SelfFold")

    def run(self, context: StepContext, state) -> StepOutcome:
        mesh = context.model.mesh
        base = np.full(mesh.n_creases, np.pi) if self.reset_others else state.crease_rest
        target = crease_targets(mesh, self.folds, base)
        rest_end = spring_rest_angles(mesh, target, context.model.params)
        f = state.applied_load.ravel()
        path, rec = _follow(context, state, f, f, rest_end, self.increments)

        def end_state(u, t):
            return at_rest(state, u=u,
                           crease_rest=state.crease_rest + t * (target - state.crease_rest),
                           spring_rest=state.spring_rest + t * (rest_end - state.spring_rest))

        outcome = rec.finish(path.success, path.status, path.message, end_state(path.u, path.t),
                             f, path.evaluation)
        lp = LoadPath(context.system, f, np.zeros_like(f), state.spring_rest,
                      rest_end - state.spring_rest)
        return continue_past_limit(
            context, state, outcome, lp, self.increments, self.on_limit_point, end_state,
            lambda mid, lam: _resume(context, mid, lam, f, rest_end, self.increments,
                                     end_state))

    def describe(self) -> dict:
        return {"folds [rad]": {str(k): float(v) for k, v in dict(self.folds).items()},
                "increments": self.increments, "reset_others": self.reset_others,
                "on_limit_point": self.on_limit_point}


@dataclass(frozen=True)
class Load(Step):
    """Add dead loads linearly over the step; they stay applied in later steps (theory 6.5).

    Parameters
    ----------
    forces : mapping {node: (fx, fy, fz)} or (n_nodes, 3) array
        TOTAL load added by this step [N] (the reference gives it per increment).
    increments : int
    on_limit_point : {"stop", "continue"}
        At a limit point: end with status "limit_point", or continue by arc length with the
        load factor as the unknown (see :mod:`.limit`).
    """

    forces: object
    increments: int = 50
    name: str = "load"
    on_limit_point: str = "stop"

    def __post_init__(self):
        check_increments(self)
        check_on_limit_point(self)

    def load_array(self, model: Model) -> np.ndarray:
        """(n_nodes, 3) load added by the step [N]."""
        return node_vectors(self.forces, model.mesh.n_nodes, "Load", "forces")

    def run(self, context: StepContext, state) -> StepOutcome:
        dF = self.load_array(context.model)
        f0 = state.applied_load.ravel()
        path, rec = _follow(context, state, f0, f0 + dF.ravel(), state.spring_rest,
                            self.increments)

        def end_state(u, t):
            return at_rest(state, u=u, applied_load=state.applied_load + t * dF)

        new = end_state(path.u, path.t)
        outcome = rec.finish(path.success, path.status, path.message, new,
                             new.applied_load.ravel(), path.evaluation)
        lp = LoadPath(context.system, f0, dF.ravel(), state.spring_rest)
        return continue_past_limit(
            context, state, outcome, lp, self.increments, self.on_limit_point, end_state,
            lambda mid, lam: _resume(context, mid, lam, (f0 + dF.ravel()), state.spring_rest,
                                     self.increments, end_state))

    def describe(self) -> dict:
        return {"total_load [N]": self.load_sum(), "increments": self.increments,
                "on_limit_point": self.on_limit_point}

    def load_sum(self) -> list | None:
        if isinstance(self.forces, Mapping):
            vecs = [np.asarray(v, float) for v in self.forces.values()]
            return np.sum(vecs, axis=0).tolist() if vecs else [0.0, 0.0, 0.0]
        return np.asarray(self.forces, float).reshape(-1, 3).sum(axis=0).tolist()


@dataclass(frozen=True)
class Gravity(Step):
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
    direction : (3,) sequence of float
        Direction of gravity in the model's axes (any length; default -z): the one quantity of
        a plain pattern that depends on how it lies in space. A flat FOLD sheet drawn in
        another plane is laid in x-y with its top side up (:func:`~simulator.fold.read_fold`,
        ``lay_flat``), so -z pulls towards its bottom side; a sheet kept standing needs its
        gravity given here.
    """

    g: float = STANDARD_GRAVITY
    scale: float = 1.0
    panels: tuple | None = None
    increments: int = 50
    name: str = "gravity"
    direction: tuple = (0.0, 0.0, -1.0)

    def __post_init__(self):
        check_increments(self)
        finite("Gravity.g", self.g, "m/s^2")
        finite("Gravity.scale", self.scale)
        d = array("Gravity.direction", self.direction, (3,))
        if not np.any(d):
            raise ParameterError("Gravity.direction = (0, 0, 0) has no direction; give a "
                                 "non-zero 3-vector, e.g. (0, 0, -1) (the default, -z).")

    def run(self, context: StepContext, state) -> StepOutcome:
        load = Load(self.scale * gravity_loads(context.model.mesh, self.g, self.direction,
                                               panels=self.panels), self.increments)
        return load.run(context, state)

    def describe(self) -> dict:
        d = np.asarray(self.direction, float)
        return {"g [m/s^2]": self.g, "scale": self.scale, "increments": self.increments,
                "panels": None if self.panels is None else list(self.panels),
                "direction": (d / np.linalg.norm(d)).tolist()}
