"""Time 2000 theta-method steps of transient heat on the single fold (198 unknowns).

Three ways: ``integrate_heat`` on a fixed shape (one factorisation, the TransientHeat step);
``theta_step`` with the same matrices (the reused factorisation); and ``theta_step`` with K and
C re-assembled every step (what a coupled thermo-mechanical step pays when the shape moves).

Run: ``python benchmarks/bench_transient.py [--steps N]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from simulator import get_case
from simulator.schedules import SquareWave
from simulator.thermal import integrate_heat, thermal_model, theta_step
from simulator.thermal.transient import heat_system


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000)
    args = parser.parse_args(argv)
    model = get_case("single_fold").model
    tm, x, dt, n = thermal_model(model), model.mesh.nodes, 2e-6, args.steps
    power = {2: SquareWave(20e-3, period=1e-3, duty=0.5)}

    t0 = time.perf_counter()
    r = integrate_heat(tm, x, power, n * dt, dt)
    t_fixed = time.perf_counter() - t0

    system = heat_system(tm, x)
    q = np.zeros(tm.n_dof)
    q[:model.mesh.n_nodes] = tm.heat_vector([20e-3])
    q = q[system.free]
    T = np.zeros(len(system.free))
    t0 = time.perf_counter()
    for _ in range(n):
        T = theta_step(system.K, system.C, T, q, q, dt)
    t_reuse = time.perf_counter() - t0

    T = np.zeros(len(system.free))
    t0 = time.perf_counter()
    for k in range(n):
        s = heat_system(tm, x + 1e-9 * k)             # a "new" shape every step
        T = theta_step(s.K, s.C, T, q, q, dt)
    t_moving = time.perf_counter() - t0

    print(f"single fold, {tm.n_dof} unknowns, {n} steps of {dt:g} s ({r.assemblies} assembly)")
    print(f"{'integrate_heat, fixed shape':40s} {t_fixed:8.3f} s  {1e6 * t_fixed / n:8.1f} us/step")
    print(f"{'theta_step, same K and C':40s} {t_reuse:8.3f} s  {1e6 * t_reuse / n:8.1f} us/step")
    print(f"{'theta_step, re-assembled every step':40s} {t_moving:8.3f} s  "
          f"{1e6 * t_moving / n:8.1f} us/step")


if __name__ == "__main__":
    main()
