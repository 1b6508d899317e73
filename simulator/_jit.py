"""One way to compile a numba kernel lazily: :func:`compile_kernel`.

Every compiled kernel of the package (springs, the fused evaluation, the thermal element data,
the sparse Cholesky, the large-pattern scatter loop) is an accelerator with a numpy or LAPACK
twin: numba is imported and the kernel compiled (or loaded from numba's cache) on first use,
and if that fails the caller keeps the reference path for the rest of the process, after one
warning.
"""

from __future__ import annotations

import logging
import os
import pathlib
import subprocess
import sys
import sysconfig

__all__ = ["compile_kernel", "HELPER_OPTIONS", "kernel_cache_warm", "warm_kernel_cache"]

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


_ROOT = pathlib.Path(__file__).resolve().parent
#: The kernels a run of a small model loads (the fused evaluation, the spring element it calls,
#: the thermal element data, the crossing watch's fold angles): source file under
#: ``simulator/`` and the compiled functions.
SMALL_MODEL_KERNELS = (
    ("mechanics/elements/_springs_jit.py", ("_cross", "_dot", "_element")),
    ("mechanics/elements/_fused_jit.py", ("_kernel", "_face", "_vertex_edge", "_contact_pair")),
    ("thermal/_thermal_jit.py", ("_kernel", "_point_triangle_distance")),
    ("mechanics/_angles_jit.py", ("_kernel", "_quiet")),
)


def _cache_dirs(source: pathlib.Path) -> list:
    """Where numba may keep the cache of functions defined in ``source``: ``NUMBA_CACHE_DIR``
    alone when it is set, else ``__pycache__`` next to the file or the user-wide cache (numba's
    locators in order)."""
    import hashlib

    folder = pathlib.Path(os.path.abspath(source)).parent
    # numba's get_suitable_cache_subpath: "<folder name>_<sha1 of the folder path>"
    subpath = f"{folder.name}_{hashlib.sha1(str(folder).encode()).hexdigest()}"
    if os.environ.get("NUMBA_CACHE_DIR"):
        return [pathlib.Path(os.environ["NUMBA_CACHE_DIR"]) / subpath]
    cache_home = os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache")
    return [folder / "__pycache__", pathlib.Path(cache_home) / "numba" / subpath]


def kernel_cache_warm(kernels=SMALL_MODEL_KERNELS) -> bool:
    """Whether numba's cache holds every kernel of ``kernels`` for the current sources, so that
    a process loads them (a few tenths of a second) instead of compiling them (several seconds
    of CPU). Checked from the files alone, without importing numba: an index file
    ``<module>.<function>-<line>.py<XY>.nbi`` newer than its source (numba rewrites the index
    when it compiles; an edited source is newer than its index). False if numba is missing.

    A stale answer costs only time: numba itself checks the index before loading from it and
    compiles when it does not match.
    """
    import importlib.util

    if importlib.util.find_spec("numba") is None:
        return False
    tag = "py" + sysconfig.get_config_var("py_version_nodot")
    for rel, functions in kernels:
        source = _ROOT / rel
        try:
            mtime = source.stat().st_mtime
        except OSError:
            return False
        for function in functions:
            pattern = f"{source.stem}.{function}-*.{tag}.nbi"
            if not any(index.stat().st_mtime >= mtime
                       for folder in _cache_dirs(source) if folder.is_dir()
                       for index in folder.glob(pattern)):
                return False
    return True


#: A background compilation younger than this [s] is taken to be still running.
_COMPILE_LOCK_AGE = 300.0


def _compile_lock() -> pathlib.Path:
    """Marker file of a running background compilation of this installation's kernels into
    this cache (``NUMBA_CACHE_DIR`` is part of the key)."""
    import hashlib
    import tempfile

    where = f"{_ROOT}|{os.environ.get('NUMBA_CACHE_DIR', '')}"
    key = hashlib.sha1(where.encode()).hexdigest()[:12]
    return pathlib.Path(tempfile.gettempdir()) / f"etorigami-compile-{key}.lock"


def compile_small_model_kernels() -> None:
    """Compile (or load) the kernels of :data:`SMALL_MODEL_KERNELS` into numba's cache, in
    this process (what :func:`warm_kernel_cache` runs in the background); removes the marker
    of a background compilation when done."""
    from .mechanics import _angles_jit
    from .mechanics.elements import _fused_jit
    from .thermal import _thermal_jit

    try:
        _fused_jit.fused_kernel()
        _thermal_jit.use_compiled()
        _angles_jit.fold_angles_kernel()
    finally:
        _compile_lock().unlink(missing_ok=True)


def compile_kernels_and_aot_module() -> None:
    """:func:`compile_small_model_kernels`, then the ahead-of-time module of
    :mod:`simulator._aot` if it is missing (what :func:`warm_kernel_cache` runs in the
    background); a failure of the latter is logged and leaves numba's kernels in use."""
    from . import _aot

    lock = _compile_lock()
    try:
        if not kernel_cache_warm():
            compile_small_model_kernels()
        if _aot.wanted():
            lock.touch()
            try:
                _aot.build()
            except Exception as exc:  # noqa: BLE001 - an accelerator of the next short run
                logger.warning("could not build the ahead-of-time kernels (%s: %s); short "
                               "commands keep numba's kernels", type(exc).__name__, exc)
    finally:
        lock.unlink(missing_ok=True)


def warm_kernel_cache() -> bool:
    """Start a detached background process that compiles the kernels of a small model into
    numba's cache and then the ahead-of-time module of :mod:`simulator._aot` (several seconds
    of CPU, on another core), unless both are there already; returns whether it was
    started. The caller does not wait: its own run keeps the kernels it has, and the next
    process finds the cache warm (:func:`kernel_cache_warm`) and the module built. Any
    failure is logged at DEBUG and ignored (only the next run's speed depends on it)."""
    import importlib.util

    from . import _aot

    if kernel_cache_warm() and not _aot.wanted():
        return False
    if importlib.util.find_spec("numba") is None:
        return False
    import time

    lock = _compile_lock()
    try:                                   # one background compilation at a time
        if time.time() - lock.stat().st_mtime < _COMPILE_LOCK_AGE:
            return False
        lock.unlink()
    except OSError:
        pass
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(_ROOT.parent)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    env.pop("ETORIGAMI_JIT", None)
    try:
        lock.touch()
        subprocess.Popen([sys.executable, "-c", "from simulator._jit import "
                          "compile_kernels_and_aot_module as c; c()"],
                         env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, start_new_session=True)
    except OSError as exc:
        logger.debug("no background compilation of the kernels (%s)", exc)
        lock.unlink(missing_ok=True)
        return False
    logger.info("compiling the numba kernels and the ahead-of-time module in a background "
                "process for the next run")
    return True
