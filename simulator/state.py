"""The state a simulation carries from one step to the next.

:class:`SimulationState` holds everything a later step needs to continue: displacements,
accumulated dead loads, crease and spring rest angles, node temperatures, crease powers and the
room temperature (the reference's controller list, theory 6.1). Steps never mutate a state; they
return a new one.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .mechanics.elements.springs import fold_angle
from .model.model import Model
from .mechanics.rest_angles import initial_crease_rest

__all__ = ["ROOM_TEMPERATURE", "SimulationState", "at_rest", "initial_state"]

#: Default room temperature [deg C].
ROOM_TEMPERATURE = 21.0


@dataclass(frozen=True, eq=False)
class SimulationState:
    """State handed from one step to the next.

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
    velocity : (n_nodes, 3) array or None
        Node velocities [m/s] left by a dynamic step; None means at rest (quasi-static steps).
    time : float
        Time reached by dynamic steps [s] (quasi-static steps do not advance it).
    circuits : tuple of (Circuit, Drive) pairs
        Heater circuits driving creases at the end of the step, their drives held constant
        (:mod:`simulator.thermal.circuits`); a later heating step keeps driving them. Empty:
        none (the powers are fixed).
    circuit_power : (C,) array or None
        The circuits' part of ``crease_power`` [W] (None: no circuit).
    """

    u: np.ndarray
    applied_load: np.ndarray
    crease_rest: np.ndarray
    spring_rest: np.ndarray
    temperature: np.ndarray
    crease_power: np.ndarray
    room_temperature: float = ROOM_TEMPERATURE
    velocity: np.ndarray | None = None
    time: float = 0.0
    circuits: tuple = ()
    circuit_power: np.ndarray | None = None

    @property
    def node_velocity(self) -> np.ndarray:
        """(n_nodes, 3) velocities [m/s], zeros when at rest."""
        return np.zeros_like(self.u) if self.velocity is None else self.velocity

    @property
    def rest_fold(self) -> np.ndarray:
        """Crease rest fold angles [rad], 0 = flat, positive towards +z."""
        return self.crease_rest - np.pi


def at_rest(state: SimulationState, **changes) -> SimulationState:
    """``replace(state, **changes)`` for a quasi-static step: the structure is left at rest
    (velocity None) unless ``changes`` say otherwise."""
    changes.setdefault("velocity", None)
    return replace(state, **changes)


def initial_state(model: Model, room_temperature: float | None = None) -> SimulationState:
    """Unloaded state: zero displacement, crease rest angles of the initial geometry (flat, pi,
    unless the mesh starts folded:
    :func:`~simulator.mechanics.rest_angles.initial_crease_rest`), spring rest angles equal to
    the spring angles of the initial geometry (theory 6.1), uniform room temperature (from the
    model's thermal parameters, else 21 deg C), no heating."""
    mesh = model.mesh
    if room_temperature is None:
        room_temperature = ROOM_TEMPERATURE if model.thermal is None \
            else model.thermal.room_temperature
    return SimulationState(
        u=np.zeros((mesh.n_nodes, 3)), applied_load=np.zeros((mesh.n_nodes, 3)),
        crease_rest=initial_crease_rest(mesh),
        spring_rest=fold_angle(mesh.nodes[mesh.springs]),
        temperature=np.full(mesh.n_nodes, float(room_temperature)),
        crease_power=np.zeros(mesh.n_creases), room_temperature=float(room_temperature))
