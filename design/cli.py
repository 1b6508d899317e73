"""Command-line interface: ``etorigami``.

The CLI sits on top of both layers (simulator and design), so it lives here;
``simulator/`` never imports it. Subcommands:

* ``etorigami demo``: the main demo (single crease: residual fold, gravity, substrate contact).
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
    except EtorigamiError as exc:
        print(f"etorigami: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    np.seterr(all="ignore")
    sys.exit(main())
