"""Thermal solve time of the integral heat loss against sheet size (issue 29, "At any size").

Flat Miura sheets of ``cells x cells`` cells (``miura_sheet_pattern``, SU-8/Au stack, every
crease heated at 1 mW, free in air), one steady solve with ``IntegralLoss(operator=...,
refinement=...)`` through ``ThermalModel.solve`` on the chosen path (``--operator
dense|fast|auto``) and refinement (``--refinement m``, ``--plain``: no Richardson
extrapolation). Each size runs in a fresh subprocess (numba compilation excluded by a warm-up
solve on a 2 x 2-cell sheet). Prints per size: triangles, sub-triangles (all levels), build +
solve time, MINRES iterations per level solve (fast path), far-field evaluations, and the
growth exponent of the time with the sub-triangle count, fitted over all sizes and pairwise
(1 = linear; the target is n log n, i.e. about 1.1 over these sizes).

The sheet's conduction is the T3 elements' (``--conduction t3``, the default here) so that
the loss's cost is measured: the integral loss's own default, the monotone conduction
(theory 4.9), builds its triangulation once per model (0.6 s for the 16 x 16-cell sheet, 4.0 s
for 36 x 36; ``--conduction monotone`` to include it).

With ``--cli CELLS`` it also times the whole CLI process heating a flat Miura sheet of
``CELLS x CELLS`` cells drawn as a plain FOLD file (``etorigami run FILE --heat all --power 1
--set thermal_steps=2``), once with the chains (``--loss-model chain``) and once with the
default (the integral loss; above the dense limit at m = 2 on its fast path), at each
``--power`` (default 0.1 and 1 mW per crease: below and far above the SU-8 limit with the
integral loss), and prints both times and their ratio (issue 29: at most 5x the chains').

Run: ``python benchmarks/bench_integral_scaling.py [--cells 4 6 8 12] [--operator fast]
[--refinement 1] [--plain] [--cli 36]``
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

_SNIPPET = """
import dataclasses, json, logging, sys, time
import numpy as np
from simulator import get_stack, stack_model
from simulator.geometry.example_patterns import miura_sheet_pattern
from simulator.thermal import IntegralLoss
from simulator.thermal import ThermalModel
cells, operator, m, plain = int(sys.argv[1]), sys.argv[2], int(sys.argv[3]), sys.argv[4] == "1"
conduction = sys.argv[5]
iterations = []
evaluations = [0]
class Count(logging.Handler):
    def emit(self, record):
        if "MINRES iterations" in record.getMessage():
            iterations.append(record.args[1])
from simulator.thermal import integral_fast
_far = integral_fast.FastSingleLayer.far
def far(self, p):
    evaluations[0] += 1
    return _far(self, p)
integral_fast.FastSingleLayer.far = far
log = logging.getLogger("simulator.thermal.integral_fast")
log.setLevel(logging.DEBUG)
log.addHandler(Count())
def model_of(c):
    p = miura_sheet_pattern(m=c, n=c)
    model = stack_model(p, get_stack("su8-au"), list(p.creases))
    extra = dict(extrapolation=False, correction_tol=0.0) if plain else {}
    prm = dataclasses.replace(model.thermal, substrate=None, conduction=conduction,
                              loss=IntegralLoss(operator=operator, refinement=m, **extra))
    return model, ThermalModel(model.mesh, prm)
for c in (2, cells):
    iterations.clear()
    evaluations[0] = 0
    model, tm = model_of(c)
    q = tm.heat_vector(np.full(model.mesh.n_creases, 1e-3))
    t0 = time.perf_counter()
    T = tm.solve(model.mesh.nodes, q)
    wall = time.perf_counter() - t0
