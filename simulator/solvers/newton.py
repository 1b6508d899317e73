"""Newton-Raphson equilibrium and path following with step cutting.

:func:`newton` solves ``f_int(u) = f_ext`` on the free DOFs for fixed rest angles.
:func:`follow_path` drives a linear path in (external load, spring rest angles)
from a start to an end over a number of increments, halving an increment that
fails and growing back after successes (the iteration and the cutting are
:func:`~simulator.solvers.nonlinear.iterate` and :func:`~simulator.solvers.nonlinear.march`).
Failures are returned as data
(``success``, ``status``, ``message``); :class:`~simulator.errors.ConvergenceError`
is raised only when ``NewtonOptions.raise_on_failure`` is set.
"""

from __future__ import annotations

import logging
import math
from dataclasses import asdict, dataclass, field, replace
from functools import cached_property

import numpy as np

from ..mechanics.equilibrium import EquilibriumSystem, SystemValues, assembled_tangent as _tangent
from ..mechanics.crossing import wrap_refusal
from ..mechanics.substrate import substrate_refusal
from .._validate import integer, non_negative, one_of
from ..errors import ParameterError
from ..linalg.ladder import check_backend, solve as linear_solve
from .branches import BranchSwitch, gave_up_at, judge, leave_critical, leave_turn, soft_mode
from .descent import BRANCHES
from .nonlinear import GROWTH_ITERATIONS, iterate, march, residual_at_round_off
from .stability import quick_stability

__all__ = ["NewtonOptions", "NewtonResult", "PathResult", "newton",
           "follow_path", "STABILITY_ACTIONS"]

logger = logging.getLogger(__name__)

#: Values of ``NewtonOptions.stability``.
STABILITY_ACTIONS = ("switch", "check", "off")
#: Load control locates a loss of stability at a bifurcation to this fraction of a step's
#: path (by halving the increment in which it happens: 1e-4 takes at most 9 halvings of the
#: 25-increment heating, within the 10 of ``NewtonOptions.max_cuts``) before it leaves it.
LOCATE_TOL = 1e-4


