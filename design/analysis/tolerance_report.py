"""Which fabrication tolerance matters: exact gradients scaled by tolerances, and first-order
uncertainty propagation (FOSM) of the outputs of a heated design.

:func:`sensitivity_report` differentiates the outputs of a steady heated state (fold angles,
crease temperatures, any objective of :mod:`simulator.sensitivity`) with respect to the
parameters given a fabrication tolerance (a 1-sigma standard deviation, SI), by one adjoint
solve per output. Each parameter's effect is ``g_i sigma_i``; with independent parameters the
first-order (first-order second-moment, FOSM) standard deviation of an output is
``sqrt(sum_i (g_i sigma_i)^2)``, and, the outputs taken as jointly normal with covariance
``G diag(sigma^2) G^T``, the probability of meeting a limit ``low <= y <= high`` is
``Phi((high - y0) / s) - Phi((low - y0) / s)`` (all limits at once: the multivariate normal's
box probability). :class:`SensitivityReport` holds it; ``to_frame()`` is the table by parameter
(display units: deg, mW, um, ppm/K, GPa), sorted by the largest effect; ``summary()`` the
table by output. :func:`~design.analysis.tolerance_mc.monte_carlo_comparison` checks it
against full simulations; :func:`~design.analysis.tolerance_plots.plot_tornado` draws it.
"""

from __future__ import annotations

import logging
import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from simulator import ParameterError

__all__ = ["SensitivityReport", "sensitivity_report", "problem_sensitivity_report",
           "parameter_kind", "parameter_crease",
           "parameter_display", "value_display", "OUTPUT_DISPLAY", "PARAMETER_DISPLAY"]

logger = logging.getLogger(__name__)

#: Parameter kind -> (display unit, factor from SI): the tables' and plots' units.
PARAMETER_DISPLAY = {"power": ("mW", 1e3), "rest_offset": ("deg", 180 / math.pi),
                     "delta_alpha": ("ppm/K", 1e6), "E": ("GPa", 1e-9), "t": ("um", 1e6),
                     "medium_conductivity": ("W/(m K)", 1.0)}
#: An objective's SI unit -> (display unit, factor from SI) of its changes.
OUTPUT_DISPLAY = {"rad": ("deg", 180 / math.pi), "K": ("K", 1.0), "m": ("um", 1e6),
                  "-": ("-", 1.0)}
_PER_CREASE = ("power", "rest_offset", "delta_alpha")
_BIMORPH = ("E1", "t1", "E2", "t2")


def parameter_kind(name: str) -> str:
    """The kind of :data:`simulator.sensitivity.PARAMETER_KINDS` of a gradient's parameter
    name (``"power[2]"`` -> ``"power"``, ``"t1"`` -> ``"bimorph"``)."""
    if _split(name) is not None:
        return _split(name)[0]
    if name in _BIMORPH:
        return "bimorph"
    if name == "medium_conductivity":
        return name
    raise ParameterError(
        f"tolerances: unknown parameter {name!r}; give power[c], rest_offset[c], "
        "delta_alpha[c] (c a crease id), E1, t1, E2, t2 or medium_conductivity.")


def parameter_crease(name: str) -> int | None:
    """The crease id of a per-crease parameter (``"power[2]"`` -> 2), else None."""
    split = _split(name)
    return None if split is None else split[1]


def _split(name) -> tuple | None:
    """``("power", 2)`` of ``"power[2]"``; None for a name that is not kind[crease id]."""
    kind, bracket, rest = str(name).partition("[")
    if kind not in _PER_CREASE or not bracket or not rest.endswith("]"):
        return None
    try:
        return kind, int(rest[:-1])
    except ValueError:
        return None


def parameter_display(name: str) -> tuple:
    """(display unit, factor from SI) of a parameter: ``"power[2]"`` -> ("mW", 1e3)."""
    kind = parameter_kind(name)
    return PARAMETER_DISPLAY[name[0] if kind == "bimorph" else kind]


