"""``etorigami modes CASE [--set ...] [--count N] [--at STATE] --out DIR``: natural modes.

Frequencies [Hz] and mode shapes of a case linearised about its flat state or the state at the
end of its loading (``--at end``, the default: after self-folding, gravity and heating), from the
reduced tangent (supports eliminated) and lumped masses. Writes ``modes.csv`` (``mode``,
``frequency [Hz]``, ...), ``modes.npz`` (shapes), ``meta.json`` and mode-shape plots.
"""

from __future__ import annotations

import pathlib

from ._common import CLIError

__all__ = ["add_modes_command"]


def _modes(args) -> int:
    from simulator import get_case, natural_modes

    from .case_params import case_overrides

    if args.count < 1:
        raise CLIError(f"--count = {args.count} must be a positive integer")
    case = get_case(args.case, **case_overrides(args.set, args.case))
    state = None
    if args.at == "end":
        result = case.run()
        if not result.success:
            raise CLIError(f"{case.name} did not reach its end state: {result.message}")
        state = result.state
    modes = natural_modes(case.model, state, count=args.count)
    out = pathlib.Path(args.out)
    modes.save(out)
    if not args.no_plots:
        from ._plots import save_mode_plots

        save_mode_plots(modes, out, count=min(args.count, 6))
    frame = modes.to_frame()
    print(f"{case.name} ({'flat' if state is None else 'end of its loading'}): {modes.status} "
          f"({modes.message}); results in {out}")
    print(frame[[c for c in ("mode", "frequency [Hz]") if c in frame]].to_string(index=False))
    return 0 if modes.success else 1


def add_modes_command(sub) -> None:
    """Register ``modes``."""
    p = sub.add_parser("modes", help="natural frequencies and mode shapes of a case")
    p.add_argument("case", help="case name (see 'etorigami cases')")
    p.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="override a case parameter in the CLI unit 'etorigami cases' "
                        "lists (lengths um, powers mW; repeatable)")
    p.add_argument("--count", type=int, default=10, help="number of modes (default 10)")
    p.add_argument("--at", choices=["flat", "end"], default="end",
                   help="linearise about the flat state or the end of the case's loading "
                        "(default end)")
    p.add_argument("--no-plots", action="store_true", help="write no mode-shape plots")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.set_defaults(func=_modes, short=True)