@dataclass(frozen=True)
class NewtonOptions:
    """Newton-Raphson settings.

    Parameters
    ----------
    criterion : {"residual", "displacement"}
        "residual": stop when the 2-norm of the free-DOF force residual [N] is at most
        ``max(atol, rtol * |r_0|)`` (the reference's self-fold / thermal meaning);
        "displacement": stop when the 2-norm of the Newton correction [m] is at most
        ``max(atol, rtol * |du_0|)`` (the reference's NR loading meaning).
    atol : float
        Absolute tolerance in N or m (reference examples: 1e-6 to 5e-7, loose for micro-scale
        devices whose self-weight is ~1e-8 N; the default 1e-13 N is near the round-off floor).
    rtol : float
        Tolerance relative to the first residual / correction of the increment.
    max_iter : int
        Newton iterations per increment before it counts as failed.
    max_cuts : int
        How many times one increment may be halved before the path gives up.
    max_total_cuts : int
        Halvings allowed over a whole path (so a path that keeps failing and recovering
        always ends, with status "failed").
    raise_on_failure : bool
        Raise :class:`~simulator.errors.ConvergenceError` instead of returning a failed result.
    stall_rtol : float
        Accept a Newton solve that fails to reach ``atol``/``rtol`` when its best iterate's
        residual is at most ``stall_rtol`` times the norm of the external load (said in the
        message). Contact makes the residual stall near 1e-12 N in some states (a point
        whose closest feature of a triangle switches between face and edge); 1e-3 of the
        self-weight is far below any physical effect. 0 disables; it never applies without
        external loads.
    reference_loop : bool
        Emulate the reference implementation's loop (theory 6.4), for comparisons with its
        outputs only: the stopping measure is taken *before* the update, so one more update
        is applied after it drops below ``atol`` (``rtol`` is ignored); at most
        ``max_iter - 1`` updates; a loop that ends above ``atol`` is still accepted (logged
        as a warning, and said in the message). With the reference's loose tolerances
        (5e-7 N against ~1e-8 N of self-weight) this takes one to a few updates per increment,
        i.e. under-converged equilibria: keep it off for real work.

    stability : {"switch", "check", "off"}
        What load control does with the stability of every accepted state
        (:func:`follow_path`): "switch" (default) checks it (one Cholesky factorisation of the
        tangent, the eigenvalues only where it fails: :func:`~simulator.solvers.stability.quick_stability`)
        and leaves an unstable equilibrium, such as the symmetric state of a flat sheet heated
        at a bifurcation, for the stable branch it falls to along its critical mode
        (:func:`~simulator.solvers.descent.choose_branch`; theory 6.9); "check" checks and
        reports but stays on the branch (a path that ends on an unstable state does not
        succeed); "off" does neither (the reference's behaviour).
    branch : {"lower", "other"}
        Which branch "switch" takes where an equilibrium turns unstable: "lower" (default) the
        one whose energy descent ends lower (a tie, as in a symmetric structure, by the sign
        of the critical mode: theory 6.9), "other" the other one.

    linear_solver : {"auto", "dense", "pardiso", "superlu"}
        Backend of the tangent solves (:mod:`simulator.linalg.ladder`): "auto" is the ladder
        (dense up to 150 free DOFs, PARDISO when MKL is installed, else SuperLU in a
        fill-reducing order); the others force one. ``ETORIGAMI_PARDISO=0`` in the environment
        still takes PARDISO out of "auto".

    Notes
    -----
    Whatever the criterion, an iteration whose correction is at round-off level
    (below 1e-13 of the model size) also counts as converged. By the residual criterion, so
    does one whose lowest residual, not lowered by three corrections more, is at the round-off
    level of the internal force (a componentwise backward error of four ulps in the node
    positions, :func:`~simulator.solvers.nonlinear.residual_at_round_off`): large sheets with
    stiff short bars cannot reach 1e-13 N, and the best iterate is taken.
    """

    criterion: str = "residual"
    atol: float = 1e-13
    rtol: float = 1e-10
    max_iter: int = 30
    max_cuts: int = 10
    max_total_cuts: int = 60
    raise_on_failure: bool = False
    stall_rtol: float = 1e-3
    reference_loop: bool = False
    linear_solver: str = "auto"
    stability: str = "switch"
    branch: str = "lower"

    def __post_init__(self):
        check_backend(self.linear_solver, "NewtonOptions.linear_solver")
        one_of("NewtonOptions.stability", self.stability, STABILITY_ACTIONS,
               hint="'switch' leaves an unstable state for the stable branch, 'check' only "
               "reports it, 'off' does neither")
        one_of("NewtonOptions.branch", self.branch, BRANCHES,
               hint="'lower': the branch of lower energy, 'other': the other one")
        if self.criterion not in ("residual", "displacement"):
            raise ParameterError(f"NewtonOptions.criterion = {self.criterion!r}; use 'residual' or "
                                 "'displacement'.")
        for name in ("atol", "rtol", "stall_rtol"):
            non_negative(f"NewtonOptions.{name}", getattr(self, name))
        if self.atol == 0 and self.rtol == 0:
            raise ParameterError("NewtonOptions: atol and rtol cannot both be 0.")
        for name in ("max_iter", "max_cuts", "max_total_cuts"):
            integer(f"NewtonOptions.{name}", getattr(self, name), 1 if name == "max_iter" else 0)

    def to_dict(self) -> dict:
        return dict(self._as_dict)           # a copy: asdict once (every simulation records it)

    @cached_property
    def _as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True, eq=False)
class NewtonResult:
    """Outcome of one Newton solve (``success``, ``status``, ``message`` as every result)."""

    u: np.ndarray
    success: bool
    iterations: int
    residual_norms: np.ndarray
    correction_norms: np.ndarray
    message: str
    evaluation: SystemValues | None = None
    #: Accepted by the stall rule (``NewtonOptions.stall_rtol``): the residual has a floor
    #: above the tolerance; ``iterations`` is then ``max_iter``.
    stalled: bool = False

    @property
    def status(self) -> str:
        """'converged' or 'failed'."""
        return "converged" if self.success else "failed"


