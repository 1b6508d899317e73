"""Vectorised element kernels: energy, gradient (n_el, 3k) and Hessian (n_el, 3k, 3k)."""
