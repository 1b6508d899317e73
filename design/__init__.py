"""etorigami design layer: design problems, optimisers, sweeps and heater allocation.

Everything a user needs is importable from here::

    from design import GripperProblem, optimize, make_executor, sweep_residual_fold

``import design`` imports no submodule: each public name is imported from its submodule on
first use (see :mod:`simulator._lazy`); NLopt, cvxpy, Dask, pandas and scipy.stats are
imported only inside the functions that use them. The package has three rooms: ``core``
(spaces, problems, evaluation logs, optimisers, executors), ``devices`` (gripper, Miura
lifter, power searches) and ``analysis`` (robustness, uncertainty, heater allocation). Every
result object (``StageResult``, ``GripperResult``, ``LiftPowerResult``, ``Evaluation``,
``OptimizationResult``, ``HeaterAllocation``, the rows of sweep tables) carries ``success``,
``status`` and ``message``; a power that was not found is None (an empty cell in CSV tables).
"""

from simulator._lazy import attach as _attach

__getattr__, __dir__ = _attach(__name__, {
    ".core.space": ("DesignSpace", "Variable"),
    ".core.problem": ("EVALUATION_STATUSES", "DesignProblem", "Evaluation"),
    ".devices.gripper_problem": ("GRIPPER_SPACE", "GripperProblem"),
    ".devices.limits": ("SU8_TG",),
    ".devices.gripper": ("ARM_CREASES", "BASE_CREASES", "REFERENCE_NEWTON", "STAGE_STATUSES",
                 "GripperDesign", "GripperResult", "StageResult", "evaluate_gripper",
                 "gripper_model"),
    ".devices.gripper_drive": ("GripperDrive", "gripper_circuits", "gripper_drive"),
    ".devices.miura": ("MIURA_SPACE", "LiftPowerResult", "MiuraDesign", "MiuraProblem",
               "heated_creases", "lift_per_power_table", "lift_power", "miura_model"),
    ".core.evaluation_log": ("EvaluationLog", "LoggedProblem"),
    ".core.optimize": ("OptimizationResult", "Optimizer", "StopOptimization", "get_optimizer",
                       "optimize", "optimizers", "register_optimizer", "unregister_optimizer"),
    ".analysis.robustness": ("CREASE_GROUPS", "RobustGripperProblem", "residual_fold_grid",
                    "sweep_residual_fold", "with_residual_fold"),
    ".analysis.heaters": ("ALLOCATION_STATUSES", "HeaterAllocation", "TEMPERATURE_MEASURES",
                          "allocate_heaters", "fold_sensitivity", "influence_matrices",
                          "limit_temperatures", "linear_allocation"),
    ".core.executors": ("DaskExecutor", "Executor", "ExecutorError", "ProcessExecutor",
                   "SerialExecutor", "TaskError", "TaskFailure", "executor_from_option",
                   "make_executor"),
    ".analysis.uncertainty": ("SCENARIOS", "Distribution", "FabricationScenario", "UncertainInput",
                     "rank_correlations", "residual_fold_per_crease", "wilson_interval"),
    ".analysis.uncertainty_sweep": ("GripperSampleProblem", "RobustYieldProblem", "summarize_yield",
                           "sweep_uncertainty"),
})

__all__ = [
    # design spaces and problems
    "Variable", "DesignSpace", "Evaluation", "DesignProblem", "EVALUATION_STATUSES",
    "GripperProblem", "GRIPPER_SPACE", "SU8_TG",
    # gripper
    "GripperDesign", "StageResult", "GripperResult", "STAGE_STATUSES", "gripper_model",
    "evaluate_gripper", "BASE_CREASES", "ARM_CREASES", "REFERENCE_NEWTON",
    "GripperDrive", "gripper_drive", "gripper_circuits",
    # Miura lifter
    "MiuraDesign", "MiuraProblem", "MIURA_SPACE", "LiftPowerResult", "miura_model",
    "heated_creases", "lift_power", "lift_per_power_table",
    # optimisation and evaluation logs
    "optimize", "OptimizationResult", "StopOptimization", "Optimizer", "optimizers",
    "get_optimizer", "register_optimizer", "unregister_optimizer", "EvaluationLog",
    "LoggedProblem",
    # robustness
    "residual_fold_grid", "with_residual_fold", "sweep_residual_fold",
    "RobustGripperProblem", "CREASE_GROUPS",
    # heater allocation
    "allocate_heaters", "linear_allocation", "HeaterAllocation", "ALLOCATION_STATUSES",
    "influence_matrices", "fold_sensitivity", "limit_temperatures", "TEMPERATURE_MEASURES",
    # executors
    "Executor", "SerialExecutor", "ProcessExecutor", "DaskExecutor", "ExecutorError",
    "TaskError", "make_executor", "executor_from_option",
    "TaskFailure",
    # fabrication uncertainty
    "Distribution", "UncertainInput", "FabricationScenario", "SCENARIOS",
    "residual_fold_per_crease", "wilson_interval", "rank_correlations",
    "sweep_uncertainty", "summarize_yield", "GripperSampleProblem", "RobustYieldProblem",
]
