"""The gripper's inverse design with exact gradients (issue 32, item 4b): its dimensions, a
width per crease and a heater power per crease for the least total heater power that still
assembles and grips, under the temperature limit on every crease.

The gripper works in two stages (:func:`~design.devices.gripper.evaluate_gripper`, theory
10.6): the base creases (2, 5) fold the base past 90 deg (*assembly*, the reference's base-fold
measure), then, with the base heat kept on, the arm creases (3, 9) bring the arm tips closer
than 100 um (*grip*). Here each heated crease has its own power (``power_2``, ``power_5``
heat from the assembly on, ``power_3``, ``power_9`` are added for the grip), and one simulation
ends on both stages' steady coupled states: the self-weight, a settled heating of the base
creases (the assembly state), a settled heating of the arm creases on top (the grip state).
Each state is differentiated (:func:`simulator.sensitivity.differentiate_state`, one
factorisation each) in the powers and, by :class:`~simulator.sensitivity.Geometry`, in the
dimensions and widths (the model rebuilt by :func:`~design.devices.gripper.make_gripper_model`;
the reference's hand-lumped self-weight and the grip stage's start, the assembly state's rest
angles, follow them).

Variables: ``La``, ``L1``, ``L2`` and the crease width, one ``W`` (:data:`GRIPPER_SPACE`'s four
dimensions) or with ``widths=True`` one per crease (``W_2``, ``W_3``, ``W_5``, ``W_9``, the
bounds of ``W``) [m], and the four powers [W]. Objective: the total power (W). Constraints
(g <= 0): ``assembly`` ``(90 deg - base fold) / fold_tolerance`` at the assembly state,
``grip`` ``(tip distance - 100 um) / distance_tolerance`` at the grip state, and
``temperature_<stage>_<crease>`` ``(T - limit) / limit`` for every crease at both states.
The chain heat loss (the one the sensitivities differentiate) throughout.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from simulator import Heat, ParameterError, simulate
from simulator._validate import integer, one_of, positive

from ..core.space import DesignSpace, Variable
from .fold_target import COUPLING_TOL, NEWTON, HeaterPowerProblem, answer_rough
from .gripper import (ARM_CREASES, ASSEMBLY_FOLD, BASE_CREASES, GRIP_DISTANCE, GripperDesign,
                      make_gripper_model, self_weight)
from .gripper_heat import GripperHeatModel
from .gripper_problem import GRIPPER_SPACE
from .limits import SU8_LIMIT

__all__ = ["GripperInverseProblem", "BaseFold", "TipDistance"]

_CHAIN = GripperHeatModel(loss_model="chain")
#: The geometry steps: :class:`~simulator.sensitivity.Geometry`'s default, ``h = 1.5e-8`` x
#: the model's size (7e-11 m), near the best balance of truncation and round-off here (the
#: gradients' errors against central differences of the whole solve, measured at the
#: assembly state: 1e-6 at most at 4.5e-11 m; truncation 5e-6 at 1.5e-10 m and 5e-2 at
#: 1.5e-8 m, growing as h^2; round-off 1e-5 at 1.5e-11 m). The residual's columns of some
#: sizes (L2: small beside the element forces) then carry round-off of 1e-4 of themselves,
#: which Geometry reports as a rough builder although the gradients do not see it (L2's
#: agree to 1e-9): :func:`~design.devices.fold_target.answer_rough` checks them at 4 h.
_STAGES = ("assembly", "grip")
_MEASURES = ("centre_line", "crease_max")


class BaseFold:
    """The gripper's base fold [rad], the reference's measure of the assembly
    (:func:`~design.devices.gripper._base_fold`): ``sign(z_0 - z_5)`` times the angle
    between ``x_1 - x_0`` (the left base panel's edge) and ``x_5 - x_4`` (the central
    panel's), an objective of :func:`simulator.sensitivity.differentiate` with its exact
    derivatives."""

    unit = "rad"

    def terms(self, model, u, T):
        x = model.mesh.nodes + u
        a, b = x[1] - x[0], x[5] - x[4]
        na, nb = np.linalg.norm(a), np.linalg.norm(b)
        c = float(np.clip(a @ b / (na * nb), -1.0, 1.0))
        dz = x[0, 2] - x[5, 2]
        sign, nonsmooth = float(np.sign(dz)) or 1.0, []
        if abs(dz) < 1e-12 * na or 1 - abs(c) < 1e-12:
            nonsmooth.append("base fold: at 0 or 180 deg (its sign or the angle's "
                             "derivative switches)")
        d_angle = -sign / math.sqrt(max(1 - c * c, 1e-300))
        ga = d_angle * (b / (na * nb) - c * a / na ** 2)
        gb = d_angle * (a / (na * nb) - c * b / nb ** 2)
        g = np.zeros_like(x)
        g[1] += ga
        g[0] -= ga
        g[5] += gb
        g[4] -= gb
        return sign * math.acos(c), g, np.zeros(len(x)), nonsmooth


class TipDistance:
    """The distance between the gripper's outer arm tips [m] (nodes 15 and 18, the
    reference's grip measure :func:`~design.devices.gripper._tip_distance`), an objective of
    :func:`simulator.sensitivity.differentiate` with its exact derivatives."""

    unit = "m"

    def terms(self, model, u, T):
        x = model.mesh.nodes + u
        r = x[15] - x[18]
        d = float(np.linalg.norm(r))
        g = np.zeros_like(x)
        g[15], g[18] = r / d, -r / d
        return d, g, np.zeros(len(x)), []


def _crease_space(widths: bool, max_power: float, start_power: tuple) -> DesignSpace:
    """La, L1, L2 and W (or W_<crease> per crease) from :data:`GRIPPER_SPACE`, then the
    powers of the base creases and of the arm creases."""
    dims = {v.name: v for v in GRIPPER_SPACE.variables}
    w = dims.pop("W")
    sizes = ([replace(w, name=f"W_{c}") for c in sorted(BASE_CREASES + ARM_CREASES)]
             if widths else [w])
    powers = [Variable(f"power_{c}", 0.0, max_power, max_power / 20, p, unit="W",
                       display_scale=1e3, display_unit="mW")
              for creases, p in zip((BASE_CREASES, ARM_CREASES), start_power)
              for c in creases]
    return DesignSpace([*dims.values(), *sizes, *powers])


class GripperInverseProblem(HeaterPowerProblem):
    """Least total heater power of the gripper over its dimensions, crease widths and
    per-crease heater powers, assembling and gripping under the temperature limit.

    Parameters
    ----------
    widths : bool
        One width per crease (``W_2``, ``W_3``, ``W_5``, ``W_9``) instead of the one ``W``.
    base : GripperDesign
        Everything that is not a variable (layers, residual folds, the air).
    fold_tolerance : float [rad]
        The scale of the assembly constraint: ``g = 1`` is a base fold this far below
        90 deg (0.5 deg).
    distance_tolerance : float [m]
        The scale of the grip constraint: ``g = 1`` is tips this far beyond 100 um (1 um).
    temperature_limit : float [degC]
        Upper bound of every crease's temperature at both states (1.2 T_g of SU-8, 252).
    temperature_measure : {"centre_line", "crease_max"}
        The crease temperature judged (theory 5.4: the centre-line mean).
    max_power : float [W]
        Upper bound of each heater power.
    start_power : (float, float) [W]
        Start power of each base crease and of each arm crease.
    heat_increments : int
        Increments of each settled heating step.
    """

    name = "gripper_inverse"

    def __init__(self, widths: bool = True, base: GripperDesign = GripperDesign(),
                 fold_tolerance: float = math.radians(0.5), distance_tolerance: float = 1e-6,
                 temperature_limit: float = SU8_LIMIT.value,
                 temperature_measure: str = "centre_line", max_power: float = 40e-3,
                 start_power: tuple = (20e-3, 4e-3), heat_increments: int = 5):
        if not isinstance(base, GripperDesign) or base.crease_widths:
            raise ParameterError(f"base = {base!r:.80}: give a GripperDesign without "
                                 "crease_widths (the widths are variables here).")
        positive("fold_tolerance", fold_tolerance, "rad")
        positive("distance_tolerance", distance_tolerance, "m")
        positive("temperature_limit", temperature_limit, "degC")
        positive("max_power", max_power, "W")
        one_of("temperature_measure", temperature_measure, _MEASURES)
        integer("heat_increments", heat_increments, 1)
        self.widths, self.base = bool(widths), base
        self.fold_tolerance, self.distance_tolerance = float(fold_tolerance), \
            float(distance_tolerance)
        self.temperature_limit, self.temperature_measure = float(temperature_limit), \
            temperature_measure
        self.heat_increments, self.max_power = heat_increments, float(max_power)
        self.creases = BASE_CREASES + ARM_CREASES
        self.space = _crease_space(self.widths, max_power, tuple(start_power))
        self.sizes = tuple(n for n in self.space.names if not n.startswith("power_"))

    def settings(self) -> dict:
        return {"problem": self.name, "widths": self.widths,
                "base": self.base.to_dict(), "heat": "chain",
                "fold_tolerance [rad]": self.fold_tolerance,
                "distance_tolerance [m]": self.distance_tolerance,
                "temperature_limit [degC]": self.temperature_limit,
                "temperature_measure": self.temperature_measure,
                "heat_increments": self.heat_increments,
                "variables": [v.to_dict() for v in self.space.variables]}

    def design(self, values: dict) -> GripperDesign:
        """The :class:`GripperDesign` of the size variables in ``values``."""
        sizes = {k: float(values[k]) for k in ("La", "L1", "L2", "W") if k in values}
        widths = tuple((int(k[2:]), float(v)) for k, v in values.items() if k.startswith("W_"))
        return replace(self.base, **sizes, crease_widths=widths)

    def model(self, values: dict):
        """The model of the size variables in ``values`` (the chain heat loss)."""
        return make_gripper_model(self.design(values), heat=_CHAIN)[0]

    def simulate(self, values: dict):
        """Self-weight, the assembly heating, the grip heating: one simulation, whose last two
        steps end on the stages' steady coupled states."""
        model, pre = make_gripper_model(self.design(values), heat=_CHAIN)
        heat = dict(increments=self.heat_increments, coupling="settled",
                    coupling_tol=COUPLING_TOL, on_limit_point="continue")
        steps = [*pre, *(Heat({c: values[f"power_{c}"] for c in creases}, name=stage, **heat)
                         for stage, creases in zip(_STAGES, (BASE_CREASES, ARM_CREASES)))]
        return simulate(model, steps, options=NEWTON)

    def _objectives(self) -> dict:
        """The objectives of each stage: its criterion, then each crease's temperature."""
        from simulator.sensitivity import CreaseTemperature

        temps = [CreaseTemperature(c, self.temperature_measure) for c in sorted(self.creases)]
        return {"assembly": [BaseFold(), *temps], "grip": [TipDistance(), *temps]}

    def _stage_values(self, result, stage: str, values: dict, gradient: bool):
        """``(values (k,), gradients (k, n) or None, failure message)`` of a stage's
        objectives; the gradients by variable in the space's order."""
        k = len(result.steps) - 2 + _STAGES.index(stage)
        rec, objectives = result.steps[k], self._objectives()[stage]
        state = rec.state
        if not gradient:
            return np.array([o.terms(result.model, state.u, state.temperature)[0]
                             for o in objectives]), None, ""
        sens = self._differentiate(result, k, objectives, values)
        bad = next((s for s in sens if s.status != "converged"), None)
        if bad is not None:
            return None, None, f"{stage}: sensitivity {bad.status}: {bad.message}"
        heated = set(BASE_CREASES) if stage == "assembly" else set(self.creases)
        keys = [f"geometry[{n}]" if not n.startswith("power_") else
                (f"power[{n[6:]}]" if int(n[6:]) in heated else None)
                for n in self.space.names]
        return (np.array([s.value for s in sens]),
                np.array([[s.gradient[key] if key else 0.0 for key in keys] for s in sens]), "")

    def _differentiate(self, result, k: int, objectives, values: dict):
        """The sensitivities of ``objectives`` at the end of step ``k`` in the powers and the
        size variables: the self-weight and the start's rest angles on each geometry."""
        from simulator.sensitivity import Geometry, differentiate_state
        from simulator.thermal import crease_temperatures

        model, start = result.model, result.steps[k - 1].state
        design = self.design(values)

        def weight(m):
            v = m.mesh.pattern.vertices
            return self_weight(replace(design, L1=v[1, 0], L2=v[4, 1], La=v[8, 1] - v[4, 1]),
                            m.mesh.n_nodes)
        rise = crease_temperatures(start.temperature, model.mesh, "actuation") \
            - start.room_temperature               # the bimorph's 7-node measure [K]
        rot = model.actuators.rotation_per_kelvin(model.mesh)

        def start_at(m):              # the start's rest angles: rot(geometry) x its rise
            return replace(start, crease_rest=start.crease_rest + (
                m.actuators.rotation_per_kelvin(m.mesh) - rot) * rise)
        size = float(np.ptp(model.mesh.nodes, axis=0).max())
        sizes = {n: values[n] for n in self.sizes}

        def run(scale):
            geometry = Geometry(lambda p: self.model({**values, **p}), sizes,
                                scale=dict.fromkeys(sizes, scale))
            return differentiate_state(model, result.steps[k].state, start, list(objectives),
                                       ("power",), geometry=geometry, loads=weight,
                                       start_at=start_at)
        sens = run(size)
        return answer_rough(sens, self.sizes, lambda: run(4 * size))

    def _constraints(self, result, gradient: bool, values=None):
        out = {s: self._stage_values(result, s, values, gradient) for s in _STAGES}
        bad = next((m for v, _, m in out.values() if v is None), None)
        if bad is not None:
            return bad
        (va, da, _), (vg, dg, _) = out["assembly"], out["grip"]
        ft, dt, limit = self.fold_tolerance, self.distance_tolerance, self.temperature_limit
        cons = {"assembly": (ASSEMBLY_FOLD - va[0]) / ft, "grip": (vg[0] - GRIP_DISTANCE) / dt}
        grads = {} if da is None else {"assembly": list(-da[0] / ft), "grip": list(dg[0] / dt)}
        creases = sorted(self.creases)
        for stage, v, d in (("assembly", va, da), ("grip", vg, dg)):
            for j, c in enumerate(creases, 1):
                cons[f"temperature_{stage}_{c}"] = (v[j] - limit) / limit
                if d is not None:
                    grads[f"temperature_{stage}_{c}"] = list(d[j] / limit)
        metrics = {"base_fold [deg]": math.degrees(va[0]),
                   "tip_distance [um]": 1e6 * vg[0],
                   "max temperature [degC]": float(max(va[1:].max(), vg[1:].max())),
                   **{f"temperature_{s}_{c} [degC]": float(v[j])
                      for s, v in (("assembly", va), ("grip", vg))
                      for j, c in enumerate(creases, 1)}}
        return cons, metrics, grads

