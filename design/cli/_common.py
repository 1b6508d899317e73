"""Helpers shared by the ``etorigami`` subcommands: CLI units, progress bars, executors.

The command line speaks micrometres, milliwatts and degrees; everything is checked here in
those units (so an error names the option and the value as typed) and converted to SI before
it reaches the library.
"""

from __future__ import annotations

import contextlib
import csv
import logging
import math
import os
import pathlib

__all__ = ["CLIError", "length_um", "power_mw", "fold_deg", "floats", "distinct", "progress_bar",
           "add_parallel_options", "executor", "kernel_backend", "saved_rows", "resume_message",
           "check_output", "add_quiet_option", "resuming_line", "BestSoFar", "show_progress", "EXIT_INTERRUPTED", "RESIDUAL_LIMIT_DEG", "PLAUSIBLE_LENGTH_UM",
           "MAX_POWER_MW"]

#: Largest |residual fold| of the gripper sweeps and robust problems [deg] (their pi/2 limit).
RESIDUAL_LIMIT_DEG = 90.0
#: Exit status of a command ended by Ctrl-C (128 + SIGINT), as shells report it.
EXIT_INTERRUPTED = 130
#: Plausible lengths at the CLI [um]: outside, a length was most likely typed in another unit
#: (0.0002 for 200 um typed in metres, 200000 for 200 um typed in nm).
PLAUSIBLE_LENGTH_UM = (0.01, 1e5)
#: Largest power the CLI accepts on one crease (or per crease) [mW]: the paper's creases fold
#: at 1-100 mW; 10 W would melt any of them, so a larger value is a typo, not a request.
MAX_POWER_MW = 1e4


class CLIError(Exception):
    """A command-line usage error, reported in one line (exit status 2)."""


def length_um(flag: str, value: float, *, minimum: float = 0.0, field: str = "") -> float:
    """Check a length given in um (``> minimum``, and within :data:`PLAUSIBLE_LENGTH_UM`) and
    return it in metres; ``field`` names the library parameter it sets (shown in the error).

    An implausible magnitude is refused with the likely intended value, e.g. ``--W = 0.0002 um
    is implausible: did you mean 200 um? (lengths are in um)``.
    """
    where = f" ({field})" if field else ""
    low, high = PLAUSIBLE_LENGTH_UM
    if not (math.isfinite(value) and value > minimum):
        raise CLIError(f"{flag} = {value:g} um must be > {minimum:g} um{where} (lengths are in "
                       f"um, plausible {low:g} to {high:g} um)")
    if not low <= value <= high:
        guess, typed = (value * 1e6, "m") if value < low else (value / 1e3, "nm")
        hint = f"did you mean {guess:g} um? " if low <= guess <= high else ""
        raise CLIError(f"{flag} = {value:g} um is implausible{where}: {hint}(lengths are in "
                       f"um, not {typed}; plausible {low:g} to {high:g} um)")
    return value / 1e6


def power_mw(flag: str, value: float, *, per: str = "per crease") -> float:
    """Check a power given in mW (0 to :data:`MAX_POWER_MW`) and return it in W."""
    if not (math.isfinite(value) and 0.0 <= value <= MAX_POWER_MW):
        raise CLIError(f"{flag} = {value:g} mW is outside the plausible range 0 to "
                       f"{MAX_POWER_MW:g} mW {per} (the creases fold at 1-100 mW)")
    return value / 1e3


def fold_deg(flag: str, value: float, *, within: float | None = None) -> float:
    """Check a fold angle given in degrees (in (-180, 180], or in [-within, within]) and
    return it in rad."""
    if not (math.isfinite(value) and -180.0 < value <= 180.0):
        raise CLIError(f"{flag} = {value:g} deg must be a fold angle in (-180, 180] deg")
    if within is not None and abs(value) > within:
        raise CLIError(f"{flag} = {value:g} deg must be within -{within:g} to {within:g} deg")
    return math.radians(value)