@dataclass(frozen=True)
class SensitivityReport:
    """Gradients of a heated design's outputs scaled by fabrication tolerances, and their
    first-order propagation.

    Attributes
    ----------
    outputs : dict {name: objective}
        The differentiated outputs (:mod:`simulator.sensitivity` objectives).
    units : dict {name: str}
        Each output's SI unit ("rad", "K", "m"; a temperature's value is in degC).
    values : dict {name: float}
        Each output at the design [SI].
    gradients : dict {name: {parameter: float}}
        ``d output / d parameter`` [SI], for the parameters of ``tolerances``.
    tolerances : dict {parameter: float}
        1-sigma fabrication tolerance of each parameter [SI]; independent.
    nominal : dict {parameter: float}
        Each parameter's value at the design [SI] (a rest offset's is 0).
    sigma : dict {name: float or None}
        First-order standard deviation of each output [SI] (None: no gradient).
    limits : dict {name: (low, high)}
        The limits asked for [SI]; None for an open side.
    probability : dict {name: float or None}
        First-order probability of meeting each limit (normal approximation).
    probability_all : float or None
        First-order probability of meeting every limit at once (the outputs jointly normal);
        None without limits.
    physics : str
        The heat-loss model and medium (:meth:`simulator.ThermalParameters.describe`).
    success, status, message
        "converged", or the first output whose gradient was not ("nonsmooth", "not_steady",
        "singular": :class:`simulator.sensitivity.Sensitivity`).
    model : Model
        The model differentiated (for :func:`monte_carlo_comparison`).
    """

    outputs: dict
    units: dict
    values: dict
    gradients: dict
    tolerances: dict
    nominal: dict
    sigma: dict
    limits: dict
    probability: dict
    probability_all: float | None
    physics: str
    success: bool
    status: str
    message: str
    model: object = field(default=None, repr=False)

    def covariance(self) -> np.ndarray:
        """First-order covariance of the outputs, (n_out, n_out) [SI], in ``outputs`` order:
        ``G diag(sigma^2) G^T``."""
        names = list(self.tolerances)
        s = np.array([self.tolerances[p] for p in names])
        G = np.array([[self.gradients[o].get(p, math.nan) for p in names]
                      for o in self.outputs]) * s
        return G @ G.T

    def effect(self, output: str) -> dict:
        """``g_i sigma_i`` of each parameter on ``output`` [SI]."""
        self._check_output(output)
        return {p: self.gradients[output][p] * t for p, t in self.tolerances.items()
                if p in self.gradients[output]}

    def _check_output(self, output):
        if output not in self.outputs:
            raise ParameterError(f"output = {output!r}; the report has {list(self.outputs)}.")

    def column(self, output: str) -> str:
        """The table's column of ``output``'s effect per tolerance, e.g. ``d fold_5 [deg] per
        tolerance``."""
        self._check_output(output)
        return f"d {output} [{OUTPUT_DISPLAY[self.units[output]][0]}] per tolerance"

    def to_frame(self, sort_by: str | None = None):
        """One row per parameter, sorted by the size of its effect on ``sort_by`` (default
        the first output), largest first: ``parameter``, ``unit``, ``nominal``,
        ``tolerance`` (1 sigma, in ``unit``), and per output ``d <output> [<unit>] per
        tolerance`` (the effect of +1 sigma) and ``<output> variance share [-]`` (the
        parameter's share of the first-order variance). The gradients in SI are
        ``gradients``.
        """
        import pandas as pd

        sort_by = next(iter(self.outputs)) if sort_by is None else sort_by
        self._check_output(sort_by)
        rows = []
        for p, t in self.tolerances.items():
            unit, k = parameter_display(p)
            row = {"parameter": p, "unit": unit, "nominal": self.nominal[p] * k,
                   "tolerance": t * k}
            for o in self.outputs:
                ko = OUTPUT_DISPLAY[self.units[o]][1]
                g = self.gradients[o].get(p)
                s = self.sigma[o]
                row[self.column(o)] = None if g is None else g * t * ko
                row[f"{o} variance share [-]"] = None if g is None or not s else \
                    (g * t / s) ** 2
            rows.append(row)
        df = pd.DataFrame(rows)
        order = df[self.column(sort_by)].abs().sort_values(ascending=False, kind="stable")
        df = df.loc[order.index].reset_index(drop=True)
        df.attrs["physics"] = self.physics
        return df

    def summary(self):
        """One row per output (and ``all limits``): ``output``, ``unit``, ``nominal``,
        ``sigma (FOSM)``, ``low``, ``high`` (display units; a temperature in degC),
        ``P(meet) (FOSM) [-]``."""
        import pandas as pd

        rows = []
        for o in self.outputs:
            unit, k = value_display(self.units[o])
            low, high = self.limits.get(o, (None, None))
            rows.append({"output": o, "unit": unit, "nominal": self.values[o] * k,
                         "sigma (FOSM)": None if self.sigma[o] is None else
                         self.sigma[o] * k,
                         "low": None if low is None else low * k,
                         "high": None if high is None else high * k,
                         "P(meet) (FOSM) [-]": self.probability.get(o)})
        if self.limits:
            rows.append({"output": "all limits", "unit": "-",
                         "P(meet) (FOSM) [-]": self.probability_all})
        return pd.DataFrame(rows)


def value_display(unit: str) -> tuple:
    """(display unit, factor) of an output's value: a temperature in degC."""
    return ("degC", 1.0) if unit == "K" else OUTPUT_DISPLAY[unit]


