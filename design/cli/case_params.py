"""Case parameters at the command line: one unit table from the library's SI units to the CLI's.

The library's cases take SI values (:func:`simulator.cases.describe_cases` lists each parameter
with its SI unit); the CLI speaks um, mW, degrees and seconds. :data:`CLI_UNITS` maps every SI unit
of a case parameter to its CLI unit, the conversion to SI and the range allowed at the CLI, so
``--set crease_width=200`` means 200 um, ``etorigami cases`` prints ``crease_width = 200
[um]``, and ``--set crease_width=-5`` answers in um, before anything is built. Names that carry
their unit (``power_mW``, ``residual_fold_deg``) are already in CLI units and stay as they are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ._common import CLIError, length_um, power_mw

__all__ = ["CLIUnit", "CLI_UNITS", "cli_unit", "to_cli", "case_parameters", "case_overrides"]


@dataclass(frozen=True)
class CLIUnit:
    """How one SI unit of a case parameter is typed at the command line.

    Attributes
    ----------
    name : str
        The CLI unit (``um``, ``mW``, ``deg``, ``s``, ...); "" for dimensionless.
    divisor : float
        CLI value / divisor = SI value (1e6 for um -> m; exact powers of ten, so that
        ``200 um`` gives the same double as ``200e-6``).
    check : str
        The range check: ``length`` (> 0, plausible magnitude), ``power`` (0 to
        :data:`~design.cli._common.MAX_POWER_MW`), ``angle`` (in (-180, 180]), ``positive``,
        ``non_negative`` or "" (the library checks).
    """

    name: str
    divisor: float = 1.0
    check: str = ""


#: SI unit of a case parameter (as :func:`simulator.cases.describe_cases` gives it) -> its CLI
#: unit.
CLI_UNITS = {
    "m": CLIUnit("um", 1e6, "length"),
    "mW": CLIUnit("mW", 1.0, "power"),                 # names ending in _mW: already mW
    "mW per crease": CLIUnit("mW per crease", 1.0, "power"),
    "deg": CLIUnit("deg", 1.0, "angle"),
    "s": CLIUnit("s", 1.0, "positive"),
    "degC": CLIUnit("degC", 1.0, ""),
    "mN": CLIUnit("mN", 1.0, "positive"),
    "W/(m K)": CLIUnit("W/(m K)", 1.0, "non_negative"),
    "N s/m^3": CLIUnit("N s/m^3", 1.0, "non_negative"),
    "-": CLIUnit(""),
    "": CLIUnit(""),
}

#: Angles whose range is not a fold angle's (-180, 180] deg: (low, high, "]" or ")").
_ANGLE_RANGES = {"gamma_deg": (0.0, 90.0, ")")}


def cli_unit(si_unit: str) -> CLIUnit:
    """The :class:`CLIUnit` of an SI unit (unknown units are typed as they are, unchecked)."""
    return CLI_UNITS.get(si_unit, CLIUnit(si_unit))


def to_cli(value, si_unit: str):
    """A default (SI) in CLI units: numbers scaled (12 significant digits), others unchanged."""
    unit = cli_unit(si_unit)
    if isinstance(value, bool) or not isinstance(value, float) or unit.divisor == 1.0:
        return value
    return float(f"{value * unit.divisor:.12g}")


def case_parameters() -> dict:
    """{case name: {parameter: (default in CLI units, SI unit)}} of every built-in case."""
    from simulator.cases import describe_cases

    return {name: {p: (to_cli(default, unit), unit) for p, default, unit in params}
            for name, _, params in describe_cases()}


def _checked(name: str, value: float, unit: CLIUnit) -> float:
    """``value`` (CLI units) checked against its unit's range; returns it in SI."""
    flag = f"--set {name}"
    if unit.check == "length":
        return length_um(flag, value)
    if unit.check == "power":
        power_mw(flag, value, per=unit.name[len("mW "):] or "per crease")
        return value
    shown = f"{value:g} {unit.name}".rstrip()
    if unit.check == "angle":
        low, high, closing = _ANGLE_RANGES.get(name, (-180.0, 180.0, "]"))
        if not (math.isfinite(value) and low < value and (value < high or (
                closing == "]" and value == high))):
            raise CLIError(f"{flag} = {shown} must be in ({low:g}, {high:g}{closing} deg")
    elif unit.check == "positive" and not (math.isfinite(value) and value > 0):
        raise CLIError(f"{flag} = {shown} must be > 0 {unit.name}")
    elif unit.check == "non_negative" and not (math.isfinite(value) and value >= 0):
        raise CLIError(f"{flag} = {shown} must be >= 0 {unit.name}")
    return value / unit.divisor


def _parse_value(text: str):
    """A ``--set`` value: the words true/yes/on and false/no/off, else a number or the text
    as a CSV cell of an evaluation log is read."""
    from ..core.evaluation_log import parse_cell

    low = text.strip().lower()
    if low in ("true", "yes", "on"):
        return True
    if low in ("false", "no", "off"):
        return False
    return parse_cell(text)


def _convert(name, text, default, si_unit):
    """``text`` typed for parameter ``name`` -> its SI value, checked in CLI units."""
    value = _parse_value(text)
    unit = cli_unit(si_unit)
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise CLIError(f"--set {name} expects true or false, got {text!r}")
    elif isinstance(default, int):
        if not isinstance(value, int) or isinstance(value, bool):
            raise CLIError(f"--set {name} expects an integer, got {text!r}")
    elif isinstance(default, float) or (default is None and unit.check):
        # a number (a default of None: chosen by the case from its other parameters)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise CLIError(f"--set {name} expects a number in {unit.name or 'CLI units'}, "
                           f"got {text!r}")
        value = _checked(name, float(value), unit)
    return value


def case_overrides(pairs, case_name) -> dict:
    """Keyword overrides (SI) of a built-in case from ``--set name=value`` pairs given in CLI
    units, checked against the case's parameters, their types and their CLI ranges."""
    from simulator import get_case

    params = case_parameters().get(case_name.replace("-", "_"))
    if params is None:
        get_case(case_name)                     # raises the unknown-case error
    out = {}
    for pair in pairs or []:
        if "=" not in pair:
            raise CLIError(f"--set expects name=value, got {pair!r}")
        name, text = pair.split("=", 1)
        name = name.strip().replace("-", "_")
        if name not in params:
            raise CLIError(f"case {case_name!r} has no parameter {name!r}; "
                           f"parameters: {', '.join(params)}")
        default, si_unit = params[name]
        out[name] = _convert(name, text, default, si_unit)
    return out
