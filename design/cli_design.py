"""Design subcommands of the ``etorigami`` command: gripper evaluate, optimize, sweep.

Lengths are given in micrometres and angles in degrees on the command line; everything is
converted to SI before it reaches the library.
"""

from __future__ import annotations

import json
import math
import pathlib
import time


from simulator.errors import ParameterError

__all__ = ["add_design_commands"]

METHODS = ("cd", "cobyla", "bobyqa", "neldermead", "sbplx", "direct")


def _parallel_options(parser):
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--parallel", metavar="N", help="evaluate on N local processes "
                                                       "('all' = every core)")
    group.add_argument("--dask", metavar="ADDRESS", help="evaluate on a Dask cluster: a "
                       "scheduler address (tcp://host:8786) or 'local' for a LocalCluster")


def _executor(args):
    from .executors import executor_from_option

    return executor_from_option(getattr(args, "parallel", None), getattr(args, "dask", None))


def _bar(total=None, desc="", disable=False):
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="eval", disable=disable)


# ---------------------------------------------------------------------------- gripper
def _gripper_evaluate(args) -> int:
    from .gripper import GripperDesign, evaluate_gripper

    design = GripperDesign(W=args.W * 1e-6, L1=args.L1 * 1e-6, L2=args.L2 * 1e-6,
                           La=args.La * 1e-6, residual_fold=math.radians(args.residual_fold))
    t0 = time.perf_counter()
    res = evaluate_gripper(design, mode=args.mode)
    out = res.to_dict()
    out["wall_time_s"] = round(time.perf_counter() - t0, 3)
    if args.json:
        print(json.dumps(out, indent=2, default=float))
    else:
        print(f"gripper W={args.W:g} L1={args.L1:g} L2={args.L2:g} La={args.La:g} um, residual "
              f"fold {args.residual_fold:g} deg ({args.mode}): "
              f"{'met' if res.success else 'NOT MET'} - {res.message}")
        def mw(value):
            return f"{value:8.3f} mW" if value is not None else "   not met"

        for stage in ("assembly", "grip"):
            print(f"  {stage:<9} {mw(out[f'{stage}_power [mW]'])} per crease   "
                  f"{out[f'{stage}_temperature [degC]']:7.2f} degC   "
                  f"{out[f'{stage}_simulations']:4d} simulations")
        print(f"  total     {mw(out['total_power [mW]'])}   max crease temperature "
              f"{out['max_crease_temperature [degC]']:.2f} degC   ({out['wall_time_s']:.2f} s)")
    return 0 if res.success else 1


# ---------------------------------------------------------------------------- optimize
def _problem(args):
    from .problem import GripperProblem

    if args.target == "miura":
        from .miura import MiuraProblem
        return MiuraProblem()
    residuals = _floats(args.robust) if args.robust else None
    base = GripperProblem(mode=args.mode, residual_fold=math.radians(args.residual_fold))
    if residuals:
        from .robustness import RobustGripperProblem
        return RobustGripperProblem(base, [math.radians(v) for v in residuals])
    return base


def _optimize(args) -> int:
    from .optimize import optimize

    problem = _problem(args)
    bar = _bar(desc=f"{args.target} {args.method}", disable=args.quiet)

    def callback(evaluation):
        bar.update(1)
        bar.set_postfix(objective=f"{evaluation.objective * 1e3:.4g} mW")

    executor = _executor(args)
    options = {"parallel_candidates": True} if args.method == "cd" and (
        args.parallel or args.dask) else {}
    try:
        res = optimize(problem, args.method, out=args.out, executor=executor,
                       max_evaluations=args.max_evaluations, callback=callback, **options)
    finally:
        bar.close()
        executor.close()
    x = ", ".join(f"{k}={_display(problem, k, v)}" for k, v in res.x.items())
    print(f"{args.method}: {res.status} ({res.message}); best {res.objective * 1e3:.4g} mW at "
          f"{x}; {res.n_evaluations} evaluations ({res.n_computed} computed, {res.n_reused} "
          f"reused) in {res.wall_time:.1f} s" + (f"; results in {args.out}" if args.out else ""))
    return 0 if res.success else 1


def _display(problem, name, value):
    var = problem.space[name]
    return f"{value * var.display_scale:.4g} {var.display_unit}"


# ---------------------------------------------------------------------------- sweep
def _floats(text: str) -> list:
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ParameterError(f"expected comma-separated numbers, got {text!r}") from None


