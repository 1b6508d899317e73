"""The local process-pool executor (private; re-exported by :mod:`design.core.executors`):
:class:`ProcessExecutor`, its worker start-up (``forkserver`` or ``spawn``, SIGINT ignored)
and pool management. Its task loop is :class:`design.core._pool_run.PoolRun`."""

from __future__ import annotations

import concurrent.futures as cf
import logging
import multiprocessing
import os
import pickle
import signal

from simulator import ParameterError
from simulator._validate import integer

from ._executor_base import (Executor, ExecutorError, check_failures, children_ignore_sigint,
                             callable_name)

__all__ = ["ProcessExecutor", "MAX_RETRIES"]

logger = logging.getLogger("design.core.executors")

#: Default retries of a task whose worker process died.
MAX_RETRIES = 2


def _check_picklable(fn, kind: str) -> None:
    try:
        pickle.dumps(fn)
    except Exception as exc:                  # any pickling failure, reported the same way
        raise ExecutorError(
            f"{kind} executor: cannot send {callable_name(fn)} to worker processes ({type(exc).__name__}: "
            f"{exc}); use a top-level function of an importable module, a functools.partial of "
            "one, or a bound method of a picklable object (not a lambda or a nested "
            "function).") from exc


def _ignore_sigint() -> None:
    """Worker initializer: Ctrl-C is the parent's business (it stops the workers), so a
    worker neither raises KeyboardInterrupt nor prints a traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _start_forkserver_ignoring_sigint() -> None:
    """Start multiprocessing's fork server (if not running yet) with SIGINT ignored.

    Its children get the server's original SIGINT disposition back: started so, they ignore
    Ctrl-C from birth, not only once the pool's initializer has run (otherwise a Ctrl-C that
    reaches a worker still starting up prints its KeyboardInterrupt traceback). A server that
    some other code started earlier is left as it is."""
    from multiprocessing import forkserver

    with children_ignore_sigint():
        forkserver.ensure_running()


class _RecordingContext:
    """A multiprocessing context that keeps the processes it starts (the pool's workers), so
    that the executor can name and stop them without reading the pool's internals."""

    def __init__(self, ctx):
        self._ctx = ctx
        self.processes: list = []

    def __getattr__(self, name):
        return getattr(self._ctx, name)

    def Process(self, *args, **kwargs):          # noqa: N802 - multiprocessing's spelling
        proc = self._ctx.Process(*args, **kwargs)
        self.processes.append(proc)
        return proc

    def alive(self) -> list:
        return [p for p in self.processes if p.pid is not None and p.is_alive()]


def _default_start_method() -> str:
    return "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"


class ProcessExecutor(Executor):
    """A local process pool (``concurrent.futures.ProcessPoolExecutor``, one item per task).

    Parameters
    ----------
    workers : int, optional
        Worker processes (default: all cores, ``os.cpu_count()``).
    start_method : {"forkserver", "spawn"}, optional
        Default ``forkserver`` where available, else ``spawn`` (never ``fork``: unsafe with
        threads). Workers start on the first ``map`` and are reused until ``close``.

    Notes
    -----
    Workers inherit the environment: on many cores, set ``OPENBLAS_NUM_THREADS=1`` (as Dask
    does in its workers) to avoid oversubscribing BLAS threads.
    """

    kind = "process"

    def __init__(self, workers: int | None = None, start_method: str | None = None,
                 max_retries: int = MAX_RETRIES):
        workers = (os.cpu_count() or 1) if workers is None else workers
        integer("ProcessExecutor: workers", workers, hint="or None for all cores")
        start_method = start_method or _default_start_method()
        if start_method not in ("forkserver", "spawn"):
            raise ParameterError(f"ProcessExecutor: start_method = {start_method!r}; use "
                                 "'forkserver' or 'spawn'.")
        if not (isinstance(max_retries, int) and max_retries >= 0):
            raise ParameterError(f"ProcessExecutor: max_retries = {max_retries!r} must be a "
                                 "non-negative integer.")
        self.workers, self.start_method, self.max_retries = workers, start_method, max_retries
        self._pool = None
        self._context = None

    def _ensure_pool(self):
        if self._pool is None:
            self._context = _RecordingContext(multiprocessing.get_context(self.start_method))
            if self.start_method == "forkserver":
                _start_forkserver_ignoring_sigint()
            self._pool = cf.ProcessPoolExecutor(max_workers=self.workers,
                                                mp_context=self._context,
                                                initializer=_ignore_sigint)
            logger.info("process pool: %d workers (%s)", self.workers, self.start_method)
        return self._pool

    def worker_pids(self) -> list:
        """Process ids of the current pool's workers (empty before the first ``map``)."""
        if self._pool is None:
            return []
        return sorted(p.pid for p in self._context.alive())

    def map(self, fn, items, progress=None, *, on_result=None, failures="raise") -> list:
        check_failures(failures)
        items = list(items)
        if not items:
            return []
        _check_picklable(fn, self.kind)
        from ._pool_run import PoolRun

        run = PoolRun(self, fn, items, on_result, progress, failures)
        try:
            return run.run()
        except BaseException as exc:
            run.cancel()
            if isinstance(exc, KeyboardInterrupt):
                self._terminate()                 # Ctrl-C: do not wait for running tasks
            raise

    def _discard_pool(self) -> None:
        """Drop a broken pool (its workers are gone); the next task starts a new one."""
        pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)

    def _terminate(self) -> None:
        """Stop the workers now; their running tasks are lost."""
        pool, self._pool = self._pool, None
        if pool is None:
            return
        processes = self._context.alive()
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in processes:
            proc.terminate()
        for proc in processes:
            proc.join(timeout=5)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
