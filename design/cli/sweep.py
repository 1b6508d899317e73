"""``etorigami sweep residual-fold`` (gripper power vs the residual fold of its creases) and
``etorigami sweep uncertainty`` (yield, power spread and the inputs that matter under a
fabrication scenario, sampled with a seed).

Designs are given in micrometres and residual folds in degrees. Every point is appended to
``DIR/evaluations.csv`` as soon as it finishes; the same command run again reuses them.
"""

from __future__ import annotations

import os
import pathlib
import sys

from ._common import (RESIDUAL_LIMIT_DEG, CLIError, add_parallel_options, executor, floats,
                      fold_deg, length_um, progress_bar, resume_message, resuming_line)

__all__ = ["add_sweep_commands", "SCENARIO_NAMES"]

#: Names of :data:`design.analysis.uncertainty.SCENARIOS` (listed here so that building the parser
#: imports no simulator code; a test checks they agree).
SCENARIO_NAMES = ("default", "residual-fold", "off")


def _design_arg(text: str, space) -> dict:
    """``start`` or ``W=300,La=1500,L1=500,L2=500`` (display units) -> {name: SI value}."""
    if text.strip().lower() == "start":
        return space.to_mapping(space.start)
    out = {}
    for part in text.split(","):
        if "=" not in part:
            raise CLIError(f"--design expects name=value pairs or 'start', got {text!r}")
        name, value = part.split("=", 1)
        var = space[name.strip()]
        try:
            number = float(value)
        except ValueError:
            raise CLIError(f"--design: {name} = {value!r} is not a number") from None
        length_um(f"--design {var.name}", number)
        out[var.name] = number / var.display_scale
    return space.to_mapping(out)


def _run(args, out: pathlib.Path, total: int, desc: str, sweep):
    """``sweep(executor, log, progress)`` on the chosen executor, logging to
    ``out/evaluations.csv``, with a progress bar."""
    out.mkdir(parents=True, exist_ok=True)
    line = resuming_line(out / "evaluations.csv", total, "points")
    if line:
        print(line, file=sys.stderr, flush=True)
    ex = executor(args)
    try:
        with progress_bar(total=total, desc=desc, disable=args.quiet) as bar:
            return sweep(ex, out / "evaluations.csv",
                         lambda done, _total: bar.update(done - bar.n))
    finally:
        ex.close()


def _sweep(args) -> int:
    from ..devices.gripper import GripperHeatModel
    from ..devices.gripper_problem import GripperProblem
    from ..analysis.robustness import residual_fold_grid, sweep_residual_fold

    problem = GripperProblem(mode=args.mode, heat=GripperHeatModel(loss_model=args.loss_model))
    designs = [_design_arg(d, problem.space) for d in (args.design or ["start"])]
    values = floats("--values", args.values)
    for v in values:
        fold_deg("--values", v, within=RESIDUAL_LIMIT_DEG)
    groups = tuple(g.strip() for g in args.groups.split(",")) if args.groups else None
    grid = residual_fold_grid(values, creases=groups)
    out = pathlib.Path(args.out)
    frame = _run(args, out, len(designs) * len(grid), "residual-fold sweep",
                 lambda ex, log, shown: sweep_residual_fold(problem, designs, grid, executor=ex,
                                                            log=log, progress=shown))
    frame.to_csv(out / "sweep.csv", index=False)
    cols = [c for c in frame.columns if c.startswith("residual_fold") or c in (
        "W [um]", "La [um]", "L1 [um]", "L2 [um]", "total_power [mW]", "feasible", "success")]
    print(frame[cols].to_string(index=False))
    for line in _reasons(frame, cols):
        print(line)
    print(f"{len(frame)} points written to {out / 'sweep.csv'}")
    return 0


def _reasons(frame, cols) -> list:
    """One line per point that is not feasible: its residual folds and why (the crease, its
    temperature and the limit; or why the criterion was not met)."""
    folds = [c for c in cols if c.startswith("residual_fold")]
    lines = []
    for i, row in frame[~frame["feasible"].astype(bool)].iterrows():
        at = ", ".join(f"{c[:-len(' [deg]')].replace('_', ' ')} {row[c]:g} deg"
                       for c in folds)
        lines.append(f"point {i} ({at}): {row['status']}: {row['message']}")
    return lines


