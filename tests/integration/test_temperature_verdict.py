"""One temperature verdict (issue 28, item 5): ``run``, ``gripper evaluate``, the design
problems and the sweeps judge the 1.2 T_g limit on one measure, the crease centre-line mean,
through one function (:meth:`simulator.thermal.TemperatureLimit.judge`); every "exceeded" or "not
feasible" names the crease, its temperature and the limit, and a hottest node shown beside it
is labelled as information."""

import math

import pytest

from design import (GripperHeatModel, GripperProblem, evaluate_gripper, residual_fold_grid,
                    sweep_residual_fold)
from design.cli import main
from simulator.thermal import TemperatureLimit, TemperatureVerdict


@pytest.fixture
def judged(monkeypatch):
    """Every :meth:`TemperatureLimit.judge` call (its limit and verdict), in order."""
    calls, judge = [], TemperatureLimit.judge

    def spy(self, temperature, mesh, creases=None):
        verdict = judge(self, temperature, mesh, creases)
        calls.append((self, verdict))
        return verdict

    monkeypatch.setattr(TemperatureLimit, "judge", spy)
    return calls


def test_run_and_gripper_evaluate_judge_the_same_measure(tmp_path, capsys, judged):
    """The double fold at 10 mW: fold 2 (crease 5) has a centre-line mean of 250.06 degC,
    within 1.2 T_g = 252 degC, while its hottest node is at 266.7 degC: the verdict is "met"."""
    assert main(["run", "double-fold", "--out", str(tmp_path / "df"), "-q"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert ("temperature limit met: crease 5: centre-line mean 250.06 degC <= 1.2 T_g = 252 "
            "degC (hottest crease on that measure, record 380, step heat)") in lines
    assert ("hottest node 266.67 degC (crease 5, record 380, step heat, information: the limit "
            "is judged on the crease centre-line mean)") in lines
    assert not [line for line in lines if "exceeded" in line]
    run_limit, run_verdict = judged[-1]           # after the pre-check's estimate, the summary
    assert {limit for limit, _ in judged} == {run_limit}
    assert run_verdict.success and run_verdict.temperature == pytest.approx(250.0568, abs=1e-4)
    assert run_verdict.hottest_node == pytest.approx(266.6739, abs=1e-4)

    judged.clear()
    assert main(["gripper", "evaluate", "--loss-model", "integral"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert judged and {limit for limit, _ in judged} == {run_limit}   # one limit, one measure
    assert run_limit.measure == "centre_line"
    # (the integral loss with its monotone sheet conduction, theory 4.9, on the sheet refined
    # r = 2 at 4 and 2 sub-triangles per mesh edge, theory 4.11: 197.49 and 252.09 degC at 6
    # and 4, 202.08 and 262.96 degC on the mesh triangles)
    assert ("temperature limit met: crease 5: centre-line mean 198.27 degC <= 1.2 T_g = 252 "
            "degC (the stages' heated creases at their stopping powers)") in lines
    # the accurate operator rebuilt at every shape gives 198.28 and 253.38 degC at the same
    # assembly power; the default corrects it between rebuilds (theory 4.7; 253.35 degC before
    # the near-plane height test followed the secant, 8 Dec 2026). Creases 2 and 5 are mirror
    # images: which holds the hottest node is decided at round-off (1e-5 K)
    assert ("hottest node 253.33 degC (crease 2, information: the limit is judged on the crease "
            "centre-line mean)") in lines
    assert not [line for line in lines if "max crease temperature" in line]


def test_the_gripper_verdict_is_what_the_problem_constrains():
    """``gripper evaluate``'s verdict, the problem's constraint and its message are one."""
    res = evaluate_gripper()
    v = res.temperature_verdict()
    assert isinstance(v, TemperatureVerdict) and v.limit == GripperProblem().limit
    assert (v.crease, v.temperature) == (5, res.assembly.temperature)      # 202.08 degC
    assert v.hottest_node == res.to_dict()["max_crease_temperature [degC]"] > v.temperature
    ev = GripperProblem().evaluate(GripperProblem().space.start)
    assert ev.constraints["temperature"] == v.constraint and ev.feasible
    assert ev.message == "both stages met"
    strict = GripperProblem(temperature_measure="crease_max")
    assert res.temperature_verdict(strict.limit).temperature == v.hottest_node


def test_an_infeasible_sweep_point_says_why(tmp_path, capsys):
    """At a residual fold of -20 deg the start gripper's base crease 2 is at 281.02 degC on its
    centre line with the paper's chains: the row is infeasible, and its message names the
    crease, the temperature and the limit; the CLI prints it under the table."""
    paper = GripperProblem(heat=GripperHeatModel(loss_model="chain"))
    frame = sweep_residual_fold(paper, None, residual_fold_grid([-20, 0]))
    hot, ok = frame.iloc[0], frame.iloc[1]
    reason = "crease 2: centre-line mean 281.02 degC > 1.2 T_g = 252 degC"
    assert not hot["feasible"] and hot["status"] == "infeasible"
    assert hot["message"] == f"both stages met; not feasible: {reason}"
    assert ok["feasible"] and ok["message"] == "both stages met"
    assert main(["sweep", "residual-fold", "--values=-20,0", "--loss-model", "chain", "--out",
                 str(tmp_path / "s"), "-q"]) == 0
    out = capsys.readouterr().out
    assert (f"point 0 (residual fold -20 deg): infeasible: both stages met; not feasible: "
            f"{reason}") in out.splitlines()
    assert "point 1 " not in out
    assert main(["gripper", "evaluate", "--residual-fold=-20", "--loss-model", "chain"]) == 0
    out = capsys.readouterr().out
    assert "met - both stages met; the temperature limit is exceeded" in out
    assert f"temperature limit exceeded: {reason}" in out


def test_an_optimiser_without_a_feasible_design_names_the_crease():
    """Every evaluation of a too-hot residual fold is infeasible; the optimisation's message
    returns the least-violating design with the reason."""
    from design import optimize

    problem = GripperProblem(residual_fold=math.radians(-20),
                             heat=GripperHeatModel(loss_model="chain"))    # the paper's chains
    res = optimize(problem, "cd", max_evaluations=1)
    assert not res.success
    assert res.message.endswith("no feasible evaluation (the least-violating design is "
                                "returned: both stages met; not feasible: crease 2: centre-line "
                                "mean 281.02 degC > 1.2 T_g = 252 degC)")
