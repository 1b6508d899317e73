"""The :func:`simulate` facade: run steps in order, collect one result.

``simulate`` is deliberately thin: it checks its inputs, hands each :class:`~simulator.steps.Step`
the state the previous one left (``step.run(context, state)``), turns every
:class:`~simulator.steps.StepOutcome` into a :class:`~simulator.results.StepResult` (support
reactions and energies at its end state) and stops after the first step that does not succeed.
"""

from __future__ import annotations

import logging
import time
from dataclasses import replace

import numpy as np

from .errors import ConvergenceError, ParameterError
from .model.model import Model
from .solvers.newton import NewtonOptions
from .results import SimulationResult, StepResult
from .state import SimulationState, initial_state
from .steps.base import Step, StepContext, StepOutcome, StepRecorder, watch_recorders

__all__ = ["simulate"]

logger = logging.getLogger(__name__)


def simulate(model: Model, steps, state: SimulationState | None = None,
             options: NewtonOptions | None = None, progress=None,
             interruptible: bool = False) -> SimulationResult:
    """Run loading steps in order, each starting from the state the previous one left.

    Parameters
    ----------
    model : Model
    steps : sequence of Step
        E.g. ``[SelfFold(...), Gravity(...), Heat(...)]``.
    state : SimulationState, optional
        Start state (default: :func:`~simulator.state.initial_state`).
    options : NewtonOptions, optional
    progress : callable, optional
        ``progress(done, total)`` after every accepted increment of every step.
    interruptible : bool
        If True, a ``KeyboardInterrupt`` (Ctrl-C) during a step ends the run with a partial
        result instead of the exception: the steps done, and the interrupted step with the
        increments it had accepted, status ``"interrupted"`` (its end state is the last accepted
        increment's displacements, temperatures and powers; see
        :meth:`~simulator.steps.StepRecorder.last_state`). Default False: the exception
        propagates.

    Returns
    -------
    SimulationResult
        Stops after the first step that does not succeed (its result says why); raises
        :class:`~simulator.errors.ConvergenceError` then only if ``options.raise_on_failure``.
    """
    options = NewtonOptions() if options is None else options
    _check_inputs(model, steps, state, options)
    steps = list(steps)
    context = StepContext(model, options, progress)
    start = initial_state(model) if state is None else state
    state, results = start, []
    t_start = time.perf_counter()
    for step in steps:
        t0 = time.perf_counter()
        with watch_recorders() as recorders:
            try:
                outcome = step.run(context, state)
            except KeyboardInterrupt:
                if not interruptible:
                    raise
                outcome = _interrupted(step, recorders, state)
        if not isinstance(outcome, StepOutcome):
            raise TypeError(f"{type(step).__name__}.run returned {type(outcome).__name__}; a "
                            "step must return a StepOutcome (use StepRecorder.finish).")
        results.append(_step_result(step, outcome, context, time.perf_counter() - t0,
                                    len(results)))
        state = outcome.state
        logger.info("step %s: %s, %d increments, %d Newton iterations, %d cuts", step.name,
                    outcome.status, len(outcome.load_factor), outcome.iterations, outcome.cuts)
        if not outcome.success:
            break
    result = SimulationResult(results, state, model, start, options.to_dict(),
                              time.perf_counter() - t_start)
    if not result.success and options.raise_on_failure:
        raise ConvergenceError(result.message, result)
    return result


def _interrupted(step, recorders, state) -> StepOutcome:
    """The outcome of a step stopped by Ctrl-C: the records of its first recorder so far."""
    rec = recorders[0] if recorders else StepRecorder(state)
    message = (f"interrupted by the user after {len(rec)} accepted increment"
               f"{'s' if len(rec) != 1 else ''} of step {step.name!r}")
    logger.info(message)
    return rec.finish(False, "interrupted", message, rec.last_state(),
                      rec.start.applied_load.ravel())


def _check_inputs(model, steps, state, options) -> None:
    if not isinstance(model, Model):
        raise ParameterError(f"simulate: model is a {type(model).__name__}; build one with "
                             "make_model(pattern, supports, ...).")
    if isinstance(steps, Step) or not hasattr(steps, "__iter__"):
        raise ParameterError("simulate: steps must be a list of steps, e.g. [Heat(...)].")
    for k, s in enumerate(steps):
        if not isinstance(s, Step):
            raise ParameterError(f"simulate: steps[{k}] = {s!r} is not a Step (SelfFold, Load, "
                                 "Gravity, Heat, AmbientTemperature, ... or a Step subclass).")
    if state is not None and not isinstance(state, SimulationState):
        raise ParameterError(f"simulate: state is a {type(state).__name__}; give a "
                             "SimulationState (e.g. result.state) or None.")
    if not isinstance(options, NewtonOptions):
        raise ParameterError(f"simulate: options is a {type(options).__name__}; give "
                             "NewtonOptions(...).")


def _step_result(step: Step, outcome: StepOutcome, context: StepContext, wall,
                 index: int) -> StepResult:
    """The StepResult of ``outcome``: reactions and energies at its end, its events named by
    the step (``step.name`` at position ``index``)."""
    state, system = outcome.state, context.system
    ev = outcome.evaluation or system.evaluate(state.u, state.spring_rest, hessian=False)
    fixed = system.free_index < 0
    reactions = np.where(fixed, ev.f_int - outcome.f_ext, 0.0).reshape(-1, 3)
    return StepResult(
        name=step.name, success=outcome.success, status=outcome.status, message=outcome.message,
        state=state, iterations=outcome.iterations, cuts=outcome.cuts,
        load_factor=outcome.load_factor, u_history=outcome.u,
        temperature_history=outcome.temperature, power_history=outcome.power,
        increment_iterations=outcome.increment_iterations,
        residual_norms=list(outcome.residual_norms), reactions=reactions,
        energies=ev.energies, wall_time=wall, settings=step.describe(), columns=outcome.columns,
        velocity_history=outcome.velocity, stable=outcome.stable,
        first_increment=outcome.first_increment,
        events=tuple(replace(e, step=step.name, step_index=index) for e in outcome.events))
