"""Evaluate a list of points ``(problem, x)`` for a sweep table: the one loop of look-up, map,
append and lost evaluations that the residual-fold and uncertainty sweeps share.

An optimiser's run goes through :class:`~design.core.evaluation_log.EvaluationRun` instead: it
accepts any ``executor.map(fn, items) -> list`` and logs in the order of its run.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping

import numpy as np

from ._executor_base import SerialExecutor, TaskFailure
from .evaluation_log import EvaluationLog, design_key, settings_hash
from .problem import Evaluation

__all__ = ["evaluate_points", "lost_evaluation", "design_list"]

logger = logging.getLogger(__name__)


def design_list(space, designs) -> list:
    """Designs as ``{name: value}`` dicts (validated): ``None`` (the start design), a mapping,
    a vector, or a sequence of mappings or vectors."""
    if designs is None:
        return [space.to_mapping(space.start)]
    if isinstance(designs, Mapping):
        return [space.to_mapping(designs)]
    items = list(designs)
    if items and all(isinstance(v, (int, float, np.floating, np.integer)) for v in items):
        return [space.to_mapping(items)]
    return [space.to_mapping(d) for d in items]


def lost_evaluation(problem, x, reason: str) -> Evaluation:
    """A failed evaluation of a point whose task never returned (its worker died)."""
    return Evaluation(problem.space.to_mapping(x), math.inf, success=False, status="failed",
                      message=f"not evaluated: {reason}")


def _evaluate_point(task):
    """Worker task (top level, picklable): ``(problem, x) -> Evaluation``."""
    problem, x = task
    return problem.evaluate(x)


def evaluate_points(points, executor=None, progress=None, log=None) -> list:
    """The evaluations of ``points``, a sequence of ``(problem, x)``, in order.

    Points of the same problem settings and design key are computed once. With ``log`` (an
    evaluation log CSV, :class:`~design.core.evaluation_log.EvaluationLog`; one settings hash
    per problem) the logged points are read back and each new one is appended as soon as it
    finishes, in this process, whatever the executor: an interrupted sweep resumes where it
    stopped. A point whose task never returned (its worker died more often than the executor
    retries it) becomes a failed evaluation (:func:`lost_evaluation`), not logged, so that
    the same command tries it again.

    Parameters
    ----------
    points : sequence of (problem, x)
        ``x`` a mapping or a vector of ``problem.space``.
    executor : Executor, optional
        Default serial; not closed here.
    progress : callable, optional
        ``progress(done, total)`` over the points computed (not those read back).
    log : str or os.PathLike, optional

    Returns
    -------
    list of Evaluation
    """
    points = list(points)
    hashes = [settings_hash(problem.settings()) for problem, _ in points]
    keys = [(h, design_key(p.space, x)) for h, (p, x) in zip(hashes, points)]
    books = {} if log is None else {h: EvaluationLog(log, points[hashes.index(h)][0])
                                    for h in dict.fromkeys(hashes)}
    found = {}
    for key, (_, x) in zip(keys, points):
        if key not in found:
            found[key] = None if log is None else books[key[0]].lookup(x)
    todo = [k for k, ev in found.items() if ev is None]
    first = {k: points[keys.index(k)] for k in todo}

    def finished(j, ev):                  # in this process, as each point completes
        key = todo[j]
        problem, x = first[key]
        if isinstance(ev, TaskFailure):   # not logged: the same command tries it again
            found[key] = lost_evaluation(problem, x, ev.reason)
            return
        found[key] = ev
        if log is not None:               # reopened when several problems share the file:
            book = books[key[0]]          # another one's rows may have added columns
            (book if len(books) == 1 else EvaluationLog(log, problem)).append(ev)

    logger.info("%d points: %d distinct to compute on %r (%d logged)", len(points), len(todo),
                executor, len(found) - len(todo))
    (executor or SerialExecutor()).map(_evaluate_point, [first[k] for k in todo], progress,
                                       on_result=finished, failures="return")
    return [found[k] for k in keys]