def distinct(values, scale: float = 1e6) -> str:
    """The distinct ``values`` times ``scale`` (default: metres to um), 4 significant digits,
    ascending, joined by '/': ``"21/500"``."""
    return "/".join(sorted({f"{v * scale:.4g}" for v in values}, key=float))


def floats(flag: str, text: str) -> list:
    """Comma-separated numbers, e.g. ``-20,-10,0``."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise CLIError(f"{flag}: expected comma-separated numbers, got {text!r}") from None
    if not values:
        raise CLIError(f"{flag}: expected comma-separated numbers, got {text!r}")
    return values


#: Help of ``-q/--quiet``, the one option for a quiet command (every command and study).
QUIET_HELP = ("quiet: no progress bar (there is none when stderr is not a terminal either); the "
              "summary and warnings that affect the result are still printed")


def add_quiet_option(parser, top: bool = False) -> None:
    """``-q/--quiet`` on ``parser``; on a subcommand (``top`` False) it is SUPPRESSed by default
    so that ``etorigami -q run ...`` and ``etorigami run ... -q`` mean the same."""
    import argparse

    parser.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP,
                        **({} if top else {"default": argparse.SUPPRESS}))


def show_progress(quiet: bool) -> bool:
    """Whether to draw a progress bar: not quiet, and stderr is a terminal (frames of a bar
    redirected into a log file are noise)."""
    import sys

    isatty = getattr(sys.stderr, "isatty", None)
    return not quiet and bool(isatty and isatty())


class _HiddenBar:
    """What a disabled tqdm bar does, without importing tqdm: ``update`` and the drawing
    methods do nothing, ``reset(total)`` sets ``total``; ``n`` stays 0."""

    def __init__(self, total=None):
        self.total, self.n, self.leave, self.disable = total, 0, True, True

    def reset(self, total=None) -> None:
        self.n = 0
        if total is not None:
            self.total = total

    def __getattr__(self, name):                # update, close, set_postfix_str, refresh, ...
        if name.startswith("__"):
            raise AttributeError(name)
        return lambda *args, **kwargs: None


@contextlib.contextmanager
def progress_bar(total=None, desc: str = "", unit: str = "eval", disable: bool = False):
    """A tqdm bar on stderr that erases itself when the command is interrupted or fails;
    hidden when ``disable`` (``--quiet``) or when stderr is not a terminal (then tqdm is not
    even imported: a short command's start-up)."""
    if not show_progress(disable):
        yield _HiddenBar(total)
        return
    from tqdm import tqdm

    bar = tqdm(total=total, desc=desc, unit=unit)
    try:
        yield bar
    except BaseException:
        bar.leave = False
        raise
    finally:
        bar.close()


def add_parallel_options(parser) -> None:
    """``--parallel N`` / ``--dask ADDRESS`` (mutually exclusive)."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--parallel", metavar="N", help="evaluate on N local processes "
                                                       "('all' = every core)")
    group.add_argument("--dask", metavar="ADDRESS", help="evaluate on a Dask cluster: a "
                       "scheduler address (tcp://host:8786) or 'local' for a LocalCluster")


def executor(args):
    """The executor chosen by ``--parallel`` / ``--dask`` (serial by default).

    Dask's own INFO and WARNING logs (cluster start, workers killed on Ctrl-C) are shown only
    with ``--verbose``.
    """
    from ..core.executors import executor_from_option

    if getattr(args, "dask", None) and not getattr(args, "verbose", False):
        import distributed  # noqa: F401 - configures its loggers on import; quieten them after

        logging.getLogger("distributed").setLevel(logging.ERROR)

    return executor_from_option(getattr(args, "parallel", None), getattr(args, "dask", None))


@contextlib.contextmanager
def kernel_backend(short: bool):
    """Context for a command: its kernels are those :func:`simulator._jit.command_tier` chooses
    (short ones, one case or one gripper evaluation: the ahead-of-time compiled kernels when
    built, else numba's; long ones: numba's), the same on the first run after install and on
    later ones, so that the same command gives the same floats. Only here does the CLI ask for
    background work: on a cold numba cache a short command compiles the thermal kernel in a
    second process beside the fused one (:func:`simulator._jit.compile_thermal_kernel_beside`),
    and after it the ahead-of-time module is built in a detached process for the next run
    (:func:`simulator._jit.warm_kernel_cache`). ``ETORIGAMI_JIT`` set: neither."""
    from simulator import _jit

    tier = _jit.command_tier(short)
    asks = short and tier == "numba" and _jit.environment().jit is None
    if asks:
        _jit.compile_thermal_kernel_beside()
    with _jit.use(tier):
        yield
    if asks:
        _jit.warm_kernel_cache()


def saved_rows(path) -> int:
    """Complete data rows of a CSV file (0 if it does not exist)."""
    if path is None or not os.path.exists(path):
        return 0
    with open(path, newline="", encoding="utf-8") as fh:
        text = fh.read()
    rows = list(csv.reader(text.splitlines()))
    if rows and not text.endswith("\n"):
        rows = rows[:-1]                       # a row cut by the interrupt is dropped on resume
    return max(len(rows) - 1, 0)


def resuming_line(log, total=None, what: str = "evaluations") -> str | None:
    """The line a resumed command prints before its work, e.g. ``resuming: 12 of 40 points
    saved in out/evaluations.csv are reused``; None when nothing is saved yet (``total`` None:
    the count of the command's evaluations is not known in advance)."""
    n = saved_rows(log)
    if not n:
        return None
    of = f" of {total}" if total is not None else ""
    noun = what if (total or n) != 1 else what[:-1]
    return f"resuming: {n}{of} {noun} saved in {log} are reused (matching ones are not recomputed)"


class BestSoFar:
    """The best feasible objective [mW] of the evaluations seen so far, for a progress bar
    (``str()``: ``"9.85 mW"``, or ``"none feasible"``)."""

    def __init__(self):
        self.best = None

    def add(self, evaluation) -> None:
        """Take one :class:`design.Evaluation` into account."""
        if getattr(evaluation, "feasible", False):
            mw = 1e3 * evaluation.objective
            self.best = mw if self.best is None else min(self.best, mw)

    def __str__(self) -> str:
        return "none feasible" if self.best is None else f"{self.best:.4g} mW"


def resume_message(log, what: str = "evaluations") -> str:
    """The one line printed when a resumable command is interrupted."""
    if log is None:
        return f"interrupted: nothing saved (no --out); give --out DIR to keep the {what}"
    n = saved_rows(log)
    noun = what if n != 1 else what[:-1]
    return f"interrupted: {n} {noun} saved in {log}; run the same command again to resume"


def _can_write_in(folder: pathlib.Path) -> bool:
    """True if files can be made in ``folder``, or in its nearest existing ancestor when it does
    not exist yet (probed by making and removing a temporary folder: ``os.access`` says yes to
    root even on /proc)."""
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        return False
    try:
        import tempfile

        os.rmdir(tempfile.mkdtemp(prefix=".etorigami-probe-", dir=folder))
    except OSError:
        return False
    return True


def check_output(flag: str, path, kind: str = "dir") -> None:
    """Refuse an output path that cannot be written, before any work.

    Parameters
    ----------
    flag : str
        The option, e.g. ``--out`` (named in the error).
    path : str or path-like or None
        The path given (None: nothing to check).
    kind : {"dir", "file"}
        A folder to create or reuse, or a file to create or replace.

    Raises
    ------
    CLIError
        If a folder is an existing file, a file is an existing folder, or the path's folder
        cannot be created or written.
    """
    if path is None:
        return
    p = pathlib.Path(path)
    if kind == "dir" and p.exists() and not p.is_dir():
        raise CLIError(f"{flag} {p} is an existing file; give a folder (new or existing)")
    if kind == "file" and p.is_dir():
        raise CLIError(f"{flag} {p} is a folder; give a file name")
    if not _can_write_in(p if kind == "dir" else p.parent):
        raise CLIError(f"{flag} {p} cannot be written (its folder cannot be created or is not "
                       "writable); give another path")
