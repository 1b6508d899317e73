"""Wall time of the paper's cases at their default settings.

The paper reports (MATLAB reference, laptop i7-8750H / desktop i9-10900K): single crease 13 s
for 250 thermal increments, double crease 18 s, crane about 30 s, Miura lifter about 50 s.

Run: ``python benchmarks/bench_cases.py``
"""

from __future__ import annotations

import time

from simulator.cases import get_case

CASES = [("single_fold", {}, "13 s (250 increments)"),
         ("single_fold", {"residual_fold_deg": -10, "gravity": True, "thermal_steps": 250}, "13 s"),
         ("double_fold", {}, "18 s"),
         ("crane", {}, "~30 s"),
         ("crane", {"deactivated": True}, "~30 s"),
         ("miura_lifter", {}, "~50 s"),
         ("miura_lifter", {"substrate": True}, "~50 s"),
         ("miura_lifter", {"cells_x": 4, "cells_y": 2, "substrate": True}, "-")]


def main():
    print(f"{'case':<14}{'settings':<58}{'increments':>11}{'Newton its':>11}{'wall [s]':>10}"
          f"{'per increment [ms]':>20}   paper (MATLAB)")
    for name, kw, paper in CASES:
        case = get_case(name, **kw)
        t0 = time.perf_counter()
        res = case.run()
        wall = time.perf_counter() - t0
        heat = res.steps[-1]
        print(f"{name:<14}{str(kw):<58}{heat.increments:>11}{heat.iterations:>11}{wall:>10.2f}"
              f"{1e3 * heat.wall_time / max(heat.increments, 1):>20.2f}   {paper}"
              + ("" if res.success else f"   [{res.status}: {res.message}]"))


if __name__ == "__main__":
    main()
