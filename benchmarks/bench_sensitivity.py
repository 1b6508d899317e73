"""Cost of one adjoint gradient (simulator.sensitivity, theory 12.3) against the simulation it
differentiates, on the single and double fold and on Miura lifters over a substrate.

Issue 32 asks that the gradient of one objective with respect to 100 parameters cost at most
twice the final converged solve it differentiates. Both are CPU times of this process.

Run: ``python benchmarks/bench_sensitivity.py`` (``--quick``: without the 8 x 8-cell sheet)
"""

from __future__ import annotations

import sys
import time

import numpy as np

from simulator import Heat, simulate
from simulator.cases import get_case
from simulator.sensitivity import FoldAngle, NodeCoordinate, differentiate

CASES = [("single_fold", {}), ("double_fold", {}),
         ("miura_lifter", {"cells_x": 4, "cells_y": 4, "substrate": True, "thermal_steps": 20}),
         ("miura_lifter", {"cells_x": 8, "cells_y": 8, "substrate": True, "thermal_steps": 20})]


def _settled(case):
    """The case's steps with its heating step's coupling "settled" (a steady end)."""
    heat = case.steps[-1]
    return [*case.steps[:-1], Heat(heat.power, increments=heat.increments, coupling="settled")]


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    cases = CASES[:-1] if "--quick" in argv else CASES
    print(f"{'case':<14}{'settings':<62}{'parameters':>11}{'gradient [s]':>14}"
          f"{'simulation [s]':>16}   status")
    for name, kw in cases:
        case = get_case(name, **kw)
        steps = _settled(case)
        t0 = time.process_time()
        result = simulate(case.model, steps)
        simulation = time.process_time() - t0
        state = result.steps[-1].state
        objective = (FoldAngle(int(case.model.mesh.crease_ids[-1])) if name != "miura_lifter"
                     else NodeCoordinate(int(np.argmax(np.abs(state.u[:, 2]))), "z"))
        t0 = time.process_time()
        g = differentiate(result, objective)
        gradient = time.process_time() - t0
        print(f"{name:<14}{str(kw):<62}{len(g.gradient):>11}{gradient:>14.3f}"
              f"{simulation:>16.2f}   {g.status}")



if __name__ == "__main__":
    main()