def sensitivity_report(result, tolerances: dict, outputs: dict | None = None,
                       limits: dict | None = None, step: int = -1) -> SensitivityReport:
    """Gradients of a heated design's outputs scaled by fabrication tolerances, with their
    first-order (FOSM) standard deviations and probabilities of meeting limits.

    Parameters
    ----------
    result : SimulationResult
        A simulation whose step ``step`` is a successful ``Heat`` step with ``coupling``
        "settled" (:func:`simulator.sensitivity.differentiate`: the chain heat loss).
    tolerances : dict {parameter: float}
        1-sigma tolerance [SI] of each parameter, independent: ``"power[c]"`` [W],
        ``"rest_offset[c]"`` (the residual fold of crease c) [rad], ``"delta_alpha[c]"``
        [1/K], ``"E1"``, ``"E2"`` [Pa], ``"t1"``, ``"t2"`` [m], ``"medium_conductivity"``
        [W/(m K)].
    outputs : dict {name: objective}, optional
        The outputs (:class:`~simulator.sensitivity.FoldAngle`,
        :class:`~simulator.sensitivity.CreaseTemperature`, ...). Default: ``fold_<c>`` (the
        fold angle) and ``temperature_<c>`` (the hottest crease node, "crease_max") of every
        heated crease c.
    limits : dict {name: (low, high)}, optional
        Bounds of outputs [SI: rad, degC, m], None for an open side, e.g. ``{"fold_5":
        (math.radians(100), None), "temperature_5": (None, 250.0)}``.
    step : int
        Index of the heating step in ``result.steps``.

    Returns
    -------
    SensitivityReport
    """
    from simulator.sensitivity import CreaseTemperature, FoldAngle, differentiate

    tolerances = _check_tolerances(tolerances)
    steps = list(getattr(result, "steps", None) or ())
    if not steps or not hasattr(result, "model"):
        raise ParameterError(f"result = {type(result).__name__}: give the SimulationResult of "
                             "a simulation that ends with a Heat step.")
    try:
        rec = steps[step]
    except (IndexError, TypeError):
        raise ParameterError(f"step = {step!r}; the result has {len(steps)} steps.") from None
    if outputs is None:
        mesh = result.model.mesh
        heated = [int(c) for c, p in zip(mesh.crease_ids, rec.state.crease_power) if p > 0]
        outputs = {**{f"fold_{c}": FoldAngle(c) for c in heated},
                   **{f"temperature_{c}": CreaseTemperature(c, "crease_max") for c in heated}}
    if not outputs:
        raise ParameterError("outputs: give at least one {name: objective} (the default, the "
                             "heated creases' folds and temperatures, found no heated crease).")
    outputs = dict(outputs)
    limits = _check_limits(limits, outputs)
    kinds = sorted({parameter_kind(p) for p in tolerances})
    sens = {o: differentiate(result, obj, kinds, step=step) for o, obj in outputs.items()}
    known = max((list(s.gradient) for s in sens.values()), key=len)
    missing = [p for p in tolerances if p not in known]
    if missing and known:
        raise ParameterError(f"tolerances: {missing} are not parameters of this model; its "
                             f"parameters: {known}.")
    bad = next((o for o, s in sens.items() if s.status != "converged"), None)
    gradients = {o: {p: s.gradient[p] for p in tolerances if p in s.gradient}
                 for o, s in sens.items()}
    sigma = {o: _fosm(gradients[o], tolerances) for o in outputs}
    values = {o: s.value for o, s in sens.items()}
    probability = {o: _probability(values[o], sigma[o], *limits[o]) for o in limits}
    report = SensitivityReport(
        outputs=outputs, units={o: s.unit for o, s in sens.items()}, values=values,
        gradients=gradients, tolerances=tolerances,
        nominal=_nominal(result.model, rec.state, tolerances), sigma=sigma, limits=limits,
        probability=probability, probability_all=None,
        physics=result.model.thermal.describe(len(result.model.mesh.triangles)),
        success=bad is None, status="converged" if bad is None else sens[bad].status,
        message="converged" if bad is None else f"{bad}: {sens[bad].message}",
        model=result.model)
    joint = _joint_probability(report) if limits else None
    from dataclasses import replace

    logger.info("sensitivity report: %d outputs, %d parameters, %s", len(outputs),
                len(tolerances), report.status)
    return replace(report, probability_all=joint)