def _uncertainty(args) -> int:
    import json

    from ..devices.gripper import GripperHeatModel
    from ..devices.gripper_problem import GripperProblem
    from ..analysis.uncertainty import SCENARIOS
    from ..analysis.uncertainty_sweep import summarize_yield, sweep_uncertainty

    if args.samples < 1:
        raise CLIError(f"--samples = {args.samples} must be at least 1")
    problem = GripperProblem(mode=args.mode, heat=GripperHeatModel(loss_model=args.loss_model))
    scenario = SCENARIOS[args.scenario]
    designs = [_design_arg(d, problem.space) for d in (args.design or ["start"])]
    samples = scenario.sample(args.samples, args.seed, args.method)
    out = pathlib.Path(args.out)
    table = _run(args, out, len(designs) * len(samples), "uncertainty sweep",
                 lambda ex, log, shown: sweep_uncertainty(problem, scenario, samples, designs,
                                                          executor=ex, log=log, progress=shown))
    summary, sensitivity = summarize_yield(table, scenario)
    table.to_csv(out / "uncertainty.csv", index=False)
    summary.to_csv(out / "summary.csv", index=False)
    sensitivity.to_csv(out / "sensitivity.csv", index=False)
    with open(out / "scenario.json", "w", encoding="utf-8") as fh:
        json.dump({**scenario.to_dict(), "samples": args.samples, "seed": args.seed,
                   "method": args.method}, fh, indent=1)
    print(summary.to_string(index=False))
    print(f"{len(table)} points written to {out / 'uncertainty.csv'} (summary.csv, "
          "sensitivity.csv beside it)")
    return 0


def _interrupted(args) -> str:
    return resume_message(os.path.join(args.out, "evaluations.csv"), "points")


def _add_common_options(parser, func) -> None:
    """``--design``, ``--mode``, ``--loss-model``, ``--out``, ``-q``, ``--parallel``/``--dask``
    of every sweep."""
    parser.add_argument("--design", action="append", metavar="start|W=..,La=..,L1=..,L2=..",
                        help="design in um (repeatable; default the start design)")
    parser.add_argument("--mode", choices=("bisect", "staircase"), default="bisect")
    parser.add_argument("--loss-model", choices=("integral", "chain"), default="integral",
                        help="heat loss: the boundary-integral model over the substrate "
                             "(default; theory 4.7) or the paper's fitted chains (its "
                             "optimisation's setting)")
    parser.add_argument("--out", required=True, metavar="DIR")
    add_parallel_options(parser)
    parser.set_defaults(func=func, interrupted=_interrupted)


def add_sweep_commands(sub) -> None:
    """Register ``sweep residual-fold`` and ``sweep uncertainty``."""
    sweep = sub.add_parser("sweep", help="robustness sweeps")
    ssub = sweep.add_subparsers(dest="sweep_command", metavar="KIND", required=True)
    rf = ssub.add_parser("residual-fold", help="gripper power vs residual fold angle")
    rf.add_argument("--values", default="-20,-10,0", metavar="DEG,DEG,...",
                    help="residual folds in degrees, e.g. --values=-20,-10,0 (the default; "
                         "use the = form when the first value is negative)")
    rf.add_argument("--groups", metavar="base,arm", help="sweep crease groups independently "
                                                        "(product grid)")
    _add_common_options(rf, _sweep)

    un = ssub.add_parser("uncertainty", help="gripper yield and power spread under "
                                             "fabrication uncertainty")
    un.add_argument("--samples", type=int, default=32, metavar="N", help="samples (default 32)")
    un.add_argument("--seed", type=int, default=0, metavar="S",
                    help="sampling seed: the same seed gives the same table (default 0)")
    un.add_argument("--method", choices=("mc", "lhs"), default="lhs",
                    help="Monte Carlo or Latin hypercube (default lhs)")
    un.add_argument("--scenario", choices=SCENARIO_NAMES, default="default",
                    help="fabrication scenario (see design.analysis.uncertainty.SCENARIOS)")
    _add_common_options(un, _uncertainty)
