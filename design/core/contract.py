"""The result contract of the design layer, in the sense of scipy's ``OptimizeResult``.

Every result object returned to users is a frozen dataclass with

* ``success`` (bool): the thing asked for was achieved (a criterion met, a design
  evaluated, a feasible optimum found, the targets reached);
* ``status`` (str): one short word saying how it ended (``"met"``, ``"not_met"``,
  ``"feasible"``, ``"infeasible"``, ``"converged"``, ``"failed"``, ``"max_evaluations"``...);
* ``message`` (str): a sentence for people.

A power that was not found (criterion never met) is ``None`` in Python and an empty cell in
CSV tables (NaN in a DataFrame), never 0 or infinity.
"""

from __future__ import annotations

import numpy as np

from simulator import ParameterError

__all__ = ["check_outcome", "power_if"]


def check_outcome(obj, success_words=None, failure_words=None) -> None:
    """Raise :class:`ParameterError` unless ``obj`` has a bool ``success``, a str ``status``
    among the words allowed for that outcome (any word when None) and a str ``message``."""
    name = type(obj).__name__
    if not isinstance(obj.success, (bool, np.bool_)):
        raise ParameterError(f"{name}.success = {obj.success!r} must be True or False.")
    allowed = success_words if obj.success else failure_words
    if not isinstance(obj.status, str) or (allowed is not None and obj.status not in allowed):
        raise ParameterError(f"{name}.status = {obj.status!r} with success = {obj.success}; "
                             f"use one of {', '.join(allowed or ())}.")
    if not isinstance(obj.message, str):
        raise ParameterError(f"{name}.message = {obj.message!r} must be a str.")


def power_if(success: bool, power, scale: float = 1.0):
    """``scale * power`` when ``success``, else None (an unmet power is never 0 or inf)."""
    return scale * power if success and power is not None else None
