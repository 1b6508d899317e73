"""Design subcommands: gripper evaluate, optimize (with resume), sweep residual-fold."""

import json

import pandas as pd
import pytest

from design.cli import main


def test_gripper_evaluate_json_matches_reference_g2(capsys):
    """The reference's G2 in the paper setting (--loss-model chain)."""
    code = main(["gripper", "evaluate", "--W", "300", "--La", "1500", "--L1", "500", "--L2",
                 "500", "--mode", "staircase", "--loss-model", "chain", "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("assembly_power [mW]", "grip_power [mW]", "total_power [mW]",
                "max_crease_temperature [degC]", "success", "status", "message"):
        assert key in out
    assert out["assembly_power [mW]"] == pytest.approx(9.1)
    assert out["grip_power [mW]"] == pytest.approx(0.8)
    assert out["success"] is True and out["status"] == "met"


def test_gripper_evaluate_table(capsys):
    assert main(["gripper", "evaluate", "--W", "300", "--La", "1500", "--L1", "500", "--L2",
                 "500"]) == 0
    out = capsys.readouterr().out
    assert "assembly" in out and "grip" in out and "mW per crease" in out


def test_gripper_evaluate_with_the_integral_heat_loss(capsys):
    """--loss-model integral: the boundary-integral model over the substrate (cycle 9 design:
    13.125 mW full-function power on the sheet refined r = 2 (theory 4.11; 13.1375 with the
    accurate operator rebuilt at every shape, one step of the bisection; 13.225 at the refined
    sheet's levels before 8 Dec 2026); 12.475 mW on the mesh triangles, 12.68 mW in
    results/device_heat_models before the near-substrate rebuild test and the monotone sheet
    conduction of theory 4.9; the chain model 23.4 mW)."""
    argv = ["gripper", "evaluate", "--W", "290", "--La", "1150", "--L1", "550", "--L2", "550"]
    assert main(argv + ["--loss-model", "integral", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["loss_model [-]"] == "integral" and out["success"] is True
    assert 2 * (out["assembly_power [mW]"] + out["grip_power [mW]"]) == pytest.approx(13.125,
                                                                                      abs=0.02)
    assert main(argv + ["--loss-model", "integral"]) == 0
    assert "(bisect, integral heat loss)" in capsys.readouterr().out


def test_optimize_resumes_from_its_log(tmp_path, capsys):
    out = tmp_path / "cd"
    argv = ["optimize", "gripper", "--method", "cd", "--out", str(out), "-q"]
    assert main(argv + ["--max-evaluations", "2"]) in (0, 1)
    first = capsys.readouterr()
    assert "2 computed, 0 reused" in first.out and "resuming" not in first.err
    main(argv + ["--max-evaluations", "3"])
    second = capsys.readouterr()
    assert "1 computed, 2 reused" in second.out
    log = out / "evaluations.csv"
    assert f"resuming: 2 of 3 evaluations saved in {log} are reused" in second.err
    assert (out / "evaluations.csv").exists() and (out / "result.json").exists()


def test_sweep_residual_fold(tmp_path, capsys):
    out = tmp_path / "sweep"
    assert main(["sweep", "residual-fold", "--values=-10,0", "--design",
                 "W=300,La=1500,L1=500,L2=500", "--out", str(out), "-q"]) == 0
    frame = pd.read_csv(out / "sweep.csv")
    assert len(frame) == 2 and "total_power [mW]" in frame.columns
    assert list(frame["residual_fold [deg]"]) == [-10.0, 0.0]
    assert main(["sweep", "residual-fold", "--values=-10,0,10", "--design",
                 "W=300,La=1500,L1=500,L2=500", "--out", str(out), "-q"]) == 0
    assert "resuming: 2 of 3 points saved in " in capsys.readouterr().err


def test_best_so_far_keeps_the_lowest_feasible_objective():
    from types import SimpleNamespace as E

    from design.cli._common import BestSoFar

    best = BestSoFar()
    assert str(best) == "none feasible"
    for objective, feasible in ((0.012, True), (0.005, False), (0.0099, True), (0.02, True)):
        best.add(E(objective=objective, feasible=feasible))
    assert str(best) == "9.9 mW"


@pytest.mark.parametrize("argv, message", [
    (["gripper", "evaluate", "--W", "-5"], "GripperDesign.W"),
    (["sweep", "residual-fold", "--values", "a,b", "--out", "x"], "comma-separated numbers"),
    (["sweep", "residual-fold", "--design", "Q=3", "--out", "x"], "Unknown design variable"),
])
def test_design_cli_errors(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_infeasible_design_reports_not_met_not_zero(capsys):
    code = main(["gripper", "evaluate", "--W", "50", "--json"])
    assert code == 1
    out = json.loads(capsys.readouterr().out)
    assert out["success"] is False and out["total_power [mW]"] is None
    assert out["assembly_power [mW]"] is None and "power cap" in out["message"]


def test_the_design_commands_take_the_loss_model(tmp_path):
    """The design commands default to the integral loss (issue 29) and take --loss-model for
    the gripper and the Miura lifter alike."""
    from design.cli import _parser
    from design.cli.optimize import _problem

    parser = _parser()
    for argv in (["sweep", "residual-fold", "--values=0", "--out", "x"],
                 ["optimize", "gripper", "--out", "x"], ["optimize", "miura", "--out", "x"]):
        assert parser.parse_args(argv).loss_model == "integral"
        assert parser.parse_args([*argv, "--loss-model", "chain"]).loss_model == "chain"
    for target in ("gripper", "miura"):
        for loss in ("integral", "chain"):
            args = parser.parse_args(["optimize", target, "--loss-model", loss, "--out", "x"])
            problem = _problem(args)
            assert (problem.heat if target == "gripper" else problem.base).loss_model == loss
