"""One executor interface for sweeps, multi-start optimisation and coordinate descent.

``map(fn, items, progress=None) -> list`` (results in input order), ``close()``, context
manager, ``kind`` (``"serial"``, ``"process"``, ``"dask"``) and ``workers`` (parallel slots):

* :class:`SerialExecutor`: in this process, in order;
* :class:`ProcessExecutor`: a local process pool (default: all cores; ``forkserver`` or
  ``spawn`` start, never ``fork``, so it is safe with threads);
* :class:`DaskExecutor`: an existing Dask cluster (scheduler address) or a ``LocalCluster``
  that it starts and closes (``"local"``).

:func:`make_executor` builds one by kind, :func:`executor_from_option` from the CLI options
``--parallel N|auto`` and ``--dask ADDRESS|local``.

``fn`` must be picklable: a top-level function of an importable module, a
``functools.partial`` of one, or a bound method of a picklable object (e.g. a design
problem's ``evaluate``), not a lambda or a nested function. Workers import ``fn``'s module by
name, so etorigami must be installed on remote workers. Problems never raise, so an exception
escaping a task is unexpected: ``map`` cancels the pending tasks and raises :class:`TaskError`
(task index, item, original error as ``__cause__`` with the worker's traceback). Results are
the same floats with every executor on one machine (each task runs the same deterministic
code; tested bit for bit); across different CPUs this is not guaranteed.

Per-task results and faults
---------------------------
``map(..., on_result=fn)`` calls ``fn(index, result)`` in the calling process as each task
completes (completion order), so a sweep can log every point as soon as it is done. A worker
that dies (killed, out of memory) costs only its own tasks: the process pool is rebuilt and
the tasks that were running are retried, each at most ``max_retries`` times (default 2; a task
retried after a crash runs alone, so an innocent neighbour is charged at most once); Dask
reschedules such tasks itself (``distributed.scheduler.allowed-failures``) and then reports
``KilledWorker``. With ``failures="return"`` a task that still fails (or raises) is returned as
a :class:`TaskFailure` (index, item, reason, attempts) and the other tasks go on; the default,
``failures="raise"``, raises :class:`TaskError`.

Running a sweep on an existing Dask cluster
-------------------------------------------
Install etorigami in every worker's environment, then start a scheduler and single-threaded
worker processes (``dask-scheduler`` / ``dask-worker`` in older releases)::

    dask scheduler --port 8786                                    # scheduler host
    dask worker tcp://scheduler:8786 --nworkers 8 --nthreads 1    # each worker host

Dask's nannies set ``MALLOC_TRIM_THRESHOLD_=65536`` in workers, which makes the simulations
about 2.4 times slower; before starting the workers, unset it in the Dask configuration
(``~/.config/dask/distributed.yaml``; ``DaskExecutor("local")`` does this itself)::

    distributed:
      nanny:
        pre-spawn-environ:
          MALLOC_TRIM_THRESHOLD_: null

Then, on the client::

    from design.executors import DaskExecutor
    from design.problem import GripperProblem
    from design.robustness import residual_fold_grid, sweep_residual_fold

    with DaskExecutor("tcp://scheduler:8786") as ex:
        table = sweep_residual_fold(GripperProblem(), designs,
                                    residual_fold_grid([-10, -5, 0]), executor=ex)
    table.to_csv("sweep.csv", index=False)

Closing the executor closes only its client; the cluster keeps running.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import logging
import multiprocessing
import os
import pickle
import signal
from abc import ABC, abstractmethod
from dataclasses import dataclass

from simulator.errors import EtorigamiError, ParameterError

__all__ = ["Executor", "SerialExecutor", "ProcessExecutor", "DaskExecutor", "ExecutorError",
           "TaskError", "TaskFailure", "make_executor", "executor_from_option", "KINDS",
           "MAX_RETRIES"]

logger = logging.getLogger(__name__)

KINDS = ("serial", "process", "dask")
#: Dask's nannies set MALLOC_TRIM_THRESHOLD_=65536 in workers; a fixed glibc threshold also
#: fixes the mmap threshold and made gripper evaluations 2.4 times slower: left unset here.
_MALLOC_KEY = "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"
#: Default retries of a task whose worker process died.
MAX_RETRIES = 2
_FAILURE_MODES = ("raise", "return")


class ExecutorError(EtorigamiError, RuntimeError):
    """An executor could not start, connect or send work."""


class TaskError(ExecutorError):
    """A task raised (original exception: ``__cause__``); ``index`` and ``item`` name it."""

    def __init__(self, message: str, index: int, item):
        super().__init__(message)
        self.index, self.item = index, item


@dataclass(frozen=True)
class TaskFailure:
    """A task that did not produce a result (returned by ``map(..., failures="return")``).

    Attributes
    ----------
    index : int
        Position of the task in the items.
    item : object
    reason : str
        What happened (the exception, or the worker's death and the number of attempts).
    attempts : int
        Times the task was started.
    """

    index: int
    item: object
    reason: str
    attempts: int = 1

    @property
    def success(self) -> bool:
        return False


def _check_failures(failures: str) -> None:
    if failures not in _FAILURE_MODES:
        raise ParameterError(f"map: failures = {failures!r}; use 'raise' or 'return'.")


def _name(fn) -> str:
    return getattr(fn, "__qualname__", None) or getattr(getattr(fn, "func", None), "__qualname__",
                                                        None) or type(fn).__name__


def _task_error(fn, index: int, total: int, item, exc: BaseException, where: str) -> TaskError:
    text = repr(item)
    text = text if len(text) <= 200 else text[:197] + "..."
    return TaskError(f"task {index} of {total} ({_name(fn)} on {text}) raised "
                     f"{type(exc).__name__}: {exc} [{where}]", index, item)


def _check_picklable(fn, kind: str) -> None:
    try:
        pickle.dumps(fn)
    except Exception as exc:                  # any pickling failure, reported the same way
        raise ExecutorError(
            f"{kind} executor: cannot send {_name(fn)} to worker processes ({type(exc).__name__}: "
            f"{exc}); use a top-level function of an importable module, a functools.partial of "
            "one, or a bound method of a picklable object (not a lambda or a nested "
            "function).") from exc


class Executor(ABC):
    """Interface: ``map``, ``close``, context manager, ``kind``, ``workers``."""

    kind: str = ""
    workers: int = 1

    @abstractmethod
    def map(self, fn, items, progress=None, *, on_result=None, failures="raise") -> list:
        """``[fn(item) for item in items]``, possibly in parallel; results in input order.

        Parameters
        ----------
        fn : callable
            Picklable for process and Dask executors (see the module docstring).
        items : iterable
        progress : callable, optional
            ``progress(done, total)``, called as tasks complete (in completion order).
        on_result : callable, optional
            ``on_result(index, result)``, called in this process as each task completes
            (before ``progress``; with a :class:`TaskFailure` for a failed task).
        failures : {"raise", "return"}
            A task that raised, or whose worker died more than ``max_retries`` times:
            raise :class:`TaskError` (pending tasks cancelled) or return a
            :class:`TaskFailure` in its place and go on.

        Raises
        ------
        TaskError
            A task failed and ``failures="raise"``.
        """

    def close(self) -> None:
        """Release workers (idempotent)."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __repr__(self):
        return f"{type(self).__name__}(kind={self.kind!r}, workers={self.workers})"


class SerialExecutor(Executor):
    """Evaluate in this process, one item after the other."""

    kind = "serial"
    workers = 1

    def map(self, fn, items, progress=None, *, on_result=None, failures="raise") -> list:
        _check_failures(failures)
        items = list(items)
        out = []
        for i, item in enumerate(items):
            try:
                out.append(fn(item))
            except Exception as exc:
                err = _task_error(fn, i, len(items), item, exc, "serial")
                if failures == "raise":
                    raise err from exc
                out.append(TaskFailure(i, item, str(err)))
            _report(on_result, progress, i, out[-1], i + 1, len(items))
        return out


def _report(on_result, progress, index, result, done, total) -> None:
    if on_result is not None:
        on_result(index, result)
    if progress is not None:
        progress(done, total)


def _ignore_sigint() -> None:
    """Worker initializer: Ctrl-C is the parent's business (it stops the workers), so a
    worker neither raises KeyboardInterrupt nor prints a traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def _children_ignore_sigint():
    """Processes started in this block inherit an ignored SIGINT: Ctrl-C reaches every process
    of a terminal's foreground group, and only this one should handle it (it stops them)."""
    try:
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:                            # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _start_forkserver_ignoring_sigint() -> None:
    """Start multiprocessing's fork server (if not running yet) with SIGINT ignored.

    Its children get the server's original SIGINT disposition back: started so, they ignore
    Ctrl-C from birth, not only once the pool's initializer has run (otherwise a Ctrl-C that
    reaches a worker still starting up prints its KeyboardInterrupt traceback). A server that
    some other code started earlier is left as it is."""
    from multiprocessing import forkserver

    with _children_ignore_sigint():
        forkserver.ensure_running()


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

    Workers inherit the environment: on many cores, set ``OPENBLAS_NUM_THREADS=1`` (as Dask
    does in its workers) to avoid oversubscribing BLAS threads.
    """

    kind = "process"

    def __init__(self, workers: int | None = None, start_method: str | None = None,
                 max_retries: int = MAX_RETRIES):
        workers = (os.cpu_count() or 1) if workers is None else workers
        if not (isinstance(workers, int) and workers >= 1):
            raise ParameterError(f"ProcessExecutor: workers = {workers!r} must be a positive "
                                 "integer (or None for all cores).")
        start_method = start_method or _default_start_method()
        if start_method not in ("forkserver", "spawn"):
            raise ParameterError(f"ProcessExecutor: start_method = {start_method!r}; use "
                                 "'forkserver' or 'spawn'.")
        if not (isinstance(max_retries, int) and max_retries >= 0):
            raise ParameterError(f"ProcessExecutor: max_retries = {max_retries!r} must be a "
                                 "non-negative integer.")
        self.workers, self.start_method, self.max_retries = workers, start_method, max_retries
        self._pool = None

    def _ensure_pool(self):
        if self._pool is None:
            ctx = multiprocessing.get_context(self.start_method)
            if self.start_method == "forkserver":
                _start_forkserver_ignoring_sigint()
            self._pool = cf.ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx,
                                                initializer=_ignore_sigint)
            logger.info("process pool: %d workers (%s)", self.workers, self.start_method)
        return self._pool

    def worker_pids(self) -> list:
        """Process ids of the current pool's workers (empty before the first ``map``)."""
        return sorted((getattr(self._pool, "_processes", None) or {}).keys())

    def map(self, fn, items, progress=None, *, on_result=None, failures="raise") -> list:
        _check_failures(failures)
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
        processes = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in processes:
            proc.terminate()
        for proc in processes:
            proc.join(timeout=5)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None


class DaskExecutor(Executor):
    """A Dask distributed cluster: an existing one, or a ``LocalCluster`` it starts.

    Parameters
    ----------
    address : str
        Scheduler address (``"tcp://host:8786"``) of a running cluster, or ``"local"`` to
        start a ``LocalCluster`` (worker processes with one thread each, no dashboard, quiet
        logs) that :meth:`close` shuts down.
    workers : int, optional
        Worker processes of the local cluster (default: all cores). Not allowed with an
        address: the cluster's size is the sum of its worker threads.
    timeout : float
        Seconds to wait for the scheduler.

    Dask serialises ``fn`` with cloudpickle and so also accepts lambdas; keep to top-level
    callables anyway, so that the same code runs with every executor.
    """

    kind = "dask"

    def __init__(self, address: str = "local", workers: int | None = None,
                 timeout: float = 30.0):
        import dask
        from distributed import Client, LocalCluster

        if not isinstance(address, str) or not address:
            raise ParameterError(f"DaskExecutor: address = {address!r}; give a scheduler address "
                                 "like 'tcp://host:8786' or 'local'.")
        if workers is not None and not (isinstance(workers, int) and workers >= 1):
            raise ParameterError(f"DaskExecutor: workers = {workers!r} must be a positive integer.")
        self.address, self._cluster = address, None
        if address == "local":
            n = workers or os.cpu_count() or 1
            with dask.config.set({_MALLOC_KEY: None}), _children_ignore_sigint():  # _MALLOC_KEY
                self._cluster = LocalCluster(  # no dashboard; its bare HTTP server: any port
                    n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                    scheduler_kwargs={"dashboard_address": ":0"}, silence_logs=logging.CRITICAL)
            try:
                self.client = Client(self._cluster, timeout=timeout)
            except BaseException:
                self._cluster.close()
                raise
            self.workers = n
        else:
            if workers is not None:
                raise ParameterError("DaskExecutor: workers sets the size of a local cluster; "
                                     f"the cluster at {address} has its own workers.")
            try:
                self.client = Client(address, timeout=timeout)
            except (OSError, TimeoutError) as exc:
                raise ExecutorError(f"could not connect to the Dask scheduler at {address!r} "
                                    f"within {timeout:g} s: {exc}") from exc
            self.workers = max(1, sum(self.client.nthreads().values()))
        logger.info("dask executor: %s, %d worker threads", address, self.workers)

    def map(self, fn, items, progress=None, *, on_result=None, failures="raise") -> list:
        from distributed import as_completed

        _check_failures(failures)
        items = list(items)
        if not items:
            return []
        futures = self.client.map(fn, items, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        out = [None] * len(items)
        try:
            for done, fut in enumerate(as_completed(futures), 1):
                i = index[fut.key]
                if fut.status != "finished":
                    exc = fut.exception().with_traceback(fut.traceback()) \
                        if fut.status == "error" else ExecutorError(f"task {fut.status}")
                    err = _task_error(fn, i, len(items), items[i], exc, f"dask {self.address}")
                    if failures == "raise":
                        raise err from exc
                    out[i] = TaskFailure(i, items[i], str(err))
                else:
                    out[i] = fut.result()
                _report(on_result, progress, i, out[i], done, len(items))
            return out
        finally:
            self.client.cancel(futures)           # pending ones on error; releases the rest

    def close(self) -> None:
        if getattr(self, "client", None) is not None:
            self.client.close()
            self.client = None
        if self._cluster is not None:
            self._cluster.close()
            self._cluster = None


def make_executor(kind: str = "serial", workers: int | None = None,
                  address: str | None = None) -> Executor:
    """An executor by kind.

    Parameters
    ----------
    kind : {"serial", "process", "dask"}
    workers : int, optional
        Process count (process pool, local Dask cluster); default all cores.
    address : str, optional
        Dask scheduler address or ``"local"`` (default ``"local"``).
    """
    if kind == "serial":
        return SerialExecutor()
    if kind == "process":
        return ProcessExecutor(workers)
    if kind == "dask":
        return DaskExecutor(address or "local", workers)
    raise ParameterError(f"executor kind = {kind!r}; use one of {', '.join(KINDS)}.")


_SERIAL_WORDS = ("serial", "no", "off", "none", "false")
_ALL_WORDS = ("", "auto", "all", "yes", "on", "true")


def executor_from_option(parallel: str | None = None, dask: str | None = None) -> Executor:
    """An executor from CLI-style options ``--parallel`` and ``--dask``.

    Parameters
    ----------
    parallel : str, optional
        ``None``, ``"serial"``, ``"0"`` or ``"1"``: serial; ``"auto"``/``"all"``/``""``: a
        process pool on all cores; an integer ``N >= 2``: ``N`` worker processes.
    dask : str, optional
        A scheduler address (``"tcp://host:8786"``) or ``"local"``; takes precedence over
        ``parallel``, which then sets the number of workers of the local cluster.
    """
    workers, serial = None, parallel is None
    if parallel is not None:
        text = str(parallel).strip().lower()
        if text in _SERIAL_WORDS:
            serial = True
        elif text not in _ALL_WORDS:
            try:
                workers = int(text)
            except ValueError:
                raise ParameterError(f"--parallel {parallel!r}: give a number of worker "
                                     "processes, 'auto' (all cores) or 'serial'.") from None
            if workers < 0:
                raise ParameterError(f"--parallel {parallel!r} must not be negative.")
            serial = workers <= 1
    if dask is not None:
        address = dask.strip()
        if address.lower() == "local":
            return DaskExecutor("local", max(workers, 1) if workers is not None else None)
        if workers is not None:
            raise ParameterError(f"--parallel {parallel} sets the size of a local Dask cluster; "
                                 f"the cluster at {address} has its own workers.")
        return DaskExecutor(address)
    return SerialExecutor() if serial else ProcessExecutor(workers)