@dataclass(frozen=True, eq=False)
class PathResult:
    """Outcome of a path-following solve.

    Attributes
    ----------
    success : bool
        True if the path reached its end.
    status : str
        "converged", "failed" or "stopped".
    message : str
    u : (n_nodes, 3) final displacements (the last converged ones on failure)
    t : float
        Path parameter reached, in [0, 1].
    iterations : int
        Total Newton iterations.
    cuts : int
        Number of increment halvings.
    history : list of (t, u, iterations) per accepted increment
    residual_norms : list of arrays, residual history of each accepted increment
    evaluation : SystemValues at the final state
    stability : list of Stability or None, per accepted increment (None: not checked,
        ``NewtonOptions.stability="off"``)
    switches : list of BranchSwitch, the unstable states met and where they were left
    """

    success: bool
    status: str
    message: str
    u: np.ndarray
    t: float
    iterations: int
    cuts: int
    history: list = field(default_factory=list)
    residual_norms: list = field(default_factory=list)
    evaluation: SystemValues | None = None
    stability: list = field(default_factory=list)
    switches: list = field(default_factory=list)

    @property
    def stable(self) -> bool | None:
        """Whether the last accepted state is stable (None: not checked or none accepted)."""
        st = self.stability[-1] if self.stability else None
        return None if st is None else st.stable


def newton(system: EquilibriumSystem, u0: np.ndarray, f_ext: np.ndarray, spring_rest: np.ndarray,
           options: NewtonOptions = NewtonOptions()) -> NewtonResult:
    """Solve ``f_int(u) = f_ext`` on the free DOFs from the start ``u0`` (n_nodes, 3).

    Fixed DOFs keep their values from ``u0``. ``f_ext`` is the (n_dof,) external load [N].
    """
    if options.reference_loop:
        return _reference_newton(system, u0, f_ext, spring_rest, options)
    free = system.free
    u = u0.copy().ravel()
    size = getattr(system, "size", None) or float(np.max(np.ptp(system.model.mesh.nodes, axis=0)))
    f_free = f_ext[free]
    problem = _LoadControl(u, free, f_free, *_operations(system, spring_rest,
                                                         options.linear_solver))
    out = iterate(problem, max_iter=options.max_iter, atol=options.atol, rtol=options.rtol,
                  size=size, criterion=options.criterion, max_step=system.max_step,
                  keep_best=u.copy, at_round_off=residual_at_round_off(system, free))
    res_norms, cor_norms = out.residual_norms, out.correction_norms
    if out.reason == "round-off":                  # the best iterate, at round-off level
        return _newton_result(out.best[2], True, out.iterations, res_norms, cor_norms,
                              out.message, out.point)
    if out.success:
        return _newton_result(u, True, out.iterations, res_norms, cor_norms,
                              out.message, out.point)
    if out.reason != "max_iter":
        return _newton_result(u0, False, out.iterations, res_norms, cor_norms, out.message)
    stall = options.stall_rtol * math.sqrt(f_free.dot(f_free))
    best_rn, best_ev, best_u = out.best or (math.inf, None, None)
    if best_rn <= stall:
        return _newton_result(best_u, True, options.max_iter, res_norms, cor_norms,
                              f"converged (residual stalled at {best_rn:.3g} N, at most "
                              f"{options.stall_rtol:g} of the load)", best_ev, stalled=True)
    return _newton_result(u0, False, options.max_iter, res_norms, cor_norms, out.message)


class _LoadControl:
    """Newton's problem of load control for :func:`~simulator.solvers.nonlinear.iterate`:
    residual ``f_ext - f_int`` on the free DOFs, correction by the tangent.

    ``evaluate``, ``correct`` and ``apply`` are closures over the arrays (set per instance:
    no attribute look-ups per iteration on the hot path of small models)."""

    def __init__(self, u, free, f_free, evaluate, correct):
        self.u = u
        shaped = u.reshape(-1, 3)                       # a view: follows the updates of u

        def residual():
            ev = evaluate(shaped)
            return f_free - ev.f_int[free], ev

        def apply(du, scale):
            u[free] += du
        self.evaluate, self.correct, self.apply = residual, correct, apply


