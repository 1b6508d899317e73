"""Heater powers of any heated pattern that bring its fold angles to targets with the least
total power: an inverse-design problem with exact gradients (:mod:`simulator.sensitivity`).

Variables: the heater power of each heated crease (W), as many as the model has (a Miura
sheet of 8 x 8 cells: 112). Objective: the total power (W). Constraints (g <= 0), two per
target crease, ``(fold - target - tol) / tol`` and ``(target - fold - tol) / tol`` (the fold
angle within ``tol`` of its target), and one per crease of the model, ``(T - limit) /
limit`` (``T`` its centre-line mean or hottest node, degC). ``evaluate_with_gradient`` adds
every gradient by one factorisation of the coupled Jacobian (a list of objectives to
:func:`simulator.sensitivity.differentiate`): the total power's gradient is 1 per heater.
:class:`~design.devices.fold_target.FoldTargetProblem` is the double fold's lower-bound form.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from simulator import Heat, ParameterError, simulate
from simulator._validate import integer, one_of, positive

from ..core.space import DesignSpace, Variable
from .fold_target import COUPLING_TOL, NEWTON, HeaterPowerProblem, answer_rough
from .limits import SU8_LIMIT

__all__ = ["FoldShapeProblem"]

_MEASURES = ("centre_line", "crease_max")


class FoldShapeProblem(HeaterPowerProblem):
    """Least total heater power that brings fold angles within ``tolerance`` of targets, with
    every crease under a temperature limit.

    Parameters
    ----------
    model : Model
        A model with actuators and a heat loss :mod:`simulator.sensitivity` differentiates:
        the chain loss (``ChainLoss``), e.g. ``make_miura_model(MiuraDesign(...,
        loss_model="chain"))``, or the dense integral loss (``IntegralLoss``, not lumped; on
        large sheets its fast operator is not differentiated and the gradient is refused).
        Heated from its initial state by one settled ``Heat`` step.
    targets : dict {crease: fold angle [rad]}
        Target fold angles (signed, as :class:`simulator.sensitivity.FoldAngle` measures them)
        of some creases of the model.
    tolerance : float [rad]
        Allowed ``|fold - target|`` (0.5 deg).
    temperature_limit : float [degC]
        Upper bound of every crease's temperature (1.2 T_g of SU-8, 252 degC).
    temperature_measure : {"centre_line", "crease_max"}
        The crease temperature judged: the centre-line mean (theory 5.4) or the hottest node.
    creases : sequence of int, optional
        The heated creases, the variables (default: every crease with an actuator).
    max_power, start_power : float [W]
        Upper bound and start value of each heater power.
    heat_increments : int
        Increments of the heating step (``coupling="settled"``: a steady coupled state). From
        a flat sheet (a bifurcation point of a Miura mechanism) too few increments can land
        on another folding mode: an 8 x 8-cell Miura at 2.7 mW per crease does in 2, not in
        5 or 10.
    label : str
        Names the model in :meth:`settings` (the evaluation log's hash).
    widths : bool
        Add the width of each heated crease as a variable ``W_<crease>`` [m] (start: the
        model's; the model rebuilt from its pattern with those widths, its supports and
        parameters kept), its gradients by :class:`~simulator.sensitivity.Geometry`.
    width_bounds : (float, float) [m]
        Bounds of the widths (the design layer's crease-width bounds, ``MIURA_SPACE`` and
        ``GRIPPER_SPACE``: 100-300 um).
    """

    name = "fold_shape"

    def __init__(self, model, targets: dict, tolerance: float = math.radians(0.5),
                 temperature_limit: float = SU8_LIMIT.value,
                 temperature_measure: str = "centre_line", creases=None,
                 max_power: float = 0.03, start_power: float = 0.005,
                 heat_increments: int = 10, label: str = "model", widths: bool = False,
                 width_bounds: tuple = (100e-6, 300e-6)):
        loss = getattr(getattr(model, "thermal", None), "loss", None)
        kind = getattr(loss, "model", None)
        if kind not in ("chain", "integral") or getattr(loss, "lumped", False) \
                or model.actuators is None:
            raise ParameterError(
                f"model: heat loss {kind!r}{' (lumped)' if getattr(loss, 'lumped', False) else ''}"
                f"{'' if model.actuators is not None else ', no actuators'}; FoldShapeProblem "
                "needs a model with actuators and a heat loss simulator.sensitivity "
                "differentiates: the chain loss or the integral loss, not lumped; e.g. "
                "MiuraDesign(loss_model='chain').")
        ids = [int(c) for c in model.mesh.crease_ids]
        self.creases = tuple(sorted(int(c) for c in (
            model.actuators.delta_alpha if creases is None else creases)))
        if not self.creases or any(c not in ids for c in self.creases):
            raise ParameterError(f"creases = {creases!r}: give creases of the model "
                                 f"({ids[:5]}...).")
        bad = {c: t for c, t in dict(targets).items()
               if int(c) not in ids or not math.isfinite(t)}
        if bad or not targets:
            raise ParameterError(f"targets = {bad or targets!r}: give finite fold angles "
                                 "[rad] of creases of the model.")
        positive("tolerance", tolerance, "rad")
        positive("temperature_limit", temperature_limit, "degC")
        positive("max_power", max_power, "W")
        one_of("temperature_measure", temperature_measure, _MEASURES)
        integer("heat_increments", heat_increments, 1)
        self.model, self.all_creases = model, tuple(ids)
        self.targets = {int(c): float(t) for c, t in sorted(targets.items())}
        self.tolerance, self.temperature_limit = float(tolerance), float(temperature_limit)
        self.temperature_measure, self.heat_increments = temperature_measure, heat_increments
        self.label, self.widths = str(label), bool(widths)
        lo, hi = (float(v) for v in width_bounds)
        if self.widths and not 0 < lo < hi:
            raise ParameterError(f"width_bounds = {width_bounds!r}: give (lower, upper) "
                                 "crease widths [m], 0 < lower < upper.")
        start = model.mesh.pattern.crease_width
        sizes = [Variable(f"W_{c}", lo, hi, (hi - lo) / 20, min(max(float(start[c]), lo), hi))
                 for c in self.creases] if self.widths else []
        self.space = DesignSpace([
            Variable(f"power_{c}", 0.0, max_power, max_power / 20, start_power, unit="W",
                     display_scale=1e3, display_unit="mW") for c in self.creases] + sizes)

    def settings(self) -> dict:
        return {"problem": self.name, "model": self.label,
                "nodes": int(self.model.mesh.n_nodes), "creases": list(self.creases),
                "targets [rad]": {str(c): t for c, t in self.targets.items()},
                "tolerance [rad]": self.tolerance,
                "temperature_limit [degC]": self.temperature_limit,
                "temperature_measure": self.temperature_measure,
                "heat_increments": self.heat_increments,
                "variables": [v.to_dict() for v in self.space.variables]}

    def model_at(self, values: dict):
        """The model with the crease widths ``W_<crease>`` in ``values`` (the model itself
        without width variables): rebuilt from its pattern, supports and parameters kept."""
        widths = {int(k[2:]): float(v) for k, v in values.items() if k.startswith("W_")}
        if not widths:
            return self.model
        from simulator import make_mesh, make_model

        m = self.model
        pattern = m.mesh.pattern
        mesh = make_mesh(replace(pattern, crease_width={
            int(c): float(pattern.crease_width[c]) for c in self.all_creases} | widths))
        return make_model(mesh, m.supports, m.params, m.contact, m.thermal, m.actuators)

    def simulate(self, values: dict):
        """The simulation of a design (``{"power_<crease>": W}``, with ``"W_<crease>"``
        [m]): one settled heating."""
        return simulate(self.model_at(values), [
            Heat({c: values[f"power_{c}"] for c in self.creases},
                 increments=self.heat_increments, coupling="settled",
                 coupling_tol=COUPLING_TOL)], options=NEWTON)

    def _objectives(self) -> tuple:
        """``(folds, temperatures)``: the objectives of :mod:`simulator.sensitivity`."""
        from simulator.sensitivity import CreaseTemperature, FoldAngle

        return ([FoldAngle(c) for c in self.targets],
                [CreaseTemperature(c, self.temperature_measure) for c in self.all_creases])

    def _values(self, result, gradient: bool, values=None):
        """``(values (k,), gradients (k, n) or None, failure message)`` of the objectives,
        the gradients by variable in the space's order."""
        folds, temps = self._objectives()
        objectives = folds + temps
        state = result.steps[-1].state
        if not gradient:
            return np.array([o.terms(result.model, state.u, state.temperature)[0]
                             for o in objectives]), None, ""
        sens = self._differentiate(result, objectives, values)
        bad = next((s for s in sens if s.status != "converged"), None)
        if bad is not None:
            return None, None, f"sensitivity {bad.status}: {bad.message}"
        keys = [f"geometry[{n}]" if n.startswith("W_") else f"power[{n[6:]}]"
                for n in self.space.names]
        return (np.array([s.value for s in sens]),
                np.array([[s.gradient[k] for k in keys] for s in sens]), "")

    def _differentiate(self, result, objectives, values):
        """The objectives' sensitivities in the powers and the widths (``W_<crease>``, by
        :class:`~simulator.sensitivity.Geometry`; rough reports answered by
        :func:`~design.devices.fold_target.answer_rough`)."""
        from simulator.sensitivity import Geometry, differentiate

        if not self.widths:
            return differentiate(result, objectives, "power")
        sizes = {n: values[n] for n in self.space.names if n.startswith("W_")}
        size = float(np.ptp(result.model.mesh.nodes, axis=0).max())

        def run(scale):
            return differentiate(result, objectives, "power", geometry=Geometry(
                self.model_at, sizes, scale=dict.fromkeys(sizes, scale)))
        return answer_rough(run(size), tuple(sizes), lambda: run(4 * size))

    def _constraints(self, result, gradient: bool, values=None):
        v, dv, message = self._values(result, gradient, values)
        if v is None:
            return message
        nf, tol, limit = len(self.targets), self.tolerance, self.temperature_limit
        error = v[:nf] - np.array(list(self.targets.values()))          # fold - target [rad]
        temps = v[nf:]
        cons, grads = {}, {}
        for i, c in enumerate(self.targets):
            cons[f"above_{c}"], cons[f"below_{c}"] = (error[i] - tol) / tol, (-error[i] - tol) / tol
            if dv is not None:
                grads[f"above_{c}"], grads[f"below_{c}"] = list(dv[i] / tol), list(-dv[i] / tol)
        for j, c in enumerate(self.all_creases):
            cons[f"temperature_{c}"] = (temps[j] - limit) / limit
            if dv is not None:
                grads[f"temperature_{c}"] = list(dv[nf + j] / limit)
        metrics = {"max fold error [deg]": float(np.degrees(np.abs(error).max())),
                   "max temperature [degC]": float(temps.max()),
                   **{f"fold_{c} [deg]": float(np.degrees(v[i]))
                      for i, c in enumerate(self.targets)},
                   **{f"temperature_{c} [degC]": float(t)
                      for c, t in zip(self.all_creases, temps)}}
        return cons, metrics, grads
