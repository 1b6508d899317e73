"""The coordinate-descent back end of :func:`design.core.optimize.optimize` (private): the paper's
fixed-step search on the lattice ``x0 + k step`` (see :mod:`design.core.optimize`)."""

from __future__ import annotations

import numpy as np

from simulator._validate import integer

from .evaluation_log import BudgetExhausted, EvaluationRun, StopOptimization


def _x_columns(space, x) -> dict:
    return {f"x.{v.name} [{v.unit}]": float(u) for v, u in zip(space.variables, x)}


def coordinate_descent(run: EvaluationRun, x0, max_evaluations=None, max_cycles=15,
                        parallel_candidates=False, metric=None):
    """Coordinate descent from ``x0``; returns ``(status, message, cycles)`` (``cycles``: one
    row per cycle, row 0 the start; with a ``metric``, default the problem's
    :attr:`~design.core.problem.DesignProblem.report_metric`, its value at the last candidate
    and at the current design). The budget ``max_evaluations`` is enforced by ``run``."""
    space = run.space
    metric = metric or getattr(run.logged.problem, "report_metric", None)
    integer("max_cycles", max_cycles)
    tol = 1e-9 * (space.upper - space.lower)
    k = np.zeros(len(space), dtype=int)

    def point(kk):
        return np.clip(x0 + kk * space.step, space.lower, space.upper)

    def inside(kk, i):
        v = x0[i] + kk[i] * space.step[i]
        return space.lower[i] - tol[i] <= v <= space.upper[i] + tol[i]

    def row(cycle, moved, last, complete=True):
        m = lambda e: np.nan if e is None else e.metrics.get(metric, np.nan)
        reported = {} if metric is None else {f"last_candidate.{metric}": m(last),
                                              f"current.{metric}": m(current)}
        return {"cycle": cycle, "moved": ";".join(moved), "complete": complete,
                **_x_columns(space, point(k)), "objective": current.objective,
                "feasible": current.feasible, **reported, "n_evaluations": len(run.evaluations)}

    cycles, status = [], "max_cycles"
    try:
        current = run.evaluate(point(k))
    except BudgetExhausted:  # pragma: no cover - budget >= 1 is enforced
        return "max_evaluations", "no evaluation allowed", []
    cycles.append(row(0, [], None))
    for cycle in range(1, max_cycles + 1):
        moved, last = [], None
        try:
            for i, name in enumerate(space.names):
                cands = []
                for d in (-1, 1):
                    kk = k.copy()
                    kk[i] += d
                    if inside(kk, i):
                        cands.append((d, kk))
                if parallel_candidates and len(cands) > 1:
                    run.prefetch([point(c) for _, c in cands])   # side by side, kept aside
                for d, kk in cands:
                    last = run.evaluate(point(kk))
                    if last.feasible and last.objective < current.objective:
                        k, current = kk, last
                        moved.append(f"{name}{'-' if d < 0 else '+'}")
                        break
        except (BudgetExhausted, StopOptimization) as exc:
            cycles.append(row(cycle, moved, last, complete=False))
            if isinstance(exc, StopOptimization):
                return "stopped", f"stopped by the callback in cycle {cycle}: {exc}", cycles
            return "max_evaluations", (f"evaluation budget ({run.budget}) exhausted in "
                                       f"cycle {cycle}"), cycles
        cycles.append(row(cycle, moved, last))
        if not moved:
            status = "converged"
            break
    msg = (f"no coordinate moved in cycle {len(cycles) - 1}" if status == "converged" else
           f"cycle limit ({max_cycles}) reached; the last cycle still moved")
    return status, msg, cycles
