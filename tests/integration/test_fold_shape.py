"""Inverse design of heater powers (:class:`design.devices.FoldShapeProblem`) on a small
Miura sheet in air with the chain heat loss: adjoint gradients of every constraint against
central differences, a gradient run that meets the targets within 0.5 deg and the
temperature limit, and the refusals."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from design import optimize
from design.devices import FoldShapeProblem, MiuraDesign, make_miura_model
from simulator import IntegralLoss
from simulator.errors import ParameterError
from simulator.sensitivity import FoldAngle

TOL = math.radians(0.5)
LIMIT = 252.0


@pytest.fixture(scope="module")
def sheet():
    """``(problem, reference powers {crease: W})``: a 2 x 2-cell sheet whose targets are the
    fold angles of a non-uniform reference design (a feasible design exists)."""
    model = make_miura_model(MiuraDesign(cells_x=2, cells_y=2, substrate=False,
                                         loss_model="chain"))
    ids = [int(c) for c in model.mesh.crease_ids]
    reference = {c: 1.0e-3 + 0.5e-3 * (k % 3) for k, c in enumerate(ids)}
    probe = FoldShapeProblem(model, {ids[0]: 0.0})
    state = probe.simulate({f"power_{c}": p for c, p in reference.items()}).steps[-1].state
    targets = {c: FoldAngle(c).terms(model, state.u, state.temperature)[0] for c in ids}
    problem = FoldShapeProblem(model, targets, tolerance=TOL, temperature_limit=LIMIT,
                               max_power=4e-3, start_power=0.5e-3)
    return problem, reference


@pytest.fixture(scope="module")
def integral_sheet():
    """The 2 x 2-cell sheet with the integral loss (rebuilt at every shape, no correction
    between rebuilds, on the mesh's own sheet: theory 12.6), at targets of 0.2 rad."""
    model = make_miura_model(MiuraDesign(cells_x=2, cells_y=2, substrate=False))
    model = dataclasses.replace(model, thermal=dataclasses.replace(
        model.thermal, loss=IntegralLoss(shape_tol=0.0, correction_tol=0.0),
        sheet_refinement=1))
    ids = [int(c) for c in model.mesh.crease_ids]
    return FoldShapeProblem(model, {c: 0.2 for c in ids}, tolerance=TOL,
                            temperature_limit=LIMIT, max_power=4e-3, start_power=0.5e-3), None


@pytest.mark.parametrize("which", ["sheet", "integral_sheet"])
def test_gradients_match_central_differences(which, request):
    """Every constraint's adjoint gradient against central differences of ``evaluate``
    (``h = eps^(1/3) max(|P|, 1 mW)``), to 1e-5 relative (of the constraint's largest
    entry); the total power's gradient is 1 per heater. With the chain and the integral
    loss (a quarter of the powers: it runs the creases hotter)."""
    problem, _ = request.getfixturevalue(which)
    scale_power = 0.25 if which == "integral_sheet" else 1.0
    names = problem.space.names
    x = scale_power * np.array([1.2e-3 + 0.3e-3 * (k % 4) for k in range(len(names))])
    ev = problem.evaluate_with_gradient(x)
    assert ev.success, ev.message
    assert ev.objective_gradient == {n: 1.0 for n in names}
    fd = {}
    for i, var in enumerate(names):
        h = np.finfo(float).eps ** (1 / 3) * max(abs(x[i]), 1e-3)
        plus = problem.evaluate(x + h * np.eye(len(x))[i])
        minus = problem.evaluate(x - h * np.eye(len(x))[i])
        for name in ev.constraints:
            fd.setdefault(name, {})[var] = (plus.constraints[name]
                                            - minus.constraints[name]) / (2 * h)
    checked = 0
    for name, grad in ev.constraint_gradients.items():
        scale = max(abs(v) for v in fd[name].values())
        if scale < 1e-3:           # a fold of the clamped column: no gradient either way
            assert max(abs(v) for v in grad.values()) < 1e-3, name
            continue
        checked += 1
        for var in names:
            assert grad[var] == pytest.approx(fd[name][var], rel=1e-5, abs=1e-5 * scale), \
                (name, var)
    assert checked >= len(names)


def test_mma_meets_the_targets_and_the_limit(sheet):
    """MMA from an under-powered start ends feasible: every fold within 0.5 deg of its
    target, every crease under the limit, with less power than the reference design."""
    problem, reference = sheet
    start = problem.evaluate(problem.space.to_mapping(
        [v.start for v in problem.space.variables]))
    assert not start.feasible                      # the start misses the targets
    r = optimize(problem, "mma", max_evaluations=80)
    assert r.success, r.message
    m = r.best.metrics
    for c, target in problem.targets.items():
        assert abs(m[f"fold_{c} [deg]"] - math.degrees(target)) <= 0.5, c
    assert max(m[f"temperature_{c} [degC]"] for c in problem.all_creases) <= LIMIT
    assert m["max fold error [deg]"] <= 0.5
    assert r.objective < sum(reference.values())


def test_refusals(sheet):
    problem, _ = sheet
    model = problem.model
    lumped = make_miura_model(MiuraDesign(cells_x=2, cells_y=2, substrate=False))
    lumped = dataclasses.replace(lumped, thermal=dataclasses.replace(
        lumped.thermal, loss=IntegralLoss(lumped=True)))
    c = problem.all_creases[0]
    with pytest.raises(ParameterError, match="lumped.*not lumped"):
        FoldShapeProblem(lumped, {c: 0.1})
    with pytest.raises(ParameterError, match="targets"):
        FoldShapeProblem(model, {10_000: 0.1})
    with pytest.raises(ParameterError, match="targets"):
        FoldShapeProblem(model, {c: math.nan})
    with pytest.raises(ParameterError, match="creases"):
        FoldShapeProblem(model, {c: 0.1}, creases=[10_000])
    with pytest.raises(ParameterError, match="tolerance"):
        FoldShapeProblem(model, {c: 0.1}, tolerance=0.0)
    with pytest.raises(ParameterError, match="temperature_measure"):
        FoldShapeProblem(model, {c: 0.1}, temperature_measure="mean")
