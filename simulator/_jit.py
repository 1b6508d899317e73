"""One way to compile a numba kernel lazily: :func:`compile_kernel`.

Every compiled kernel of the package (springs, the fused evaluation, the thermal element data,
the sparse Cholesky, the large-pattern scatter loop) is an accelerator with a numpy or LAPACK
twin: numba is imported and the kernel compiled (or loaded from numba's cache) on first use,
and if that fails the caller keeps the reference path for the rest of the process, after one
warning.
"""

from __future__ import annotations

import logging

__all__ = ["compile_kernel", "HELPER_OPTIONS"]

logger = logging.getLogger(__name__)

#: numba options of helpers called from compiled code only: no Python or C wrappers (less to
#: compile). Shared by the element kernels and the compiled linear algebra.
HELPER_OPTIONS = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True}


def compile_kernel(what: str, build, instead: str):
    """``build()`` (imports numba, compiles or loads the kernel, returns it), logged; ``None``
    with one warning ``"numba could not compile the <what> (...); <instead>"`` if it raises.

    Parameters
    ----------
    what : str
        The kernel, e.g. ``"thermal kernel"``.
    build : callable
        Compiles the kernel and returns the compiled function.
    instead : str
        What the caller does without it, e.g. ``"using numpy"``.
    """
    logger.info("compiling the %s with numba (cached after the first time)", what)
    try:
        return build()
    except Exception as exc:  # noqa: BLE001 - numba is an accelerator, never a requirement
        logger.warning("numba could not compile the %s (%s: %s); %s", what,
                       type(exc).__name__, exc, instead)
        return None
