"""Path-following steps: arc-length loading, displacement control, and continuation of
load-controlled steps (self-fold, heating) past limit points.

* :class:`ArcLengthLoad`: a dead-load pattern whose load factor is an unknown (MGDCM), ending at
  a target load factor, a target displacement or a number of increments;
* :class:`DisplacementControl`: a node's displacement along a direction driven to a target, the
  load factor of a reference load (default: a unit force there) being the reaction;

What load-controlled steps do at a limit point (``on_limit_point``) is in :mod:`.limit`.

Every recorded increment carries the columns ``stable``, ``negative_eigenvalues``,
``lowest_eigenvalue [N/m]`` and ``displacement [m]`` (the monitored or controlled
displacement).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..solvers.continuation import mgdcm
from ..solvers.displacement_control import displacement_control
from .._validate import finite, positive
from ..errors import ParameterError
from ..events import crossing_stop
from ..solvers.load_path import LoadPath
from ..model.model import AXES
from .base import Step, StepContext, StepOutcome, StepRecorder, check_increments
from ..state import at_rest
from .limit import record_continuation
from .mechanical import Load

__all__ = ["ArcLengthLoad", "DisplacementControl"]


def _direction(value, owner: str) -> np.ndarray:
    """Unit 3-vector from "x", "y", "z" (optionally signed, "-z") or a 3-vector."""
    if isinstance(value, str):
        sign = -1.0 if value.startswith("-") else 1.0
        axis = value.lstrip("+-")
        if axis not in AXES:
            raise ParameterError(f"{owner}: direction {value!r}; use 'x', 'y', 'z' (or '-z') or "
                                 "a 3-vector.")
        d = np.zeros(3)
        d[AXES[axis]] = sign
        return d
    d = np.asarray(value, float)
    if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.any(d):
        raise ParameterError(f"{owner}: direction {value!r} must be a non-zero finite 3-vector "
                             "or an axis name.")
    return d / np.linalg.norm(d)


def _dof_weights(model, node: int, d: np.ndarray, owner: str) -> np.ndarray:
    """(n_dof,) weights of node ``node``'s displacement along ``d``; errors if supported."""
    n = model.mesh.n_nodes
    if isinstance(node, bool) or not (isinstance(node, (int, np.integer)) and 0 <= node < n):
        raise ParameterError(f"{owner}: node {node!r} does not exist (0..{n - 1}).")
    fixed = model.fixed_mask[node]
    bad = [a for a, k in AXES.items() if d[k] != 0 and fixed[k]]
    if bad:
        raise ParameterError(f"{owner}: node {node} is supported in {''.join(bad)}, so its "
                             "displacement along that direction cannot be controlled; choose a "
                             "free node or direction.")
    c = np.zeros(3 * n)
    c[3 * node:3 * node + 3] = d
    return c


@dataclass(frozen=True)
class ArcLengthLoad(Step):
    """Dead-load pattern with the load factor as an unknown, traced by MGDCM arc length.

    The applied load is ``lambda forces`` on top of the loads of earlier steps (and stays
    applied afterwards, as for :class:`~simulator.steps.Load`).

    Parameters
    ----------
    forces : mapping {node: (fx, fy, fz)} or (n_nodes, 3) array
        Reference load pattern P [N].
    arc_length : float
        Load-factor increment of the first step (> 0); later predictors move the structure by
        the same displacement norm, adapted to the Newton effort (see
        :func:`~simulator.solvers.continuation.mgdcm`).
    max_increments : int
        Accepted increments at most; without a target the step ends there.
    target_load_factor : float, optional
        End where the load factor reaches this value moving towards it.
    target_displacement : float, optional
        End where the monitored displacement reaches this value [m].
    monitor : (node, direction), optional
        Displacement recorded and used by ``target_displacement`` (default: the most loaded
        node along its load).
    max_arc_length : float, optional
        Cap of the adapted arc length (default 4 x ``arc_length``).
    """

    forces: object = None
    arc_length: float = 0.05
    max_increments: int = 100
    target_load_factor: float | None = None
    target_displacement: float | None = None
    monitor: tuple | None = None
    max_arc_length: float | None = None
    name: str = "arc_length_load"

    def __post_init__(self):
        check_increments(self, "max_increments")
        for attr in ("arc_length", "max_arc_length"):
            positive(f"ArcLengthLoad.{attr}", getattr(self, attr), hint="a load-factor "
                     "increment", allow_none=attr == "max_arc_length")
        finite("ArcLengthLoad.target_load_factor", self.target_load_factor, allow_none=True)
        finite("ArcLengthLoad.target_displacement", self.target_displacement, "m",
               allow_none=True)
        if self.forces is None:
            raise ParameterError("ArcLengthLoad: give forces, e.g. {node: (0, 0, -1e-6)} [N].")
        if self.monitor is not None:
            _direction(self.monitor[1], "ArcLengthLoad.monitor")

    def _monitor(self, model, P):
        if self.monitor is not None:
            node, d = self.monitor
            return _dof_weights(model, node, _direction(d, "ArcLengthLoad.monitor"),
                                "ArcLengthLoad.monitor")
        node = int(np.argmax(np.linalg.norm(P, axis=1)))
        c = np.zeros(P.size)
        c[3 * node:3 * node + 3] = P[node] / np.linalg.norm(P[node])
        return c

    def run(self, context: StepContext, state) -> StepOutcome:
        P = Load(self.forces).load_array(context.model)
        if not np.any(P):
            raise ParameterError("ArcLengthLoad: the reference load is zero.")
        c = self._monitor(context.model, P)
        path = LoadPath(context.system, state.applied_load.ravel(), P.ravel(), state.spring_rest)
        target = None if self.target_displacement is None else (c, self.target_displacement)
        res = mgdcm(path, state.u, 0.0, arc_length=self.arc_length,
                    max_increments=self.max_increments,
                    target_load_factor=self.target_load_factor, target_displacement=target,
                    monitor=c, options=context.options, max_arc_length=self.max_arc_length,
                    callback=_progress(context, state, self.max_increments))
        rec = StepRecorder(state)
        crossing = record_continuation(rec, res, state.temperature, state.crease_power, c,
                                       mesh=context.model.mesh,
                                       supports=context.model.supports)
        return _finish(rec, res, state, P, crossing)

    def describe(self) -> dict:
        return {"reference_load [N]": Load(self.forces).load_sum(), "arc_length": self.arc_length,
                "max_increments": self.max_increments,
                "target_load_factor": self.target_load_factor,
                "target_displacement [m]": self.target_displacement,
                "monitor": None if self.monitor is None else [int(self.monitor[0]),
                                                              str(self.monitor[1])]}