def problem_sensitivity_report(problem, x, tolerances: dict) -> SensitivityReport:
    """:func:`sensitivity_report` of a design problem at the design ``x``: the problem
    simulates ``x`` and gives the outputs and limits (its constraints).

    Parameters
    ----------
    problem : DesignProblem
        A problem with ``simulate(x)``, ``outputs()`` and ``limits()``
        (:class:`design.devices.FoldTargetProblem`: the folds at least their targets, the
        crease temperatures at most the limit); ``problem.steps(x)`` gives the steps for
        :func:`~design.analysis.tolerance_mc.monte_carlo_comparison`.
    x : sequence or dict
        The design (a vector in the problem's variable order, or {name: value}).
    tolerances : dict {parameter: float}
        As for :func:`sensitivity_report`.
    """
    missing = [m for m in ("simulate", "outputs", "limits") if not hasattr(problem, m)]
    if missing:
        raise ParameterError(f"problem: {type(problem).__name__} has no {', '.join(missing)}; "
                             "use a FoldTargetProblem, or simulate the design and call "
                             "sensitivity_report(result, tolerances, outputs, limits).")
    result = problem.simulate(x)
    if not result.success:
        raise ParameterError(f"x: the design's simulation ended {result.status!r} "
                             f"({result.message}); give a design that simulates.")
    return sensitivity_report(result, tolerances, outputs=problem.outputs(),
                              limits=problem.limits())


def _check_tolerances(tolerances) -> dict:
    if not isinstance(tolerances, dict) or not tolerances:
        raise ParameterError(f"tolerances = {tolerances!r}: give a dict {{parameter: 1-sigma "
                             "tolerance [SI]}, e.g. {'power[2]': 5e-4, 't1': 1e-8}.")
    out = {}
    for p, t in tolerances.items():
        parameter_kind(p)
        if isinstance(t, bool) or not (isinstance(t, numbers.Real) and math.isfinite(t)
                                       and t >= 0):
            raise ParameterError(f"tolerances[{p!r}] = {t!r}: give a finite standard "
                                 "deviation >= 0 in SI units.")
        out[str(p)] = float(t)
    if not any(out.values()):
        raise ParameterError("tolerances: every tolerance is 0; give at least one > 0.")
    return out


def _check_limits(limits, outputs) -> dict:
    out = {}
    for o, bounds in dict(limits or {}).items():
        if o not in outputs:
            raise ParameterError(f"limits: {o!r} is not an output; outputs: {list(outputs)}.")
        try:
            low, high = bounds
        except (TypeError, ValueError):
            raise ParameterError(f"limits[{o!r}] = {bounds!r}: give (low, high), None for an "
                                 "open side.") from None
        low = None if low is None else float(low)
        high = None if high is None else float(high)
        if (low is None and high is None) or (low is not None and high is not None
                                               and not low < high):
            raise ParameterError(f"limits[{o!r}] = {bounds!r}: give low < high, at least one "
                                 "of them a number.")
        out[o] = (low, high)
    return out


def _fosm(gradient: dict, tolerances: dict) -> float | None:
    """``sqrt(sum (g_i sigma_i)^2)``; None without a gradient."""
    if not gradient:
        return None
    return float(math.sqrt(sum((g * tolerances[p]) ** 2 for p, g in gradient.items())))


def _probability(value, sigma, low, high) -> float | None:
    """P(low <= Y <= high) for Y ~ N(value, sigma^2)."""
    from scipy.stats import norm

    if sigma is None:
        return None
    lo = -math.inf if low is None else low
    hi = math.inf if high is None else high
    if sigma == 0:
        return float(lo <= value <= hi)
    return float(norm.cdf((hi - value) / sigma) - norm.cdf((lo - value) / sigma))


def _joint_probability(report) -> float | None:
    """P(every limit met) with the outputs jointly normal (first-order covariance)."""
    from scipy.stats import multivariate_normal

    names = list(report.limits)
    if any(report.sigma[o] is None for o in names):
        return None
    if len(names) == 1:
        return report.probability[names[0]]
    index = [list(report.outputs).index(o) for o in names]
    cov = report.covariance()[np.ix_(index, index)]
    mean = np.array([report.values[o] for o in names])
    lo = np.array([-math.inf if report.limits[o][0] is None else report.limits[o][0]
                   for o in names])
    hi = np.array([math.inf if report.limits[o][1] is None else report.limits[o][1]
                   for o in names])
    dist = multivariate_normal(mean=mean, cov=cov, allow_singular=True)
    return float(np.clip(dist.cdf(hi, lower_limit=lo), 0.0, 1.0))


def _nominal(model, state, tolerances) -> dict:
    """Each parameter's value at the design [SI]."""
    mesh, acts = model.mesh, model.actuators
    out = {}
    for p in tolerances:
        kind = parameter_kind(p)
        if kind in ("power", "rest_offset", "delta_alpha"):
            c = parameter_crease(p)
            out[p] = (float(state.crease_power[mesh.crease_row_of(c)]) if kind == "power"
                      else 0.0 if kind == "rest_offset"
                      else float(acts.delta_alpha.get(c, 0.0)) if acts else math.nan)
        elif kind == "bimorph":
            out[p] = float(getattr(acts.bimorph, p)) if acts else math.nan
        else:
            out[p] = float(model.thermal.medium.thermal_conductivity)
    return out
