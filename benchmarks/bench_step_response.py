"""Time ``single_fold_step_response`` with 2000 fixed time steps (issue 10 target: < 5 s).

The case's ElectroThermal step (1 s on at 3 mW, 1 s off) with dt_min = dt_max = 1 ms, i.e.
exactly 2000 coupled time steps (heat, rest angles, dynamic mechanics), after self-fold and
gravity (not timed). Prints the wall time, the time per step, the heat assemblies and Newton
iterations. ``--shape-tol`` keeps the heat matrices while no node moved more than that [m]
(default the case's 5e-6; 0 re-assembles every step, about 1.8 times slower). About 80 % of
the time is the mechanics (EquilibriumSystem.evaluate with contact, ~2.7 per step).

Run: ``python benchmarks/bench_step_response.py [--steps N] [--shape-tol M] [--quasi-static]``
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from simulator import get_case, simulate


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--shape-tol", type=float, default=5e-6)
    parser.add_argument("--quasi-static", action="store_true")
    args = parser.parse_args(argv)
    dt = 2.0 / args.steps
    case = get_case("single_fold_step_response", dt=dt, dt_min=dt, dt_max=dt,
                    mechanics="quasi_static" if args.quasi_static else "dynamic")
    pre = simulate(case.model, case.steps[:-1])
    step = dataclasses.replace(case.steps[-1], shape_tol=args.shape_tol)
    t0 = time.perf_counter()
    res = simulate(case.model, [step], state=pre.state)
    wall = time.perf_counter() - t0
    s = res.steps[0]
    fold = np.degrees(res.fold_angle[:, 0])
    print(f"single_fold_step_response: {s.message}; {s.iterations} Newton iterations")
    print(f"wall time {wall:.2f} s ({1e3 * wall / args.steps:.2f} ms per step; target 2000 "
          f"steps < 5 s); peak fold {fold.max():.3f} deg, final {fold[-1]:.3f} deg")


if __name__ == "__main__":
    main()
