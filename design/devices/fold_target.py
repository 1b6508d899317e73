"""Heater powers that reach target fold angles with the least total power: a design problem
with exact gradients (:mod:`simulator.sensitivity`).

Variables: the heater power of each heated crease (W). Objective: the total power (W).
Constraints (g <= 0): each target crease folds at least its target, ``(target - fold) /
target``, and each heated crease stays below the temperature limit, ``(T - limit) / limit``
(``T`` the hottest crease node, degC). ``evaluate_with_gradient`` adds their gradients by
one adjoint solve per constraint (the total power's gradient is 1 per heater), so the
gradient methods of :func:`design.optimize` run on it.
"""

from __future__ import annotations

import math

from dataclasses import replace

from simulator import Heat, NewtonOptions, ParameterError, SelfFold, simulate
from simulator.cases import get_case

from ..core.problem import DesignProblem, EvaluationOutcome
from ..core.space import DesignSpace, Variable

__all__ = ["FoldTargetProblem"]

#: Newton and coupling tolerances of the evaluations: tight, so that the finite differences
#: of the evaluations agree with the gradients (the state's noise is about 1e-13 of itself).
NEWTON = NewtonOptions(atol=1e-15, rtol=1e-14)
COUPLING_TOL = 1e-10
#: A geometry parameter whose residual columns Geometry reports rough (their central
#: differences at h and 4 h disagree: round-off where a column is small beside the element
#: forces) is differentiated again at the step 4 h; where every objective's derivative in it
#: changes by at most this fraction of that objective's largest geometry derivative (the
#: truncation error at 4 h is 16 times that at h), the report is answered; else it stands.
ROUGH_GRADIENT_RTOL = 1e-4


class HeaterPowerProblem(DesignProblem):
    """Least total heater power: the powers of ``self.creases`` [W] are the variables
    ``power_<crease>`` (beside others a subclass may add, e.g. dimensions), the objective
    their sum (its gradient 1 in each, 0 in the others); a subclass gives
    ``simulate(values)`` and ``_constraints(result, gradient, values) -> (constraints,
    metrics, constraint gradients)``, or a str saying why the simulated design cannot be
    judged."""

    def _outcome(self, values: dict, gradient: bool) -> EvaluationOutcome:
        result = self.simulate(values)
        if not result.success:
            return EvaluationOutcome(math.inf, {}, {}, "failed", result.message)
        out = self._constraints(result, gradient, values)
        if isinstance(out, str):
            return EvaluationOutcome(math.inf, {}, {}, "failed", out)
        cons, metrics, grads = out
        powers = {f"power_{c}" for c in self.creases}
        return EvaluationOutcome(sum(v for k, v in values.items() if k in powers), cons,
                                 metrics, objective_gradient=[
                                     float(v.name in powers) for v in self.space.variables]
                                 if gradient else None,
                                 constraint_gradients=grads if gradient else None)

    def _evaluate(self, values: dict) -> EvaluationOutcome:
        return self._outcome(values, gradient=False)

    def _evaluate_with_gradient(self, values: dict) -> EvaluationOutcome:
        return self._outcome(values, gradient=True)


