"""``etorigami optimize``: minimise the power of a gripper or Miura design.

With ``--out DIR`` every evaluation is appended to ``DIR/evaluations.csv`` as it finishes; the
same command run again reuses them (an interrupted run resumes where it stopped).
"""

from __future__ import annotations

import argparse
import os
import sys

from simulator import EtorigamiError

from ._common import (RESIDUAL_LIMIT_DEG, BestSoFar, add_parallel_options, executor,
                      floats, fold_deg, progress_bar, resume_message, resuming_line)

__all__ = ["add_optimize_command"]


class _Methods:
    """The ``--method`` choices: the optimiser registry (:func:`design.optimizers`), read
    when argparse checks a value or prints the help, so building the parser imports no
    optimiser (``etorigami --version`` stays light) and a registered method is a choice."""

    def __iter__(self):
        from ..core.optimize import optimizers

        return iter(optimizers())

    def __contains__(self, name) -> bool:
        from ..core.optimize import get_optimizer

        try:
            get_optimizer(name)
        except EtorigamiError:
            return False
        return True

    @staticmethod
    def help() -> str:
        """The methods, each with its aliases and description."""
        from ..core.optimize import optimizers

        return "; ".join(f"{name}{' (' + ', '.join(o.aliases) + ')' if o.aliases else ''}: "
                         f"{o.description}" for name, o in optimizers().items())


class _MethodsHelp(argparse.HelpFormatter):
    """Fills ``%(methods)s`` of the ``--method`` help from the registry when printed."""

    def _get_help_string(self, action):
        text = super()._get_help_string(action)
        return text.replace("%(methods)s", _Methods.help()) if isinstance(
            action.choices, _Methods) else text


def _problem(args):
    from ..devices.gripper_problem import GripperProblem

    if args.target == "miura":
        from ..devices.miura import MiuraDesign, MiuraProblem
        return MiuraProblem(base=MiuraDesign(loss_model=args.loss_model))
    from ..devices.gripper import GripperHeatModel

    base = GripperProblem(mode=args.mode, heat=GripperHeatModel(loss_model=args.loss_model),
                          residual_fold=fold_deg("--residual-fold", args.residual_fold))
    if args.robust:
        from ..analysis.robustness import RobustGripperProblem
        folds = [fold_deg("--robust", v, within=RESIDUAL_LIMIT_DEG)
                 for v in floats("--robust", args.robust)]
        return RobustGripperProblem(base, folds)
    return base


def _display(problem, name, value):
    var = problem.space[name]
    return f"{value * var.display_scale:.4g} {var.display_unit}"


def _optimize(args) -> int:
    from ..core.optimize import get_optimizer, optimize

    problem = _problem(args)
    ex = executor(args)
    options = {"parallel_candidates": True} if (args.parallel or args.dask) and (
        "parallel_candidates" in get_optimizer(args.method).options) else {}
    if args.out:
        line = resuming_line(os.path.join(args.out, "evaluations.csv"), args.max_evaluations)
        if line:
            print(line, file=sys.stderr, flush=True)
    best = BestSoFar()
    try:
        with progress_bar(desc=f"{args.target} {args.method}", disable=args.quiet) as bar:
            def callback(evaluation):
                best.add(evaluation)
                bar.update(1)
                bar.set_postfix_str(f"best {best}", refresh=False)

            res = optimize(problem, args.method, out=args.out, executor=ex,
                           max_evaluations=args.max_evaluations, callback=callback, **options)
    finally:
        ex.close()
    x = ", ".join(f"{k}={_display(problem, k, v)}" for k, v in res.x.items())
    print(f"{args.method}: {res.status} ({res.message}); best {res.objective * 1e3:.4g} mW at "
          f"{x}; {res.n_evaluations} evaluations ({res.n_computed} computed, {res.n_reused} "
          f"reused) in {res.wall_time:.1f} s" + (f"; results in {args.out}" if args.out else ""))
    return 0 if res.success else 1


def _interrupted(args) -> str:
    return resume_message(os.path.join(args.out, "evaluations.csv") if args.out else None)


def add_optimize_command(sub) -> None:
    """Register ``optimize`` on an argparse subparsers object."""
    opt = sub.add_parser("optimize", help="minimise the power of a gripper or Miura design",
                         formatter_class=_MethodsHelp)
    opt.add_argument("target", choices=("gripper", "miura"))
    opt.add_argument("--method", choices=_Methods(), default="cd", metavar="METHOD",
                     help="optimiser (default cd), one of the registered methods: %(methods)s")
    opt.add_argument("--out", metavar="DIR", help="folder for the evaluation log (resumable) "
                                                  "and results")
    opt.add_argument("--max-evaluations", type=int, default=None, metavar="N")
    opt.add_argument("--mode", choices=("bisect", "staircase"), default="bisect")
    opt.add_argument("--loss-model", choices=("integral", "chain"), default="integral",
                     help="heat loss: the boundary-integral model over the substrate "
                          "(default; theory 4.7) or the paper's fitted chains (its "
                          "optimisation's setting)")
    opt.add_argument("--residual-fold", type=float, default=0.0, metavar="DEG",
                     help="residual fold of the actuated creases in degrees, in (-180, 180]")
    opt.add_argument("--robust", metavar="DEG,DEG,...",
                     help="optimise the worst case over these residual folds (gripper), "
                          "e.g. --robust=-20,-10,0")
    add_parallel_options(opt)
    opt.set_defaults(func=_optimize, interrupted=_interrupted)
