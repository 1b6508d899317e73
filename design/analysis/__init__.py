"""Analyses of designs: robustness over residual folds, fabrication uncertainty, tolerance
sensitivity reports and heater allocation.

The public names (``from design.analysis import wilson_interval``): residual-fold sweeps and
robust problems, fabrication scenarios with their yield sweeps and statistics, the sensitivity
report of fabrication tolerances (exact gradients, first-order propagation, its Monte Carlo
check and tornado plot), and the heater allocation with its influence matrices and fold
sensitivities.
"""

from simulator._lazy import attach as _attach

__getattr__, __dir__ = _attach(__name__, {
    ".robustness": ("CREASE_GROUPS", "RobustGripperProblem", "residual_fold_grid",
                    "sweep_residual_fold", "with_residual_fold"),
    ".uncertainty": ("SCENARIOS", "Distribution", "FabricationScenario", "UncertainInput",
                     "rank_correlations", "residual_fold_per_crease", "wilson_interval"),
    ".uncertainty_sweep": ("GripperSampleProblem", "RobustYieldProblem", "summarize_yield",
                           "sweep_uncertainty"),
    ".tolerance_report": ("SensitivityReport", "problem_sensitivity_report",
                          "sensitivity_report"),
    ".tolerance_mc": ("MonteCarloComparison", "monte_carlo_comparison", "perturbed_protocol"),
    ".tolerance_plots": ("plot_tornado",),
    ".heaters": ("ALLOCATION_STATUSES", "HeaterAllocation", "TEMPERATURE_MEASURES",
                 "allocate_heaters", "fold_sensitivity", "influence_matrices",
                 "limit_temperatures", "linear_allocation"),
})

__all__ = [
    # robustness over residual folds
    "residual_fold_grid", "sweep_residual_fold", "with_residual_fold", "RobustGripperProblem",
    "CREASE_GROUPS",
    # fabrication uncertainty
    "FabricationScenario", "SCENARIOS", "Distribution", "UncertainInput", "sweep_uncertainty",
    "summarize_yield", "GripperSampleProblem", "RobustYieldProblem", "residual_fold_per_crease",
    "wilson_interval", "rank_correlations",
    # sensitivity of fabrication tolerances
    "sensitivity_report", "problem_sensitivity_report", "SensitivityReport",
    "monte_carlo_comparison", "MonteCarloComparison",
    "perturbed_protocol", "plot_tornado",
    # heater allocation
    "allocate_heaters", "linear_allocation", "HeaterAllocation", "ALLOCATION_STATUSES",
    "influence_matrices", "fold_sensitivity", "limit_temperatures", "TEMPERATURE_MEASURES",
]
