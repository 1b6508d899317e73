"""Command-line interface: ``etorigami``.

The CLI sits on top of both layers (simulator and design), so it lives here;
``simulator/`` never imports it. Subcommands:

* ``etorigami demo``: the main demo (single crease: residual fold, gravity, substrate contact);
* ``etorigami cases``: the paper's cases with their parameters, defaults and units;
* ``etorigami run CASE [--set name=value ...] --out DIR``: run a case and write its results;
* ``etorigami gripper evaluate``, ``etorigami optimize``, ``etorigami sweep residual-fold``: the
  design tools (:mod:`design.cli_design`).
"""

from __future__ import annotations

import argparse
import logging
import sys
import time

import numpy as np

from simulator import __version__
from simulator.errors import EtorigamiError

__all__ = ["main"]


def _demo(args) -> int:
    from simulator.demo import single_fold_demo

    t0 = time.perf_counter()
    report = single_fold_demo(residual_fold_deg=args.residual_fold, gravity=not args.no_gravity)
    wall = time.perf_counter() - t0
    mesh = report["model"].mesh
    print(f"etorigami {__version__} demo: single crease on a substrate")
    print(f"  mesh: {mesh.n_nodes} nodes, {len(mesh.bars)} bars, {len(mesh.springs)} springs, "
          f"{len(mesh.triangles)} triangles")
    print(f"  {'step':<12}{'status':<12}{'increments':>11}{'Newton its':>12}{'fold [deg]':>12}"
          f"{'tip z [um]':>12}{'contacts':>10}")
    for row in report["steps"]:
        print(f"  {row['step']:<12}{row['status']:<12}{row['increments']:>11}{row['iterations']:>12}"
              f"{row['fold_deg']:>12.3f}{row['tip_z_um']:>12.2f}{row['contacts']:>10}")
    print(f"  wall time {wall:.2f} s")
    return 0 if all(r["status"] == "converged" for r in report["steps"]) else 1


def _parse_value(text: str):
    low = text.strip().lower()
    if low in ("true", "yes", "on"):
        return True
    if low in ("false", "no", "off"):
        return False
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def _overrides(pairs, case_name):
    import inspect

    from simulator.cases import CASES, get_case

    fn = CASES.get(case_name.replace("-", "_"))
    if fn is None:
        get_case(case_name)                     # raises the unknown-case error
    params = inspect.signature(fn).parameters
    out = {}
    for pair in pairs or []:
        if "=" not in pair:
            raise EtorigamiCLIError(f"--set expects name=value, got {pair!r}")
        name, text = pair.split("=", 1)
        name = name.strip().replace("-", "_")
        if name not in params:
            raise EtorigamiCLIError(f"case {case_name!r} has no parameter {name!r}; "
                                    f"parameters: {', '.join(params)}")
        value, default = _parse_value(text), params[name].default
        if isinstance(default, bool) and not isinstance(value, bool):
            raise EtorigamiCLIError(f"{name} expects true or false, got {text!r}")
        if isinstance(default, int) and not isinstance(default, bool) and not isinstance(value, int):
            raise EtorigamiCLIError(f"{name} expects an integer, got {text!r}")
        if isinstance(default, float) and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if isinstance(default, (int, float)) and not isinstance(value, (int, float)):
            raise EtorigamiCLIError(f"{name} expects a number, got {text!r}")
        out[name] = value
    return out


class EtorigamiCLIError(Exception):
    """A command-line usage error (reported in one line)."""


def _cases(args) -> int:
    from simulator.cases import describe_cases

    for name, doc, params in describe_cases():
        print(f"{name.replace('_', '-')}: {doc}")
        for pname, default, unit in params:
            unit = f" [{unit}]" if unit and unit != "-" else ""
            print(f"    {pname} = {default!r}{unit}")
    return 0


def _run(args) -> int:
    from tqdm import tqdm

    from simulator.cases import get_case

    overrides = _overrides(args.set, args.case)
    case = get_case(args.case, **overrides)
    bar = None

    def progress(done, total):
        nonlocal bar
        if bar is None or bar.total != total:
            if bar is not None:
                bar.close()
            bar = tqdm(total=total, desc=case.name, unit="inc", disable=args.quiet)
        bar.update(done - bar.n)

    t0 = time.perf_counter()
    result = case.run(progress=progress)
    if bar is not None:
        bar.close()
    out = result.save(args.out, {"case": case.name, "parameters": case.parameters})
    frame = result.to_frame()
    last = frame[frame["step"] == frame["step"].max()]
    print(f"{case.name}: {result.status} ({result.message}) in {time.perf_counter() - t0:.1f} s; "
          f"results in {out}")
    print(last[["crease", "power [mW]", "fold_angle [deg]", "temperature [degC]",
                "temperature_max [degC]"]].to_string(index=False))
    return 0 if result.success else 1


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="etorigami",
        description="Simulation and design of electro-thermally actuated origami.")
    parser.add_argument("--version", action="version", version=f"etorigami {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log solver progress")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    demo = sub.add_parser("demo", help="run the main demo: a single crease with a residual fold "
                                       "resting on a substrate under gravity")
    demo.add_argument("--residual-fold", type=float, default=-10.0, metavar="DEG",
                      help="residual fold angle of the crease in degrees (default -10)")
    demo.add_argument("--no-gravity", action="store_true", help="switch gravity off")
    demo.set_defaults(func=_demo)
    cases = sub.add_parser("cases", help="list the paper's cases with parameters and defaults")
    cases.set_defaults(func=_cases)
    run = sub.add_parser("run", help="run a case and write creases.csv, nodes.npz, meta.json")
    run.add_argument("case", help="case name, e.g. single-fold (see 'etorigami cases')")
    run.add_argument("--set", action="append", metavar="NAME=VALUE",
                     help="override a case parameter (repeatable), e.g. --set gravity=true")
    run.add_argument("--out", required=True, metavar="DIR", help="output folder")
    run.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    run.set_defaults(func=_run)
    from .cli_design import add_design_commands

    add_design_commands(sub)
    return parser


def main(argv=None) -> int:
    """Entry point of the ``etorigami`` command; returns the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return args.func(args)
    except (EtorigamiError, EtorigamiCLIError) as exc:
        print(f"etorigami: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:                       # output piped into e.g. `head`
        sys.stderr.close()
        return 0


if __name__ == "__main__":  # pragma: no cover
    np.seterr(all="ignore")
    sys.exit(main())