levels = [m] if plain or m < 3 else [m, max(m // 2, 2)]
print(json.dumps(dict(cells=cells, triangles=len(model.mesh.triangles),
                      sub=len(model.mesh.triangles) * sum(k * k for k in levels), time=wall,
                      iterations=iterations[:] or None, evaluations=evaluations[0],
                      fast=bool(getattr(tm.integral, "fast", False)),
                      max_rise=float(T.max() - tm.params.room_temperature))))
"""


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, nargs="+", default=[4, 6, 8, 12])
    ap.add_argument("--operator", choices=("auto", "dense", "fast"), default="fast")
    ap.add_argument("--refinement", type=int, default=3)
    ap.add_argument("--plain", action="store_true", help="no Richardson extrapolation")
    ap.add_argument("--conduction", choices=("t3", "monotone"), default="t3",
                    help="the sheet's conduction (default t3: the loss's cost alone)")
    ap.add_argument("--cli", type=int, metavar="CELLS",
                    help="also time the CLI heating a CELLS x CELLS plain FOLD Miura sheet")
    ap.add_argument("--power", type=float, nargs="+", default=[0.1, 1.0], metavar="MW",
                    help="crease powers of the CLI timing [mW per crease] (default 0.1 1)")
    args = ap.parse_args(argv)
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    if args.cli:
        cli_times(args.cli, env, args.power)
    rows = []
    print(f"load: {os.getloadavg()[0]:.2f} (1-min average; 2 cores)")
    print(f"{'cells':>5} {'triangles':>9} {'sub-tri':>8} {'time [s]':>9} {'evals':>6} path  "
          "MINRES per level solve")
    for cells in args.cells:
        out = subprocess.run([sys.executable, "-c", _SNIPPET, str(cells), args.operator,
                              str(args.refinement), "1" if args.plain else "0", args.conduction],
                             capture_output=True, text=True, env=env, check=True)
        row = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append(row)
        print(f"{row['cells']:>5} {row['triangles']:>9} {row['sub']:>8} {row['time']:>9.2f} "
              f"{row['evaluations']:>6} {'fast ' if row['fast'] else 'dense'} "
              f"{row['iterations'] or '-'}", flush=True)
    if len(rows) > 1:
        n = np.log([r["sub"] for r in rows])
        t = np.log([r["time"] for r in rows])
        print(f"growth exponent of the time with the sub-triangle count: "
              f"{np.polyfit(n, t, 1)[0]:.2f} over all sizes; pairwise "
              + ", ".join(f"{(t[i + 1] - t[i]) / (n[i + 1] - n[i]):.2f}"
                          for i in range(len(rows) - 1)))


def cli_times(cells: int, env, powers=(0.1, 1.0)) -> None:
    """Whole-process wall and CPU time of ``etorigami run`` heating a plain FOLD Miura sheet,
    chains against the default (integral) loss, at each crease power of ``powers`` [mW], with
    the hottest crease (its mean temperature) each model reaches: at 1 mW per crease the integral
    loss puts the 36 x 36-cell sheet far above the SU-8 limit (the CLI warns; the sheet folds
    its creases to 140-170 deg), at 0.1 mW it stays below it."""
    import tempfile
    import time

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"miura{cells}.fold"
        code = ("import json, sys; from simulator.geometry.example_patterns import "
                "miura_sheet_pattern as m; from simulator.io.fold.writer import pattern_to_fold "
                "as f; d = f(m(m={0}, n={0})); json.dump({{k: v for k, v in d.items() if "
                "'etorigami' not in k}}, open(sys.argv[1], 'w'))").format(cells)
        subprocess.run([sys.executable, "-c", code, str(path)], env=env, check=True)
        for power in powers:
            times, cpu = {}, {}
            for loss in ("chain", "integral"):
                out = Path(tmp) / f"{loss}{power:g}"
                argv = [sys.executable, "-m", "design.cli", "run", str(path), "--heat", "all",
                        "--power", f"{power:g}", "--set", "thermal_steps=2", "-q", "--out",
                        str(out)] + (["--loss-model", "chain"] if loss == "chain" else [])
                before = os.times()
                t0 = time.perf_counter()
                subprocess.run(argv, env=env, check=True, capture_output=True)
                times[loss] = time.perf_counter() - t0
                after = os.times()
                cpu[loss] = (after.children_user + after.children_system
                             - before.children_user - before.children_system)
                hottest = _hottest(out / "creases.csv")
                print(f"CLI, {cells} x {cells} cells, {power:g} mW per crease, {loss}: "
                      f"{times[loss]:.1f} s wall, {cpu[loss]:.1f} s CPU (whole process); "
                      f"hottest crease (mean) {hottest:.0f} degC", flush=True)
            print(f"  integral / chains at {power:g} mW: {times['integral'] / times['chain']:.2f}x "
                  f"wall, {cpu['integral'] / cpu['chain']:.2f}x CPU (issue 29: <= 5x)", flush=True)


def _hottest(csv) -> float:
    """The hottest crease temperature [degC] at the end of a run's ``creases.csv``."""
    import pandas as pd

    frame = pd.read_csv(csv)
    return float(frame.loc[frame["step"] == frame["step"].max(), "temperature [degC]"].max())


if __name__ == "__main__":
    main()
