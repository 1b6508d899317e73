"""Time the 20 lowest natural modes of a flat Miura sheet of ~10^4 nodes.

The sheet (``miura_sheet_pattern``, m x n cells, SU-8, panel 0 clamped) is linearised about its
flat state; :func:`simulator.solvers.modes.natural_modes` assembles the tangent, lumps the masses and runs
the sparse shift-invert eigen-solver. Prints the node count, DOFs, wall time and the lowest
frequencies. Target (issue 10): under 10 s for 20 modes at 10^4 nodes.

Run: ``python benchmarks/bench_modes.py [--cells 30] [--count 20]``
"""

from __future__ import annotations

import argparse
import time

from simulator import Supports, make_model, natural_modes
from simulator.example_patterns import miura_sheet_pattern


def make_miura_model(cells: int):
    """Flat m x m Miura sheet with the corners and centre of panel 0 clamped."""
    model = make_model(miura_sheet_pattern(m=cells, n=cells))
    return make_model(model.mesh, Supports.nodes(model.mesh.panel_nodes(0)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=30)
    parser.add_argument("--count", type=int, default=20)
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    model = make_miura_model(args.cells)
    t1 = time.perf_counter()
    res = natural_modes(model, count=args.count)
    t2 = time.perf_counter()
    print(f"Miura {args.cells}x{args.cells}: {model.mesh.n_nodes} nodes, {model.mesh.n_dof} DOFs; "
          f"model built in {t1 - t0:.2f} s")
    print(f"{res.count} modes ({res.solver}, {res.status}) in {t2 - t1:.2f} s "
          f"(natural_modes wall time {res.wall_time:.2f} s)")
    print("frequencies [Hz]:", " ".join(f"{f:.4g}" for f in res.frequency))


if __name__ == "__main__":
    main()
