"""The doors: ``simulator.__all__`` and ``design.__all__`` name what exists, ``import design``
stays light, and every design result follows one contract (success, status, message)."""

import dataclasses
import subprocess
import sys

import pytest

import design
import simulator


@pytest.mark.parametrize("package", [simulator, design])
def test_every_public_name_exists(package):
    missing = [n for n in package.__all__ if not hasattr(package, n)]
    assert missing == [] and len(set(package.__all__)) == len(package.__all__)


def test_design_exports_what_a_user_needs():
    needed = {"GripperDesign", "evaluate_gripper", "GripperProblem", "MiuraDesign",
              "MiuraProblem", "make_miura_model", "heated_creases", "lift_power", "optimize",
              "make_executor", "sweep_residual_fold", "allocate_heaters", "DesignSpace",
              "Evaluation", "DesignProblem", "RobustGripperProblem", "OptimizationResult",
              "SerialExecutor", "ProcessExecutor", "DaskExecutor", "HeaterAllocation"}
    assert needed <= set(design.__all__)
    assert callable(design.optimize) and design.optimize.__name__ == "optimize"  # not the module


def test_import_design_loads_no_optional_heavy_dependency():
    code = ("import sys, design\n"
            "print(','.join(m for m in ('nlopt', 'cvxpy', 'dask', 'distributed', 'matplotlib')"
            " if m in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == ""


@pytest.mark.parametrize("cls", [design.StageResult, design.GripperResult,
                                 design.LiftPowerResult, design.Evaluation,
                                 design.OptimizationResult, design.HeaterAllocation])
def test_results_are_frozen_and_carry_success_status_message(cls):
    assert dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen
    names = {f.name for f in dataclasses.fields(cls)} | set(dir(cls))
    assert {"success", "status", "message"} <= names
    assert not {"converged", "met", "failed"} & names


def test_heater_allocation_checks_its_status():
    with pytest.raises(simulator.ParameterError, match="status = 'converged' with success = "
                                                       "False"):
        design.HeaterAllocation(False, "converged", "", {}, None, 0, {})
