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

    from design import DaskExecutor, GripperProblem, residual_fold_grid, sweep_residual_fold

    with DaskExecutor("tcp://scheduler:8786") as ex:
        table = sweep_residual_fold(GripperProblem(), designs,
                                    residual_fold_grid([-10, -5, 0]), executor=ex)
    table.to_csv("sweep.csv", index=False)

Closing the executor closes only its client; the cluster keeps running.
"""

from __future__ import annotations

from simulator import ParameterError

from ._dask_executor import DaskExecutor
from ._executor_base import Executor, ExecutorError, SerialExecutor, TaskError, TaskFailure
from ._process_executor import MAX_RETRIES, ProcessExecutor

__all__ = ["Executor", "SerialExecutor", "ProcessExecutor", "DaskExecutor", "ExecutorError",
           "TaskError", "TaskFailure", "make_executor", "executor_from_option", "KINDS",
           "MAX_RETRIES"]

KINDS = ("serial", "process", "dask")


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
