"""Time-dependent mechanical drives of the time-domain steps (theory 8.7).

:class:`~simulator.steps.Dynamics` and :class:`~simulator.steps.ElectroThermal` accept

* ``forces``: an (n_nodes, 3) array [N], or a mapping ``{node: (fx, fy, fz)}`` whose values
  may also be ``((fx, fy, fz), schedule)``: the vector [N] times the schedule's value at time t
  (a dimensionless factor, any :class:`~simulator.schedules.Schedule`);
* ``folds``: a mapping ``{crease id: fold angle [rad] or schedule}``: the crease's rest fold
  angle, constant or the schedule's value [rad] at time t (e.g.
  ``SineSignal(amplitude=0.02, frequency=50.0, offset=0.3)``).

Time t runs from the start of the step. Constant entries act suddenly at t = 0, as before.
:class:`MechanicalDrive` turns them into the functions t -> load (n_dof,) and t -> crease rest
angles (C,) that the integrators take; the end state keeps the values at the end of the step.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import ParameterError
from ..mechanics.rest_angles import spring_rest_angles
from ..schedules import Schedule
from .mechanical import check_folds, crease_targets, node_vectors

__all__ = ["check_force_drive", "check_fold_drive", "MechanicalDrive", "describe_drive"]


def _scheduled(value) -> bool:
    return (isinstance(value, tuple) and len(value) == 2 and isinstance(value[1], Schedule))


def check_force_drive(owner: str, forces) -> None:
    """Raise :class:`ParameterError` unless ``forces`` is None, an array or a mapping of
    vectors and (vector, schedule) pairs (the vector checked on use)."""
    if forces is None or not isinstance(forces, Mapping):
        return
    for node, value in forces.items():
        vec = value[0] if _scheduled(value) else value
        try:
            arr = np.asarray(vec, dtype=float)
        except (TypeError, ValueError):
            arr = None
        if arr is None or arr.shape != (3,) or not np.all(np.isfinite(arr)):
            raise ParameterError(f"{owner}: force of node {node!r} is {value!r}; give a finite "
                                 "(fx, fy, fz) [N] or ((fx, fy, fz), schedule) with a "
                                 "Schedule such as SineSignal(1.0, frequency=...).")


def check_fold_drive(owner: str, folds) -> None:
    """Raise :class:`ParameterError` unless every fold is a fold angle [rad] in (-pi, pi] or a
    :class:`~simulator.schedules.Schedule`."""
    if not isinstance(folds, Mapping):
        raise ParameterError(f"{owner}: folds = {folds!r} must be a mapping {{crease id: fold "
                             "angle [rad] or Schedule}.")
    check_folds({c: v for c, v in folds.items() if not isinstance(v, Schedule)}, owner)


class MechanicalDrive:
    """Loads and rest angles of a time-domain step as functions of the step time t [s].

    Parameters
    ----------
    model : Model
    state : SimulationState
        The state the step starts from (its dead loads and crease rest angles).
    forces, folds
        The step's drives (module docstring).
    owner : str
        Step name for error messages.
    """

    def __init__(self, model, state, forces, folds, owner: str):
        self.mesh, self.params = model.mesh, model.params
        n = self.mesh.n_nodes
        const, self.force_terms = {}, []
        if isinstance(forces, Mapping):
            for node, value in forces.items():
                if _scheduled(value):
                    vec = node_vectors({node: value[0]}, n, owner, "forces").ravel()
                    self.force_terms.append((vec, value[1]))
                else:
                    const[node] = value
            base = node_vectors(const, n, owner, "forces") if const else 0.0
        else:
            base = 0.0 if forces is None else node_vectors(forces, n, owner, "forces")
        self.load0 = (state.applied_load + base).ravel()
        folds = dict(folds or {})
        self.fold_terms = [(self.mesh.crease_row_of(c), s) for c, s in folds.items()
                           if isinstance(s, Schedule)]
        self.fixed = {c: v for c, v in folds.items() if not isinstance(v, Schedule)}
        self.crease0 = crease_targets(self.mesh, self.fixed, state.crease_rest) if self.fixed \
            else state.crease_rest
        self.changed_rest = bool(self.fixed)

    @property
    def schedules(self) -> list:
        """Every schedule of the drive (for the switch times of adaptive steppers)."""
        return [s for _, s in self.force_terms] + [s for _, s in self.fold_terms]

    @property
    def timed(self) -> bool:
        """Whether anything changes during the step (else loads and rest angles are constant)."""
        return bool(self.force_terms or self.fold_terms)

    def load(self, t: float) -> np.ndarray:
        """(n_dof,) external load [N] at step time t [s]."""
        out = self.load0.copy()
        for vec, s in self.force_terms:
            out += vec * s(t)
        return out

    def crease_rest(self, t: float, base=None) -> np.ndarray:
        """(C,) crease rest angles [rad] at step time t; ``base`` (C,) replaces the state's
        (e.g. the thermally actuated rest angles), the listed creases override it."""
        out = self.crease0.copy() if base is None else crease_targets(self.mesh, self.fixed, base)
        for row, s in self.fold_terms:
            out[row] = np.pi + s(t)
        return out

    def spring_rest(self, t: float, base=None) -> np.ndarray:
        """(n_springs,) spring rest angles [rad] at step time t (see :meth:`crease_rest`)."""
        return spring_rest_angles(self.mesh, self.crease_rest(t, base), self.params)


def describe_drive(forces, folds) -> dict:
    """JSON-able description of a step's drives for ``meta.json``."""
    out = {}
    if isinstance(forces, Mapping):
        out["forces [N]"] = {
            str(k): ({"vector": list(np.asarray(v[0], float)), **v[1].describe()}
                     if _scheduled(v) else list(np.asarray(v, float)))
            for k, v in forces.items()}
    elif forces is not None:
        out["forces [N]"] = np.asarray(forces, float).sum(axis=0).tolist()
    else:
        out["forces [N]"] = None
    out["folds [rad]"] = {str(k): (v.describe() if isinstance(v, Schedule) else float(v))
                          for k, v in dict(folds or {}).items()}
    return out
