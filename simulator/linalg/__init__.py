"""Linear algebra: the one factorisation ladder (dense LAPACK, PARDISO, SuperLU with nested
dissection, fallbacks; :mod:`.factorize`) with its thresholds (:mod:`.thresholds`) shared by
every solver, and the single-threaded dense factorisations of the integral heat-loss operator
(compiled kernels, :mod:`.dense_jit`, and blocked LAPACK from
:data:`~.thresholds.LOSS_DENSE_LAPACK_MIN` sub-triangles on, :mod:`.dense_lapack`)."""

from .ladder import BACKENDS, Factor, factorize, solve

__all__ = ["BACKENDS", "Factor", "factorize", "solve"]
