"""Named, bounded design variables and the vector <-> named mapping."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass

import numpy as np

from simulator import ParameterError
from simulator._deprecation import warn_deprecated
from simulator._validate import finite, positive

__all__ = ["Variable", "DesignSpace"]


@dataclass(frozen=True)
class Variable:
    """One design variable.

    Parameters
    ----------
    name : str
    lower, upper : float
        Bounds in SI units (lower < upper).
    step : float
        Step of the coordinate descent (> 0, SI).
    start : float
        Start value (inside the bounds).
    unit : str
        SI unit of the value (for reports).
    display_scale : float
        Factor to the unit used in reports and the CLI (1e6 for um).
    display_unit : str
    """

    name: str
    lower: float
    upper: float
    step: float
    start: float
    unit: str = "m"
    display_scale: float = 1e6
    display_unit: str = "um"

    def __post_init__(self):
        for f in ("lower", "upper", "start"):
            finite(f"Variable {self.name!r}: {f}", getattr(self, f))
        positive(f"Variable {self.name!r}: step", self.step)
        if not self.lower < self.upper:
            raise ParameterError(f"Variable {self.name!r}: lower = {self.lower!r} must be below "
                                 f"upper = {self.upper!r}.")
        if not self.lower <= self.start <= self.upper:
            raise ParameterError(f"Variable {self.name!r}: start = {self.start!r} is outside "
                                 f"[{self.lower!r}, {self.upper!r}].")

    def to_dict(self) -> dict:
        return asdict(self)


class DesignSpace:
    """An ordered set of :class:`Variable` with conversions between vectors and dicts."""

    def __init__(self, variables: Sequence[Variable]):
        variables = tuple(variables)
        if not variables or not all(isinstance(v, Variable) for v in variables):
            raise ParameterError("DesignSpace needs a non-empty sequence of Variable objects.")
        names = [v.name for v in variables]
        if len(set(names)) != len(names):
            raise ParameterError(f"DesignSpace: duplicate variable names in {names}.")
        self.variables = variables
        self.names = tuple(names)
        self.lower = np.array([v.lower for v in variables])
        self.upper = np.array([v.upper for v in variables])
        self.step = np.array([v.step for v in variables])
        self.start = np.array([v.start for v in variables])

    def __len__(self) -> int:
        return len(self.variables)

    def __getitem__(self, name: str) -> Variable:
        return self.variables[self.index(name)]

    def index(self, name: str) -> int:
        if name not in self.names:
            raise ParameterError(f"Unknown design variable {name!r}; variables: "
                                 f"{', '.join(self.names)}.")
        return self.names.index(name)

    def to_vector(self, values) -> np.ndarray:
        """Vector (n,) from a mapping {name: value} (missing names take their start value) or
        from a sequence in variable order."""
        if isinstance(values, Mapping):
            for k in values:
                self.index(k)
            x = np.array([float(values.get(n, v.start)) for n, v in zip(self.names,
                                                                         self.variables)])
        else:
            x = np.asarray(values, dtype=float).ravel()
            if x.shape != (len(self),):
                raise ParameterError(f"A design vector needs {len(self)} values "
                                     f"({', '.join(self.names)}); got {x.shape[0]}.")
        if not np.all(np.isfinite(x)):
            raise ParameterError(f"Design values must be finite; got {x.tolist()}.")
        return x

    def to_mapping(self, x) -> dict:
        """``{name: value}`` of a design given as a vector in variable order (or as a mapping,
        checked and completed with the start values); the inverse of :meth:`to_vector`."""
        x = self.to_vector(x)
        return {n: float(v) for n, v in zip(self.names, x)}

    def to_dict(self, x) -> dict:
        """Deprecated spelling of :meth:`to_mapping` (``to_dict`` elsewhere serialises the
        object itself; this one converts a design); goes in the next release."""
        warn_deprecated("DesignSpace.to_dict(x) is deprecated (it goes in the next release): "
                        "use DesignSpace.to_mapping(x), the same {name: value} dict.")
        return self.to_mapping(x)

    def contains(self, x, tol: float = 1e-12) -> bool:
        x = self.to_vector(x)
        span = self.upper - self.lower
        return bool(np.all(x >= self.lower - tol * span) and np.all(x <= self.upper + tol * span))

    def validate(self, x) -> np.ndarray:
        """The vector of ``x``, raising ParameterError naming a variable outside its bounds."""
        x = self.to_vector(x)
        span = self.upper - self.lower
        for n, v, lo, hi, s in zip(self.names, x, self.lower, self.upper, span):
            if not lo - 1e-12 * s <= v <= hi + 1e-12 * s:
                var = self[n]
                raise ParameterError(
                    f"design variable {n} = {v * var.display_scale:g} {var.display_unit} is outside "
                    f"its bounds [{lo * var.display_scale:g}, {hi * var.display_scale:g}] "
                    f"{var.display_unit}.")
        return x

    def normalize(self, x) -> np.ndarray:
        """Map to [0, 1]^n."""
        return (self.to_vector(x) - self.lower) / (self.upper - self.lower)

    def denormalize(self, z) -> np.ndarray:
        return self.lower + np.asarray(z, float) * (self.upper - self.lower)

    def bound_margins(self, x) -> dict:
        """Size-bound constraints g <= 0, normalised by the range: ``<name>_lower``, ``_upper``."""
        x = self.to_vector(x)
        span = self.upper - self.lower
        out = {}
        for n, v, lo, hi, s in zip(self.names, x, self.lower, self.upper, span):
            out[f"{n}_lower"] = float((lo - v) / s)
            out[f"{n}_upper"] = float((v - hi) / s)
        return out

    def bound_margin_gradients(self) -> dict:
        """The gradients of :meth:`bound_margins` (constant): ``{<name>_lower: {variable:
        d g / d variable}, ...}`` in 1/(the variable's unit)."""
        out = {}
        for i, (n, s) in enumerate(zip(self.names, self.upper - self.lower)):
            for side, sign in (("lower", -1.0), ("upper", 1.0)):
                out[f"{n}_{side}"] = {m: sign / float(s) if j == i else 0.0
                                      for j, m in enumerate(self.names)}
        return out

    def to_dicts(self) -> list:
        return [v.to_dict() for v in self.variables]
