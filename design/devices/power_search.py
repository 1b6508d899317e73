"""Power searches: the smallest heating power at which a stage's criterion holds.

Both strategies work on a *stage* object with three methods:

* ``heat(state, dp, increments=1, coupling="staggered") -> (state, ok, message)``: add power
  ``dp`` [W] per heated crease from a saved simulation state;
* ``look(state) -> (measure, met, temperature, max_crease_temperature)``, and ``met(state)``
  (the criterion alone, what the searches ask after every trial: :meth:`HeatingStage.met`
  takes it from ``look``, a stage may give it without judging temperatures);
* ``result(status, power, state, message)``: the stage's result object; ``status`` is
  ``"met"`` (the criterion holds at ``power``), ``"not_met"`` (not below the power cap) or
  ``"failed"`` (a heating simulation failed at ``power``).

:func:`staircase_search` is the reference's search (fixed steps); :func:`bisect_search` grows
the step and bisects the crossing, restarting trials from saved states so that nothing is
recomputed from zero. Used by the gripper (:mod:`design.devices.gripper`) and the Miura lifter
(:mod:`design.devices.miura`).

Both stages heat through :class:`HeatingStage`: every trial is a :class:`~simulator.steps.Heat`
step with ``on_limit_point="continue"``, so where load control stalls at a limit point (the
structure snaps) arc length in the power carries the trial on to its final power, and the snap
(power per crease, jump of the most-moving node) is kept with the trial's state: the step's
``"snap"`` :class:`~simulator.events.Event` records, read as data (never parsed from a
message). A criterion met only after a snap is reported as met, with ``after a snap (...)``
in the message and the snap events on the stage's result. Load
control is unchanged where it converges, so trials without a failure give the same numbers as
plain load control. The bisect search's growth trials larger than its first step are the
exception: they run plain load control, since a failure there is retried with a smaller step
(arc length from a trial that stalled after a large jump in power can land on another branch:
coordinate-descent design W 300, La 1200, L1 500, L2 550 um lost its grip that way, and paid
for it with a fifth of the whole descent's Newton iterations).
"""

from __future__ import annotations

from dataclasses import dataclass

from simulator import Heat, simulate

__all__ = ["staircase_search", "bisect_search", "HeatingTrial", "HeatingStage", "heating_trial"]


@dataclass(frozen=True)
class HeatingTrial:
    """One heating trial of a power search.

    Attributes
    ----------
    state : SimulationState at the end of the trial (the last converged one if it failed)
    success : bool (the trial reached its final power)
    message : str (the simulation's message)
    snap : str or None
        The snaps passed by arc length, e.g. ``"snap at 9.21 mW per crease: displacement
        jumps 302.8 um"`` (several joined by ``"; "``); None if load control never stalled at
        a limit point.
    increments : int (load-controlled and arc-length increments solved)
    snaps : tuple of Event
        The ``"snap"`` events of the trial's Heat step (``snap`` in words); empty if none.
    """

    state: object
    success: bool
    message: str
    snap: str | None
    increments: int
    snaps: tuple = ()


def heating_trial(model, creases, state, dp, increments=1, coupling="staggered",
                  options=None, follow_snaps=True) -> HeatingTrial:
    """Add ``dp`` [W] to each crease of ``creases`` from ``state``, following snaps.

    Load control in ``increments`` increments; where it stalls, arc length in the power
    (``Heat(..., on_limit_point="continue")``), unless ``follow_snaps`` is False (plain load
    control: the trial fails there). The snap powers in :attr:`HeatingTrial.snap` are those of
    ``creases[0]`` [mW per crease] (the stage's heated creases, whatever other creases carry).
    """
    res = simulate(model, [Heat({tuple(creases): dp}, increments=increments, coupling=coupling,
                                on_limit_point="continue" if follow_snaps else "stop")],
                   state=state, options=options)
    step = res.steps[-1] if res.steps else None
    snaps = tuple(e for e in step.events if e.kind == "snap") \
        if res.success and step is not None else ()
    row = model.mesh.crease_row[creases[0]]
    text = "; ".join(f"snap at {1e3 * e.power_per_crease[row]:.4g} mW per crease: displacement "
                     f"jumps {1e6 * e.jump:.4g} um" for e in snaps)
    return HeatingTrial(res.state, res.success, res.message, text or None,
                        step.increments if step is not None else 0, snaps)


