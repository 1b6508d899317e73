"""Time one Newton iteration (assembly of forces + tangent, and the linear solve).

Meshes: the reference single fold with contact on, the gripper with contact on, and flat
Miura sheets from ~10^3 to ~10^4 nodes (contact off), in a slightly perturbed state so that
every kernel does real work. Prints a table and the growth exponent of the time per
iteration with node count between ~10^3 and ~10^4 nodes (1 = linear).

Run: ``python benchmarks/bench_newton.py [--repeat N]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from simulator.cases import single_fold_model
from simulator import (BarHingeParameters, ContactParameters, SelfFold, Supports, make_model,
                       simulate)
from simulator.example_patterns import gripper_pattern, miura_sheet_pattern
from simulator.mechanics import equilibrium_system
from simulator.linalg import solve as _solve_linear


def _time_iteration(model, u, rest, repeat):
    system = equilibrium_system(model)
    f_ext = np.zeros(model.mesh.n_dof)
    t_eval, t_solve = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        ev = system.evaluate(u, rest)
        r = (f_ext - ev.f_int)[system.free]
        t1 = time.perf_counter()
        du = system.solve_dense_tangent(ev, r) if isinstance(ev.tangent, np.ndarray) \
            else _solve_linear(ev.K, r)             # what Newton does
        t2 = time.perf_counter()
        assert du is not None
        t_eval.append(t1 - t0)
        t_solve.append(t2 - t1)
    return float(np.median(t_eval)), float(np.median(t_solve)), ev.n_contacts


def _single_fold():
    model = single_fold_model(contact=True)
    res = simulate(model, [SelfFold({2: np.radians(-40)}, increments=10)])  # rests on contact
    return model, res.state.u, res.state.spring_rest


def _gripper():
    pattern = gripper_pattern()
    mesh_supports = Supports.nodes([4, 5, 6, 7, 37, 20, 21, 22, 23, 41])
    model = make_model(pattern, mesh_supports, BarHingeParameters(diagonal_rate=100),
                       contact=ContactParameters())
    res = simulate(model, [SelfFold({2: 0.3, 5: 0.3}, increments=5)])
    return model, res.state.u, res.state.spring_rest


def _miura(cells):
    pattern = miura_sheet_pattern(m=cells, n=cells)
    model = make_model(pattern, None, BarHingeParameters())
    panel0 = model.mesh.panel_nodes(0)
    model = make_model(model.mesh, Supports.nodes(panel0))
    rng = np.random.default_rng(0)
    u = rng.normal(size=(model.mesh.n_nodes, 3)) * 1e-9
    u[panel0] = 0
    from simulator.steps import initial_state
    return model, u, initial_state(model).spring_rest


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=30)
    args = parser.parse_args(argv)
    cases = [("single fold, contact", _single_fold), ("gripper, contact", _gripper)]
    cases += [(f"Miura {c}x{c}", (lambda c=c: _miura(c))) for c in (10, 15, 20, 25, 30, 32)]
    rows = []
    print(f"{'mesh':<22}{'nodes':>7}{'DOFs':>8}{'contacts':>9}{'assembly [ms]':>15}"
          f"{'solve [ms]':>12}{'iteration [ms]':>16}")
    for name, build in cases:
        model, u, rest = build()
        repeat = args.repeat if model.mesh.n_nodes < 2000 else max(5, args.repeat // 5)
        te, ts, nc = _time_iteration(model, u, rest, repeat)
        rows.append((name, model.mesh.n_nodes, te + ts))
        print(f"{name:<22}{model.mesh.n_nodes:>7}{model.mesh.n_dof:>8}{nc:>9}{te * 1e3:>15.3f}"
              f"{ts * 1e3:>12.3f}{(te + ts) * 1e3:>16.3f}")
    miura = [(n, t) for name, n, t in rows if name.startswith("Miura")]
    n = np.array([m[0] for m in miura], float)
    t = np.array([m[1] for m in miura])
    slope = np.polyfit(np.log(n), np.log(t), 1)[0]
    print(f"\nMiura: time per iteration grows as nodes^{slope:.2f} between {int(n[0])} and "
          f"{int(n[-1])} nodes (ratio {t[-1] / t[0]:.1f}x for {n[-1] / n[0]:.1f}x nodes)")


if __name__ == "__main__":
    main()
