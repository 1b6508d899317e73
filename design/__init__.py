"""etorigami design layer: design problems, optimisers, sweeps and heater allocation.

Everything a user needs is importable from here::

    from design import GripperProblem, optimize, make_executor, sweep_residual_fold

``import design`` costs little more than ``import simulator`` (measured 0.72 s against
0.54 s): NLopt, cvxpy and Dask are imported only inside the functions that use them. Every
result object (``StageResult``, ``GripperResult``, ``LiftPowerResult``, ``Evaluation``,
``OptimizationResult``, ``HeaterAllocation``, the rows of sweep tables) carries
``success``, ``status`` and ``message``; a power that was not found is None (an empty cell
in CSV tables).
"""

from .space import DesignSpace, Variable
from .problem import (EVALUATION_STATUSES, GRIPPER_SPACE, SU8_TG, DesignProblem, Evaluation,
                      GripperProblem)
from .gripper import (ARM_CREASES, BASE_CREASES, REFERENCE_NEWTON, STAGE_STATUSES,
                      GripperDesign, GripperResult, StageResult, evaluate_gripper, gripper_model)
from .miura import (MIURA_SPACE, LiftPowerResult, MiuraDesign, MiuraProblem, heated_creases,
                    lift_per_power_table, lift_power, miura_model)
from .evaluation_log import EvaluationLog, LoggedProblem
# the function, not the submodule of the same name (bound after the submodule is loaded)
from .optimize import METHODS, OptimizationResult, StopOptimization, optimize
from .robustness import (CREASE_GROUPS, RobustGripperProblem, residual_fold_grid,
                         sweep_residual_fold, with_residual_fold)
from .heaters import (ALLOCATION_STATUSES, HeaterAllocation, allocate_heaters,
                      fold_sensitivity, influence_matrices, linear_allocation)
from .executors import (DaskExecutor, Executor, ExecutorError, ProcessExecutor, SerialExecutor,
                        TaskError, executor_from_option, make_executor)
from .executors import TaskFailure
from .uncertainty import (SCENARIOS, Distribution, FabricationScenario, UncertainInput,
                          rank_correlations, residual_fold_per_crease, wilson_interval)
from .uncertainty_sweep import (GripperSampleProblem, RobustYieldProblem, summarize_yield,
                                sweep_uncertainty)

__all__ = [
    # design spaces and problems
    "Variable", "DesignSpace", "Evaluation", "DesignProblem", "EVALUATION_STATUSES",
    "GripperProblem", "GRIPPER_SPACE", "SU8_TG",
    # gripper
    "GripperDesign", "StageResult", "GripperResult", "STAGE_STATUSES", "gripper_model",
    "evaluate_gripper", "BASE_CREASES", "ARM_CREASES", "REFERENCE_NEWTON",
    # Miura lifter
    "MiuraDesign", "MiuraProblem", "MIURA_SPACE", "LiftPowerResult", "miura_model",
    "heated_creases", "lift_power", "lift_per_power_table",
    # optimisation and evaluation logs
    "optimize", "OptimizationResult", "StopOptimization", "METHODS", "EvaluationLog",
    "LoggedProblem",
    # robustness
    "residual_fold_grid", "with_residual_fold", "sweep_residual_fold",
    "RobustGripperProblem", "CREASE_GROUPS",
    # heater allocation
    "allocate_heaters", "linear_allocation", "HeaterAllocation", "ALLOCATION_STATUSES",
    "influence_matrices", "fold_sensitivity",
    # executors
    "Executor", "SerialExecutor", "ProcessExecutor", "DaskExecutor", "ExecutorError",
    "TaskError", "make_executor", "executor_from_option",
    "TaskFailure",
    # fabrication uncertainty
    "Distribution", "UncertainInput", "FabricationScenario", "SCENARIOS",
    "residual_fold_per_crease", "wilson_interval", "rank_correlations",
    "sweep_uncertainty", "summarize_yield", "GripperSampleProblem", "RobustYieldProblem",
]
