"""The task loop of :meth:`design.core.executors.ProcessExecutor.map` (private): a bounded window
of tasks in flight, per-task reporting, and recovery from worker deaths."""

from __future__ import annotations

import concurrent.futures as cf
import logging
from collections import deque
from concurrent.futures.process import BrokenProcessPool

from ._executor_base import TaskFailure, report, sigint_deferred, task_error

logger = logging.getLogger("design.core.executors")


class PoolRun:
    """One :meth:`ProcessExecutor.map`: at most ``workers`` tasks in flight, so that a worker's
    death charges only the tasks that were running. After a death the pool is rebuilt and those
    tasks are queued again, first; a task that was in flight during a death runs alone, so
    that a second death is its own."""

    def __init__(self, ex, fn, items, on_result, progress, failures):
        self.ex, self.fn, self.items = ex, fn, items
        self.on_result, self.progress, self.failures = on_result, progress, failures
        self.queue = deque(range(len(items)))
        self.starts = [0] * len(items)
        self.deaths = [0] * len(items)
        self.flight: dict = {}
        self.out: list = [None] * len(items)
        self.done = 0

    def run(self) -> list:
        while self.queue or self.flight:
            self._fill()
            finished, _ = cf.wait(self.flight, return_when=cf.FIRST_COMPLETED)
            broken = self._collect(finished)
            if broken:                            # the pool is broken: every task in flight ends
                broken += self._collect(cf.wait(self.flight)[0])
                self._recover(broken)
        return self.out

    def _fill(self) -> None:
        pool = self.ex._ensure_pool()
        while self.queue and len(self.flight) < self.ex.workers:
            i = self.queue[0]
            suspect = any(self.deaths[j] for j in self.flight.values())
            if suspect or (self.deaths[i] and self.flight):
                return                            # a suspect runs alone
            with sigint_deferred():              # submit may start a worker: not halfway
                try:
                    fut = pool.submit(self.fn, self.items[i])
                except BrokenProcessPool:         # a worker died since the last wait
                    if not self.flight:           # no task of ours to learn it from
                        self.ex._discard_pool()
                    return
                self.queue.popleft()
                self.starts[i] += 1
                self.flight[fut] = i

    def _collect(self, finished) -> list:
        """Record finished futures; return the indices whose worker died."""
        broken = []
        for fut in finished:
            i = self.flight.pop(fut)
            exc = fut.exception()
            if isinstance(exc, BrokenProcessPool):
                broken.append(i)
            elif exc is not None:
                self._fail(i, exc, "process pool")
            else:
                self._finish(i, fut.result())
        return broken

    def _recover(self, broken) -> None:
        self.ex._discard_pool()
        for i in sorted(broken, reverse=True):
            self.deaths[i] += 1
            if self.deaths[i] > self.ex.max_retries:
                self._fail(i, BrokenProcessPool(f"its worker process died {self.deaths[i]} "
                                                "times (killed or out of memory)"),
                           f"process pool, {self.starts[i]} attempts")
            else:
                self.queue.appendleft(i)
        logger.warning("process pool: a worker died; pool rebuilt, %d task(s) retried",
                       sum(1 for i in broken if self.deaths[i] <= self.ex.max_retries))

    def _fail(self, i, exc, where) -> None:
        err = task_error(self.fn, i, len(self.items), self.items[i], exc, where)
        if self.failures == "raise":
            raise err from exc
        self._finish(i, TaskFailure(i, self.items[i], str(err), self.starts[i]))

    def _finish(self, i, result) -> None:
        self.out[i] = result
        self.done += 1
        report(self.on_result, self.progress, i, result, self.done, len(self.items))

    def cancel(self) -> None:
        for fut in self.flight:
            fut.cancel()