class FoldTargetProblem(HeaterPowerProblem):
    """Least total heater power of a case's creases reaching target fold angles, with the
    crease temperatures under a limit.

    Parameters
    ----------
    targets : dict {crease: fold angle [rad]}
        Lower bounds of the fold angles (positive).
    temperature_limit : float [degC]
        Upper bound of every heated crease's hottest node.
    case : str
        A case of :func:`simulator.cases.get_case` with a self-fold first and a heating last
        (``"double_fold"``, ``"single_fold"``); its heated creases are the variables.
    max_power : float [W]
        Upper bound of each heater power.
    start_power : float [W]
        Start design, every heater.
    heat_increments : int
        Increments of the heating step (``coupling="settled"``: a steady coupled state).
    """

    name = "fold_target"

    def __init__(self, targets: dict, temperature_limit: float = 250.0,
                 case: str = "double_fold", max_power: float = 0.02,
                 start_power: float = 0.01, heat_increments: int = 5):
        self.case = get_case(case, thermal_steps=heat_increments, coupling="settled")
        heat = self.case.steps[-1]
        if not isinstance(heat, Heat) or not isinstance(self.case.steps[0], SelfFold):
            raise ParameterError(f"case = {case!r} must start with a SelfFold and end with a "
                                 "Heat step; use 'double_fold' or 'single_fold'.")
        self.creases = tuple(sorted(self.case.model.actuators.delta_alpha))
        bad = {c: t for c, t in dict(targets).items()
               if c not in self.creases or not (math.isfinite(t) and t > 0)}
        if bad or not targets:
            raise ParameterError(f"targets = {targets!r}: give positive fold angles [rad] of "
                                 f"the heated creases {self.creases}.")
        if not (math.isfinite(temperature_limit) and temperature_limit > 0):
            raise ParameterError(f"temperature_limit = {temperature_limit!r} must be a "
                                 "positive temperature [degC].")
        self.targets = {int(c): float(t) for c, t in targets.items()}
        self.temperature_limit = float(temperature_limit)
        self.case_name, self.heat_increments = case, int(heat_increments)
        self.space = DesignSpace([
            Variable(f"power_{c}", 0.0, max_power, 1e-3, start_power, unit="W",
                     display_scale=1e3, display_unit="mW") for c in self.creases])

    def settings(self) -> dict:
        return {"problem": self.name, "case": self.case_name,
                "targets [rad]": {str(c): t for c, t in self.targets.items()},
                "temperature_limit [degC]": self.temperature_limit,
                "heat_increments": self.heat_increments,
                "variables": [v.to_dict() for v in self.space.variables]}

    def steps(self, x) -> list:
        """The case's steps with the heating of design ``x`` (a vector or {name: value}):
        what :meth:`simulate` runs (with :data:`NEWTON`)."""
        values = self.space.to_mapping(x)
        steps = list(self.case.steps)
        steps[-1] = Heat({c: values[f"power_{c}"] for c in self.creases},
                         increments=self.heat_increments, coupling="settled",
                         coupling_tol=COUPLING_TOL)
        return steps

    def simulate(self, x):
        """The :class:`~simulator.results.SimulationResult` of design ``x``."""
        return simulate(self.case.model, self.steps(x), options=NEWTON)

    def outputs(self) -> dict:
        """The constraints' objectives of :mod:`simulator.sensitivity`, by constraint name:
        ``fold_<c>`` (:class:`~simulator.sensitivity.FoldAngle`) of each target crease,
        ``temperature_<c>`` (the hottest crease node) of each heated crease."""
        from simulator.sensitivity import CreaseTemperature, FoldAngle

        return {**{f"fold_{c}": FoldAngle(c) for c in self.targets},
                **{f"temperature_{c}": CreaseTemperature(c, "crease_max")
                   for c in self.creases}}

    def limits(self) -> dict:
        """The constraints as bounds of :meth:`outputs`, ``{name: (low, high)}`` [rad, degC]:
        each fold at least its target, each temperature at most the limit."""
        return {**{f"fold_{c}": (t, None) for c, t in self.targets.items()},
                **{f"temperature_{c}": (None, self.temperature_limit) for c in self.creases}}

    def _constraints(self, result, gradient: bool, values=None):
        from simulator.sensitivity import differentiate

        cons, metrics, grads = {}, {}, {}
        for name, objective in self.outputs().items():
            c = int(name.rsplit("_", 1)[1])
            if gradient:
                sens = differentiate(result, objective, "power")
                if sens.status != "converged":
                    return f"{name}: sensitivity {sens.status}: {sens.message}"
                value, dvalue = sens.value, [sens.gradient[f"power[{k}]"]
                                             for k in self.creases]
            else:
                state = result.steps[-1].state
                value = objective.terms(result.model, state.u, state.temperature)[0]
                dvalue = None
            if name.startswith("fold"):
                ref, sign, metrics[f"{name} [rad]"] = self.targets[c], -1.0, value
                cons[name] = (self.targets[c] - value) / ref
            else:
                ref, sign, metrics[f"{name} [degC]"] = self.temperature_limit, 1.0, value
                cons[name] = (value - self.temperature_limit) / ref
            if dvalue is not None:
                grads[name] = [sign * d / ref for d in dvalue]
        return cons, metrics, grads


def answer_rough(sens, sizes, coarser) -> tuple:
    """``sens`` (a tuple of :class:`~simulator.sensitivity.Sensitivity`, one per objective)
    with :class:`~simulator.sensitivity.Geometry`'s reports of rough columns of the
    parameters ``sizes`` answered where the gradients of ``coarser()`` (the same at the step
    4 h) agree (:data:`ROUGH_GRADIENT_RTOL`); other reports stand."""
    notes = set(sens[0].nonsmooth)
    rough = {n: m for n in sizes for m in notes
             if m.startswith(f"geometry[{n}]: the residual's central differences")}
    if not rough or any(s.status not in ("converged", "nonsmooth") for s in sens):
        return sens
    other = coarser()
    answered = {note for n, note in rough.items() if all(
        abs(a.gradient[f"geometry[{n}]"] - b.gradient[f"geometry[{n}]"])
        <= ROUGH_GRADIENT_RTOL * max(abs(v) for key, v in a.gradient.items()
                                     if key.startswith("geometry["))
        for a, b in zip(sens, other))}
    return tuple(_without(s, answered) for s in sens)


def _without(sens, answered: set):
    """``sens`` without the non-smooth reports ``answered``; converged if none is left."""
    left = tuple(m for m in sens.nonsmooth if m not in answered)
    if left or sens.status != "nonsmooth":
        return replace(sens, nonsmooth=left)
    return replace(sens, nonsmooth=left, status="converged", success=True,
                   message=f"converged ({len(answered)} rough geometry column(s) checked at "
                   "the step 4 h)")
