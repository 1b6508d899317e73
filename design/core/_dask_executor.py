"""The Dask executor (private; re-exported by :mod:`design.core.executors`): :class:`DaskExecutor`
on an existing cluster or on a ``LocalCluster`` that it starts and closes. Dask itself is
imported only when an executor is made."""

from __future__ import annotations

import logging
import os

from simulator import ParameterError
from simulator._validate import integer

from ._executor_base import (Executor, ExecutorError, TaskFailure, check_failures,
                             children_ignore_sigint, report, task_error)

__all__ = ["DaskExecutor"]

logger = logging.getLogger("design.core.executors")

#: Dask's nannies set MALLOC_TRIM_THRESHOLD_=65536 in workers; a fixed glibc threshold also
#: fixes the mmap threshold and made gripper evaluations 2.4 times slower: left unset here.
_MALLOC_KEY = "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"


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

    Notes
    -----
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
        integer("DaskExecutor: workers", workers, allow_none=True)
        self.address, self._cluster = address, None
        if address == "local":
            n = workers or os.cpu_count() or 1
            with dask.config.set({_MALLOC_KEY: None}), children_ignore_sigint():  # _MALLOC_KEY
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

        check_failures(failures)
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
                    err = task_error(fn, i, len(items), items[i], exc, f"dask {self.address}")
                    if failures == "raise":
                        raise err from exc
                    out[i] = TaskFailure(i, items[i], str(err))
                else:
                    out[i] = fut.result()
                report(on_result, progress, i, out[i], done, len(items))
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
