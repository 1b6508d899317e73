"""Cost of one adjoint gradient (simulator.sensitivity, theory 12.3) against the solves it
differentiates, on the single and double fold and on Miura lifters over a substrate, with the
chain heat loss and (the single and double fold, the 2 x 2-cell lifter) the integral loss at its
defaults (extrapolated, monotone conduction, refined sheet).

Issue 32 asks that the gradient of one objective with respect to 100 parameters cost at most
twice "the final converged solve it differentiates". Printed, CPU times of this process (each
the best of ``REPEATS`` runs, the whole simulation once):

- ``gradient``: :func:`~simulator.sensitivity.differentiate` of one objective with respect to
  every parameter kind (the coupled Jacobian assembled, equilibrated, factored, one transposed
  solve, the parameter columns);
- ``final increment``: the final converged solve, defined as the heating step's last
  increment re-solved: from the state one increment before the end (the step's first n - 1
  increments, staggered as in the step), one ``Heat`` increment with ``coupling="settled"``
  to the final power (its Newton iterations with their factorisations, and the coupling loop's
  thermal solves until the temperatures settle);
- ``one solve``: the least a solve of that state can cost, one assembly, factorisation and
  solve of the equilibrium system's tangent at the converged state plus one thermal solve on
  its shape (one Newton iteration and one heat balance);
- ``simulation``: the whole simulation (every step and increment);

and the ratios ``gradient / final increment`` (the acceptance's) and ``gradient / one solve``.

Run: ``python benchmarks/bench_sensitivity.py`` (``--quick``: without the 8 x 8-cell sheet)
"""

from __future__ import annotations

import sys
import time

import numpy as np

from simulator import Heat, simulate
from simulator.cases import get_case
from simulator.linalg.ladder import solve as linear_solve
from simulator.mechanics.equilibrium import equilibrium_system
from simulator.sensitivity import FoldAngle, NodeCoordinate, differentiate
from simulator.thermal import thermal_model

_INTEGRAL = {"loss_model": "integral"}
CASES = [("single_fold", {}), ("double_fold", {}),
         ("miura_lifter", {"cells_x": 4, "cells_y": 4, "substrate": True, "thermal_steps": 20}),
         ("single_fold", _INTEGRAL), ("double_fold", _INTEGRAL),
         ("miura_lifter", {"cells_x": 2, "cells_y": 2, "substrate": True, "thermal_steps": 20,
                           **_INTEGRAL}),
         ("miura_lifter", {"cells_x": 8, "cells_y": 8, "substrate": True, "thermal_steps": 20})]
REPEATS = 5


def _best(fn, repeats=REPEATS):
    """``(value, seconds)``: ``fn()`` and the least CPU time of ``repeats`` calls."""
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        value = fn()
        times.append(time.process_time() - t0)
    return value, min(times)


def _settled(case):
    """The case's steps with its heating step's coupling "settled" (a steady end)."""
    heat = case.steps[-1]
    return [*case.steps[:-1], Heat(heat.power, increments=heat.increments, coupling="settled")]


def _before_last(case):
    """The state one increment before the end of the case's (settled) heating, and the last
    increment's step: the final converged solve's start and its step."""
    heat = case.steps[-1]
    n = heat.increments
    part = {k: v * (n - 1) / n for k, v in heat.power.items()}
    last = Heat({k: v / n for k, v in heat.power.items()}, increments=1, coupling="settled")
    steps = [*case.steps[:-1], Heat(part, increments=n - 1, coupling="staggered")]
    result = simulate(case.model, steps)
    assert result.success, result.message
    return result.steps[-1].state, last


def _one_solve(model, state):
    """One assembly, factorisation and solve of the tangent and one thermal solve, at
    ``state``."""
    system, tm = equilibrium_system(model), thermal_model(model)
    ev = system.evaluate(state.u, state.spring_rest, hessian=True)
    r = ev.f_int[system.free] - state.applied_load.ravel()[system.free]
    du = linear_solve(ev.K, r)
    T = tm.solve(model.mesh.nodes + state.u, tm.heat_vector(state.crease_power))
    return du, T


def measure(name, kw) -> dict:
    """The four times of one case (see the module docstring), [s]."""
    case = get_case(name, **kw)
    t0 = time.process_time()
    result = simulate(case.model, _settled(case))
    simulation = time.process_time() - t0
    state = result.steps[-1].state
    objective = (FoldAngle(int(case.model.mesh.crease_ids[-1])) if name != "miura_lifter"
                 else NodeCoordinate(int(np.argmax(np.abs(state.u[:, 2]))), "z"))
    g, gradient = _best(lambda: differentiate(result, objective))
    start, last = _before_last(case)
    final, increment = _best(lambda: simulate(case.model, [last], state=start))
    assert final.success, final.message
    _, one = _best(lambda: _one_solve(case.model, state))
    return {"parameters": len(g.gradient), "gradient": gradient, "increment": increment,
            "one": one, "simulation": simulation, "status": g.status}


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    cases = CASES[:-1] if "--quick" in argv else CASES
    print(f"{'case':<14}{'loss':>9}{'cells':>6}{'parameters':>11}{'gradient [s]':>14}"
          f"{'final increment [s]':>21}{'one solve [s]':>15}{'simulation [s]':>16}"
          f"{'grad/final':>12}{'grad/one':>10}   status")
    for name, kw in cases:
        m = measure(name, kw)
        cells = f"{kw['cells_x']}x{kw['cells_y']}" if "cells_x" in kw else "-"
        print(f"{name:<14}{kw.get('loss_model', 'chain'):>9}{cells:>6}{m['parameters']:>11}"
              f"{m['gradient']:>14.4f}"
              f"{m['increment']:>21.4f}{m['one']:>15.4f}{m['simulation']:>16.2f}"
              f"{m['gradient'] / m['increment']:>12.2f}{m['gradient'] / m['one']:>10.2f}"
              f"   {m['status']}")


if __name__ == "__main__":
    main()