_SINGULAR = "tangent stiffness is singular (mechanism or unsupported body?)"


def _reference_newton(system, u0, f_ext, spring_rest, options):
    """The reference's Newton loop (theory 6.4 and 6.5; see ``NewtonOptions.reference_loop``):
    :func:`~simulator.solvers.nonlinear.iterate` with ``reference_loop``, on the system's own
    ``evaluate`` and the ladder's solve; an unconverged end is accepted with a warning."""
    free = system.free
    backend = options.linear_solver
    problem = _LoadControl(
        u0.copy().ravel(), free, f_ext[free], lambda u: system.evaluate(u, spring_rest),
        lambda ev, r: _or_singular(linear_solve(_tangent(ev), r, backend=backend)))
    out = iterate(problem, max_iter=options.max_iter, atol=options.atol, rtol=options.rtol,
                  size=0.0, criterion=options.criterion, reference_loop=True)
    if out.reason in ("no correction", "not finite"):
        return _newton_result(u0, False, out.iterations, out.residual_norms,
                              out.correction_norms, out.message)
    if not out.success:
        logger.warning(out.message)
    return _newton_result(problem.u, True, out.iterations, out.residual_norms,
                          out.correction_norms, out.message, out.point)


def _or_singular(du):
    """A correction, or :data:`_SINGULAR` for a singular tangent (the protocol of iterate)."""
    return _SINGULAR if du is None else du


def _operations(system, spring_rest, backend="auto"):
    """``evaluate(u)`` and ``correct(ev, r)`` for a system: an EquilibriumSystem's prepared
    evaluator and, for the dense tangents of its fused kernel, its sparse / dense solve
    (:meth:`~simulator.mechanics.equilibrium.EquilibriumSystem.solve_dense_tangent`); else
    ``evaluate`` and the ladder's :func:`~simulator.linalg.ladder.solve` (any object with the
    ``evaluate`` interface). A forced sparse ``backend`` solves the CSR form of a dense
    tangent. ``correct`` returns the correction, or :data:`_SINGULAR` when the tangent is
    singular (the protocol of :func:`~simulator.solvers.nonlinear.iterate`)."""
    evaluator = getattr(system, "evaluator", None)
    evaluate = evaluator(spring_rest) if evaluator is not None else \
        (lambda u: system.evaluate(u, spring_rest))
    dense = getattr(system, "solve_dense_tangent", None)
    sparse_only = backend in ("pardiso", "superlu")
    if dense is not None and not sparse_only:
        def correct(ev, r):                    # (the loop of small models: kept short)
            K = ev.tangent if type(ev) is SystemValues else _tangent(ev)
            du = dense(ev, r) if isinstance(K, np.ndarray) else linear_solve(K, r,
                                                                              backend=backend)
            return _SINGULAR if du is None else du
    else:
        def correct(ev, r):
            K = _tangent(ev)
            if sparse_only and isinstance(K, np.ndarray):
                K = ev.K
            du = linear_solve(K, r, backend=backend)
            return _SINGULAR if du is None else du
    return evaluate, correct


def _newton_result(u, converged, iterations, res, cor, message, ev=None, stalled=False):
    return NewtonResult(u=np.asarray(u).reshape(-1, 3).copy(), success=converged,
                        iterations=iterations, residual_norms=np.array(res),
                        correction_norms=np.array(cor), message=message, evaluation=ev,
                        stalled=stalled)


#: Largest departure of an increment's displacement from the path's direction so far, relative
#: to the larger of the two (:func:`follow_path` halves increments that turn more).
TURN_TOLERANCE = 0.5


def _turns(u_new, u_old, slope, dt) -> bool:
    """True if the increment ``u_new - u_old`` departs from ``slope * dt`` by more than
    :data:`TURN_TOLERANCE` of the larger of the two."""
    # np.linalg.norm of an array is sqrt(v . v) of its flattened v, written out (the same
    # floats; a third of the time: this is asked of every accepted state)
    du, pred = (u_new - u_old).ravel(), (slope * dt).ravel()
    off = du - pred
    scale = max(math.sqrt(du.dot(du)), math.sqrt(pred.dot(pred)))
    return scale > 0 and math.sqrt(off.dot(off)) > TURN_TOLERANCE * scale


