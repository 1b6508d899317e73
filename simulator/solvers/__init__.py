"""Solvers: Newton load control, arc-length continuation and displacement control,
dynamics (generalized-alpha), stability and natural modes."""
