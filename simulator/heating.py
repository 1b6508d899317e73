"""Electro-thermal loading steps: the paper's three-step loop per heating increment.

For every increment of a :class:`Heat` step (digest 7.5):

1. heat transfer: node temperatures for the current crease powers, with the conductivity
   assembled on the current shape (so folding changes heat loss);
2. Timoshenko bimorph: crease rest angles = rest angles at the start of the step plus
   ``W kappa(dT)``, dT = 7-node crease temperature minus its value at the start of the step;
3. bar-and-hinge equilibrium (contact, persisting gravity) by Newton with step cutting.

``coupling="staggered"`` (default, the reference's behaviour) uses the shape of the previous
increment in step 1; ``coupling="iterated"`` repeats steps 1-3 within the increment until
temperature and shape agree. :class:`AmbientTemperature` ramps the room temperature instead
(digest 7.7).
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from .bimorph import crease_temperature_weights
from .errors import ParameterError
from .loading import StepRun, _check_increments
from .properties import spring_rest_angles
from .solvers import follow_path
from .thermal import ThermalModel

__all__ = ["Heat", "AmbientTemperature", "thermal_model"]

_THERMAL: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def thermal_model(model) -> ThermalModel:
    """The cached :class:`~simulator.thermal.ThermalModel` of a model."""
    if model.thermal is None:
        raise ParameterError("This model has no thermal parameters: pass thermal="
                             "ThermalParameters(...) to make_model to use heating steps.")
    tm = _THERMAL.get(model)
    if tm is None:
        tm = _THERMAL[model] = ThermalModel(model.mesh, model.thermal)
    return tm


def _rotation_per_kelvin(model) -> np.ndarray:
    if model.actuators is None:
        return np.zeros(model.mesh.n_creases)
    return model.actuators.rotation_per_kelvin(model.mesh)


class _ThermoMechanicalStep:
    """Shared increment loop of the heating and ambient-temperature steps."""

    reports_progress = True

    def _loop(self, model, system, state, options, progress, powers, ambient, fixed_shape):
        """Run increments s = 1..S with crease powers ``powers[s]`` (C,) and room temperatures
        ``ambient[s]``; ``fixed_shape``: conductivity from the start shape (AmbientTemperature)."""
        mesh, tm = model.mesh, thermal_model(model)
        rot = _rotation_per_kelvin(model)
        w = crease_temperature_weights()
        t_ref, rest0 = state.temperature, state.crease_rest
        u, spring, f = state.u, state.spring_rest, state.applied_load.ravel()
        x_start = mesh.nodes + state.u
        run = StepRun(True, "converged", "converged", state, f)
        n_inc = len(powers)
        temp, target = state.temperature, state.crease_rest
        for s, (power, room) in enumerate(zip(powers, ambient), start=1):
            q = tm.heat_vector(power)
            temp = tm.solve(x_start if fixed_shape else mesh.nodes + u, q, room)
            for k in range(self.max_coupling_iterations):
                target = rest0 + rot * ((temp - t_ref)[mesh.crease_nodes] @ w)
                rest = spring_rest_angles(mesh, target, model.params)
                path = follow_path(system, u, f, f, spring, rest, 1, options)
                run.iterations += path.iterations
                run.cuts += path.cuts
                if not path.converged:
                    run.converged, run.status = False, "failed"
                    run.message = (f"increment {s}/{n_inc} (crease power up to "
                                   f"{1e3 * np.max(power, initial=0):.4g} mW): {path.message}")
                    run.state = replace(state, u=u, spring_rest=spring, temperature=run.temperature[-1]
                                        if run.temperature else state.temperature)
                    return run
                if self.coupling == "staggered" or fixed_shape:
                    break
                new_temp = tm.solve(mesh.nodes + path.u, q, room)
                converged = np.max(np.abs(new_temp - temp)) <= self.coupling_tol
                temp = new_temp
                if converged:
                    break
            u, spring = path.u, rest
            run.load_factor.append(s / n_inc)
            run.u.append(u)
            run.temperature.append(temp)
            run.power.append(np.asarray(power, float))
            run.increment_iterations.append(path.iterations)
            run.residual_norms += path.residual_norms
            run.evaluation = path.evaluation
            if progress is not None:
                progress(s, n_inc)
        run.state = replace(state, u=u, spring_rest=spring, temperature=temp, crease_rest=target,
                            crease_power=np.asarray(powers[-1], float),
                            room_temperature=float(ambient[-1]))
        return run


def _check_coupling(step):
    if step.coupling not in ("staggered", "iterated"):
        raise ParameterError(f"coupling = {step.coupling!r}; use 'staggered' or 'iterated'.")
    if not (isinstance(step.max_coupling_iterations, int) and step.max_coupling_iterations >= 1):
        raise ParameterError(f"max_coupling_iterations = {step.max_coupling_iterations!r} must be "
                             "a positive integer.")
    if not (math.isfinite(step.coupling_tol) and step.coupling_tol > 0):
        raise ParameterError(f"coupling_tol = {step.coupling_tol!r} must be positive [K].")


@dataclass(frozen=True)
class Heat(_ThermoMechanicalStep):
    """Ramp crease heating powers linearly over ``increments`` (digest 7.5).

    Parameters
    ----------
    power : mapping
        Power ADDED by this step on top of the current one [W], keyed by crease id, or by a
        tuple of crease ids for a heater circuit (each crease of the circuit gets the value).
    increments : int
        Heating increments (each solves temperature, rest angles and equilibrium).
    coupling : {"staggered", "iterated"}
    coupling_tol : float
        Temperature agreement [K] that ends the "iterated" loop of an increment.
    max_coupling_iterations : int
    """

    power: Mapping = field(default_factory=dict)
    increments: int = 200
    coupling: str = "staggered"
    coupling_tol: float = 1e-6
    max_coupling_iterations: int = 20
    name: str = "heat"

    def __post_init__(self):
        _check_increments(self)
        _check_coupling(self)
        if self.coupling == "staggered":
            object.__setattr__(self, "max_coupling_iterations", 1)
        for key, v in dict(self.power).items():
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v)):
                raise ParameterError(f"Heat: power of crease {key} is {v!r}; give watts.")

    def power_array(self, mesh) -> np.ndarray:
        """(C,) power added per crease row [W]."""
        out = np.zeros(mesh.n_creases)
        for key, v in dict(self.power).items():
            for c in (key if isinstance(key, tuple) else (key,)):
                out[mesh.crease_row_of(c)] += float(v)
        return out

    def run(self, model, system, state, options, progress=None):
        dP = self.power_array(model.mesh)
        end = state.crease_power + dP
        if np.any(end < 0):
            row = int(np.argmin(end))
            raise ParameterError(
                f"Heat: crease {int(model.mesh.crease_ids[row])} would end at "
                f"{1e3 * end[row]:.4g} mW; a step may lower the power (negative values) but not "
                "below zero.")
        s = np.arange(1, self.increments + 1)[:, None] / self.increments
        powers = state.crease_power + s * dP
        ambient = np.full(self.increments, state.room_temperature)
        run = self._loop(model, system, state, options, progress, powers, ambient, False)
        run.settings = {"power_added [mW]": {str(k): 1e3 * float(v) for k, v in
                                             dict(self.power).items()},
                        "increments": self.increments, "coupling": self.coupling}
        return run


@dataclass(frozen=True)
class AmbientTemperature(_ThermoMechanicalStep):
    """Ramp the room temperature to ``target`` [deg C] with the heating unchanged (digest 7.7).

    The conductivity is assembled once on the shape at the start of the step, as in the
    reference.
    """

    target: float = 21.0
    increments: int = 50
    name: str = "ambient_temperature"
    coupling: str = "staggered"
    coupling_tol: float = 1e-6
    max_coupling_iterations: int = 1

    def __post_init__(self):
        _check_increments(self)
        if not math.isfinite(self.target):
            raise ParameterError(f"AmbientTemperature.target = {self.target!r} must be finite.")

    def run(self, model, system, state, options, progress=None):
        s = np.arange(1, self.increments + 1) / self.increments
        ambient = state.room_temperature + s * (self.target - state.room_temperature)
        powers = np.repeat(state.crease_power[None], self.increments, axis=0)
        run = self._loop(model, system, state, options, progress, powers, ambient, True)
        run.settings = {"target [degC]": self.target, "increments": self.increments}
        return run
