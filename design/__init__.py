"""etorigami design layer: design problems, optimisers, sweeps and heater allocation.

Everything a user needs is importable from here::

    from design import GripperProblem, optimize, make_executor, sweep_residual_fold

``import design`` imports no submodule: each public name is imported from its submodule on
first use (see :mod:`simulator._lazy`); NLopt, cvxpy, Dask, pandas and scipy.stats are
imported only inside the functions that use them. The package has three rooms, each a
namespace with the rest of its family: :mod:`design.core` (spaces, problems, evaluation logs,
optimisers, executors), :mod:`design.devices` (gripper, Miura lifter, power searches) and
:mod:`design.analysis` (robustness, uncertainty, heater allocation). Older spellings at the
door (``design.wilson_interval``) still work for one release with a deprecation warning
naming the new place (the table is in ``_moved.py``). Every result object (``StageResult``,
``GripperResult``, ``LiftPowerResult``, ``Evaluation``, ``OptimizationResult``,
``HeaterAllocation``, the rows of sweep tables) carries ``success``, ``status`` and
``message``; a power that was not found is None (an empty cell in CSV tables).
"""

from simulator._lazy import attach as _attach

__getattr__, __dir__ = _attach(__name__, {
    ".core.space": ("DesignSpace", "Variable"),
    ".core.problem": ("DesignProblem", "Evaluation"),
    ".core.evaluation_log": ("EvaluationLog",),
    ".core.optimize": ("OptimizationResult", "Optimizer", "StopOptimization", "get_optimizer",
                       "optimize", "optimizers", "register_optimizer", "unregister_optimizer"),
    ".core.executors": ("DaskExecutor", "Executor", "ExecutorError", "ProcessExecutor",
                        "SerialExecutor", "TaskError", "TaskFailure", "make_executor"),
    ".devices.gripper": ("GripperDesign", "GripperResult", "StageResult", "evaluate_gripper",
                         "make_gripper_model"),
    ".devices.gripper_heat": ("GripperHeatModel",),
    ".devices.gripper_problem": ("GripperProblem",),
    ".devices.gripper_drive": ("GripperDrive", "gripper_drive"),
    ".devices.miura": ("LiftPowerResult", "MiuraDesign", "MiuraProblem", "heated_creases",
                       "lift_power", "make_miura_model"),
    ".analysis.robustness": ("RobustGripperProblem", "residual_fold_grid",
                             "sweep_residual_fold"),
    ".analysis.uncertainty_sweep": ("GripperSampleProblem", "RobustYieldProblem",
                                    "sweep_uncertainty"),
    ".analysis.heaters": ("HeaterAllocation", "allocate_heaters"),
    ".analysis.tolerance_report": ("SensitivityReport", "sensitivity_report"),
}, modules={"core": ".core", "devices": ".devices", "analysis": ".analysis"},
    moved="._moved", renamed="._moved")

__all__ = [
    # design spaces and problems
    "Variable", "DesignSpace", "DesignProblem", "Evaluation",
    # optimisation and evaluation logs
    "optimize", "OptimizationResult", "StopOptimization", "Optimizer", "optimizers",
    "get_optimizer", "register_optimizer", "unregister_optimizer", "EvaluationLog",
    # executors
    "Executor", "SerialExecutor", "ProcessExecutor", "DaskExecutor", "make_executor",
    "ExecutorError", "TaskError", "TaskFailure",
    # gripper
    "GripperDesign", "GripperHeatModel", "make_gripper_model", "evaluate_gripper", "GripperResult", "StageResult",
    "GripperProblem", "GripperDrive", "gripper_drive",
    # Miura lifter
    "MiuraDesign", "make_miura_model", "heated_creases", "lift_power", "LiftPowerResult",
    "MiuraProblem",
    # robustness and fabrication uncertainty
    "residual_fold_grid", "sweep_residual_fold", "RobustGripperProblem", "sweep_uncertainty",
    "GripperSampleProblem", "RobustYieldProblem",
    # sensitivity of fabrication tolerances
    "sensitivity_report", "SensitivityReport",
    # heater allocation
    "allocate_heaters", "HeaterAllocation",
    # the namespaces
    "core", "devices", "analysis",
]
