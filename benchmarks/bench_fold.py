"""Newton on a folding Miura sheet: time per iteration of a real fold increment, by solver.

Question: what does a Newton iteration cost on a large sheet that actually folds (not the
single iteration of ``bench_scaling.py`` at a perturbed flat state), with PARDISO and with
SuperLU?

Method: a Miura sheet of ``cells`` x ``cells`` cells (a = b = 1 mm, gamma = 60 deg, 10 um
SU-8 panels, 1 um creases 200 um wide), partly folded (extension ``--ext``, 0.9), panel 0
clamped; every crease's rest angle moves by ``--fold`` deg (1) along its Miura fold direction
in one increment of :func:`simulator.solvers.newton.follow_path`. Each solver runs in a fresh
subprocess (``ETORIGAMI_PARDISO=1`` / ``0``) after one warm-up evaluation; printed: Newton
iterations, time per iteration (assembly + solve), the solves' share, and the largest
displacement (both solvers must agree).

Run: ``python benchmarks/bench_fold.py [--cells 30 96] [--fold 1] [--ext 0.9]``
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_SNIPPET = """
import json, resource, sys, time
import numpy as np
import simulator.solvers.newton as newton_module
from simulator.solvers.newton import follow_path
from simulator.mechanics import equilibrium_system
sys.path.insert(0, sys.argv[4])
from bench_fold import folding_sheet
cells, fold, ext = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
model, rest, rest1 = folding_sheet(cells, ext, fold)
mesh = model.mesh
system = equilibrium_system(model)
u0, f = np.zeros((mesh.n_nodes, 3)), np.zeros(mesh.n_dof)
system.evaluate(u0, rest)                                   # warm-up (kernels, patterns)
solve_time = [0.0]
inner = newton_module.linear_solve


def timed(K, r, **options):
    t0 = time.perf_counter()
    out = inner(K, r, **options)
    solve_time[0] += time.perf_counter() - t0
    return out


newton_module.linear_solve = timed
t0 = time.perf_counter()
res = follow_path(system, u0, f, f, rest, rest1, 1)
wall = time.perf_counter() - t0
print(json.dumps(dict(nodes=mesh.n_nodes, dofs=int(system.n_free), success=bool(res.success),
                      iterations=int(res.iterations), wall=wall, solve=solve_time[0],
                      umax=float(np.abs(res.u).max()),
                      rss=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)))
"""


def folding_sheet(cells: int, ext: float = 0.9, fold_deg: float = 1.0):
    """A partly folded Miura sheet (extension ``ext``, panel 0 clamped) whose creases fold on
    by ``fold_deg`` along their Miura directions: ``(model, rest angles before, after)``."""
    import math

    import numpy as np

    from simulator.steps import initial_state
    from simulator.cases import miura_fold_signs
    from simulator.geometry.example_patterns import miura_vertices
    from simulator import BarHingeParameters, Pattern, Supports, make_model
    from simulator.materials import SU8

    a = b = 1e-3
    gamma = math.radians(60)
    v, p = miura_vertices(a, b, gamma, cells, cells, ext=ext)
    pattern = Pattern(v, p, crease_width=200e-6, crease_thickness=1e-6, panel_thickness=10e-6,
                      panel_material=SU8, crease_material=SU8)
    model = make_model(pattern, None, BarHingeParameters())
    model = make_model(model.mesh, Supports.nodes(model.mesh.panel_nodes(0)))
    mesh = model.mesh
    sign = np.zeros(mesh.n_creases)
    for crease, s in miura_fold_signs(a, b, gamma, cells, cells).items():
        sign[mesh.crease_row_of(crease)] = s
    rest = initial_state(model).spring_rest
    rest1 = rest.copy()
    crease = mesh.spring_crease >= 0
    rest1[crease] += sign[mesh.spring_crease[crease]] * math.radians(fold_deg)
    return model, rest, rest1


def run(cells: int, fold: float, ext: float, pardiso: bool) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT), ETORIGAMI_PARDISO="1" if pardiso else "0")
    out = subprocess.run([sys.executable, "-c", _SNIPPET, str(cells), str(fold), str(ext),
                          str(Path(__file__).resolve().parent)],
                         env=env, cwd=ROOT, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, nargs="+", default=[30, 96])
    ap.add_argument("--fold", type=float, default=1.0, help="fold increment [deg]")
    ap.add_argument("--ext", type=float, default=0.9, help="Miura extension (1 = flat)")
    args = ap.parse_args(argv)
    print(f"{'nodes':>7} {'DOFs':>7} {'solver':>8} {'iterations':>10} {'per iteration [s]':>17} "
          f"{'solves [%]':>10} {'peak RSS [GB]':>13} {'max |u| [m]':>13}")
    for cells in args.cells:
        for pardiso in (True, False):
            r = run(cells, args.fold, args.ext, pardiso)
            status = "" if r["success"] else "  (failed)"
            print(f"{r['nodes']:>7} {r['dofs']:>7} {'PARDISO' if pardiso else 'SuperLU':>8} "
                  f"{r['iterations']:>10} {r['wall'] / max(r['iterations'], 1):>17.3f} "
                  f"{100 * r['solve'] / r['wall']:>10.0f} {r['rss'] / 1e9:>13.2f} "
                  f"{r['umax']:>13.6e}{status}", flush=True)


if __name__ == "__main__":
    main()
