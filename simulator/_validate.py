"""Checks of user input shared by every parameter class and entry point.

Each helper returns the value converted (``float``, ``int``, array) or raises
:class:`~simulator.errors.ParameterError` with one message form::

    <field> = <value> must be <allowed> [<unit>]; <hint>.

so that every error names the field, the value given and the allowed range (with the unit when
the field has one). ``bool`` is refused where a number is asked for (``True`` is an ``int`` to
Python, never a sensible length or count), and so are NaN and strings. ``allow_none=True``
accepts ``None`` (returned unchanged) for optional fields.

These helpers are for the library's own parameter checks (simulator and design layer); they are
not part of the public API.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import ParameterError

__all__ = ["is_number", "number", "finite", "positive", "non_negative", "in_range",
           "probability", "integer", "one_of", "array", "capped", "CAP"]

#: Items a message lists at most (the rest are counted), so that a refusal stays one short line.
CAP = 10

_REALS = (int, float, np.integer, np.floating)
_all = np.logical_and.reduce          # with axis=None: ndarray.all() without its Python wrapper


def is_number(value) -> bool:
    """True for a real number (int, float or numpy scalar) that is not a bool (NaN included)."""
    return isinstance(value, _REALS) and not isinstance(value, (bool, np.bool_))


def _fail(field: str, value, allowed: str, unit: str = "", hint: str = ""):
    unit = f" [{unit}]" if unit else ""
    kind = " (a bool is not a number)" if isinstance(value, (bool, np.bool_)) else ""
    hint = f"; {hint}" if hint else ""
    raise ParameterError(f"{field} = {value!r}{kind} must be {allowed}{unit}{hint}.")


def number(field: str, value, ok, allowed: str, unit: str = "", hint: str = "",
           allow_none: bool = False):
    """``value`` as a float if it is a number (not NaN) with ``ok(value)`` True, else
    :class:`ParameterError` saying it must be ``allowed`` [``unit``]; ``None`` passes with
    ``allow_none``. The building block of the helpers below."""
    if type(value) is float and value == value and ok(value):    # the common case, cheaply
        return value
    if value is None and allow_none:
        return None
    if not (is_number(value) and not math.isnan(value) and ok(float(value))):
        _fail(field, value, allowed, unit, hint)
    return float(value)


def finite(field: str, value, unit: str = "", hint: str = "", allow_none: bool = False):
    """``value`` as a float if it is a finite number."""
    return number(field, value, math.isfinite, "a finite number", unit, hint, allow_none)


def positive(field: str, value, unit: str = "", hint: str = "", allow_none: bool = False):
    """``value`` as a float if it is a finite number > 0."""
    return number(field, value, lambda v: 0 < v < math.inf, "a finite number > 0", unit, hint,
                  allow_none)


def non_negative(field: str, value, unit: str = "", hint: str = "", allow_none: bool = False):
    """``value`` as a float if it is a finite number >= 0."""
    return number(field, value, lambda v: 0 <= v < math.inf, "a finite number >= 0", unit,
                  hint, allow_none)


def in_range(field: str, value, low: float, high: float, unit: str = "", hint: str = "",
             allow_none: bool = False, open_low: bool = False, open_high: bool = False):
    """``value`` as a float if it lies in ``[low, high]`` (ends open when asked)."""
    def ok(v):
        return (low < v if open_low else low <= v) and (v < high if open_high else v <= high)
    interval = f"{'(' if open_low else '['}{low:g}, {high:g}{')' if open_high else ']'}"
    return number(field, value, ok, f"a number in {interval}", unit, hint, allow_none)


def probability(field: str, value, hint: str = "", allow_none: bool = False):
    """``value`` as a float if it is a probability (a number in [0, 1])."""
    return number(field, value, lambda v: 0 <= v <= 1, "a probability in [0, 1]", "", hint,
                  allow_none)


def integer(field: str, value, minimum: int = 1, maximum: int | None = None, hint: str = "",
            allow_none: bool = False):
    """``value`` as an int if it is an integer (int or numpy integer, not bool) in
    ``[minimum, maximum]``."""
    if type(value) is int and value >= minimum and (maximum is None or value <= maximum):
        return value                                  # the common case, checked cheaply
    if value is None and allow_none:
        return None
    good = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    if not (good and value >= minimum and (maximum is None or value <= maximum)):
        if maximum is not None:
            allowed = f"an integer from {minimum} to {maximum}"
        else:
            allowed = {1: "a positive integer (>= 1)",
                       0: "a non-negative integer (>= 0)"}.get(minimum,
                                                                f"an integer >= {minimum}")
        _fail(field, value, allowed, "", hint)
    return int(value)


def one_of(field: str, value, choices, hint: str = ""):
    """``value`` if it is one of ``choices`` (compared with ``==``, bools never match)."""
    if type(value) is str and type(choices) is tuple and value in choices:
        return value                                  # the common case, checked cheaply
    choices = tuple(choices)
    if isinstance(value, (bool, np.bool_)) or not any(
            type(value) is type(c) and value == c for c in choices):
        _fail(field, value, "one of " + ", ".join(map(repr, choices)), "", hint)
    return value


def array(field: str, value, shape, unit: str = "", hint: str = "", finite_values: bool = True,
          dtype=float) -> np.ndarray:
    """``value`` as an array of ``dtype`` with ``shape`` (a tuple; ``None`` entries match any
    length) and, with ``finite_values``, only finite entries. (Cheap when the value is good:
    the message is built only on failure.)"""
    try:
        out = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError):
        _array_fail(field, shape, unit, hint, finite_values, f"{value!r:.80}")
    if out.shape != shape and (out.ndim != len(shape) or any(
            n is not None and m != n for m, n in zip(out.shape, shape))):
        _array_fail(field, shape, unit, hint, finite_values, f"shape {out.shape}")
    if finite_values and not _all(np.isfinite(out), axis=None):
        bad = tuple(np.argwhere(~np.isfinite(out))[0].tolist())
        _array_fail(field, shape, unit, hint, finite_values, f"{out[bad].item()!r} at index {bad}")
    return out


def _array_fail(field, shape, unit, hint, finite_values, got):
    want = str(tuple("k" if n is None else n for n in shape)).replace("'", "")
    unit = f" [{unit}]" if unit else ""
    hint = f"; {hint}" if hint else ""
    kind = "a finite array" if finite_values else "an array"
    raise ParameterError(f"{field} must be {kind} of shape {want}{unit}; got {got}{hint}.")


def capped(items, cap: int = CAP, fmt=str, brackets: bool = True) -> str:
    """``[a, b, c]``, or the first ``cap`` items and a count of the rest:
    ``[a, b, and 12 more]``, for messages that name many items (``brackets`` False: without
    the brackets)."""
    items = list(items)
    shown = ", ".join(fmt(x) for x in items[:cap])
    text = shown if len(items) <= cap else f"{shown}, and {len(items) - cap} more"
    return f"[{text}]" if brackets else text
