"""The gripper's inverse design (:class:`design.devices.GripperInverseProblem`, issue 32 item
4b): the assembly and grip criteria as objectives with exact derivatives, every constraint's
gradient (powers, dimensions, per-crease widths; both stages) against central differences of
the whole evaluation, per-crease widths of :class:`GripperDesign`, and the refusals.

Finite-difference rule of the whole evaluation (as tests/unit/test_fold_shape.py):
``h = eps^(1/3) |x|``, every run re-solved from scratch with Newton's residual tolerance
1e-15 N (relative 1e-14) and coupling_tol 1e-10 K. Agreement asked: relative 1e-5 (of the
constraint's largest derivative where an entry is near 0).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from design.devices import GripperDesign, GripperInverseProblem, make_gripper_model
from design.devices.gripper import _base_fold, _tip_distance
from design.devices.gripper_heat import GripperHeatModel
from design.devices.fold_target import answer_rough
from design.devices.gripper_inverse import BaseFold, TipDistance
from simulator.errors import ParameterError
from simulator.sensitivity import Sensitivity

CHAIN = GripperHeatModel(loss_model="chain")
#: A design of unequal widths and powers, away from the snaps of the grip: the assembly
#: state's base fold 88 deg, the grip state's tips 86 um apart (measured).
DESIGN = {"La": 720e-6, "L1": 980e-6, "L2": 1010e-6, "W_2": 190e-6, "W_3": 210e-6,
          "W_5": 200e-6, "W_9": 205e-6, "power_2": 26e-3, "power_5": 26.5e-3,
          "power_3": 6e-3, "power_9": 6.2e-3}
EPS3 = np.finfo(float).eps ** (1 / 3)


@pytest.fixture(scope="module")
def problem():
    return GripperInverseProblem(widths=True, heat_increments=2)


@pytest.fixture(scope="module")
def graded(problem):
    ev = problem.evaluate_with_gradient(DESIGN)
    assert ev.success, ev.message
    return ev


def _fd_check(problem, ev, variables):
    """Each constraint's derivative in each of ``variables`` against central differences."""
    x = np.array([DESIGN[n] for n in problem.space.names])
    worst = 0.0
    for var in variables:
        i = problem.space.names.index(var)
        h = EPS3 * abs(x[i])
        plus, minus = (problem.evaluate(x + s * h * np.eye(len(x))[i]) for s in (1, -1))
        assert plus.success and minus.success, (plus.message, minus.message)
        for name, grad in ev.constraint_gradients.items():
            fd = (plus.constraints[name] - minus.constraints[name]) / (2 * h)
            scale = max(abs(v) for v in grad.values())
            assert grad[var] == pytest.approx(fd, rel=1e-5, abs=1e-5 * scale), (name, var)
            worst = max(worst, abs(grad[var] - fd) / scale)
    return worst


def test_objectives_are_the_reference_measures_with_exact_derivatives():
    """BaseFold and TipDistance are evaluate_gripper's measures (_base_fold, _tip_distance),
    their derivatives those of central differences of the positions."""
    model = make_gripper_model(GripperDesign(), heat=CHAIN)[0]
    rng = np.random.default_rng(3)
    u = rng.normal(scale=200e-6, size=model.mesh.nodes.shape)
    u[0, 2] += 500e-6                                   # the base folded up
    T = np.zeros(model.mesh.n_nodes)
    for objective, measure in ((BaseFold(), _base_fold), (TipDistance(), _tip_distance)):
        value, gu, gT, nonsmooth = objective.terms(model, u, T)
        assert value == pytest.approx(measure(model.mesh.nodes + u), rel=1e-14)
        assert not nonsmooth and not gT.any()
        h = 1e-9
        for node in (0, 1, 4, 5, 15, 18):
            for a in range(3):
                e = np.zeros_like(u)
                e[node, a] = h
                fd = (objective.terms(model, u + e, T)[0]
                      - objective.terms(model, u - e, T)[0]) / (2 * h)
                assert gu[node, a] == pytest.approx(fd, rel=1e-6, abs=1e-6 * abs(gu).max())


def test_gradients_match_central_differences(problem, graded):
    """Every constraint (both stages' criteria, every crease's temperature at both states) in
    a power of each stage, two dimensions and a base and an arm crease's width."""
    ev = graded
    assert set(ev.constraints) == {"assembly", "grip"} | {
        f"temperature_{s}_{c}" for s in ("assembly", "grip") for c in (2, 3, 5, 9)}
    assert ev.objective == pytest.approx(sum(DESIGN[f"power_{c}"] for c in (2, 3, 5, 9)))
    assert ev.objective_gradient == {n: float(n.startswith("power_"))
                                     for n in problem.space.names}
    # the assembly state does not see the arms' powers (added after it)
    assert ev.constraint_gradients["assembly"]["power_3"] == 0.0
    assert _fd_check(problem, ev, ["power_5", "power_3", "L1", "L2", "W_2", "W_9"]) < 1e-5


