"""Fabrication uncertainty: distributions of the gripper's inputs, seeded sampling, statistics.

A :class:`FabricationScenario` lists :class:`UncertainInput` s, each a gripper parameter
(:data:`PARAMETERS`: residual folds on all creases, per crease group or per crease, layer
thicknesses, the bimorph mismatch, the air's conductivity) with a :class:`Distribution`
(fixed, normal, truncated normal, uniform) and an optional correlation group. Inputs of one
group are correlated through a Gaussian copula with equal correlation ``rho`` (e.g. the four
creases' residual folds of one wafer). :meth:`FabricationScenario.sample` draws a table by
Monte Carlo (``"mc"``) or Latin hypercube (``"lhs"``, :class:`scipy.stats.qmc.LatinHypercube`)
from a seed: the same seed gives the same table, bit for bit (the sampling runs in the calling
process, never in workers). Truncated normals are :data:`scipy.stats.truncnorm`.

Statistics of a sample table: :func:`wilson_interval` (the yield's binomial confidence
interval, :func:`scipy.stats.binomtest`), :func:`quantile` (of powers, unmet samples counted as infinite) and
:func:`rank_correlations` (Spearman's rho of each input with an output, with a Fisher-z
confidence interval, standard error ``1.06 / sqrt(n - 3)``; Fieller, Hartley and Pearson 1957).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from scipy import special

from simulator import ParameterError

from ..devices.gripper import ARM_CREASES, BASE_CREASES

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["Distribution", "UncertainInput", "FabricationScenario", "PARAMETERS",
           "SAMPLING_METHODS", "SCENARIOS", "residual_fold_per_crease", "wilson_interval", "quantile",
           "rank_correlations"]

#: Uncertain parameters: name -> (SI unit, display unit, display scale, lower, upper bound).
#: ``residual_fold`` is on all four actuated creases, ``residual_fold_base`` / ``_arm`` per
#: crease group, ``residual_fold_c<id>`` on one crease (ids 2, 5 base, 3, 9 arm).
PARAMETERS = {
    "residual_fold": ("rad", "deg", 180 / math.pi, -math.pi / 2, math.pi / 2),
    "residual_fold_base": ("rad", "deg", 180 / math.pi, -math.pi / 2, math.pi / 2),
    "residual_fold_arm": ("rad", "deg", 180 / math.pi, -math.pi / 2, math.pi / 2),
    **{f"residual_fold_c{c}": ("rad", "deg", 180 / math.pi, -math.pi / 2, math.pi / 2)
       for c in BASE_CREASES + ARM_CREASES},
    "t_gold": ("m", "um", 1e6, 1e-9, 1e-5),
    "t_su8": ("m", "um", 1e6, 1e-9, 1e-5),
    "delta_alpha": ("1/K", "ppm/K", 1e6, -1e-3, 1e-3),
    "env_conductivity": ("W/(m K)", "W/(m K)", 1.0, 1e-4, 10.0),
}
SAMPLING_METHODS = ("mc", "lhs")
_KINDS = ("fixed", "normal", "uniform")
_U_EPS = 1e-12


@dataclass(frozen=True)
class Distribution:
    """A one-dimensional distribution, sampled through its inverse CDF (a normal through
    :data:`scipy.stats.truncnorm`, truncated or not).

    Parameters
    ----------
    kind : {"fixed", "normal", "uniform"}
    loc : float
        Value (fixed) or mean (normal) [SI].
    scale : float
        Standard deviation (normal) [SI].
    low, high : float
        Bounds (uniform), or truncation of a normal (default none: -inf, inf) [SI].
    """

    kind: str
    loc: float = 0.0
    scale: float = 0.0
    low: float = -math.inf
    high: float = math.inf

    def __post_init__(self):
        if self.kind not in _KINDS:
            raise ParameterError(f"Distribution.kind = {self.kind!r}; use one of "
                                 f"{', '.join(_KINDS)}.")
        if self.kind == "normal" and not (math.isfinite(self.scale) and self.scale > 0):
            raise ParameterError(f"Distribution.scale = {self.scale!r}: a normal needs a "
                                 "positive, finite standard deviation (use kind 'fixed' for 0).")
        if self.kind == "uniform" and not (math.isfinite(self.low) and math.isfinite(self.high)):
            raise ParameterError(f"Distribution: uniform bounds low = {self.low!r}, high = "
                                 f"{self.high!r} must be finite.")
        if not self.low < self.high:
            raise ParameterError(f"Distribution: low = {self.low!r} must be below high = "
                                 f"{self.high!r}.")
        if self.kind == "normal" and not self.low <= self.loc <= self.high:
            raise ParameterError(f"Distribution: mean {self.loc!r} outside the truncation "
                                 f"[{self.low!r}, {self.high!r}].")

    @classmethod
    def fixed(cls, value: float) -> "Distribution":
        return cls("fixed", loc=float(value))

    @classmethod
    def normal(cls, mean: float, std: float, low: float = -math.inf,
               high: float = math.inf) -> "Distribution":
        """Normal, truncated to ``[low, high]`` when bounds are given."""
        return cls("normal", float(mean), float(std), float(low), float(high))

    @classmethod
    def uniform(cls, low: float, high: float) -> "Distribution":
        return cls("uniform", low=float(low), high=float(high))

    def ppf(self, u) -> np.ndarray:
        """Values at probabilities ``u`` in (0, 1) (inverse CDF), shape of ``u``."""
        u = np.asarray(u, dtype=float)
        if self.kind == "fixed":
            return np.full(u.shape, self.loc)
        if self.kind == "uniform":
            return self.low + u * (self.high - self.low)
        from scipy import stats              # imported here: scipy.stats is slow to import

        a, b = ((v - self.loc) / self.scale for v in (self.low, self.high))
        return np.clip(stats.truncnorm.ppf(u, a, b, loc=self.loc, scale=self.scale), self.low,
                       self.high)

    def describe(self) -> str:
        if self.kind == "fixed":
            return f"fixed {self.loc:g}"
        if self.kind == "uniform":
            return f"uniform [{self.low:g}, {self.high:g}]"
        cut = "" if math.isinf(self.low) and math.isinf(self.high) else \
            f" truncated to [{self.low:g}, {self.high:g}]"
        return f"normal mean {self.loc:g} std {self.scale:g}{cut}"


@dataclass(frozen=True)
class UncertainInput:
    """One uncertain gripper parameter.

    Parameters
    ----------
    parameter : str
        A key of :data:`PARAMETERS`.
    distribution : Distribution
        In SI units (rad, m, 1/K, W/(m K)); a normal is truncated to the parameter's allowed
        range (:data:`PARAMETERS`).
    group : str, optional
        Correlation group (see :class:`FabricationScenario`).
    """

    parameter: str
    distribution: Distribution
    group: str | None = None

    def __post_init__(self):
        if self.parameter not in PARAMETERS:
            raise ParameterError(f"UncertainInput.parameter = {self.parameter!r}; use one of "
                                 f"{', '.join(PARAMETERS)}.")
        lo, hi = PARAMETERS[self.parameter][3:]
        d = self.distribution
        if d.kind == "normal":                    # truncated to the allowed range
            d = Distribution.normal(d.loc, d.scale, max(d.low, lo), min(d.high, hi))
            object.__setattr__(self, "distribution", d)
        ends = (d.loc,) if d.kind == "fixed" else (d.low, d.high)
        if not all(lo <= v <= hi for v in ends):
            raise ParameterError(f"UncertainInput {self.parameter}: {d.describe()} leaves the "
                                 f"allowed range [{lo:g}, {hi:g}] {PARAMETERS[self.parameter][0]}.")

    @property
    def column(self) -> str:
        """Table column: ``<parameter> [<display unit>]``."""
        return f"{self.parameter} [{PARAMETERS[self.parameter][1]}]"

    def to_dict(self) -> dict:
        unit = PARAMETERS[self.parameter][0]
        return {"parameter": self.parameter, "unit": unit, "group": self.group,
                "distribution": self.distribution.describe()}


def residual_fold_per_crease(distribution: Distribution, group: str | None = "residual_fold",
                             creases=BASE_CREASES + ARM_CREASES) -> tuple:
    """One :class:`UncertainInput` per actuated crease, all in one correlation group."""
    return tuple(UncertainInput(f"residual_fold_c{c}", distribution, group) for c in creases)


@dataclass(frozen=True)
class FabricationScenario:
    """The uncertain inputs of a fabrication and their correlations.

    Parameters
    ----------
    inputs : tuple of UncertainInput
        Each parameter at most once; parameters not listed keep the problem's values.
    correlations : tuple of (group, rho) pairs
        Equal correlation ``0 <= rho <= 1`` of the normal scores of a group's inputs (a
        Gaussian copula); groups not listed are independent (rho 0).
    name : str
    """

    inputs: tuple
    correlations: tuple = ()
    name: str = "scenario"
    _rho: dict = field(init=False, repr=False, compare=False, default=None)

    def __post_init__(self):
        inputs = tuple(self.inputs)
        names = [i.parameter for i in inputs]
        if len(set(names)) != len(names):
            raise ParameterError(f"FabricationScenario: parameters {names} repeat one.")
        rho = dict(self.correlations)
        groups = {i.group for i in inputs if i.group is not None}
        for g, r in rho.items():
            if g not in groups:
                raise ParameterError(f"FabricationScenario: correlation group {g!r} has no "
                                     f"input (groups: {sorted(groups)}).")
            if not (isinstance(r, (int, float)) and 0 <= r <= 1):
                raise ParameterError(f"FabricationScenario: rho[{g!r}] = {r!r} must be in "
                                     "[0, 1].")
        object.__setattr__(self, "inputs", inputs)
        object.__setattr__(self, "correlations", tuple(sorted(rho.items())))
        object.__setattr__(self, "_rho", rho)

    @property
    def parameters(self) -> tuple:
        return tuple(i.parameter for i in self.inputs)

    def sample(self, n: int, seed: int, method: str = "lhs") -> pd.DataFrame:
        """``n`` samples (rows) of the parameters (columns, SI), reproducible from ``seed``.

        Monte Carlo draws independent uniforms; the Latin hypercube
        (:class:`scipy.stats.qmc.LatinHypercube`, scrambled, seeded by the same generator)
        puts one point in each of ``n`` equal-probability strata of every independent uniform (the copula mixes
        correlated inputs, so they are stratified only in their group's common score).
        """
        import pandas as pd

        if not (isinstance(n, (int, np.integer)) and n >= 1):
            raise ParameterError(f"sample: n = {n!r} must be a positive integer.")
        if method not in SAMPLING_METHODS:
            raise ParameterError(f"sample: method = {method!r}; use 'mc' or 'lhs'.")
        groups = sorted(g for g, r in self._rho.items() if r > 0)
        rng = np.random.default_rng(seed)
        d = len(self.inputs) + len(groups)
        if method == "mc":
            u = rng.random((n, d))
        else:
            from scipy.stats import qmc

            u = qmc.LatinHypercube(d, rng=rng).random(n)
        z = special.ndtri(np.clip(u, _U_EPS, 1 - _U_EPS))
        common = dict(zip(groups, z[:, len(self.inputs):].T))
        cols = {}
        for k, inp in enumerate(self.inputs):
            zk, r = z[:, k], self._rho.get(inp.group, 0.0)
            if r > 0:
                zk = math.sqrt(r) * common[inp.group] + math.sqrt(1 - r) * zk
            uk = u[:, k] if r == 0 else special.ndtr(zk)
            cols[inp.parameter] = inp.distribution.ppf(np.clip(uk, _U_EPS, 1 - _U_EPS))
        return pd.DataFrame(cols, columns=list(self.parameters))

    def to_dict(self) -> dict:
        return {"name": self.name, "inputs": [i.to_dict() for i in self.inputs],
                "correlations": dict(self.correlations)}


_DEG = math.pi / 180
#: Named scenarios. ``"default"``: an *assumed* fabrication spread (not measured): residual
#: fold of each actuated crease normal, mean -5 deg, std 4 deg, truncated to [-20, 10] deg,
#: correlated between the creases of one device (rho 0.7: one wafer's stress); gold and SU-8
#: thicknesses normal with 5 % std (0.2 +- 0.01 um, 0.8 +- 0.04 um) truncated at 3 std;
#: bimorph mismatch uniform on [34, 42] ppm/K; air conductivity uniform on [0.024, 0.030]
#: W/(m K). ``"residual-fold"``: the residual folds of the default scenario only. ``"off"``:
#: every input fixed at its nominal value (a check: the yield is the deterministic result).
SCENARIOS = {
    "default": FabricationScenario(
        residual_fold_per_crease(Distribution.normal(-5 * _DEG, 4 * _DEG, -20 * _DEG,
                                                     10 * _DEG))
        + (UncertainInput("t_gold", Distribution.normal(0.2e-6, 0.01e-6, 0.17e-6, 0.23e-6)),
           UncertainInput("t_su8", Distribution.normal(0.8e-6, 0.04e-6, 0.68e-6, 0.92e-6)),
           UncertainInput("delta_alpha", Distribution.uniform(34e-6, 42e-6)),
           UncertainInput("env_conductivity", Distribution.uniform(0.024, 0.030))),
        correlations=(("residual_fold", 0.7),), name="default"),
    "residual-fold": FabricationScenario(
        residual_fold_per_crease(Distribution.normal(-5 * _DEG, 4 * _DEG, -20 * _DEG,
                                                     10 * _DEG)),
        correlations=(("residual_fold", 0.7),), name="residual-fold"),
    "off": FabricationScenario((UncertainInput("residual_fold", Distribution.fixed(0.0)),),
                               name="off"),
}


def wilson_interval(successes: int, n: int, confidence: float = 0.95) -> tuple:
    """Wilson score interval ``(low, high)`` of a binomial proportion (NaN, NaN for n = 0).

    ``scipy.stats.binomtest(successes, n).proportion_ci(confidence, method="wilson")``: the
    low end is 0 when ``successes`` is 0 and the high end 1 when it is ``n``.
    """
    if n == 0:
        return (math.nan, math.nan)
    from scipy import stats              # imported here: scipy.stats is slow to import

    ci = stats.binomtest(int(successes), int(n)).proportion_ci(confidence, method="wilson")
    return (float(ci.low), float(ci.high))


def quantile(values, q: float) -> float:
    """The ``q`` quantile (inverted CDF, an observed value) of ``values``; NaN (not met)
    counts as +inf, and an infinite quantile is returned as inf."""
    v = np.asarray(values, dtype=float)
    v = np.where(np.isnan(v), np.inf, v)
    return float(np.quantile(v, q, method="inverted_cdf")) if v.size else math.nan


def rank_correlations(table: pd.DataFrame, inputs, output: str,
                      confidence: float = 0.95) -> pd.DataFrame:
    """Spearman's rho of each input column with ``output`` (NaN ranked highest: not met).

    Returns
    -------
    DataFrame
        ``input``, ``output``, ``spearman [-]``, ``low [-]``, ``high [-]`` (Fisher-z interval),
        ``n``; rho is NaN for an input that does not vary.
    """
    import pandas as pd
    from scipy import stats

    y = table[output].to_numpy(dtype=float)
    y = np.where(np.isnan(y), np.inf, y)
    n = len(y)
    z = stats.norm.ppf(0.5 + confidence / 2)
    rows = []
    for col in inputs:
        x = table[col].to_numpy(dtype=float)
        rho = math.nan
        if n >= 3 and np.ptp(x) > 0 and np.ptp(stats.rankdata(y)) > 0:
            rho = float(stats.spearmanr(x, y).statistic)
        low = high = math.nan
        if n > 3 and math.isfinite(rho):
            f, se = math.atanh(min(max(rho, -1 + 1e-15), 1 - 1e-15)), 1.06 / math.sqrt(n - 3)
            low, high = math.tanh(f - z * se), math.tanh(f + z * se)
        rows.append({"input": col, "output": output, "spearman [-]": rho, "low [-]": low,
                     "high [-]": high, "n": n})
    return pd.DataFrame(rows)