def _design_arg(text: str, space) -> dict:
    """``start`` or ``W=300,La=1500,L1=500,L2=500`` (display units) -> {name: SI value}."""
    if text.strip().lower() == "start":
        return space.to_dict(space.start)
    out = {}
    for part in text.split(","):
        if "=" not in part:
            raise ParameterError(f"--design expects name=value pairs or 'start', got {text!r}")
        name, value = part.split("=", 1)
        var = space[name.strip()]
        try:
            out[var.name] = float(value) / var.display_scale
        except ValueError:
            raise ParameterError(f"--design: {name} = {value!r} is not a number") from None
    return space.to_dict(out)


def _sweep(args) -> int:
    from .problem import GripperProblem
    from .robustness import residual_fold_grid, sweep_residual_fold

    problem = GripperProblem(mode=args.mode)
    designs = [_design_arg(d, problem.space) for d in (args.design or ["start"])]
    groups = tuple(g.strip() for g in args.groups.split(",")) if args.groups else None
    grid = residual_fold_grid(_floats(args.values), creases=groups)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    bar = _bar(total=len(designs) * len(grid), desc="residual-fold sweep", disable=args.quiet)
    executor = _executor(args)
    try:
        frame = sweep_residual_fold(problem, designs, grid, executor=executor,
                                    log=out / "evaluations.csv",
                                    progress=lambda done, total: bar.update(done - bar.n))
    finally:
        bar.close()
        executor.close()
    frame.to_csv(out / "sweep.csv", index=False)
    cols = [c for c in frame.columns if c.startswith("residual_fold") or c in (
        "W [um]", "La [um]", "L1 [um]", "L2 [um]", "total_power [mW]", "feasible")]
    print(frame[cols].to_string(index=False))
    print(f"{len(frame)} points written to {out / 'sweep.csv'}")
    return 0


# ---------------------------------------------------------------------------- parser
def add_design_commands(sub) -> None:
    """Register ``gripper``, ``optimize`` and ``sweep`` on an argparse subparsers object."""
    gripper = sub.add_parser("gripper", help="gripper design tools")
    gsub = gripper.add_subparsers(dest="gripper_command", metavar="ACTION", required=True)
    ev = gsub.add_parser("evaluate", help="power to assemble then grip, per heated crease")
    for name, default in (("W", 200.0), ("L1", 1000.0), ("L2", 1000.0), ("La", 700.0)):
        ev.add_argument(f"--{name}", type=float, default=default, metavar="UM",
                        help=f"{name} in um (default {default:g})")
    ev.add_argument("--mode", choices=("bisect", "staircase"), default="bisect")
    ev.add_argument("--residual-fold", type=float, default=0.0, metavar="DEG",
                    help="residual fold of the actuated creases in degrees")
    ev.add_argument("--json", action="store_true", help="print the result as JSON")
    ev.set_defaults(func=_gripper_evaluate)

    opt = sub.add_parser("optimize", help="minimise the power of a gripper or Miura design")
    opt.add_argument("target", choices=("gripper", "miura"))
    opt.add_argument("--method", choices=METHODS, default="cd")
    opt.add_argument("--out", metavar="DIR", help="folder for the evaluation log (resumable) "
                                                  "and results")
    opt.add_argument("--max-evaluations", type=int, default=None, metavar="N")
    opt.add_argument("--mode", choices=("bisect", "staircase"), default="bisect")
    opt.add_argument("--residual-fold", type=float, default=0.0, metavar="DEG")
    opt.add_argument("--robust", metavar="DEG,DEG,...",
                     help="optimise the worst case over these residual folds (gripper), "
                          "e.g. --robust=-20,-10,0")
    opt.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    _parallel_options(opt)
    opt.set_defaults(func=_optimize)

    sweep = sub.add_parser("sweep", help="robustness sweeps")
    ssub = sweep.add_subparsers(dest="sweep_command", metavar="KIND", required=True)
    rf = ssub.add_parser("residual-fold", help="gripper power vs residual fold angle")
    rf.add_argument("--values", default="-20,-10,0", metavar="DEG,DEG,...",
                    help="residual folds in degrees, e.g. --values=-20,-10,0 (the default; "
                         "use the = form when the first value is negative)")
    rf.add_argument("--groups", metavar="base,arm", help="sweep crease groups independently "
                                                        "(product grid)")
    rf.add_argument("--design", action="append", metavar="start|W=..,La=..,L1=..,L2=..",
                    help="design in um (repeatable; default the start design)")
    rf.add_argument("--mode", choices=("bisect", "staircase"), default="bisect")
    rf.add_argument("--out", required=True, metavar="DIR")
    rf.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    _parallel_options(rf)
    rf.set_defaults(func=_sweep)