def _progress(context, state, total):
    """The path follower's callback: progress, and a stop where a crease passes +-180 deg."""
    count = [0]

    def progress(lam, u):
        count[0] += 1
        context.report(min(count[0], total), total)
        return False
    return crossing_stop(context.model.mesh, state.u, progress, context.model.supports)


def _finish(rec, res, state, P, crossing) -> StepOutcome:
    """The step's outcome at the last accepted point of ``res``, or at the point where a crease
    passed +-180 deg (``crossing``, its event; status "panel_crossing")."""
    if crossing is None:
        u, lam, success, status, message = res.u, res.load_factor, res.success, res.status, \
            res.message
    else:
        u, lam, success, status = rec.last_u, crossing.load_factor, False, "panel_crossing"
        message = crossing.message
    new = at_rest(state, u=u, applied_load=state.applied_load + lam * P)
    evaluation = res.evaluation if np.array_equal(u, res.u) else None
    return rec.finish(success, status, message, new, new.applied_load.ravel(), evaluation)


@dataclass(frozen=True)
class DisplacementControl(Step):
    """Drive a node's displacement along a direction to ``target`` [m] (theory 6.9).

    The load factor multiplies a reference load (default a unit force at the node along the
    direction, so that the load factor is the reaction force [N]); it is an unknown, so the
    path passes load limit points (not turning points of the controlled displacement).

    Parameters
    ----------
    node : int
    direction : "x", "y", "z" (or "-z", ...) or 3-vector
    target : float
        Final displacement of the node along ``direction`` [m] (from the mesh position).
    increments : int
        Equal increments of the controlled displacement.
    forces : mapping or array, optional
        Reference load pattern [N] (default: 1 N at ``node`` along ``direction``).
    """

    node: int = 0
    direction: object = "z"
    target: float = 0.0
    increments: int = 50
    forces: object = None
    name: str = "displacement_control"

    def __post_init__(self):
        check_increments(self)
        _direction(self.direction, "DisplacementControl")
        finite("DisplacementControl.target", self.target, "m", hint="a displacement")

    def run(self, context: StepContext, state) -> StepOutcome:
        model = context.model
        d = _direction(self.direction, "DisplacementControl")
        c = _dof_weights(model, self.node, d, "DisplacementControl")
        if self.forces is None:
            P = np.zeros((model.mesh.n_nodes, 3))
            P[self.node] = d
        else:
            P = Load(self.forces).load_array(model)
        path = LoadPath(context.system, state.applied_load.ravel(), P.ravel(), state.spring_rest)
        res = displacement_control(path, state.u, 0.0, c, self.target,
                                   increments=self.increments, options=context.options,
                                   callback=_progress(context, state, self.increments))
        rec = StepRecorder(state)
        along = float(P[self.node] @ d)
        crossing = record_continuation(rec, res, state.temperature, state.crease_power, c,
                                       extra=lambda lam: {"reaction [N]": lam * along},
                                       mesh=context.model.mesh,
                                       supports=context.model.supports)
        return _finish(rec, res, state, P, crossing)

    def describe(self) -> dict:
        return {"node": self.node, "direction": str(self.direction),
                "target [m]": self.target, "increments": self.increments,
                "reference_load [N]": None if self.forces is None
                else Load(self.forces).load_sum()}
