"""Solvers: one Newton iteration and one cut-and-retry driver (:mod:`.nonlinear`) behind Newton
load control, arc-length continuation and displacement control, dynamics (generalized-alpha);
stability and natural modes."""
