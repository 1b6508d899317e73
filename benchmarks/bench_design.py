"""Design-layer benchmarks (issue: design layer; figures go into docs/performance.md).

1. One gripper evaluation (start design) in ``bisect`` and ``staircase`` modes
   (target: bisect <= 2 s; the paper: about 20 s per simulation).
2. The paper's full coordinate-descent run (15 cycles from the start design), serial and with
   the minus/plus candidates on 2 processes (target: <= 60 s on 2 cores; the paper: ~25 min).
3. A 100-point residual-fold sweep (start design, 0 to -20 deg) on 1 and 2 processes
   (target: near-linear speed-up).

Run: ``python benchmarks/bench_design.py`` (about 4 minutes on 2 cores); ``--quick`` skips
the serial coordinate descent.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from design import (GripperDesign, GripperProblem, evaluate_gripper, make_executor, optimize,
                    residual_fold_grid, sweep_residual_fold)


def _timed(fn, repeat=1):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def bench_evaluation():
    evaluate_gripper(GripperDesign(W=250e-6, La=900e-6, L1=800e-6, L2=900e-6))   # JIT warm-up
    for mode in ("bisect", "staircase"):
        wall, res = _timed(lambda: evaluate_gripper(GripperDesign(), mode=mode), repeat=3)
        sims = res.assembly.simulations + res.grip.simulations
        print(f"gripper evaluation, start design, {mode:<9}: {wall:6.2f} s  ({sims} simulations, "
              f"{1e3 * res.assembly.power_per_crease:.3f} + {1e3 * res.grip.power_per_crease:.3f}"
              " mW per crease)")


def bench_cd(serial: bool):
    runs = [("2 processes, parallel candidates", "process", True)]
    if serial:
        runs.insert(0, ("serial", "serial", False))
    for label, kind, parallel in runs:
        with make_executor(kind, workers=2 if kind == "process" else None) as ex:
            if kind == "process":       # start the workers before the clock
                ex.map(_warm, [0, 1])
            wall, res = _timed(lambda: optimize(GripperProblem(), "cd", executor=ex,
                                                max_cycles=15, parallel_candidates=parallel))
        d = res.x
        print(f"coordinate descent, {label:<33}: {wall:6.1f} s  ({res.n_evaluations} evaluations, "
              f"{1e3 * res.objective:.3f} mW, W {1e6 * d['W']:.0f} La {1e6 * d['La']:.0f} "
              f"L1 {1e6 * d['L1']:.0f} L2 {1e6 * d['L2']:.0f} um, {res.status})")


def _warm(_):
    evaluate_gripper(GripperDesign(W=250e-6, La=900e-6, L1=800e-6, L2=900e-6))
    return 0


def bench_sweep(points: int = 100):
    grid = residual_fold_grid(np.linspace(0.0, -20.0, points))
    walls = {}
    for workers in (1, 2):
        kind = "serial" if workers == 1 else "process"
        with make_executor(kind, workers=None if workers == 1 else workers) as ex:
            ex.map(_warm, list(range(workers)))
            walls[workers], df = _timed(lambda: sweep_residual_fold(GripperProblem(), None, grid,
                                                                    executor=ex))
        print(f"residual-fold sweep, {points} points, {workers} process(es): "
              f"{walls[workers]:6.1f} s  ({int(df['feasible'].sum())} feasible)")
    print(f"speed-up 1 -> 2 processes: {walls[1] / walls[2]:.2f}x")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the serial coordinate descent")
    args = ap.parse_args()
    bench_evaluation()
    bench_cd(serial=not args.quick)
    bench_sweep()


if __name__ == "__main__":
    main()
