"""Crease widths as variables of :class:`design.devices.FoldShapeProblem` (``widths=True``,
issue 32 item 4a): the model rebuilt from its pattern at the widths, every constraint's
gradient in the powers and the widths against central differences of ``evaluate`` on a
2 x 2-cell Miura sheet in air (chain loss), and the refusals.

Finite-difference rule (as tests/unit/test_fold_shape.py): ``h = eps^(1/3) |x|``, each run
re-solved from scratch with tight tolerances; agreement relative 1e-5 (of the constraint's
largest derivative where an entry is near 0).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from design.devices import FoldShapeProblem, MiuraDesign, make_miura_model
from simulator.errors import ParameterError
from simulator.sensitivity import FoldAngle

EPS3 = np.finfo(float).eps ** (1 / 3)


@pytest.fixture(scope="module")
def sheet():
    """``(problem, design)``: the 2 x 2-cell sheet's folds at a non-uniform design as
    targets, widths variables; the design with unequal widths (180-230 um)."""
    model = make_miura_model(MiuraDesign(cells_x=2, cells_y=2, substrate=False,
                                         loss_model="chain"))
    ids = [int(c) for c in model.mesh.crease_ids]
    probe = FoldShapeProblem(model, {ids[0]: 0.0})
    reference = {f"power_{c}": 1.0e-3 + 0.5e-3 * (k % 3) for k, c in enumerate(ids)}
    state = probe.simulate(reference).steps[-1].state
    targets = {c: FoldAngle(c).terms(model, state.u, state.temperature)[0] for c in ids}
    problem = FoldShapeProblem(model, targets, tolerance=math.radians(0.5), max_power=4e-3,
                               start_power=0.5e-3,
                               widths=True)
    design = {**{f"power_{c}": 1.2e-3 + 0.3e-3 * (k % 4) for k, c in enumerate(ids)},
              **{f"W_{c}": 180e-6 + 10e-6 * (k % 6) for k, c in enumerate(ids)}}
    return problem, design


def test_widths_are_variables_of_the_rebuilt_model(sheet):
    problem, design = sheet
    names = problem.space.names
    assert [n for n in names if n.startswith("W_")] == [f"W_{c}" for c in problem.creases]
    bounds = {v.name: (v.lower, v.upper, v.start) for v in problem.space.variables}
    assert bounds[f"W_{problem.creases[0]}"] == (100e-6, 300e-6, 200e-6)
    model = problem.model_at(design)
    c = problem.creases[1]
    assert model.mesh.pattern.crease_width[c] == design[f"W_{c}"]
    assert problem.model_at({n: v for n, v in design.items() if n.startswith("power")}) \
        is problem.model


def test_gradients_in_powers_and_widths_match_central_differences(sheet):
    """Every constraint (two per target fold, one temperature per crease) in two powers and
    three widths; the objective, the total power, has 0 in the widths."""
    problem, design = sheet
    ev = problem.evaluate_with_gradient(design)
    assert ev.success, ev.message
    assert ev.objective_gradient == {n: float(n.startswith("power_"))
                                     for n in problem.space.names}
    names = problem.space.names
    x = np.array([design[n] for n in names])
    c = problem.creases
    checked = 0
    for var in (f"power_{c[1]}", f"power_{c[-1]}", f"W_{c[0]}", f"W_{c[2]}", f"W_{c[-1]}"):
        i = names.index(var)
        h = EPS3 * abs(x[i])
        plus, minus = (problem.evaluate(x + s * h * np.eye(len(x))[i]) for s in (1, -1))
        for name, grad in ev.constraint_gradients.items():
            fd = (plus.constraints[name] - minus.constraints[name]) / (2 * h)
            scale = max(abs(v) for v in grad.values())
            if scale < 1e-3:            # a fold of the clamped column: no gradient either way
                continue
            assert grad[var] == pytest.approx(fd, rel=1e-5, abs=1e-5 * scale), (name, var)
            checked += var.startswith("W_") and abs(fd) > 1e-3 * scale
    assert checked >= 10                 # the widths move many constraints


def test_width_refusals(sheet):
    problem, _ = sheet
    c = problem.creases[0]
    with pytest.raises(ParameterError, match="width_bounds"):
        FoldShapeProblem(problem.model, {c: 0.1}, widths=True, width_bounds=(3e-4, 1e-4))
