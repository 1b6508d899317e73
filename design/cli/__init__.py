"""Command-line interface: ``etorigami`` (also ``python -m design.cli``).

The CLI sits on top of both layers (simulator and design), so it lives here; ``simulator/``
never imports it. One module per command group:

* :mod:`.simulate`: ``etorigami demo`` (the main demo: a crease on a substrate heated until it
  lifts off), ``etorigami cases``, ``etorigami run CASE|FILE.fold [--set name=value ...] --out
  DIR``;
* :mod:`.files`: ``etorigami export CASE --format fold --out FILE``, ``etorigami check FILE``,
  ``etorigami view RESULT_DIR [--out FILE.html]``;
* :mod:`.modes`: ``etorigami modes CASE [--count N] --out DIR`` (natural modes);
* :mod:`.gripper`: ``etorigami gripper evaluate``;
* :mod:`.optimize`: ``etorigami optimize gripper|miura`` (resumable with ``--out``);
* :mod:`.sweep`: ``etorigami sweep residual-fold`` and ``etorigami sweep uncertainty``
  (resumable; a dead worker costs only its own points).

Options are in um, mW, degrees and seconds, ``--set`` of a case included (the unit table of
:mod:`.case_params`); a length of implausible magnitude (0.0002 um) or a power above 10 W is
refused with a hint. ``--out`` is checked before any work (an existing file where a folder is
expected, a folder that cannot be made or written). A usage error ends with one line on stderr and exit status
2; Ctrl-C ends with one line saying what was saved and how to resume, and exit status 130.
Every command runs on one kernel tier whatever the state of numba's cache, so that it gives
the same floats on its first run and later ones: short commands (demo, run, gripper evaluate)
on the ahead-of-time compiled kernels when built, else numba's; long ones on numba's (see
:func:`design.cli._common.kernel_backend` and ``docs/kernels.md``).
"""

from __future__ import annotations

import argparse
import logging
import signal
import sys

from simulator import EtorigamiError, __version__

from ._common import EXIT_INTERRUPTED, CLIError, add_quiet_option, check_output, kernel_backend
from .files import add_file_commands
from .gripper import add_gripper_commands
from .modes import add_modes_command
from .optimize import add_optimize_command
from .simulate import add_simulate_commands
from .sweep import add_sweep_commands

__all__ = ["main"]


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="etorigami",
        description="Simulation and design of electro-thermally actuated origami. "
                    "Lengths in um, powers in mW, angles in degrees.")
    parser.add_argument("--version", action="version", version=f"etorigami {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log solver progress "
                        "(recovered step cuts, failed trial increments, kernel loading)")
    add_quiet_option(parser, top=True)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    add_simulate_commands(sub)
    add_file_commands(sub)
    add_modes_command(sub)
    add_gripper_commands(sub)
    add_optimize_command(sub)
    add_sweep_commands(sub)
    _quiet_everywhere(sub)
    return parser


def _quiet_everywhere(sub) -> None:
    """``-q/--quiet`` on every (nested) subcommand, so that one flag works on all of them."""
    for command in sub.choices.values():
        if "--quiet" not in command._option_string_actions:
            add_quiet_option(command)
        for action in command._actions:
            if isinstance(action, argparse._SubParsersAction):
                _quiet_everywhere(action)


def _interrupted(args) -> int:
    signal.signal(signal.SIGINT, signal.SIG_IGN)       # a second Ctrl-C must not add a traceback
    try:
        line = args.interrupted(args) if hasattr(args, "interrupted") else "interrupted"
    except Exception:  # noqa: BLE001 - the report of an interrupt must not fail
        line = "interrupted"
    print(line, file=sys.stderr, flush=True)
    return EXIT_INTERRUPTED


def main(argv=None) -> int:
    """Entry point of the ``etorigami`` command; returns the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    if args.command is None:
        parser.print_help()
        return 0
    held = _HeldWarnings(active=not args.verbose)
    refused = False
    try:
        check_output("--out", getattr(args, "out", None), getattr(args, "out_kind", "dir"))
        with kernel_backend(short=getattr(args, "short", False)):
            return args.func(args)
    except KeyboardInterrupt:
        held.release()
        return _interrupted(args)
    except (EtorigamiError, CLIError) as exc:
        refused = True
        print(f"etorigami: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:                       # output piped into e.g. `head`
        refused = True
        sys.stderr.close()
        return 0
    finally:
        held.close(release=not refused)


class _HeldWarnings(logging.Filter):
    """Warnings on stderr held until the command ends: printed when it gives a result (or is
    interrupted), dropped when it is refused, whose one line is then all of stderr (a WARNING
    says that a result is affected, and a refused command has none; what the FOLD reader
    repaired is printed on stdout as its notes). Not with ``--verbose``, whose log lines show
    progress as it happens; only on the handlers that write to stderr."""

    def __init__(self, active: bool = True):
        super().__init__()
        self.records, self.handlers = [], []
        if not active:
            return
        for handler in logging.getLogger().handlers:
            if getattr(handler, "stream", None) in (sys.stderr, sys.__stderr__):
                handler.addFilter(self)
                self.handlers.append(handler)

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno < logging.WARNING:
            return True
        for handler in self.handlers:             # the handler's other filters first (CLI
            if self in handler.filters and all(   # spelling of the reader's warnings)
                    f.filter(record) for f in handler.filters if f is not self):
                self.records.append((handler, record))
                break
        return False

    def release(self) -> None:
        """Print the held warnings now, and every later one as it comes."""
        for handler in self.handlers:
            handler.removeFilter(self)
        records, self.records = self.records, []
        for handler, record in records:
            if record.levelno >= handler.level:
                handler.emit(record)

    def close(self, release: bool) -> None:
        if release:
            self.release()
        for handler in self.handlers:
            handler.removeFilter(self)
        self.records, self.handlers = [], []
