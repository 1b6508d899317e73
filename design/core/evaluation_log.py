"""Append-only CSV log of design evaluations, and a problem wrapper that reuses it.

Every evaluation is appended to the CSV as soon as it finishes (one row, flushed and closed),
so a killed optimisation or sweep loses at most the evaluation in progress; re-running the
same command with the same log reuses the logged evaluations instead of recomputing them.

Rows are keyed by a hash of the problem's settings (``problem.settings()``) and by the design
vector rounded to ``1e-9`` of each variable's range, so one file can hold several problems.
Floats are written with ``repr`` and therefore read back bit-identical: a resumed,
deterministic optimiser follows exactly the path of an uninterrupted run.

Gradients (:meth:`DesignProblem.evaluate_with_gradient`) are logged in one column,
``gradient``: JSON ``{"objective": [...], "constraints": {name: [...]}}``, vectors in the
space's order, floats by ``repr`` (read back bit-identical); ``n (m + 1)`` numbers per row for
``n`` variables and ``m`` constraints. A gradient run reuses a logged design only if its row has
a gradient (or the evaluation failed).

Logging happens in the main process only: :meth:`LoggedProblem.evaluate_many` looks up the
logged designs, maps the others through an executor (whose workers run the wrapped problem's
``evaluate``), then logs the results in order. A :class:`LoggedProblem` refuses to be pickled.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import logging
import math
import os
import time
from datetime import UTC, datetime
from typing import TYPE_CHECKING

import numpy as np

from simulator import ParameterError

from .problem import Evaluation

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["EvaluationLog", "LoggedProblem", "EvaluationRun", "BudgetExhausted",
           "StopOptimization", "settings_hash", "design_key", "parse_cell"]

logger = logging.getLogger(__name__)

#: Relative resolution (of each variable's range) of the design keys.
KEY_RESOLUTION = 1e-9
_FIXED = ["eval", "settings_hash"]
_TAIL = ["objective", "success", "status", "message", "wall_time [s]", "timestamp"]


def settings_hash(settings: dict) -> str:
    """Short SHA-256 hash of a settings dict (JSON with sorted keys)."""
    text = json.dumps(settings, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def design_key(space, x) -> tuple:
    """Integers ``round((x - lower) / (upper - lower) / KEY_RESOLUTION)`` per variable."""
    z = space.normalize(x)
    return tuple(int(v) for v in np.round(z / KEY_RESOLUTION))


def parse_cell(text: str):
    """A CSV cell back to bool / int / float / str (floats round-trip exactly via repr)."""
    if text in ("True", "False"):
        return text == "True"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def _x_column(var) -> str:
    return f"x.{var.name} [{var.unit}]"


class EvaluationLog:
    """CSV log of evaluations of one problem (other problems' rows are kept, not served).

    Parameters
    ----------
    path : str or os.PathLike or None
        CSV file; loaded if it exists, created on the first append. ``None`` keeps the log
        in memory only.
    problem : DesignProblem
        Provides ``space`` (column names, keys) and ``settings()`` (hashed).

    Attributes
    ----------
    hash : str
        Hash of ``problem.settings()``.
    n_loaded : int
        Rows of this problem found in the file at construction.
    """

    def __init__(self, path, problem):
        self.path = None if path is None else os.fspath(path)
        self.space = problem.space
        self.settings = problem.settings()
        self.hash = settings_hash(self.settings)
        self._x_cols = [_x_column(v) for v in self.space.variables]
        self._entries: dict = {}
        self._header: list = []
        self._next = 1
        self.n_loaded = 0
        if self.path is not None and os.path.exists(self.path):
            self._load()

    # ------------------------------------------------------------------ reading
    def _load(self):
        with open(self.path, newline="", encoding="utf-8") as fh:
            text = fh.read()
        try:
            rows = list(csv.reader(io.StringIO(text, newline="")))
        except csv.Error as exc:
            raise ParameterError(f"evaluation log {self.path} is not a readable CSV: {exc}") \
                from exc
        if not rows:
            return
        header, body = rows[0], rows[1:]
        complete = text.endswith("\n")
        good = [r for i, r in enumerate(body)
                if len(r) == len(header) and (complete or i < len(body) - 1)]
        self._header = header
        if len(good) != len(body):
            logger.warning("%s: dropping %d incomplete row(s) (interrupted write)", self.path,
                           len(body) - len(good))
            self._rewrite(header, [dict(zip(header, r)) for r in good])
        for r in good:
            row = dict(zip(header, r))
            try:
                self._next = max(self._next, int(row["eval"]) + 1)
            except (KeyError, ValueError):
                pass
            if row.get("settings_hash") != self.hash or any(c not in row for c in self._x_cols):
                continue
            try:
                ev = self._from_row(row)
            except (KeyError, ValueError) as exc:
                logger.warning("%s: skipping unreadable row %s (%s)", self.path, row.get("eval"),
                               exc)
                continue
            self._entries[design_key(self.space, list(ev.x.values()))] = ev
            self.n_loaded += 1

    def _from_row(self, row: dict) -> Evaluation:
        x = {v.name: float(row[c]) for v, c in zip(self.space.variables, self._x_cols)}
        cons = {k[2:]: float(v) for k, v in row.items() if k.startswith("g.") and v != ""}
        metrics = {k[2:]: parse_cell(v) for k, v in row.items() if k.startswith("m.") and v != ""}
        if "success" in row:
            success, status = row["success"] == "True", row.get("status", "")
        else:                                   # logs written before the result contract
            success, status = row["failed"] != "True", ""
        grad, cgrad = _gradient_from_cell(self.space, row.get("gradient", ""))
        return Evaluation(x, float(row["objective"]), cons, metrics, success=success,
                          status=status, message=row["message"],
                          wall_time=float(row["wall_time [s]"]), objective_gradient=grad,
                          constraint_gradients=cgrad)

    def lookup(self, x) -> Evaluation | None:
        """The logged evaluation of design ``x`` (vector or mapping) for this problem, or None."""
        return self._entries.get(design_key(self.space, x))

    def __len__(self) -> int:
        return len(self._entries)

    # ------------------------------------------------------------------ writing
    def _row(self, index: int, ev: Evaluation) -> dict:
        row = {"eval": index, "settings_hash": self.hash}
        row.update({c: repr(float(ev.x[v.name]))
                    for v, c in zip(self.space.variables, self._x_cols)})
        row["objective"] = repr(float(ev.objective))
        row.update({f"g.{k}": repr(float(v)) for k, v in ev.constraints.items()})
        row.update({f"m.{k}": repr(v) if isinstance(v, float) else "" if v is None else str(v)
                    for k, v in ev.metrics.items()})
        row.update({"success": str(bool(ev.success)), "status": ev.status,
                    "message": ev.message,
                    "wall_time [s]": repr(float(ev.wall_time)),
                    **_gradient_cell(self.space, ev),
                    "timestamp": datetime.now(UTC).isoformat(timespec="seconds")})
        return row

    def _rewrite(self, header, rows):
        tmp = self.path + ".tmp"
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=header, restval="")
            w.writeheader()
            w.writerows(rows)
        os.replace(tmp, self.path)

    def append(self, ev: Evaluation) -> int:
        """Log ``ev`` (flushed at once) and return its eval index."""
        index = self._next
        self._next += 1
        self._entries[design_key(self.space, list(ev.x.values()))] = ev
        if self.path is None:
            return index
        row = self._row(index, ev)
        new = [k for k in row if k not in self._header]
        if not self._header or new:
            self._extend_header(new)
        with open(self.path, "a", newline="", encoding="utf-8") as fh:
            csv.DictWriter(fh, fieldnames=self._header, restval="").writerow(row)
            fh.flush()
        return index

    def _extend_header(self, new):
        """Add columns (constraints or metrics first seen); rewrites the file atomically."""
        d = os.path.dirname(self.path)
        if d:
            os.makedirs(d, exist_ok=True)
        old = list(self._header)
        rows = []
        if old and os.path.exists(self.path):
            with open(self.path, newline="", encoding="utf-8") as fh:
                rows = list(csv.DictReader(fh))
        mid = [c for c in old + new if c not in _FIXED + self._x_cols + _TAIL]
        mid = sorted(mid, key=lambda c: 0 if c.startswith("g.") else 1)
        extra = [c for c in old if c.startswith("x.") and c not in self._x_cols]
        self._header = _FIXED + self._x_cols + extra + [_TAIL[0]] + mid + _TAIL[1:]
        self._rewrite(self._header, rows)
        self._write_settings()

    def _write_settings(self):
        side = os.path.splitext(self.path)[0] + ".settings.json"
        known = {}
        if os.path.exists(side):
            try:
                with open(side, encoding="utf-8") as fh:
                    known = json.load(fh)
            except (OSError, ValueError):
                known = {}
        if self.hash not in known:
            known[self.hash] = self.settings
            with open(side, "w", encoding="utf-8") as fh:
                json.dump(known, fh, indent=1, sort_keys=True, default=repr)


class LoggedProblem:
    """A design problem whose evaluations go through an :class:`EvaluationLog`.

    Same interface as a DesignProblem (``space``, ``evaluate(x)``, ``settings()``); logged
    designs are returned without recomputing. Main-process only (not picklable): evaluations
    may run in workers through :meth:`evaluate_many`, logging stays here.

    Attributes
    ----------
    problem : DesignProblem
    log : EvaluationLog
    n_computed, n_reused : int
        Evaluations computed by the problem / served from the log.
    """

    def __init__(self, problem, log: EvaluationLog | None = None):
        self.problem = problem
        self.log = EvaluationLog(None, problem) if log is None else log
        self.space = problem.space
        self.name = getattr(problem, "name", "problem")
        self.n_computed = 0
        self.n_reused = 0

    def settings(self) -> dict:
        return self.problem.settings()

    def __getstate__(self):
        raise TypeError("LoggedProblem logs in the main process and cannot be pickled; send "
                        "its .problem to workers (LoggedProblem.evaluate_many does this).")

    def evaluate(self, x) -> Evaluation:
        return self.evaluate_sources([x])[0][0]

    @property
    def supplies_gradients(self) -> bool:
        """The wrapped problem supplies gradients (``evaluate_with_gradient``)."""
        return bool(getattr(self.problem, "supplies_gradients", False))

    def evaluate_with_gradient(self, x) -> Evaluation:
        return self.evaluate_sources([x], gradient=True)[0][0]

    def evaluate_many(self, xs, executor=None, gradient: bool = False) -> list:
        """Evaluations of ``xs`` in order: logged ones reused, the others mapped through
        ``executor.map(fn, items) -> list`` (default: serial) and logged in order; with
        ``gradient``, by ``evaluate_with_gradient``."""
        return [ev for ev, _ in self.evaluate_sources(xs, executor, gradient=gradient)]

    def compute(self, xs, executor=None, gradient: bool = False) -> list:
        """Evaluations of ``xs`` by the problem (mapped through ``executor``), neither looked
        up nor logged; :meth:`evaluate_sources` logs them when given them as ``computed``."""
        if not xs:
            return []
        mapper = map if executor is None else executor.map
        return list(mapper(_safe_evaluate(self.problem, gradient),
                           [self.space.to_vector(x) for x in xs]))

    def evaluate_sources(self, xs, executor=None, computed=None, gradient: bool = False) -> list:
        """Like :meth:`evaluate_many`, as ``(evaluation, reused: bool)`` pairs.

        ``computed``: ``{design_key: Evaluation}`` from :meth:`compute`, used (and logged as
        computed) instead of evaluating those designs again. With ``gradient`` a logged
        evaluation without a gradient (of a successful design) is computed again.
        """
        computed = computed or {}
        vecs = [self.space.to_vector(x) for x in xs]
        out: list = [None] * len(vecs)
        todo: dict = {}
        for i, x in enumerate(vecs):
            hit = self.log.lookup(x)
            if hit is not None and gradient and hit.success and hit.objective_gradient is None:
                hit = None
            if hit is not None:
                out[i] = (hit, True)
                self.n_reused += 1
            else:
                todo.setdefault(design_key(self.space, x), []).append(i)
        if todo:
            fresh = iter(self.compute([vecs[idx[0]] for key, idx in todo.items()
                                       if key not in computed], executor, gradient))
            for key, idx in todo.items():
                ev = computed[key] if key in computed else next(fresh)
                self.log.append(ev)
                self.n_computed += 1
                out[idx[0]] = (ev, False)
                for j in idx[1:]:
                    out[j] = (ev, True)
                    self.n_reused += 1
        return out


class BudgetExhausted(Exception):
    """The run's evaluation budget does not allow the next batch."""


class StopOptimization(Exception):
    """Raise from a ``callback`` to stop an optimisation and return its result so far."""


class EvaluationRun:
    """The evaluations of one optimisation run through a :class:`LoggedProblem`.

    Serves repeated designs from an in-run cache (each design is evaluated once per run),
    enforces the budget of distinct designs (``BudgetExhausted`` before a batch that would
    exceed it), records the history in order, logs progress and calls ``callback(evaluation)``
    after each new design (after it has been logged). :meth:`prefetch` computes designs ahead,
    together on the executor, without changing any of this.
    """

    def __init__(self, logged: LoggedProblem, budget, callback, executor, gradient=False):
        self.logged, self.space, self.budget = logged, logged.space, budget
        self.gradient = bool(gradient)
        self.callback, self.executor = callback, executor
        self.cache: dict = {}
        self.prefetched: dict = {}
        self.evaluations: list = []
        self.rows: list = []

    def _keyed(self, xs):
        xs = [np.clip(self.space.to_vector(x), self.space.lower, self.space.upper) for x in xs]
        return xs, [design_key(self.space, x) for x in xs]

    def prefetch(self, xs) -> int:
        """Compute the designs of ``xs`` that the run has neither seen nor logged, together
        through the executor, and keep them aside; returns how many were computed.

        A prefetched design enters the run (history, budget, log, callback) only when
        :meth:`evaluate_many` asks for it, so the run is the one it would be without
        prefetching; one never asked for is dropped. Nothing is computed for fewer than two
        such designs (nothing to run side by side) or beyond the budget.
        """
        xs, keys = self._keyed(xs)
        new = {k: x for k, x in zip(keys, xs) if k not in self.cache
               and k not in self.prefetched and self.logged.log.lookup(x) is None}
        if len(new) < 2 or (self.budget is not None
                            and len(self.evaluations) + len(new) > self.budget):
            return 0
        self.prefetched.update(zip(new, self.logged.compute(list(new.values()), self.executor,
                                                            self.gradient)))
        return len(new)

    def evaluate(self, x) -> Evaluation:
        return self.evaluate_many([x])[0]

    def evaluate_many(self, xs) -> list:
        xs, keys = self._keyed(xs)
        new = list(dict.fromkeys(k for k in keys if k not in self.cache))
        if self.budget is not None and len(self.evaluations) + len(new) > self.budget:
            raise BudgetExhausted
        if new:
            first = {k: xs[keys.index(k)] for k in new}
            ahead = {k: self.prefetched.pop(k) for k in new if k in self.prefetched}
            done = self.logged.evaluate_sources(list(first.values()), self.executor, ahead,
                                                self.gradient)
            for k, (ev, reused) in zip(new, done):
                self.cache[k] = ev
                self.evaluations.append(ev)
                self.rows.append({"eval": len(self.evaluations), **ev.to_row(self.space),
                                  "reused": reused})
                logger.info("eval %d%s: objective %.6g, %s%s", len(self.evaluations),
                            " (from log)" if reused else "", ev.objective, ev.status
                            + (f" (max g = {ev.max_violation:.3g})"
                               if ev.status == "infeasible" else ""),
                            "" if ev.feasible else f" - {ev.message}")
                if self.callback is not None:
                    self.callback(ev)
        return [self.cache[k] for k in keys]

    def best(self) -> Evaluation | None:
        feas = [e for e in self.evaluations if e.feasible]
        if feas:
            return min(feas, key=lambda e: e.objective)
        ok = [e for e in self.evaluations if e.success]
        if ok:
            return min(ok, key=lambda e: (e.max_violation, e.objective))
        return self.evaluations[0] if self.evaluations else None

    def history(self) -> pd.DataFrame:
        import pandas as pd

        return pd.DataFrame(self.rows)


class _safe_evaluate:
    """Picklable ``problem.evaluate`` (``evaluate_with_gradient`` with ``gradient``) that
    turns any exception into a failed Evaluation."""

    def __init__(self, problem, gradient: bool = False):
        self.problem, self.gradient = problem, gradient

    def __call__(self, x) -> Evaluation:
        t0 = time.perf_counter()
        try:
            if self.gradient:
                return self.problem.evaluate_with_gradient(x)
            return self.problem.evaluate(x)
        except Exception as exc:  # noqa: BLE001 - contract: a failed design never raises
            logger.warning("problem.evaluate(%s) raised %s: %s", x, type(exc).__name__, exc)
            values = self.problem.space.to_mapping(x)
            return Evaluation(values, math.inf, success=False, status="failed",
                              message=f"{type(exc).__name__}: {exc}",
                              wall_time=time.perf_counter() - t0)


def _gradient_cell(space, ev: Evaluation) -> dict:
    """``{"gradient": JSON}`` for an evaluation with gradients, else ``{}``."""
    if ev.objective_gradient is None:
        return {}
    names = space.names
    cons = {k: [g[n] for n in names] for k, g in (ev.constraint_gradients or {}).items()}
    text = json.dumps({"objective": [ev.objective_gradient[n] for n in names],
                       "constraints": cons})
    return {"gradient": text}


def _gradient_from_cell(space, text: str):
    """The gradients of a ``gradient`` cell: ``(objective, constraints)`` or ``(None, None)``."""
    if not text:
        return None, None
    d = json.loads(text)
    names = space.names
    return (dict(zip(names, map(float, d["objective"]))),
            {k: dict(zip(names, map(float, v))) for k, v in d["constraints"].items()})
