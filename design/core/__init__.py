"""The generic design core: design spaces, problems, evaluation logs, optimisers and
executors.

The public names (``from design.core import LoggedProblem``): design spaces and problems
(constraints g(x) <= 0), the optimiser registry, evaluation logs for resumable runs and the
executors that evaluate points in parallel. :func:`design.optimize`, the one entry of every
optimiser, is at ``design``'s door (``design.core.optimize`` is its module).
"""

from simulator._lazy import attach as _attach

__getattr__, __dir__ = _attach(__name__, {
    ".space": ("DesignSpace", "Variable"),
    ".problem": ("EVALUATION_STATUSES", "DesignProblem", "Evaluation", "EvaluationOutcome"),
    ".evaluation_log": ("EvaluationLog", "LoggedProblem"),
    ".optimize": ("OptimizationResult", "Optimizer", "StopOptimization", "get_optimizer",
                  "optimizers", "register_optimizer", "unregister_optimizer"),
    ".executors": ("DaskExecutor", "Executor", "ExecutorError", "ProcessExecutor",
                   "SerialExecutor", "TaskError", "TaskFailure", "executor_from_option",
                   "make_executor"),
})

__all__ = [
    # design spaces and problems
    "Variable", "DesignSpace", "DesignProblem", "Evaluation", "EvaluationOutcome",
    "EVALUATION_STATUSES",
    # optimisers and evaluation logs
    "OptimizationResult", "StopOptimization", "Optimizer", "optimizers", "get_optimizer",
    "register_optimizer", "unregister_optimizer", "EvaluationLog", "LoggedProblem",
    # executors
    "Executor", "SerialExecutor", "ProcessExecutor", "DaskExecutor", "make_executor",
    "executor_from_option", "ExecutorError", "TaskError", "TaskFailure",
]
