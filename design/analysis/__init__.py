"""Analyses of designs: robustness over residual folds, fabrication uncertainty and
heater allocation."""