@pytest.mark.slow
def test_gradients_match_central_differences_in_the_other_variables(problem, graded):
    assert _fd_check(problem, graded, ["power_2", "power_9", "La", "W_3", "W_5"]) < 1e-5


def test_spaces_and_designs():
    """``widths=True``: La, L1, L2, a width per crease (W's bounds) and four powers; else
    GRIPPER_SPACE's four dimensions and the powers; design() maps both."""
    per = GripperInverseProblem(widths=True)
    one = GripperInverseProblem(widths=False)
    assert per.space.names == ("La", "L1", "L2", "W_2", "W_3", "W_5", "W_9", "power_2",
                               "power_5", "power_3", "power_9")
    assert one.space.names == ("La", "L1", "L2", "W", "power_2", "power_5", "power_3",
                               "power_9")
    bounds = {v.name: (v.lower, v.upper) for v in (*per.space.variables,
                                                   *one.space.variables)}
    assert bounds["W_3"] == bounds["W"] == (100e-6, 300e-6)
    d = per.design(DESIGN)
    assert d.widths() == {2: 190e-6, 3: 210e-6, 5: 200e-6, 9: 205e-6} and d.La == 720e-6
    assert one.design({"W": 150e-6, "La": 800e-6}).widths() == dict.fromkeys((2, 3, 5, 9),
                                                                             150e-6)


def test_crease_widths_of_the_gripper_design():
    """Widths equal to W give W's model; others set each crease's strip, its bimorph's
    rotation and the node edits beside it; bad widths are refused."""
    base = GripperDesign(W=170e-6)
    same = replace(base, crease_widths=tuple((c, 170e-6) for c in (2, 3, 5, 9)))
    m0, m1 = (make_gripper_model(d, heat=CHAIN)[0] for d in (base, same))
    assert np.array_equal(m0.mesh.nodes, m1.mesh.nodes)
    assert "crease_widths" not in base.to_dict()
    wide = GripperDesign(crease_widths=((2, 100e-6), (3, 300e-6)))
    m = make_gripper_model(wide, heat=CHAIN)[0]
    assert m.mesh.pattern.crease_width[[2, 3, 5, 9]].tolist() == [100e-6, 300e-6, 200e-6,
                                                                   200e-6]
    rot = m.actuators.rotation_per_kelvin(m.mesh)
    assert rot[1] / rot[0] == pytest.approx(3.0)
    x = m.mesh.nodes
    assert x[13, 0] == pytest.approx(1000e-6 - 50e-6)       # the left arm's edge: W_2 / 2
    assert x[7, 1] == pytest.approx(1000e-6 - 150e-6)       # the central corner: W_3 / 2
    for bad, match in ((((4, 1e-4),), "actuated creases"), (((2, -1e-4),), "crease_widths"),
                       (((2, 800e-6),), "smaller than the panels"), ((2, 3), "crease id")):
        with pytest.raises(ParameterError, match=match):
            GripperDesign(crease_widths=bad)


def test_refusals():
    with pytest.raises(ParameterError, match="without crease_widths"):
        GripperInverseProblem(base=GripperDesign(crease_widths=((2, 1e-4),)))
    with pytest.raises(ParameterError, match="fold_tolerance"):
        GripperInverseProblem(fold_tolerance=0.0)
    with pytest.raises(ParameterError, match="temperature_measure"):
        GripperInverseProblem(temperature_measure="mean")
    with pytest.raises(ParameterError, match="heat_increments"):
        GripperInverseProblem(heat_increments=0)


def _sens(gradient, nonsmooth=()):
    status = "nonsmooth" if nonsmooth else "converged"
    return Sensitivity(1.0, gradient, {}, "m", not nonsmooth, status, status, tuple(nonsmooth))


def test_a_rough_column_is_answered_only_where_the_gradients_agree_at_4h():
    """Geometry's report of a rough column stands unless the gradients at the step 4 h agree
    (to 1e-4 of the objective's largest geometry derivative); other reports always stand."""
    note = ("geometry[L2]: the residual's central differences at h = 7e-11 and 4 h differ by "
            "0.0003 of themselves (Geometry.build is not smooth at the step's scale)")
    fine = [_sens({"power[2]": 5.0, "geometry[L2]": 2.0, "geometry[L1]": 1e3}, [note])]
    close = [_sens({"power[2]": 5.0, "geometry[L2]": 2.05, "geometry[L1]": 1e3})]
    far = [_sens({"power[2]": 5.0, "geometry[L2]": 2.5, "geometry[L1]": 1e3})]
    out = answer_rough(fine, ("L1", "L2"), lambda: close)
    assert out[0].success and out[0].status == "converged" and not out[0].nonsmooth
    out = answer_rough(fine, ("L1", "L2"), lambda: far)
    assert not out[0].success and out[0].nonsmooth == (note,)
    other = [_sens(fine[0].gradient, [note, "crease 2: nodes [1, 2] are equally hot"])]
    out = answer_rough(other, ("L1", "L2"), lambda: close)
    assert out[0].status == "nonsmooth" and len(out[0].nonsmooth) == 1
    assert math.isfinite(out[0].gradient["geometry[L2]"])
