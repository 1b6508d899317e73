"""Newton iteration cost against mesh size: flat Miura sheets of ~1e3, 1e4 and 1e5 nodes.

One iteration = assembly of internal force and tangent on the free DOFs plus the linear
solve (the ladder, ``simulator.linalg.solve``), on the sheet of ``benchmarks/bench_versus.py``
(``miura_sheet_pattern(m=cells, n=cells)``, panel 0 clamped, random displacements ~1e-9 m).
Every size runs in a fresh subprocess, so its peak RSS is that of one process holding one
sheet. Prints per size: build time of the equilibrium system, the first iteration (it
computes the cached fill-reducing ordering), the best of ``--repeat`` later iterations
(assembly, solve, total) and peak RSS; then the growth exponent of the iteration time with
node count, fitted over all sizes and pairwise (1 = linear).

``--old-tree PATH`` also runs an older checkout (with the same module layout, e.g. one made
by ``git archive <commit> | tar -x -C PATH``), alternating old and new per size.

Run: ``python benchmarks/bench_scaling.py [--cells 10 30 96] [--repeat 3] [--old-tree PATH]``
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
import json, resource, sys, time
import numpy as np
from simulator import initial_state
from simulator.mechanics import equilibrium_system
from simulator.geometry.example_patterns import miura_sheet_pattern
from simulator.model.model import Supports, make_model
from simulator.linalg import solve as _solve_linear
from simulator.model.properties import BarHingeParameters
cells, repeat = int(sys.argv[1]), int(sys.argv[2])
model = make_model(miura_sheet_pattern(m=cells, n=cells), None, BarHingeParameters())
panel0 = model.mesh.panel_nodes(0)
model = make_model(model.mesh, Supports.nodes(panel0))
u = np.random.default_rng(0).normal(size=(model.mesh.n_nodes, 3)) * 1e-9
u[panel0] = 0
rest = initial_state(model).spring_rest
t0 = time.perf_counter()
system = equilibrium_system(model)
build = time.perf_counter() - t0
runs = []
for _ in range(repeat + 1):
    t0 = time.perf_counter()
    ev = system.evaluate(u, rest)
    t1 = time.perf_counter()
    du = _solve_linear(ev.K, -ev.f_int[system.free])
    runs.append((t1 - t0, time.perf_counter() - t1))
first, rest_runs = runs[0], runs[1:]
best = min(rest_runs, key=sum)
print(json.dumps(dict(nodes=model.mesh.n_nodes, dofs=int(system.n_free), build=build,
                      first=sum(first), assembly=best[0], solve=best[1], iteration=sum(best),
                      du_norm=float(np.linalg.norm(du)),
                      rss=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)))
"""


def run_size(tree: Path, cells: int, repeat: int) -> dict:
    """One sheet in a fresh interpreter on the checkout ``tree``; its figures as a dict."""
    env = dict(os.environ, PYTHONPATH=str(tree), PYTHONDONTWRITEBYTECODE="1")
    out = subprocess.run([sys.executable, "-c", _SNIPPET, str(cells), str(repeat)], env=env,
                         cwd=tree, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def exponents(nodes, times) -> tuple[float, list[float]]:
    """Slope of log(time) against log(nodes): least squares over all, and per neighbour pair."""
    x, y = np.log(np.asarray(nodes, float)), np.log(np.asarray(times, float))
    fit = float(np.polyfit(x, y, 1)[0]) if len(x) > 1 else float("nan")
    return fit, [float((y[i + 1] - y[i]) / (x[i + 1] - x[i])) for i in range(len(x) - 1)]


def _table(label: str, rows: list[dict]) -> None:
    print(f"\n{label}")
    print(f"{'nodes':>7}{'DOFs':>8}{'build [s]':>11}{'first [s]':>11}{'assembly [s]':>14}"
          f"{'solve [s]':>11}{'iteration [s]':>15}{'peak RSS [GB]':>15}{'|du| [m]':>14}")
    for r in rows:
        print(f"{r['nodes']:>7}{r['dofs']:>8}{r['build']:>11.3f}{r['first']:>11.3f}"
              f"{r['assembly']:>14.4f}{r['solve']:>11.4f}{r['iteration']:>15.4f}"
              f"{r['rss'] / 1e9:>15.2f}{r['du_norm']:>14.6e}")
    fit, pairs = exponents([r["nodes"] for r in rows], [r["iteration"] for r in rows])
    print(f"iteration time ~ nodes^{fit:.2f} (fit over {len(rows)} sizes); pairwise: "
          + ", ".join(f"{a['nodes']}->{b['nodes']}: {p:.2f}"
                      for a, b, p in zip(rows, rows[1:], pairs)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, nargs="+", default=[10, 30, 96],
                        help="cells per side of each sheet (default 10 30 96: ~1e3, 1e4, 1e5 "
                             "nodes)")
    parser.add_argument("--repeat", type=int, default=3, help="timed iterations after the first")
    parser.add_argument("--old-tree", type=Path, help="also run this older checkout")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error(f"--repeat = {args.repeat} must be >= 1")
    new, old = [], []
    for cells in args.cells:
        if args.old_tree:
            old.append(run_size(args.old_tree, cells, args.repeat))
        new.append(run_size(ROOT, cells, args.repeat))
    if old:
        _table(f"old tree {args.old_tree}", old)
    _table(f"this tree {ROOT}", new)


if __name__ == "__main__":
    main()
