"""The sweeps' one evaluation loop (design.core.points): look-up, map, append, lost points;
and the named outcome of a problem's ``_evaluate``."""

from __future__ import annotations

import math

import pytest

from design.core import DesignProblem, DesignSpace, EvaluationOutcome, SerialExecutor, \
    TaskFailure, Variable
from design.core.evaluation_log import EvaluationLog
from design.core.points import design_list, evaluate_points


class Line(DesignProblem):
    """f = a x: cheap, counts its evaluations."""

    space = DesignSpace([Variable("x", 0.0, 1.0, 0.1, 0.5, unit="-", display_scale=1.0,
                                  display_unit="-")])

    def __init__(self, a=1.0):
        self.a, self.calls = a, 0

    def _evaluate(self, v):
        self.calls += 1
        return EvaluationOutcome(self.a * v["x"], {"x_max": v["x"] - 0.9}, {"m [-]": 2.0})

    def settings(self):
        return {"problem": "line", "a": self.a}


class LosesItem(SerialExecutor):
    """Serial, except that the task of ``lost`` never returns (as if its worker died)."""

    def __init__(self, lost):
        self.lost = lost

    def map(self, fn, items, progress=None, *, on_result=None, failures="raise"):
        items, out = list(items), []
        for i, item in enumerate(items):
            out.append(TaskFailure(i, item, "worker died 3 times", 3) if i == self.lost
                       else fn(item))
            on_result(i, out[-1])
        return out


def test_outcome_is_named_and_a_plain_tuple_still_works():
    ev = Line(2.0).evaluate({"x": 0.25})
    assert ev.objective == 0.5 and ev.status == "feasible" and ev.metrics == {"m [-]": 2.0}
    out = EvaluationOutcome(1.0, {}, {})
    assert (out.failure, out.message) == (None, "") and tuple(out)[:1] == (1.0,)

    class Old(Line):
        def _evaluate(self, v):
            return v["x"], {}, {}, "not_met", "below the cap"

    old = Old().evaluate({"x": 0.25})
    assert old.status == "not_met" and not old.success and old.message == "below the cap"


def test_points_in_order_equal_points_once_and_logged_points_read_back(tmp_path):
    p, q = Line(1.0), Line(3.0)
    points = [(p, {"x": 0.2}), (q, {"x": 0.2}), (p, [0.2]), (p, {"x": 0.4})]
    evs = evaluate_points(points, log=tmp_path / "log.csv")
    assert [ev.objective for ev in evs] == pytest.approx([0.2, 0.6, 0.2, 0.4])
    assert evs[0] is evs[2] and (p.calls, q.calls) == (2, 1)      # same problem and design
    assert len(EvaluationLog(tmp_path / "log.csv", p)) == 2
    assert len(EvaluationLog(tmp_path / "log.csv", q)) == 1
    again = evaluate_points(points, log=tmp_path / "log.csv")      # all read back
    assert (p.calls, q.calls) == (2, 1)
    assert [ev.objective for ev in again] == [ev.objective for ev in evs]


def test_a_lost_point_is_a_failed_evaluation_and_not_logged(tmp_path):
    p = Line()
    evs = evaluate_points([(p, {"x": 0.1}), (p, {"x": 0.3})], LosesItem(lost=1),
                          log=tmp_path / "log.csv")
    assert evs[0].success and evs[1].status == "failed" and math.isinf(evs[1].objective)
    assert evs[1].x == {"x": 0.3} and "worker died 3 times" in evs[1].message
    log = EvaluationLog(tmp_path / "log.csv", p)
    assert log.lookup({"x": 0.1}) is not None and log.lookup({"x": 0.3}) is None


def test_design_list_takes_none_a_mapping_a_vector_or_a_sequence():
    s = Line.space
    assert design_list(s, None) == [{"x": 0.5}]
    assert design_list(s, {"x": 0.2}) == design_list(s, [0.2]) == [{"x": 0.2}]
    assert design_list(s, [{"x": 0.1}, [0.3]]) == [{"x": 0.1}, {"x": 0.3}]


def test_one_class_is_named_evaluation():
    """design's Evaluation (one evaluated design); the equilibrium system's values at one
    configuration are SystemValues."""
    import ast
    import pathlib

    root = pathlib.Path(__file__).resolve().parents[2]
    found = [p.relative_to(root).as_posix() for pkg in ("simulator", "design")
             for p in sorted((root / pkg).rglob("*.py"))
             for node in ast.walk(ast.parse(p.read_text()))
             if isinstance(node, ast.ClassDef) and node.name == "Evaluation"]
    assert found == ["design/core/problem.py"]
