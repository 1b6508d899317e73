"""Every dense / sparse size threshold of the package, each with its reason (the one place).

The factorisation ladder (:func:`simulator.linalg.ladder.factorize`) reads them at call time
(``thresholds.X``), so a test may change one with ``monkeypatch.setattr(thresholds, ...)``.
Different consumers need different dense limits for measured reasons; they are all here.
"""

from __future__ import annotations

__all__ = ["DENSE_LIMIT", "SPARSE_MIN", "PARDISO_LIMIT", "ND_LIMIT", "CONDUCTION_DENSE_LIMIT",
           "TRANSIENT_DENSE_LIMIT", "EIGEN_DENSE_LIMIT", "LOSS_DENSE_LAPACK_MIN",
           "DENSE_ONE_THREAD_MIN"]

#: Up to this many free DOFs mechanical tangents are dense: evaluated by the fused kernel
#: (compiled backend) and solved densely by LAPACK or the compiled sparse Cholesky (faster
#: for small meshes). The default dense limit of the ladder (Newton, arc length, dynamics).
DENSE_LIMIT = 150

#: From this many free DOFs (and up to :data:`DENSE_LIMIT`) the fused path factors sparsely
#: (:class:`~simulator.linalg.small_solve.SparseCholesky`); smaller systems are solved by
#: LAPACK, as fast there, and their runs do not compile the sparse factorisation.
SPARSE_MIN = 64

#: From this many unknowns on, sparse symmetric systems are factorised by PARDISO when it is
#: available. Above the dense limit PARDISO is faster than SuperLU at every size measured on
#: Miura sheets: 3x at 441 unknowns, 4x at 3,105, 5x at 7,140, 5-6x at 3e5.
PARDISO_LIMIT = 150

#: From this many unknowns on, SuperLU factorises symmetric systems in METIS nested-dissection
#: order (below it SuperLU's minimum degree is as fast, and results stay those of earlier
#: versions).
ND_LIMIT = 10_000

#: Up to this many free nodes the steady conduction matrix (symmetric positive definite, one
#: unknown per node, factorised once per solve) is factorised densely by Cholesky.
CONDUCTION_DENSE_LIMIT = 400

#: Transient heat keeps one factorisation for thousands of time steps: sparse triangular
#: solves are cheaper than dense ones at every size, so it never goes dense (0).
TRANSIENT_DENSE_LIMIT = 0

#: Up to this many free DOFs eigen-analyses (stability, natural modes) use a dense symmetric
#: eigensolver (all eigenvalues, exact inertia); above, shift-invert Lanczos with a factor from
#: the ladder.
EIGEN_DENSE_LIMIT = 600

#: The integral heat-loss operator (dense, theory 4.7) is factorised by single-threaded blocked
#: LAPACK (:mod:`~simulator.linalg.dense_lapack`: Cholesky, LU where not positive definite) from
#: this many sub-triangles on, below by the compiled row-oriented kernels of
#: :mod:`~simulator.linalg.dense_jit` (faster there: no call overhead). Measured 7 Dec 2026
#: (``cholesky_loss`` against ``dense_jit.loss_factor``, the gripper's operator with its 37
#: sheet nodes, best of 400): n = 44 0.036 against 0.029 ms, n = 64 0.047 against 0.053 ms,
#: n = 128 0.13 against 0.19 ms, n = 176 (the gripper's m = 2) 0.20 against 0.34 ms, n = 396
#: 1.1 against 3.1 ms (earlier, 256 here: n = 176 0.35 against 0.29 ms, the call overhead of
#: threadpoolctl's limit since cut to 0.01 ms).
LOSS_DENSE_LAPACK_MIN = 64

#: Dense factorisations and eigen-decompositions of the small-model rung limit BLAS to one
#: thread (:func:`~simulator.linalg.dense_lapack.one_blas_thread`) from this many rows on;
#: below, the limit's 12-30 us would cost more than threads can (measured 7 Dec 2026, idle:
#: dpotrf with rcond n = 24 11 against 42 us with the limit, n = 60 29 against 43 us, n = 120
#: 94 against 93 us; at load 3.4, n = 400 25 ms with OpenBLAS's threads against 4.0 ms).
DENSE_ONE_THREAD_MIN = 100
