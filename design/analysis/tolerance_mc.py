"""Monte Carlo check of a :class:`~design.analysis.tolerance_report.SensitivityReport`:
the same parameters, normal with the same standard deviations, through full simulations.

:func:`perturbed_protocol` applies parameter changes to a model and its steps (the heater
power to the heating step, a residual fold to the self-fold before it, the bimorph and the
medium to the model). :func:`monte_carlo_comparison` samples the report's tolerances (seeded,
in the calling process), simulates every sample and compares, per output, the sample
standard deviation (with its chi-square confidence interval) and the fraction meeting the
limits (with its Wilson interval) with the first-order values. Since every sample's
first-order prediction ``y0 + sum g_i dp_i`` is known, it also gives the linearisation's
error sample by sample, which has no sampling error.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np

from simulator import Heat, NewtonOptions, ParameterError, SelfFold, simulate

from .tolerance_report import (OUTPUT_DISPLAY, parameter_crease, parameter_display,
                                 parameter_kind, value_display)
from .uncertainty import wilson_interval

__all__ = ["MonteCarloComparison", "monte_carlo_comparison", "perturbed_protocol",
           "sigma_interval"]

logger = logging.getLogger(__name__)


def perturbed_protocol(model, steps, changes: dict, heat_step: int = -1) -> tuple:
    """``(model, steps)`` with parameters moved by ``changes`` {parameter: change [SI]}
    (names of :func:`~design.analysis.tolerance_report.sensitivity_report`'s tolerances).

    ``power[c]`` is added to crease c's power in ``steps[heat_step]`` (a ``Heat``);
    ``rest_offset[c]`` to crease c's target in the last ``SelfFold`` before it (the rest
    angle the heating starts from); the others to the model's actuators or medium.
    """
    steps = list(steps)
    i = heat_step % len(steps) if steps else 0
    if not steps or not isinstance(steps[i], Heat):
        raise ParameterError(f"heat_step = {heat_step}: steps[{heat_step}] must be a Heat step.")
    acts, thermal = model.actuators, model.thermal
    power, folds, delta_alpha, bimorph = {}, {}, {}, {}
    for p, d in changes.items():
        kind = parameter_kind(p)
        c = parameter_crease(p)
        target = {"power": power, "rest_offset": folds, "delta_alpha": delta_alpha}.get(kind)
        if target is not None:
            target[c] = target.get(c, 0.0) + float(d)
        elif kind == "bimorph":
            bimorph[p] = float(d)
        else:
            thermal = replace(thermal, medium=thermal.medium.with_properties(
                thermal_conductivity=thermal.medium.thermal_conductivity + float(d)))
    if (delta_alpha or bimorph) and acts is None:
        raise ParameterError("changes: delta_alpha and the bimorph layers need a model with "
                             "actuators.")
    if delta_alpha:
        da = dict(acts.delta_alpha)
        acts = replace(acts, delta_alpha={c: da.get(c, 0.0) + delta_alpha.get(c, 0.0)
                                          for c in set(da) | set(delta_alpha)})
    if bimorph:
        b = acts.bimorph
        acts = replace(acts, bimorph=replace(b, **{q: getattr(b, q) + d
                                                   for q, d in bimorph.items()}))
    if power:
        steps[i] = replace(steps[i], power=_per_crease(steps[i].power, power))
    if folds:
        j = next((k for k in range(i - 1, -1, -1) if isinstance(steps[k], SelfFold)), None)
        if j is None or not steps[j].reset_others and set(folds) - set(steps[j].folds):
            raise ParameterError("changes: a rest_offset needs a SelfFold before the heating "
                                 "step that sets the crease's rest angle.")
        steps[j] = replace(steps[j], folds=_per_crease(steps[j].folds, folds))
    return replace(model, actuators=acts, thermal=thermal), steps


def _per_crease(mapping, add: dict) -> dict:
    """``mapping`` {crease or tuple of creases: value} per crease, plus ``add``."""
    out = {}
    for key, v in dict(mapping).items():
        for c in (key if isinstance(key, tuple) else (key,)):
            out[int(c)] = out.get(int(c), 0.0) + float(v)
    for c, d in add.items():
        out[c] = out.get(c, 0.0) + d
    return out


@dataclass(frozen=True)
class MonteCarloComparison:
    """First-order propagation against Monte Carlo simulations.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per output and ``all limits``: ``output``, ``unit``, ``sigma (FOSM)``,
        ``sigma (MC)`` with ``sigma_low (MC)``, ``sigma_high (MC)`` (chi-square interval),
        ``mean (MC)``, ``nominal``, ``linearisation error (rms)`` (of ``y - y_lin`` over the
        samples), ``P(meet) (FOSM) [-]``, ``P(meet) (MC) [-]`` with ``P_low (MC) [-]``,
        ``P_high (MC) [-]`` (Wilson interval); display units (deg, K, um).
    samples : pandas.DataFrame
        One row per sample: ``sample``, each parameter's change ``d <parameter> [<unit>]``,
        each output ``<output> [<unit>]`` and its first-order prediction ``<output> FOSM
        [<unit>]``, ``success``, ``status``, ``message``.
    n_samples, n_failed : int
    confidence : float
        Of the intervals.
    seed : int
    success, status, message
        "converged", or "failed" when more than half the samples failed.
    """

    table: object
    samples: object
    n_samples: int
    n_failed: int
    confidence: float
    seed: int
    success: bool
    status: str
    message: str


def monte_carlo_comparison(report, steps, n_samples: int = 200, seed: int = 0,
                           options: NewtonOptions | None = None, confidence: float = 0.95,
                           heat_step: int = -1, progress=None) -> MonteCarloComparison:
    """Sample the report's parameters (independent normals, its tolerances as standard
    deviations), simulate each sample and compare with the first-order values.

    Parameters
    ----------
    report : SensitivityReport
    steps : sequence of Step
        The steps that made the report's result (simulated on ``report.model``).
    n_samples : int
    seed : int
        Of :func:`numpy.random.default_rng`; the same seed gives the same samples.
    options : NewtonOptions, optional
        Of every simulation (those of the report's result, for a fair comparison).
    confidence : float
        Of the intervals of the standard deviations and the probabilities.
    heat_step : int
        Index of the heating step in ``steps``.
    progress : callable, optional
        Called with the number of samples done after each one.
    """
    if not (isinstance(n_samples, int) and n_samples >= 3):
        raise ParameterError(f"n_samples = {n_samples!r}: give an integer >= 3.")
    if not 0 < confidence < 1:
        raise ParameterError(f"confidence = {confidence!r}: give a level in (0, 1).")
    names = list(report.tolerances)
    sigma = np.array([report.tolerances[p] for p in names])
    draws = np.random.default_rng(seed).standard_normal((n_samples, len(names))) * sigma
    perturbed_protocol(report.model, steps, {}, heat_step)         # checks steps
    y = np.full((n_samples, len(report.outputs)), np.nan)
    rows = []
    for i, d in enumerate(draws):
        rows.append(_sample(report, steps, dict(zip(names, d)), options, heat_step, y[i]))
        if progress is not None:
            progress(i + 1)
    G = np.array([[report.gradients[o].get(p, math.nan) for p in names]
                  for o in report.outputs])
    y0 = np.array([report.values[o] for o in report.outputs])
    y_lin = y0 + draws @ G.T
    samples = _samples_frame(report, names, draws, y, y_lin, rows)
    ok = np.all(np.isfinite(y), axis=1)
    table = _comparison_table(report, y[ok], y_lin[ok], confidence)
    failed = int(n_samples - ok.sum())
    status = "converged" if failed <= n_samples / 2 else "failed"
    message = f"{ok.sum()} of {n_samples} samples simulated" + (
        f"; {failed} failed (left out of the statistics)" if failed else "")
    logger.info("monte carlo comparison: %s", message)
    return MonteCarloComparison(table, samples, n_samples, failed, confidence, seed,
                                status == "converged", status, message)


def _sample(report, steps, changes, options, heat_step, y_out) -> dict:
    """Simulate one sample; its outputs into ``y_out`` (NaN if it failed)."""
    try:
        model, sample_steps = perturbed_protocol(report.model, steps, changes, heat_step)
        result = simulate(model, sample_steps, options=options or NewtonOptions())
    except ParameterError as error:        # e.g. a sampled power below zero
        return {"success": False, "status": "invalid", "message": str(error)}
    if not result.success:
        return {"success": False, "status": result.status, "message": result.message}
    state = result.steps[heat_step].state
    for k, objective in enumerate(report.outputs.values()):
        y_out[k] = objective.terms(model, state.u, state.temperature)[0]
    return {"success": True, "status": "converged", "message": "converged"}


def _samples_frame(report, names, draws, y, y_lin, rows):
    import pandas as pd

    df = pd.DataFrame({"sample": np.arange(len(draws))})
    for j, p in enumerate(names):
        unit, k = parameter_display(p)
        df[f"d {p} [{unit}]"] = draws[:, j] * k
    for j, o in enumerate(report.outputs):
        unit, k = value_display(report.units[o])
        df[f"{o} [{unit}]"] = y[:, j] * k
        df[f"{o} FOSM [{unit}]"] = y_lin[:, j] * k
    return pd.concat([df, pd.DataFrame(rows)], axis=1)


def _met(y, limits: dict, outputs: list) -> np.ndarray:
    """(n,) bool: each sample meets every limit of ``limits``."""
    ok = np.ones(len(y), bool)
    for o, (low, high) in limits.items():
        j = outputs.index(o)
        ok &= (y[:, j] >= (-math.inf if low is None else low)) & \
            (y[:, j] <= (math.inf if high is None else high))
    return ok


def sigma_interval(s: float, n: int, confidence: float) -> tuple:
    """Confidence interval of a normal standard deviation from the sample's ``s`` of ``n``
    values: ``s sqrt((n - 1) / chi2_{(1 +- c)/2}(n - 1))``."""
    from scipy.stats import chi2

    a = (1 - confidence) / 2
    return (s * math.sqrt((n - 1) / chi2.ppf(1 - a, n - 1)),
            s * math.sqrt((n - 1) / chi2.ppf(a, n - 1)))


def _comparison_table(report, y, y_lin, confidence):
    import pandas as pd

    outputs, n, rows = list(report.outputs), len(y), []
    for j, o in enumerate(outputs):
        unit, k = value_display(report.units[o])
        s = float(np.std(y[:, j], ddof=1)) if n > 1 else math.nan
        low, high = sigma_interval(s, n, confidence) if n > 1 else (math.nan, math.nan)
        fosm = report.sigma[o]
        row = {"output": o, "unit": unit, "nominal": report.values[o] * k,
               "mean (MC)": float(np.mean(y[:, j])) * k if n else math.nan,
               "sigma (FOSM)": None if fosm is None else fosm * k,
               "sigma (MC)": s * k, "sigma_low (MC)": low * k, "sigma_high (MC)": high * k,
               "linearisation error (rms)": float(np.sqrt(np.mean(
                   (y[:, j] - y_lin[:, j]) ** 2))) * k if n else math.nan}
        if o in report.limits:
            row.update(_probabilities(report.probability[o],
                                      _met(y, {o: report.limits[o]}, outputs), confidence))
        rows.append(row)
    if report.limits:
        rows.append({"output": "all limits", "unit": "-", **_probabilities(
            report.probability_all, _met(y, report.limits, outputs), confidence)})
    df = pd.DataFrame(rows)
    df.attrs["display units"] = {o: OUTPUT_DISPLAY[report.units[o]][0] for o in outputs}
    return df


def _probabilities(fosm, met, confidence) -> dict:
    n, k = len(met), int(met.sum())
    low, high = wilson_interval(k, n, confidence) if n else (math.nan, math.nan)
    return {"P(meet) (FOSM) [-]": fosm, "P(meet) (MC) [-]": k / n if n else math.nan,
            "P_low (MC) [-]": low, "P_high (MC) [-]": high}
