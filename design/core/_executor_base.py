"""The executor interface (private; public names are re-exported by :mod:`design.core.executors`):
:class:`Executor`, its errors and :class:`TaskFailure`, the :class:`SerialExecutor`, and the
helpers that the parallel executors share (task error messages, per-task reporting, SIGINT
handling of the worker processes they start)."""

from __future__ import annotations

import contextlib
import signal
from abc import ABC, abstractmethod
from dataclasses import dataclass

from simulator import EtorigamiError, ParameterError

__all__ = ["Executor", "SerialExecutor", "ExecutorError", "TaskError", "TaskFailure"]

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


def check_failures(failures: str) -> None:
    if failures not in _FAILURE_MODES:
        raise ParameterError(f"map: failures = {failures!r}; use 'raise' or 'return'.")


def callable_name(fn) -> str:
    return getattr(fn, "__qualname__", None) or getattr(getattr(fn, "func", None), "__qualname__",
                                                        None) or type(fn).__name__


def task_error(fn, index: int, total: int, item, exc: BaseException, where: str) -> TaskError:
    text = repr(item)
    text = text if len(text) <= 200 else text[:197] + "..."
    return TaskError(f"task {index} of {total} ({callable_name(fn)} on {text}) raised "
                     f"{type(exc).__name__}: {exc} [{where}]", index, item)


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
            Picklable for process and Dask executors (see :mod:`design.core.executors`).
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
        check_failures(failures)
        items = list(items)
        out = []
        for i, item in enumerate(items):
            try:
                out.append(fn(item))
            except Exception as exc:
                err = task_error(fn, i, len(items), item, exc, "serial")
                if failures == "raise":
                    raise err from exc
                out.append(TaskFailure(i, item, str(err)))
            report(on_result, progress, i, out[-1], i + 1, len(items))
        return out


def report(on_result, progress, index, result, done, total) -> None:
    if on_result is not None:
        on_result(index, result)
    if progress is not None:
        progress(done, total)


@contextlib.contextmanager
def _sigint_handler(handler):
    """``handler`` for SIGINT during this block, the previous one after it; nothing changes
    outside the main thread (where Python does not allow it)."""
    try:
        previous = signal.signal(signal.SIGINT, handler)
    except ValueError:                            # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def sigint_deferred():
    """A Ctrl-C during this block takes effect when it ends (the signal is raised again then,
    for the handler in force before).

    Starting a pool worker is Python code: a KeyboardInterrupt in the middle of it can leave
    a started worker that the pool does not know, so Ctrl-C does not stop it; it then keeps
    the fork server and the terminal's pipes alive."""
    caught = []
    try:
        with _sigint_handler(lambda signum, frame: caught.append(signum)):
            yield
    finally:                                      # also when the block raised: Ctrl-C wins
        if caught:
            signal.raise_signal(signal.SIGINT)


def children_ignore_sigint():
    """Processes started in this block inherit an ignored SIGINT: Ctrl-C reaches every process
    of a terminal's foreground group, and only this one should handle it (it stops them)."""
    return _sigint_handler(signal.SIG_IGN)
