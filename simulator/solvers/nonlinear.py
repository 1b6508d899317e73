"""One Newton iteration and one cut-and-retry driver for every nonlinear solve of the package.

:func:`iterate` is Newton's method on a problem that supplies its residual, its correction
(the solve with its tangent; for arc length the bordered system with its constraint row) and
its update; the stopping tests (residual or correction criterion, the round-off floor
:data:`ROUND_OFF`), the step limit (``max_step``: no node moves farther in one correction,
so contact cannot be jumped through) and the bookkeeping live here once. Load control
(:func:`~simulator.solvers.newton.newton`), the arc-length and displacement-control corrector
(:func:`~simulator.solvers.load_path.correct_point`) and the implicit dynamic step
(:class:`~simulator.solvers.generalized_alpha.TimeIntegrator`) use it.

:func:`march` drives a path parameter ``t`` from 0 to 1 in equal increments, halving an
increment that fails (at most ``max_cuts`` times in a row and ``max_total_cuts`` in all) and
doubling it back towards its nominal size after an uncut success that converged easily (its
``grow`` says so: for load control, in at most :data:`GROWTH_ITERATIONS` of ``max_iter``
corrections): load control
(:func:`~simulator.solvers.newton.follow_path`) and displacement control
(:func:`~simulator.solvers.displacement_control.displacement_control`) use it. :func:`bisect` is its
form for a span that must be covered as given (a time step of a fixed output grid): a failed
span is split into two halves, each split again on failure, to a bounded depth; the dynamic
step (:meth:`~simulator.solvers.generalized_alpha.TimeIntegrator.step`) uses it.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["ROUND_OFF", "STALL_PATIENCE", "ROUND_OFF_ULPS", "residual_at_round_off", "END_TOL",
           "GROWTH_ITERATIONS", "GROWTH_PATIENCE", "Iteration", "iterate", "limit_step", "March",
           "march", "bisect"]

logger = logging.getLogger(__name__)

#: A correction whose largest entry is at most this fraction of the model size [m/m] is at
#: round-off level: the iteration has converged whatever its criterion says.
ROUND_OFF = 1e-13
#: Corrections without a new lowest residual after which :func:`iterate` asks its
#: ``at_round_off`` whether the lowest one is at the round-off level of the residual (so a
#: converging iteration is never cut short, and one that converges to its tolerance never pays
#: for the test).
STALL_PATIENCE = 3
#: A path parameter within this of 1 has reached the end of the path.
END_TOL = 1e-12
#: An accepted increment lets the next one double (:func:`march`) only if its Newton solve took
#: at most this fraction of ``max_iter`` corrections. One that needed more sits near the
#: increment Newton can manage, and its double fails: measured on a heated flat Miura sheet (12
#: x 12 cells at 1 mW per crease), accepted increments of 20 to 30 corrections were followed by
#: doubles that all failed after the full 30 (210 of its 899 corrections), while those of at
#: most 14 doubled successfully.
GROWTH_ITERATIONS = 0.5
#: Successes in a row at one increment after which :func:`march` doubles it even if none came
#: easily (so a path of hard increments cannot crawl: one with Newton's stall rule accepting
#: every increment of a snap, with ``max_iter`` corrections each, otherwise never grew back).
GROWTH_PATIENCE = 4
#: What ``ndarray.max()`` / ``min()`` call, without their Python wrappers (two calls fewer per
#: iteration on small models; the same values).
_max, _min = np.maximum.reduce, np.minimum.reduce


def limit_step(dx: np.ndarray, max_step: float | None) -> tuple[float, float]:
    """Scale ``dx`` in place so that no entry exceeds ``max_step`` [m] in magnitude (None: no
    limit); ``(factor applied, max |dx| after it)``, the factor 1.0 when not exceeded."""
    step = max(dx.max(), -dx.min()) if dx.size else 0.0       # = max |dx|
    if max_step is None or step <= max_step:
        return 1.0, step
    scale = max_step / step
    dx *= scale
    return scale, max(dx.max(), -dx.min())


#: Node positions carry a rounding error of about one ulp (``x = nodes + u``), which the internal
#: force turns into up to ``|K| eps |x|``; a residual within this many times that bound at every
#: free DOF is at its round-off level (:func:`residual_at_round_off`; measured on the
#: flat-folder Kirby pattern at 10 mm with 200 um creases, whose Newton residual stalls at
#: 1e-9 N: at most 2.1 times the bound over 12 corrections, 0.3 to 2.1 at its largest entry).
ROUND_OFF_ULPS = 4.0


def residual_at_round_off(system, free):
    """``at_round_off(point, r, u) -> bool`` for :func:`iterate`: whether the free-DOF residual
    ``r`` at ``point`` (a SystemValues or a PathPoint, with its tangent) is at the round-off
    level of the internal force, ``|r_i| <= ROUND_OFF_ULPS eps (|K| |x|)_i`` at every free DOF
    i (``free``: their indices), ``x = nodes + u`` with the flat displacements ``u`` (n_dof,)
    of that point, ``K`` the tangent: a componentwise backward error of a few ulps in the node positions.

    No correction can do better, and near a critical state (soft out-of-plane modes of a large
    sheet against stiff short bars: Kirby at 10 mm, lowest eigenvalue 1e-5 N/m against
    6e10 N/m) the corrections of that noise only wander along the soft modes: ``atol``
    (1e-13 N) lies under this level there (1e-9 N for Kirby), and Newton would fail every
    increment. The bound is loose where stiff bars dominate (their strains are computed from
    the displacements, not the positions), so :func:`iterate` asks it only of an iteration
    that has stopped improving. None for a system without a mesh (only the tolerances
    apply)."""
    mesh = getattr(getattr(system, "model", None), "mesh", None)
    if getattr(mesh, "nodes", None) is None:
        return None

    def at_round_off(point, r, u):                 # (built per solve, called rarely: lazy)
        K = getattr(point, "tangent", None)              # a SystemValues', as assembled
        K = getattr(point, "K", None) if K is None else K  # a PathPoint's
        if K is None:
            return False
        x = np.abs(np.asarray(mesh.nodes, float).ravel()[free] + u[free])
        limit = ROUND_OFF_ULPS * np.finfo(float).eps
        bound = (np.abs(K) @ x) if isinstance(K, np.ndarray) else abs(K) @ x
        return bool(np.all(np.abs(r) <= limit * bound))
    return at_round_off


@dataclass
class Iteration:
    """Outcome of :func:`iterate`.

    Attributes
    ----------
    success : bool
    iterations : int
        Corrections applied (the evaluation index at which it stopped).
    residual_norms, correction_norms : lists of 2-norms [N], [m]
    message : str
        "converged", "converged (correction at round-off level)", "converged (residual ... N
        at its round-off level)" or why it failed.
    point : the problem's point (from ``evaluate``) at the final iterate
    reason : str
        "converged", "round-off" (converged: the best iterate's residual at its round-off
        level, ``at_round_off``), "not finite" (a residual), "no correction" (``correct`` said
        why) or "max_iter" (no convergence in ``max_iter`` corrections).
    best : tuple or None
        With ``keep_best`` and reason "max_iter" or "round-off": ``(rn, point, state)`` of the
        evaluation with the smallest residual norm (the first of equals), ``state`` what
        ``keep_best`` returned there; else None. Reason "round-off" (a success): that
        evaluation's residual is at its round-off level (``at_round_off``); the caller takes
        ``state`` as the solution.
    """

    success: bool
    iterations: int
    residual_norms: list = field(default_factory=list)
    correction_norms: list = field(default_factory=list)
    message: str = ""
    point: object = None
    reason: str = "converged"
    best: tuple | None = None


def iterate(problem, *, max_iter: int, atol: float, rtol: float, size: float,
            criterion: str = "residual", max_step: float | None = None,
            tolerance=None, keep_best=None, record_final: bool = False,
            reference_loop: bool = False, at_round_off=None) -> Iteration:
    """Newton's method on ``problem`` from its current iterate.

    Parameters
    ----------
    problem : object with
        ``evaluate() -> (r, point)``: the residual (n,) [N] at the current iterate and whatever
        the problem keeps of that evaluation; ``correct(point, r) -> dx``: the correction
        (n,) [m], or a str saying why there is none (a singular tangent); ``apply(dx, scale)``:
        add ``dx`` (already limited) to the iterate, ``scale`` being the factor the step limit
        applied to it (for unknowns outside ``dx``, such as a load factor).
    max_iter : int
        Corrections at most.
    atol, rtol : float
        The criterion's tolerance is ``max(atol, rtol * reference)``.
    size : float
        Model size [m] for the round-off floor (:data:`ROUND_OFF`).
    criterion : {"residual", "displacement"}
        Stop on the residual norm (reference: the first one) or on the correction norm
        (reference: the first correction).
    max_step : float, optional
        Largest entry of a correction [m] (:func:`limit_step`).
    tolerance : callable, optional
        ``tolerance(point, first_residual_norm) -> float``: the residual tolerance instead of
        ``max(atol, rtol * first)`` (dynamics scales it by the step's force norms).
    keep_best : callable, optional
        ``keep_best() -> state``: a copy of the problem's current iterate, taken at every
        evaluation whose residual norm is below all before it (e.g. the bound ``u.copy`` of
        the unknowns: no Python call per iteration); the best one is returned in
        ``Iteration.best`` when the iteration runs out of corrections (a stall rule).
    record_final : bool
        Record the residual norm of the evaluation that follows a correction-based stop.
    reference_loop : bool
        The reference's loop instead (theory 6.4, :func:`_reference_iterate`): only
        ``max_iter``, ``atol``, ``criterion`` apply.
    at_round_off : callable, optional
        With ``keep_best`` (whose state must be the flat displacements, or a tuple starting
        with them): ``at_round_off(point, r, u) -> bool``, whether the residual ``r`` at
        ``point`` (displacements ``u``) is at the round-off level of its evaluation (no
        correction can lower it: :func:`residual_at_round_off`). Asked (once per best iterate,
        residual criterion) when :data:`STALL_PATIENCE` corrections have not lowered the
        lowest residual: where it is, the iteration stops with success, reason "round-off"
        and that iterate in ``best``.
    """
    if reference_loop:
        return _reference_iterate(problem, max_iter, atol, criterion)
    res, cor, ref, best = [], [], None, None
    best_rn, best_it, best_r = math.inf, 0, None
    evaluate, correct, apply = problem.evaluate, problem.correct, problem.apply
    by_residual, by_correction = criterion == "residual", criterion == "displacement"
    floor = ROUND_OFF * size
    for it in range(max_iter + 1):
        r, point = evaluate()
        rn = math.sqrt(r.dot(r))                       # = np.linalg.norm(r), less overhead
        res.append(rn)
        if keep_best is not None and rn < best_rn:
            best_rn, best, best_it, best_r = rn, (rn, point, keep_best()), it, r
        if not math.isfinite(rn):
            return Iteration(False, it, res, cor, "residual is not finite", point, "not finite")
        if by_residual:
            if ref is None:
                ref = rn
                tol = max(atol, rtol * ref)               # fixed by the first residual
            if rn <= (tol if tolerance is None else tolerance(point, ref)):
                return Iteration(True, it, res, cor, "converged", point)
            if at_round_off is not None and it - best_it == STALL_PATIENCE and \
                    at_round_off(best[1], best_r, _displacements(best[2])):
                return Iteration(True, it, res, cor, f"converged (residual {best_rn:.3g} N at "
                                 "its round-off level)", best[1], "round-off", best)
        if it == max_iter:
            break
        dx = correct(point, r)
        if isinstance(dx, str):
            return Iteration(False, it, res, cor, dx, point, "no correction")
        step = max(_max(dx), -_min(dx)) if dx.size else 0.0       # = max |dx|
        scale = 1.0
        if max_step is not None and step > max_step:
            scale, step = limit_step(dx, max_step)
        apply(dx, scale)
        dn = math.sqrt(dx.dot(dx))
        cor.append(dn)
        message = None
        if by_correction:
            ref = dn if ref is None else ref
            if dn <= max(atol, rtol * ref):
                message = "converged"
        if message is None and dx.size and step <= floor:
            message = "converged (correction at round-off level)"
        if message is not None:
            r, point = evaluate()
            if record_final:
                res.append(math.sqrt(r.dot(r)))
            return Iteration(True, it + 1, res, cor, message, point)
    return Iteration(False, max_iter, res, cor, f"no convergence in {max_iter} iterations "
                     f"(last residual {res[-1]:.3g} N)", point, "max_iter", best)


def _displacements(state):
    """The flat displacements of a ``keep_best`` state (the array, or a tuple's first entry)."""
    return state[0] if isinstance(state, tuple) else state


def _reference_iterate(problem, max_iter: int, atol: float, criterion: str) -> Iteration:
    """The reference's Newton loop: the measure (residual or correction norm, as
    ``criterion`` says) is taken before each update is applied, so one more update always
    follows the one that meets ``atol``; at most ``max_iter - 1`` updates; the final iterate
    is evaluated. Ends "max_iter" (not a success: the caller decides) when out of updates."""
    res, cor, measure, updates = [], [], math.inf, 0
    while updates < max_iter - 1 and measure > atol:
        r, point = problem.evaluate()
        dx = problem.correct(point, r)
        if isinstance(dx, str):
            return Iteration(False, updates, res, cor, dx, point, "no correction")
        problem.apply(dx, 1.0)
        updates += 1
        res.append(math.sqrt(r.dot(r)))
        cor.append(math.sqrt(dx.dot(dx)))
        measure = res[-1] if criterion == "residual" else cor[-1]
        if not math.isfinite(measure):
            return Iteration(False, updates, res, cor, "residual is not finite", point,
                             "not finite")
    _, point = problem.evaluate()
    if measure <= atol:
        return Iteration(True, updates, res, cor, f"reference loop: {updates} updates", point)
    return Iteration(False, updates, res, cor, f"reference loop: accepted unconverged after "
                     f"{updates} updates ({criterion} {measure:.3g} > {atol:.3g})", point,
                     "max_iter")


@dataclass
class March:
    """Outcome of :func:`march`: ``status`` "converged", "failed" (the last failed attempt's
    outcome in ``failure``) or "stopped"; the parameter ``t`` reached, the increment ``dt``
    in force, the cuts in a row at the end and in all."""

    status: str
    t: float
    dt: float
    in_row: int
    cuts: int
    failure: object = None


def march(attempt, accept, increments: int, max_cuts: int, max_total_cuts: int,
          what: str = "increment", grow=None) -> March:
    """Drive ``t`` from 0 to 1 in ``increments`` equal increments with step cutting.

    ``attempt(t_try) -> (ok, outcome)`` tries the increment to ``t_try`` from the last
    accepted point; ``accept(t_try, outcome) -> bool`` takes a successful one (True stops the
    march, status "stopped"). A failed increment is halved, at most ``max_cuts`` times in a
    row and ``max_total_cuts`` times in all (then status "failed"); after an uncut success
    (two successes in a row) the increment doubles again, up to its nominal
    ``1 / increments``, if ``grow(outcome)`` (None: always) says that success came easily
    (e.g. in few Newton corrections, :data:`GROWTH_ITERATIONS`): a double of an increment that
    barely converged mostly fails, and a failed attempt costs the full ``max_iter``. After
    :data:`GROWTH_PATIENCE` successes at one increment it doubles whatever ``grow`` says (a
    path whose every increment is hard, such as one accepted by Newton's stall rule near a
    limit point, still gets back to its nominal increment, at a quarter of the rate). Growth
    only decides how soon the increment returns to its nominal size; failures are halved as
    before, so the points where a path is located by halving are not coarser.
    """
    nominal = 1.0 / increments
    t, dt, in_row, cuts = 0.0, nominal, 0, 0
    held = 0                    # successes since the increment last changed
    while t < 1.0 - END_TOL:
        t_try = min(1.0, t + dt)
        ok, outcome = attempt(t_try)
        if not ok:
            if in_row >= max_cuts or cuts >= max_total_cuts:
                return March("failed", t, dt, in_row, cuts, outcome)
            dt, in_row, cuts, held = dt / 2, in_row + 1, cuts + 1, 0
            logger.info("%s to t = %.6g failed; halving to %.3g", what, t_try, dt)
            continue
        t = t_try
        stop = accept(t, outcome)
        held += 1
        if in_row == 0 and dt < nominal and (grow is None or held >= GROWTH_PATIENCE
                                             or grow(outcome)):
            dt, held = min(nominal, 2 * dt), 0
        in_row = 0
        if stop:
            return March("stopped", t, dt, in_row, cuts)
    return March("converged", 1.0, dt, in_row, cuts)


def bisect(attempt, halves, join, start, span, depth: int):
    """Cover ``span`` from ``start``, halving a failed span recursively (``depth`` levels).

    ``attempt(start, span) -> report`` (with ``success`` and, if it succeeded, the end
    ``state``); ``halves(start, span) -> (first, second)`` the two half spans;
    ``join(first, second) -> report`` the report of a split span from its halves' reports
    (``second`` None when the first half failed). The report of ``span``.
    """
    report = attempt(start, span)
    if report.success or depth == 0:
        return report
    first_span, second_span = halves(start, span)
    first = bisect(attempt, halves, join, start, first_span, depth - 1)
    if not first.success:
        return join(first, None)
    second = bisect(attempt, halves, join, first.state, second_span, depth - 1)
    return join(first, second)
