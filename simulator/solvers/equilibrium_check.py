"""Is a given state an equilibrium? The check of every analysis about a state (theory 9.3).

Natural modes and the stability of a state linearise the structure about it; about a state
out of equilibrium the tangent carries the stress stiffness of forces that are not there, and
the answer can be far off without any sign of it (the reference's micro-mirror, self-folded
with the reference's loose Newton loop, leftover bar strains about 1e-7: first frequency
838 Hz instead of 360 Hz). :func:`check_equilibrium` measures the free-DOF force residual
``r = f_ext - f_int`` of a state (``f_ext`` its dead loads, ``f_int`` at its displacements
and spring rest angles) against the stiffness scale of the model,

    rho = |r|_2 / (max_i K_ii * L)      (K_ii the free-DOF tangent diagonal [N/m], L the
                                         model size [m]),

the residual as a fraction of the force that strains the stiffest element by its own length.
The state is in equilibrium when ``rho <= EQUILIBRIUM_RTOL`` = 1e-12:

* round-off: the converged end states of all the built-in cases sit at rho <= 3e-17
  (round-off in the element forces is about machine epsilon times the strain), and Newton's
  own criterion (1e-13 N, or 1e-10 of the increment's first residual) ends far below 1e-12;
* effect: near its equilibrium the micro-mirror (silicon panels on thin hinges, the largest
  stiffness contrast of the built-in models) moves its first eigenvalue by about 3e8 rho
  (relative), so 1e-12 keeps that below 3e-4 (1.5e-4 in frequency); the reference loop's
  states (atol 1e-6 to 1e-5 N) sit at rho = 2e-8 to 3e-8 and are flagged.

A load-relative measure would be undefined for self-folded and heated states, which carry no
applied load. :func:`analysis_state` applies the check for an analysis: warn (logging WARNING,
the result says so), refuse (:class:`~simulator.errors.ParameterError`), or re-converge the
state first (Newton at the state's rest angles and dead loads; one or two iterations from a
nearly converged state).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from .._result import ResultFiles
from ..errors import ParameterError
from ..model.model import Model
from ..mechanics.equilibrium import equilibrium_system
from ..state import SimulationState, at_rest, initial_state

__all__ = ["EQUILIBRIUM_RTOL", "EQUILIBRIUM_ACTIONS", "EquilibriumCheck", "check_equilibrium",
           "checked_state", "analysis_state"]

logger = logging.getLogger(__name__)

#: Largest residual, relative to max K_ii times the model size, of a state in equilibrium
#: (see the module docstring for the reasons).
EQUILIBRIUM_RTOL = 1e-12

#: What an analysis does with a state out of equilibrium: warn and analyse it, refuse it
#: (ParameterError), or re-converge it first.
EQUILIBRIUM_ACTIONS = ("warn", "raise", "reconverge")


@dataclass(frozen=True, eq=False)
class EquilibriumCheck(ResultFiles):
    """The force residual of a state (``success`` True: the check ran; ``status``
    "equilibrium" or "not in equilibrium").

    Attributes
    ----------
    residual_norm : float
        2-norm of the free-DOF residual ``f_ext - f_int`` [N].
    force_scale : float
        ``max_i K_ii * L`` [N]: largest free-DOF tangent diagonal [N/m] times the model size.
    tolerance : float
        Largest ``relative`` residual of an equilibrium (:data:`EQUILIBRIUM_RTOL`).
    reconverged_from : float or None
        Residual [N] of the given state when this check is of its re-converged version.
    iterations : int
        Newton iterations of that re-convergence (0 if none).
    """

    residual_norm: float
    force_scale: float
    tolerance: float = EQUILIBRIUM_RTOL
    reconverged_from: float | None = None
    iterations: int = 0

    @property
    def relative(self) -> float:
        """``residual_norm / force_scale`` (0 for a zero residual, inf without stiffness)."""
        if self.residual_norm == 0:
            return 0.0
        return self.residual_norm / self.force_scale if self.force_scale > 0 else math.inf

    @property
    def in_equilibrium(self) -> bool:
        return self.relative <= self.tolerance

    @property
    def success(self) -> bool:
        return True

    @property
    def status(self) -> str:
        return "equilibrium" if self.in_equilibrium else "not in equilibrium"

    @property
    def message(self) -> str:
        size = (f"force residual {self.residual_norm:.3g} N = {self.relative:.3g} of max K_ii x "
                f"model size ({self.force_scale:.3g} N; tolerance {self.tolerance:g})")
        again = ("" if self.reconverged_from is None else
                 f" after re-converging from {self.reconverged_from:.3g} N in "
                 f"{self.iterations} Newton iteration(s)")
        if self.in_equilibrium:
            return f"in equilibrium: {size}{again}"
        return f"not in equilibrium: {size}{again}"

    def to_dict(self) -> dict:
        return {"in_equilibrium": self.in_equilibrium, "residual_norm [N]": self.residual_norm,
                "relative_residual": self.relative, "force_scale [N]": self.force_scale,
                "tolerance": self.tolerance, "reconverged_from [N]": self.reconverged_from,
                "iterations": self.iterations}

    _csv_name = "equilibrium.csv"


def check_equilibrium(model, state: SimulationState, evaluation=None,
                      tolerance: float = EQUILIBRIUM_RTOL) -> EquilibriumCheck:
    """The force residual of ``state`` against the model's stiffness scale (module docstring).

    Parameters
    ----------
    model : Model
    state : SimulationState
    evaluation : SystemValues, optional
        ``equilibrium_system(model).evaluate(state.u, state.spring_rest, hessian=True)`` if
        already at hand (saves one assembly).
    tolerance : float
        Largest relative residual of an equilibrium, > 0.

    Returns
    -------
    EquilibriumCheck
    """
    if not (isinstance(tolerance, (int, float)) and math.isfinite(tolerance) and tolerance > 0):
        raise ParameterError(f"check_equilibrium: tolerance = {tolerance!r}; give a relative "
                             f"residual > 0 (default {EQUILIBRIUM_RTOL:g}).")
    system = equilibrium_system(model)
    ev = evaluation if evaluation is not None else \
        system.evaluate(state.u, state.spring_rest, hessian=True)
    free = system.free
    r = np.asarray(state.applied_load, float).ravel()[free] - ev.f_int[free]
    diag = ev.K.diagonal() if len(free) else np.zeros(0)
    scale = float(np.max(diag, initial=0.0)) * system.size
    return EquilibriumCheck(float(np.linalg.norm(r)), scale, float(tolerance))


def checked_state(model, state, caller: str) -> SimulationState:
    """``state`` (None: the initial state of ``model``) after checking the types of both; a
    :class:`~simulator.errors.ParameterError` naming ``caller`` otherwise."""
    if not isinstance(model, Model):
        raise ParameterError(f"{caller}: model is a {type(model).__name__}; build one with "
                             "make_model(...).")
    state = initial_state(model) if state is None else state
    if not isinstance(state, SimulationState):
        raise ParameterError(f"{caller}: state is a {type(state).__name__}; give a "
                             "SimulationState (e.g. result.state) or None.")
    return state


def analysis_state(model, state: SimulationState, equilibrium: str, caller: str,
                   options=None):
    """The state an analysis linearises about, and its check.

    ``equilibrium`` (one of :data:`EQUILIBRIUM_ACTIONS`) says what to do when ``state`` is not
    in equilibrium: "warn" (log a WARNING naming ``caller`` and the residual, analyse it),
    "raise" (:class:`~simulator.errors.ParameterError`) or "reconverge" (Newton from the state
    at its rest angles and dead loads with ``options``, default ``NewtonOptions()``; if that
    fails, warn and analyse the given state). Returns ``(state, check, evaluation)`` with the
    tangent evaluation at the returned state.
    """
    if equilibrium not in EQUILIBRIUM_ACTIONS:
        raise ParameterError(f"{caller}: equilibrium = {equilibrium!r}; use 'warn' (analyse "
                             "and say so), 'raise' (refuse) or 'reconverge' (Newton first).")
    system = equilibrium_system(model)
    ev = system.evaluate(state.u, state.spring_rest, hessian=True)
    check = check_equilibrium(model, state, ev)
    if check.in_equilibrium:
        return state, check, ev
    if equilibrium == "raise":
        raise ParameterError(f"{caller}: the state is {check.message}; converge it first "
                             "(tighter NewtonOptions, not reference_loop) or pass "
                             "equilibrium='reconverge'.")
    if equilibrium == "reconverge":
        state, check, ev = _reconverge(model, state, check, ev, options)
    if not check.in_equilibrium:
        logger.warning("%s: the state is %s; the results are those of a linearisation about a "
                       "state that is not an equilibrium (equilibrium='reconverge' re-converges "
                       "it first)", caller, check.message)
    return state, check, ev


def _reconverge(model, state, check, ev, options):
    """Newton from ``state`` at its rest angles and dead loads: (state, check, evaluation),
    the given ones with a note in the log if Newton fails."""
    from .newton import NewtonOptions, newton

    system = equilibrium_system(model)
    res = newton(system, state.u, np.asarray(state.applied_load, float).ravel(),
                 state.spring_rest, NewtonOptions() if options is None else options)
    if not res.success:
        logger.warning("re-converging the state failed: %s", res.message)
        return state, check, ev
    new = at_rest(state, u=res.u)
    ev_new = system.evaluate(new.u, new.spring_rest, hessian=True)
    after = check_equilibrium(model, new, ev_new, check.tolerance)
    return new, EquilibriumCheck(after.residual_norm, after.force_scale, after.tolerance,
                                 check.residual_norm, res.iterations), ev_new
