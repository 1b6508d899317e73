"""Linear algebra: the one factorisation ladder (dense LAPACK, PARDISO, SuperLU with nested
dissection, fallbacks; :mod:`.factorize`) with its thresholds (:mod:`.thresholds`) shared by
every solver, and the compiled single-threaded dense factorisations of the integral heat-loss
operator (:mod:`._dense_jit`)."""

from .ladder import BACKENDS, Factor, factorize, solve

__all__ = ["BACKENDS", "Factor", "factorize", "solve"]
