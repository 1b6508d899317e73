"""Compiled kernels, process-wide: which backend the element kernels use
(:func:`spring_kernel_backend`, a context manager) and numba's on-disk cache of them
(:func:`kernel_cache_warm`, :func:`warm_kernel_cache`). Simulations need none of this: the
default compiles on first use; these are for tools that choose between compiling and the
numpy twins (the CLI's short commands, benchmarks)."""

from ._jit import kernel_cache_warm, warm_kernel_cache
from .mechanics.elements.springs import spring_kernel_backend

__all__ = ["spring_kernel_backend", "kernel_cache_warm", "warm_kernel_cache"]