def follow_path(system: EquilibriumSystem, u0: np.ndarray, f_start: np.ndarray, f_end: np.ndarray,
                rest_start: np.ndarray, rest_end: np.ndarray, increments: int,
                options: NewtonOptions = NewtonOptions(), callback=None,
                locate_tol: float = LOCATE_TOL, previous=None) -> PathResult:
    """Follow ``f(t) = f_start + t (f_end - f_start)``, ``rest(t)`` likewise, for t in [0, 1].

    The path is split into ``increments`` equal increments. A failed increment is halved
    (up to ``options.max_cuts`` times in a row); after two successes in a row, the last in at
    most :data:`~simulator.solvers.nonlinear.GROWTH_ITERATIONS` of ``options.max_iter``
    corrections, the increment doubles again up to its nominal size. ``callback(t, u)``, if
    given, is called after every accepted increment and may return True to stop early (status
    "stopped").

    Every converged increment is checked for stability (``options.stability``,
    :func:`~simulator.solvers.branches.judge`). Where the equilibrium turns unstable at a
    bifurcation the increment is halved until it is at most ``locate_tol`` (in t; the callers
    whose t spans only part of a step scale it so that it is :data:`LOCATE_TOL` of the step),
    and the state is left for a stable branch there, so that the branch taken does not depend
    on the increments.

    An increment whose converged state turns away from the path's direction so far (the
    secant of the last accepted increment; ``previous = (dt, u)``: the state ``u`` a length
    ``dt`` of path parameter before ``u0``, for the first) by more than
    :data:`TURN_TOLERANCE` is halved in the same way: near a bifurcation that the states on
    either side of it both pass as stable, Newton may otherwise jump to whichever branch its
    increment reaches.
    """
    integer("increments", increments)
    u, history, residuals, last_ev = u0.copy(), [], [], None
    stability, switches, judged, t_now = [], [], [None], [0.0]
    jumped = [False]               # the attempt being accepted switched branch
    below = [False]                # the last attempt was refused: not physical (theory 6.11)
    soft_memo = [None, None]       # (t, soft_mode) of the last accepted state
    check = options.stability != "off"
    # the path's direction so far, (u1 - u0) / dt over the last accepted increment (or
    # ``previous``): kept as (u1, u0, dt) until asked for (direction()), as most are not
    slope = [None if not check or previous is None or previous[0] <= 0 else
             (u0, previous[1], previous[0])]
    # (located no finer than the cuts allow: march gives up after max_cuts halvings in a row)
    tol = max(locate_tol, 0.5 ** (options.max_cuts - 1) / increments)
    total_iter = 0
    ends = (f_start, f_end, rest_start, rest_end)

    def attempt(t_try):
        nonlocal total_iter
        res = newton(system, u, f_start + t_try * (f_end - f_start),
                     rest_start + t_try * (rest_end - rest_start), options)
        total_iter += res.iterations
        last = stability[-1] if stability else None
        judged[:] = [None]
        jumped[0] = False
        if res.success and check and res.evaluation is not None:
            prev = stability[-1] if stability else None
            locate = (prev is None or prev.stable) and t_try - t_now[0] > tol * (1 + 1e-9)
            n_switches = len(switches)
            res, judged[0] = judge(system, res, t_try, ends, options, switches, locate)
            if len(switches) > n_switches:
                jumped[0] = True                        # a switch: no direction to keep
            elif res.success and judged[0].stable and slope[0] is not None and \
                    _turns(res.u, u, direction(), t_try - t_now[0]) and \
                    (soft := _soft(t_now[0])) is not None:
                if t_try - t_now[0] > tol * (1 + 1e-9):
                    res = replace(res, success=False, message=(
                        "the path turned sharply within the increment (a bifurcation "
                        "passed): halving it"))
                elif options.stability == "switch":
                    # located: Newton crossed the bifurcation by itself, to the branch its
                    # round-off favoured; take the one the critical mode's choice gives
                    res, judged[0] = leave_turn(system, res, u, soft, t_try, ends, options,
                                                switches)
                    jumped[0] = True
        elif (not res.success and options.stability == "switch" and last is not None
                and last.negative == 0 and last.mode is not None):
            # the last state is critical (a singular tangent: Cholesky failed, no negative
            # eigenvalue), e.g. exactly at a bifurcation: leave it along its critical mode
            res = leave_critical(system, res, u, last, t_try, ends, options, switches)
            if res.success:
                jumped[0] = True
                judged[0] = quick_stability(_tangent(res.evaluation), options.linear_solver)
        why = substrate_refusal(system, res.u) if res.success else ""
        if res.success and not why:
            r0, r1 = (rest_start + t * (rest_end - rest_start) for t in (t_now[0], t_try))
            why = wrap_refusal(system, u, r0, res.u, r1)
        below[0] = bool(why)
        if why:
            # a node passed through the substrate (a crease node, or a step longer than the
            # contact distance), or a spring the law's wrap point: refused, so that the
            # increment is halved (theory 6.11)
            logger.debug("path parameter %.6g refused: %s", t_try, why)
            res = replace(res, success=False, message=f"{why}: halving it")
        return res.success, res

    def _soft(t0):
        """The softest mode of the last accepted state if a bifurcation lies ahead of it
        (:func:`~simulator.solvers.branches.soft_mode`), computed once per state."""
        if soft_memo[0] != t0:
            soft_memo[:] = [t0, soft_mode(system, u, last_ev, t0, ends, options, direction())]
        return soft_memo[1]

    def direction():
        """The path's direction (n_nodes, 3) [m per unit t], or None."""
        if type(slope[0]) is tuple:
            u1, u0_, dt = slope[0]
            slope[0] = (u1 - np.asarray(u0_, float).reshape(-1, 3)) / dt
        return slope[0]

    def accept(t, res):
        nonlocal u, last_ev
        if jumped[0]:
            slope[0] = None
        elif check and t > t_now[0]:
            slope[0] = (res.u, u, t - t_now[0])
        jumped[0] = False
        t_now[0] = t
        st = judged[0]
        if st is not None and not st.stable and options.stability == "check" and (
                not stability or stability[-1] is None or stability[-1].stable):
            switches.append(BranchSwitch(t, st, u_from=res.u))            # stability lost
        u, last_ev = res.u, res.evaluation
        history.append((t, u, res.iterations))
        residuals.append(res.residual_norms)
        stability.append(st)
        return callback is not None and callback(t, u)
    # an easy success: few corrections, or the stall rule's (its count, max_iter, says that the
    # residual has a floor, not that the increment was hard: growing after it costs no failures)
    easy = GROWTH_ITERATIONS * options.max_iter
    run = march(attempt, accept, increments, options.max_cuts, options.max_total_cuts,
                grow=lambda res: res.iterations <= easy or res.stalled)
    extra = {"stability": stability, "switches": switches}
    if run.status == "failed":
        msg = (f"gave up at t = {run.t:.6g} after {run.in_row} step cuts in a row, "
               f"{run.cuts} in all (increment {run.dt:.3g}): {run.failure.message}")
        if below[0]:
            msg += ("; every shorter increment ends in such a state too, which the model does "
                    "not prevent: the step cannot go on")
        elif check:
            msg += gave_up_at(system, u, last_ev, run.t, ends, options)
        logger.info(msg)          # data: the caller decides (a step fails, a search moves on)
        return PathResult(False, "failed", msg, u, run.t, total_iter, run.cuts, history,
                          residuals, last_ev, **extra)
    if run.status == "stopped":
        return PathResult(False, "stopped", f"stopped by callback at t = {run.t:.6g}", u, run.t,
                          total_iter, run.cuts, history, residuals, last_ev, **extra)
    return PathResult(True, "converged", "converged", u, 1.0, total_iter, run.cuts, history,
                      residuals, last_ev, **extra)

