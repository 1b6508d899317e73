"""Stability of the states load control accepts, and where an unstable one goes (theory 6.12).

:func:`~simulator.solvers.newton.follow_path` judges every converged increment with
:func:`judge` (one Cholesky factorisation where the state is stable,
:func:`~simulator.solvers.stability.quick_stability`). An unstable state at a bifurcation
(critical mode orthogonal to the load derivative) is left for the stable state it falls to
along its critical mode (:func:`~simulator.solvers.descent.choose_branch`), and an increment
that fails from a critical state (a singular tangent) starts from there
(:func:`leave_critical`); each is a :class:`BranchSwitch`. States past a limit point (mode
along the load) are kept for the steps' limit-point handling (:mod:`simulator.steps.limit`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from ..mechanics.equilibrium import assembled_tangent as _tangent
from .descent import choose_branch
from .load_path import LoadPath, model_size
from .path_trace import BIFURCATION_ALIGNMENT
from .stability import NEGATIVE_RTOL, negative_tolerance, quick_stability, tangent_stability

__all__ = ["BranchSwitch", "judge", "leave_critical", "leave_turn", "soft_mode",
           "gave_up_at"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class BranchSwitch:
    """An accepted equilibrium found unstable by load control, and where it was left.

    Attributes
    ----------
    t : float
        Path parameter of the increment (the state was stable at the previous one).
    unstable : Stability of the state load control converged to
    choice : BranchChoice or None
        The pushes along the critical mode and the branch taken
        (:func:`~simulator.solvers.descent.choose_branch`); None when not tried ("check") or
        when the model is too large for the descent.
    stability : Stability or None
        Of the state reached (None: none reached, the path stays on the unstable state).
    u_from : (n_nodes, 3) the unstable state's displacements [m]
    """

    t: float
    unstable: object
    choice: object = None
    stability: object = None
    u_from: np.ndarray | None = None

    @property
    def switched(self) -> bool:
        """True if a stable state was reached."""
        return self.stability is not None and self.stability.stable

    def describe(self) -> str:
        """The switch in words (for messages and events)."""
        st = self.unstable
        if st.negative:
            head = (f"equilibrium unstable at path parameter {self.t:.6g} ({st.negative} "
                    f"negative eigenvalue(s), lowest {st.lowest:.3g} N/m)")
        elif st.lowest:
            head = (f"a bifurcation passed between two stable states at path parameter "
                    f"{self.t:.6g} (the path turned sharply; lowest eigenvalue before it "
                    f"{st.lowest:.3g} N/m)")
        else:
            head = (f"load control failed from a critical equilibrium (singular tangent) at "
                    f"path parameter {self.t:.6g}")
        c = self.choice
        if not self.switched:
            why = "no stable state found along the critical mode" if c is not None else \
                "not left (NewtonOptions.stability='check' or too large for the descent)"
            return f"{head}: {why}"
        if c.tie:
            how = ("two branches of equal energy: took the critical mode's positive sign; "
                   "NewtonOptions(branch='other') takes the other")
        elif c.gap is None:
            how = "the only branch the pushes reached"
        else:
            how = (f"took the branch of {'lower' if c.gap > 0 else 'higher'} energy "
                   f"({abs(c.gap):.3g} J from the other; NewtonOptions(branch="
                   f"'{'other' if c.gap > 0 else 'lower'}') takes the other)")
        return f"{head}: left along its critical mode to a stable branch, {how}"


def judge(system, res, t, ends, options, switches, locate: bool = False):
    """``(res, stability)`` of a converged Newton result ``res`` at ``t``. With
    ``options.stability == "switch"`` an unstable one whose critical mode is orthogonal to the
    load derivative (a bifurcation: |cos| below
    :data:`~simulator.solvers.path_trace.BIFURCATION_ALIGNMENT`) is left for the stable state
    it falls to (:func:`_fall`; :class:`BranchSwitch` appended to ``switches``) where one is
    reached; one whose mode is along it (load control passed a limit point onto the unstable
    branch) is kept, recorded unstable: the step's limit-point handling (arc length past the
    snap, :mod:`simulator.steps.limit`) takes it from the failure that follows, and a step
    that ends there does not succeed.

    ``locate``: the loss of stability at a bifurcation is still to be located (the state
    before was stable and the increment is longer than the path's location tolerance): the
    result is refused (failed, so that the increment is halved) instead of left, and the
    branch is chosen at the first unstable state of an increment within the tolerance, the
    same point whatever the increments (theory 6.12)."""
    # The tangent of the accepted state itself (its evaluation, assembled by the residual
    # check that accepted it), factorised once more: Newton's last factorisation is of the
    # iterate before, whose correction was not below tolerance (the residual criterion stops
    # on the residual that follows it; an increment converged in one correction leaves only
    # the previous accepted state's tangent). Judged there, a loss of stability would be seen
    # one correction late and located off the increment it happens in.
    st = quick_stability(_tangent(res.evaluation), options.linear_solver)
    if st.stable or options.stability != "switch":
        return res, st
    if st.load_alignment(_path(system, ends).at(res.u, t).q) >= BIFURCATION_ALIGNMENT:
        return res, st       # past a limit point: the step's limit-point handling decides
    if locate:
        return replace(res, success=False, message=(
            "the equilibrium turned unstable within the increment (a bifurcation): halving it "
            "to locate where")), st
    landed, ev, sw = _fall(system, res.u, st, t, ends, options)
    switches.append(sw)
    if landed is None:
        return res, st
    return replace(res, u=np.asarray(sw.choice.u, float).reshape(-1, 3), evaluation=ev), landed


#: |cos| between the softest mode and the path's direction above which a sharp turn is taken
#: for the approach to a fold of the path (it already moves mostly along the mode) rather
#: than for a symmetric bifurcation passed (measured: 0.002-0.62 at the square twist's
#: bifurcations, 0.90-1.0 at the heated Miura's approach to its snap).
SLOPE_ALIGNMENT = 0.7


#: Two equilibria closer than this fraction of the model size are the same state.
SAME_STATE = 1e-7


def soft_mode(system, u, ev, t0, ends, options, slope=None):
    """Stability (with the critical mode) of the stable state ``u`` at ``t0`` (evaluation
    ``ev``, or None) whose next increment turned sharply, if its softest mode is orthogonal to
    the load derivative (|cos| below
    :data:`~simulator.solvers.path_trace.BIFURCATION_ALIGNMENT`) and not along the path's
    direction ``slope`` (n_nodes, 3) (|cos| below :data:`SLOPE_ALIGNMENT`): a symmetric
    bifurcation ahead, the path not yet moving along the mode; None otherwise (a
    limit point or an asymmetric critical point ahead, which the path approaches along the
    mode: it turns because it is about to snap, which the steps' limit-point handling
    takes)."""
    st, _, align = _eigen_state(system, u, ev, t0, ends, options)
    if st.mode is None or align >= BIFURCATION_ALIGNMENT:
        return None
    if slope is not None and st.load_alignment(np.asarray(slope).ravel()[system.free]) >= \
            SLOPE_ALIGNMENT:
        return None
    return st


def gave_up_at(system, u, ev, t, ends, options) -> str:
    """What the last accepted state ``u`` at ``t`` (evaluation ``ev``, or None) of a path that
    gave up is, for its message (theory 6.12): critical (lowest eigenvalue zero within
    round-off, ``NEGATIVE_RTOL n eps max|K_ii|``), a limit point or a bifurcation by its mode's
    alignment with the load derivative; unstable; or stable, Newton not converging from it.
    One eigen-analysis, at the failure; "" for a model without free DOFs."""
    st, K, align = _eigen_state(system, u, ev, t, ends, options)
    if st is None:
        return ""
    stiffest = float(np.max(np.abs(K.diagonal())))
    zero = NEGATIVE_RTOL * negative_tolerance(K)
    if st.negative:
        return (f"; the state there is unstable ({st.negative} negative eigenvalue(s), lowest "
                f"{st.lowest:.3g} N/m)")
    if st.lowest > zero:
        return (f"; the state there is stable (lowest eigenvalue {st.lowest:.3g} N/m) and "
                "Newton does not converge from it")
    kind = (f"a limit point (its mode along the load, |cos| {align:.2f}): the load cannot rise "
            "past it on this branch" if align >= BIFURCATION_ALIGNMENT else
            f"a bifurcation (its mode across the load, |cos| {align:.2f})")
    return (f"; the state there is critical, {kind}: lowest eigenvalue {st.lowest:.3g} N/m, "
            f"zero within round-off ({zero:.3g} N/m against the stiffest diagonal entry "
            f"{stiffest:.3g} N/m)")


def _eigen_state(system, u, ev, t, ends, options):
    """``(stability, tangent, |cos| of its mode with the load derivative)`` of the state ``u``
    at ``t`` (evaluation ``ev``, or None: evaluated at the path's rest angles there), by
    :func:`~simulator.solvers.stability.tangent_stability`; ``(None, K, nan)`` without free
    DOFs."""
    path = _path(system, ends)
    if ev is None:
        ev = system.evaluate(u, path.rest(t))
    K = _tangent(ev)
    if K.shape[0] == 0:
        return None, K, float("nan")
    st = tangent_stability(K, linear_solver=options.linear_solver, rtol=NEGATIVE_RTOL)
    return st, K, st.load_alignment(path.at(u, t).q)


def leave_turn(system, res, u, st, t, ends, options, switches):
    """``(res, stability)``: a converged stable Newton result ``res`` at ``t`` whose increment
    from the stable state ``u`` (stability ``st``, with its softest mode, from
    :func:`soft_mode`) turned sharply, within the location tolerance: a bifurcation passed
    between two stable states, Newton taking the branch its round-off favoured. Replaced by the
    stable state at ``t`` that ``u`` falls to along its softest mode (:func:`_fall`, the same
    choice as at an unstable state); ``res`` unchanged where none is reached."""
    landed, ev1, sw = _fall(system, u, st, t, ends, options)
    if landed is None:
        switches.append(sw)
        return res, quick_stability(_tangent(res.evaluation), options.linear_solver)
    u1 = np.asarray(sw.choice.u, float).reshape(-1, 3)
    if np.max(np.abs(u1 - res.u)) <= SAME_STATE * model_size(system):
        return res, landed                 # Newton's state is the chosen one: no switch
    switches.append(sw)
    return replace(res, u=u1, evaluation=ev1), landed


def leave_critical(system, res, u, st, t, ends, options, switches):
    """A failed Newton result ``res`` at ``t`` from the critical state ``u`` (stability
    ``st``: singular, with its mode): the stable state at ``t`` that ``u`` falls to along the
    mode, as a successful result, or ``res`` unchanged."""
    landed, ev, sw = _fall(system, u, st, t, ends, options)
    if landed is None:
        return res
    switches.append(sw)
    return replace(res, u=np.asarray(sw.choice.u, float).reshape(-1, 3), evaluation=ev,
                   success=True, message="converged (left a critical state along its mode)")


def _path(system, ends):
    """The :class:`~simulator.solvers.load_path.LoadPath` of
    :func:`~simulator.solvers.newton.follow_path`'s ends
    ``(f_start, f_end, rest_start, rest_end)``."""
    f_start, f_end, rest_start, rest_end = ends
    return LoadPath(system, f_start, f_end - f_start, rest_start, rest_end - rest_start)


def _fall(system, u, st, t, ends, options):
    """``(stability, evaluation, BranchSwitch)`` of the stable state at ``t`` that ``u``
    (n_nodes, 3) falls to along the critical mode of ``st``; stability and evaluation None
    where none is reached."""
    path = _path(system, ends)
    choice = choose_branch(path, u, t, st.mode, options, options.branch)
    if choice is None or choice.u is None:
        sw = BranchSwitch(t, st, choice, u_from=u)
        logger.info("%s", sw.describe())
        return None, None, sw
    ev = system.evaluate(choice.u, path.rest(t))
    landed = quick_stability(_tangent(ev), options.linear_solver)
    sw = BranchSwitch(t, st, choice, landed, u)
    logger.info("%s", sw.describe())
    return (landed, ev, sw) if landed.stable else (None, None, sw)
