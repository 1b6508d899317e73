"""What the CLI's ``etorigami cases`` tells about a case parameter beyond its default and unit:
allowed values of text parameters, what a power is per (:func:`parameter_note`)."""

from __future__ import annotations

__all__ = ["parameter_note", "CHOICES", "POWER_MEANING"]

#: Allowed values of the cases' text parameters: by parameter name, or by (case, parameter).
CHOICES = {"coupling": ("staggered", "iterated", "settled"), "on_limit_point": ("stop", "continue"),
           "mechanics": ("dynamic", "quasi_static"),
           ("verification_strip", "variant"): ("within", "loss"),
           ("snap_through", "variant"): ("force", "heated"),
           "loss_model": ("chain", "integral")}
#: What the ``power_mW`` of each case is: per which crease or circuit.
POWER_MEANING = {
    "single_fold": "the one crease's power at the end of the ramp",
    "single_fold_prefolded": "the one crease's power at the end of the ramp",
    "single_fold_step_response": "the one crease's power while on",
    "double_fold": "per crease, both creases alike",
    "miura_lifter": "per crease, every crease alike",
    "crane": "the base power q; the creases get q/2 ... 4 q (reference classes); default "
             "4 mW with the chain heat loss, 0.7 mW with the integral one",
    "snap_through": "per crease, every crease alike (variant 'heated' only)"}


def parameter_note(case: str, parameter: str) -> str:
    """What a user should know about a case parameter beyond its default and unit: its
    allowed values (``"one of 'staggered', 'iterated'"``), what a power is per, or ""."""
    key = case.replace("-", "_")
    choices = CHOICES.get((key, parameter), CHOICES.get(parameter))
    if choices:
        return "one of " + ", ".join(repr(c) for c in choices)
    if parameter == "power_mW":
        return POWER_MEANING.get(key, "")
    if parameter == "env_conductivity" and key == "single_fold":
        return "the reference script's water-like value; air is 0.026"
    return ""
