"""Linear algebra: the factorisation ladder (dense LAPACK, PARDISO, SuperLU with nested
dissection) shared by every solver."""
