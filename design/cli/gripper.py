"""``etorigami gripper evaluate``: the power to assemble, then grip, of one gripper design, and
the verdict on the 1.2 T_g limit, judged on the crease centre-line mean as by ``run`` and the
design problems (:meth:`~design.devices.gripper.GripperResult.temperature_verdict`).

Lengths are given in micrometres and the residual fold in degrees.
"""

from __future__ import annotations

import json
import time

from ._common import CLIError, fold_deg, length_um

__all__ = ["add_gripper_commands"]

_LENGTHS = (("W", 200.0), ("L1", 1000.0), ("L2", 1000.0), ("La", 700.0))


def _design(args):
    """The :class:`~design.devices.gripper.GripperDesign` of the options, checked in CLI units."""
    from ..devices.gripper import GripperDesign

    si = {name: length_um(f"--{name}", getattr(args, name), field=f"GripperDesign.{name}")
          for name, _ in _LENGTHS}
    if args.W >= min(args.L1, args.L2, args.La):
        raise CLIError(f"--W = {args.W:g} um must be smaller than --L1, --L2 and --La "
                       f"(here {args.L1:g}, {args.L2:g}, {args.La:g} um)")
    return GripperDesign(**si, residual_fold=fold_deg("--residual-fold", args.residual_fold))


def _mw(value):
    return f"{value:8.3f} mW" if value is not None else "   not met"


def _gripper_evaluate(args) -> int:
    from ..devices.gripper import GripperHeatModel, evaluate_gripper

    design = _design(args)
    t0 = time.perf_counter()
    res = evaluate_gripper(design, mode=args.mode,
                           heat=GripperHeatModel(loss_model=args.loss_model))
    verdict = res.temperature_verdict()
    out = res.to_dict()
    out.update({"temperature_limit [degC]": verdict.limit.value,
                "temperature_status": verdict.status, "temperature_verdict": verdict.message,
                "wall_time [s]": round(time.perf_counter() - t0, 3)})
    ok = res.success
    if args.json:
        print(json.dumps(out, indent=2, default=float))
        return 0 if ok else 1
    print(f"gripper W={args.W:g} L1={args.L1:g} L2={args.L2:g} La={args.La:g} um, residual "
          f"fold {args.residual_fold:g} deg ({args.mode}, {args.loss_model} heat loss): "
          f"{'met' if ok else 'NOT MET'} - {res.message}"
          + ("" if verdict.success else "; the temperature limit is exceeded"))
    for stage in ("assembly", "grip"):
        print(f"  {stage:<9} {_mw(out[f'{stage}_power [mW]'])} per crease   "
              f"{out[f'{stage}_temperature [degC]']:7.2f} degC   "
              f"{out[f'{stage}_simulations']:4d} simulations")
    print(f"  total     {_mw(out['total_power [mW]'])}   ({out['wall_time [s]']:.2f} s)")
    print(f"temperature limit {verdict.status}: {verdict.message} (the stages' heated creases "
          "at their stopping powers)")
    print(verdict.information())
    return 0 if ok else 1


def _not_saved(args) -> str:
    return "interrupted: nothing saved (gripper evaluate keeps no log); run the same command again"


def add_gripper_commands(sub) -> None:
    """Register ``gripper evaluate`` on an argparse subparsers object."""
    gripper = sub.add_parser("gripper", help="gripper design tools")
    gsub = gripper.add_subparsers(dest="gripper_command", metavar="ACTION", required=True)
    ev = gsub.add_parser("evaluate", help="power to assemble then grip, per heated crease")
    for name, default in _LENGTHS:
        ev.add_argument(f"--{name}", type=float, default=default, metavar="UM",
                        help=f"{name} in um (default {default:g})")
    ev.add_argument("--mode", choices=("bisect", "staircase"), default="bisect")
    ev.add_argument("--residual-fold", type=float, default=0.0, metavar="DEG",
                    help="residual fold of the actuated creases in degrees, in (-180, 180]")
    ev.add_argument("--loss-model", choices=("integral", "chain"), default="integral",
                    help="heat loss to the air: the boundary-integral model over the "
                         "substrate (default; theory 4.7: nothing fitted, within 1.5 %% of "
                         "the 3-D FE on folded shapes) or the paper's fitted chains (its "
                         "optimisation's setting; 37-80 %% too cool, about 2.7 times faster)")
    ev.add_argument("--json", action="store_true", help="print the result as JSON")
    ev.set_defaults(func=_gripper_evaluate, interrupted=_not_saved, short=True)
