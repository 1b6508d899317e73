"""Power searches: the smallest heating power at which a stage's criterion holds.

Both strategies work on a *stage* object with three methods:

* ``heat(state, dp, increments=1, coupling="staggered") -> (state, ok, message)``: add power
  ``dp`` [W] per heated crease from a saved simulation state;
* ``look(state) -> (measure, met, temperature, max_crease_temperature)``;
* ``result(status, power, state, message)``: the stage's result object; ``status`` is
  ``"met"`` (the criterion holds at ``power``), ``"not_met"`` (not below the power cap) or
  ``"failed"`` (a heating simulation failed at ``power``).

:func:`staircase_search` is the reference's search (fixed steps); :func:`bisect_search` grows
the step and bisects the crossing, restarting trials from saved states so that nothing is
recomputed from zero. Used by the gripper (:mod:`design.gripper`) and the Miura lifter
(:mod:`design.miura`).
"""

from __future__ import annotations

__all__ = ["staircase_search", "bisect_search"]


def staircase_search(stage, state, step, cap):
    """Add ``step`` per heated crease, one increment at a time, until the criterion holds.

    Returns ``(stage result, state at the stop)``; gives up at the power ``cap`` (status
    ``"not_met"``) or when a simulation fails (``"failed"``).
    """
    power = 0.0
    while power < cap - 1e-15:
        state, ok, msg = stage.heat(state, step)
        power += step
        if not ok:
            return stage.result("failed", power, state, f"simulation failed at "
                                                        f"{power * 1e3:.2f} mW: {msg}"), state
        if stage.look(state)[1]:
            return stage.result("met", power, state, "criterion met"), state
    return stage.result("not_met", power, state, f"criterion not met below the power cap "
                                                 f"{cap * 1e3:.3g} mW per crease"), state


def bisect_search(stage, state, step, tol, cap, max_step, coupling="staggered"):
    """Grow the power step geometrically (``step`` doubling up to ``max_step``) from saved
    states until the criterion holds, then bisect the crossing to ``tol``.

    Every trial restarts from the saved state below the crossing. Returns
    ``(stage result, state at the smallest power found to meet the criterion)``.
    """
    lo_state, lo, dp = state, 0.0, step
    while True:                                            # grow until the criterion holds
        hi = min(lo + dp, cap)
        trial, ok, msg = stage.heat(lo_state, hi - lo, coupling=coupling)
        if not ok:
            if dp > step:                                  # too big a jump: retry smaller
                dp = max(step, dp / 4)
                continue
            return stage.result("failed", hi, trial, f"simulation failed at {hi * 1e3:.3g} mW: "
                                                     f"{msg}"), trial
        if stage.look(trial)[1]:
            hi_state = trial
            break
        if hi >= cap - 1e-15:
            return stage.result("not_met", hi, trial, f"criterion not met below the power cap "
                                                      f"{cap * 1e3:.3g} mW per crease"), trial
        lo_state, lo, dp = trial, hi, min(2 * dp, max_step)
    while hi - lo > tol:                                   # bisect the crossing
        mid = 0.5 * (lo + hi)
        trial, ok, msg = stage.heat(lo_state, mid - lo, coupling=coupling)
        if ok and stage.look(trial)[1]:
            hi, hi_state = mid, trial
        elif ok:
            lo, lo_state = mid, trial
        else:
            break
    return stage.result("met", hi, hi_state, "criterion met"), hi_state