class HeatingStage:
    """Heating trials of a power search from saved states, with the snaps on the way to each.

    Subclasses add ``look(state)`` and ``result(status, power, state, message)`` (see the
    module docstring) and may extend :meth:`heat`.

    Parameters
    ----------
    model : Model
    creases : tuple of int (the heated creases; each gets the trial's power)
    options : NewtonOptions, optional
    """

    def __init__(self, model, creases, options=None):
        self.model, self.creases, self.options = model, tuple(creases), options
        self.simulations = self.increments = 0
        self._snaps = {}       # id(state) -> (state, snap notes, snap events on the way to it)

    def heat(self, state, dp, increments=1, coupling="staggered", follow_snaps=True):
        """Add ``dp`` [W] per heated crease in ``increments`` increments (snaps followed by
        arc length unless ``follow_snaps`` is False); returns ``(state, ok, message)``."""
        trial = heating_trial(self.model, self.creases, state, dp, increments, coupling,
                              self.options, follow_snaps)
        self.simulations += 1
        self.increments += trial.increments
        snaps = self.snaps(state) + ((trial.snap,) if trial.snap else ())
        if snaps:
            self._snaps[id(trial.state)] = (trial.state, snaps,
                                            self.snap_events(state) + trial.snaps)
        return trial.state, trial.success, trial.message

    def met(self, state) -> bool:
        """Whether the criterion holds at ``state`` (``look(state)[1]``; a subclass may tell it
        without the temperatures ``look`` also judges)."""
        return bool(self.look(state)[1])

    def _kept(self, state) -> tuple:
        kept = self._snaps.get(id(state))
        return kept if kept is not None and kept[0] is state else (state, (), ())

    def snaps(self, state) -> tuple:
        """Snap notes of the trials that led from the search's start to ``state``."""
        return self._kept(state)[1]

    def snap_events(self, state) -> tuple:
        """``"snap"`` :class:`~simulator.events.Event` records of the trials that led from the
        search's start to ``state`` (their ``load_factor`` is that of their own trial)."""
        return self._kept(state)[2]

    def after_snaps(self, message, state) -> str:
        """``message`` with ``" after a snap (...)"`` if a snap led to ``state``."""
        snaps = self.snaps(state)
        return f"{message} after a snap ({'; '.join(snaps)})" if snaps else message


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
        if stage.met(state):
            return stage.result("met", power, state, "criterion met"), state
    return stage.result("not_met", power, state, f"criterion not met below the power cap "
                                                 f"{cap * 1e3:.3g} mW per crease"), state


def bisect_search(stage, state, step, tol, cap, max_step, coupling="staggered"):
    """Grow the power step geometrically (``step`` doubling up to ``max_step``) from saved
    states until the criterion holds, then bisect the crossing to ``tol``.

    Every trial restarts from the saved state below the crossing. A growth trial larger than
    ``step`` that fails is retried with a quarter of the step (at least ``step``); such trials
    run plain load control (``follow_snaps=False``): a limit point is passed by arc length only
    from a trial of ``step`` (or in the bisection), whose failure ends the search. Returns
    ``(stage result, state at the smallest power found to meet the criterion)``.
    """
    lo_state, lo, dp = state, 0.0, step
    while True:                                            # grow until the criterion holds
        hi = min(lo + dp, cap)
        retry = dp > step                                  # a failure is retried smaller
        trial, ok, msg = stage.heat(lo_state, hi - lo, coupling=coupling,
                                    follow_snaps=not retry)
        if not ok:
            if retry:                                      # too big a jump: retry smaller
                dp = max(step, dp / 4)
                continue
            return stage.result("failed", hi, trial, f"simulation failed at {hi * 1e3:.3g} mW: "
                                                     f"{msg}"), trial
        if stage.met(trial):
            hi_state = trial
            break
        if hi >= cap - 1e-15:
            return stage.result("not_met", hi, trial, f"criterion not met below the power cap "
                                                      f"{cap * 1e3:.3g} mW per crease"), trial
        lo_state, lo, dp = trial, hi, min(2 * dp, max_step)
    while hi - lo > tol:                                   # bisect the crossing
        mid = 0.5 * (lo + hi)
        trial, ok, msg = stage.heat(lo_state, mid - lo, coupling=coupling)
        if ok and stage.met(trial):
            hi, hi_state = mid, trial
        elif ok:
            lo, lo_state = mid, trial
        else:
            break
    return stage.result("met", hi, hi_state, "criterion met"), hi_state
