"""Design spaces, evaluations and the problem wrapper."""

import math
import pickle

import numpy as np
import pytest

from design import DesignProblem, Evaluation, GripperProblem
from design.devices import GRIPPER_SPACE
from design.core.space import DesignSpace, Variable
from simulator.errors import EtorigamiDeprecationWarning, ParameterError


def test_vector_and_named_mapping_round_trip():
    x = GRIPPER_SPACE.to_vector({"La": 900e-6})
    assert x.tolist() == [200e-6, 900e-6, 1000e-6, 1000e-6]        # missing names: start
    assert GRIPPER_SPACE.to_mapping(x) == {"W": 200e-6, "La": 900e-6, "L1": 1000e-6,
                                           "L2": 1000e-6}
    z = GRIPPER_SPACE.normalize(x)
    np.testing.assert_allclose(GRIPPER_SPACE.denormalize(z), x)
    assert GRIPPER_SPACE.names == ("W", "La", "L1", "L2")


def test_to_dict_of_a_vector_is_the_deprecated_spelling_of_to_mapping():
    x = GRIPPER_SPACE.to_vector({"La": 900e-6})
    with pytest.warns(EtorigamiDeprecationWarning, match=r"DesignSpace\.to_mapping\(x\)") as rec:
        old = GRIPPER_SPACE.to_dict(x)
    assert old == GRIPPER_SPACE.to_mapping(x) and len(rec) == 1
    assert rec[0].filename == __file__                 # attributed to the caller's line


def test_bound_margins_are_normalised_and_signed():
    g = GRIPPER_SPACE.bound_margins({"W": 100e-6})
    assert g["W_lower"] == pytest.approx(0.0) and g["W_upper"] == pytest.approx(-1.0)
    assert all(v <= 1e-12 for v in g.values())
    assert GRIPPER_SPACE.bound_margins({"W": 350e-6})["W_upper"] == pytest.approx(0.25)


@pytest.mark.parametrize("make, match", [
    (lambda: Variable("W", 3.0, 1.0, 0.1, 2.0), "lower"),
    (lambda: Variable("W", 0.0, 1.0, 0.0, 0.5), "step"),
    (lambda: Variable("W", 0.0, 1.0, -0.1, 0.5), "step"),
    (lambda: Variable("W", 0.0, 1.0, 0.1, 2.0), "start"),
    (lambda: Variable("W", 0.0, float("nan"), 0.1, 0.5), "upper"),
    (lambda: DesignSpace([]), "non-empty"),
    (lambda: DesignSpace([Variable("a", 0, 1, 0.1, 0.5), Variable("a", 0, 1, 0.1, 0.5)]),
     "duplicate"),
    (lambda: GRIPPER_SPACE.to_vector({"Q": 1.0}), "Unknown design variable 'Q'"),
    (lambda: GRIPPER_SPACE.to_vector([1.0, 2.0]), "needs 4 values"),
    (lambda: GRIPPER_SPACE.validate({"W": 50e-6}), "W = 50 um is outside its bounds"),
])
def test_bad_spaces_and_points(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


class _Exploding(DesignProblem):
    space = DesignSpace([Variable("a", 0.0, 1.0, 0.1, 0.5, unit="-", display_scale=1,
                                  display_unit="-")])

    def _evaluate(self, values):
        raise RuntimeError("solver exploded")


def test_failures_become_failed_evaluations():
    ev = _Exploding().evaluate({"a": 0.3})
    assert not ev.success and ev.status == "failed" and math.isinf(ev.objective)
    assert not ev.feasible and "solver exploded" in ev.message
    out = _Exploding().evaluate({"a": 3.0})                     # outside the bounds
    assert not out.success and "outside its bounds" in out.message


def test_evaluation_row_and_feasibility():
    ev = Evaluation({"a": 1.0}, 2.0, {"g1": -0.1, "g2": 0.2}, {"m [mW]": 3.0})
    assert not ev.feasible and ev.max_violation == pytest.approx(0.2)
    assert ev.success and ev.status == "infeasible"
    row = ev.to_row()
    assert row["x.a"] == 1.0 and row["g.g2"] == 0.2 and row["m.m [mW]"] == 3.0
    assert row["success"] and row["status"] == "infeasible" and "wall_time [s]" in row
    with pytest.raises(ParameterError, match="status = 'feasible' with success = True"):
        Evaluation({"a": 1.0}, 2.0, {"g2": 0.2}, status="feasible")
    with pytest.raises(ParameterError, match="success = 1"):
        Evaluation({"a": 1.0}, 2.0, success=1)


def test_gripper_problem_is_picklable_and_validated():
    p = GripperProblem(mode="staircase", residual_fold_groups=(("arm", -0.1),))
    assert pickle.loads(pickle.dumps(p)) == p
    assert p.group_folds() == {"base": 0.0, "arm": -0.1}
    assert p.temperature_limit == pytest.approx(252.0)
    with pytest.raises(ParameterError, match="groups"):
        GripperProblem(residual_fold_groups=(("wing", 0.1),))
    with pytest.raises(ParameterError, match="temperature_measure"):
        GripperProblem(temperature_measure="hottest")
