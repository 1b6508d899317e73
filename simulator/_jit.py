"""Which compiled kernels run: the one place that decides (docs: ``docs/kernels.md``).

Every compiled kernel of the package (springs, the fused evaluation, the thermal element data,
the sparse Cholesky, the fold angles, the integral loss's single-layer terms, the large-pattern
scatter loop) is an accelerator with a numpy twin. Three tiers run them:

* ``"numpy"``: the numpy (and LAPACK) reference path; nothing compiled.
* ``"numba"``: numba's JIT kernels, compiled on first use (cached by numba on disk).
* ``"aot"``: the kernels of a small model compiled ahead of time with ``numba.pycc``
  (:mod:`simulator._aot`: loaded without importing numba, bit for bit the JIT kernels' floats);
  kernels the module does not hold are numba's.

:func:`tier` says which tier is in force; every kernel module asks :func:`numba_selected`
(compiled or numpy) and :func:`aot_kernel` (the ahead-of-time copy, if any), never the
environment. The environment variables ``ETORIGAMI_*`` are read here only
(:func:`environment`). The default is ``"numba"`` when numba is installed and
``ETORIGAMI_JIT`` is not off, else ``"numpy"``; :func:`use` (or
:func:`simulator.mechanics.elements.springs.spring_kernel_backend`) changes it within a
``with`` block, and :func:`command_tier` is the CLI's choice for a command. No state of the disk (numba's cache
warm or cold) changes the tier: the same command gives the same floats on its first and
later runs.

Nothing here starts a process unless asked: :func:`warm_kernel_cache` (called by the CLI after
a short command) compiles the kernels and the ahead-of-time module in a detached background
process for the next run, and :func:`compile_thermal_kernel_beside` (called by the CLI before a
short command on a cold cache) one kernel beside the run's own compilation.
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib.util
import logging
import os
import pathlib
import subprocess
import sys
import sysconfig

__all__ = ["AVAILABLE", "BACKENDS", "TIERS", "VARIABLES", "Environment", "environment",
           "default_backend", "numba_selected", "tier", "use", "aot_kernel", "command_tier",
           "compile_kernel", "HELPER_OPTIONS", "kernel_cache_warm", "warm_kernel_cache",
           "compile_thermal_kernel_beside"]

logger = logging.getLogger(__name__)

#: numba is installed (checked without importing it).
AVAILABLE = importlib.util.find_spec("numba") is not None
#: The tiers, fastest first (see the module's docstring).
TIERS = ("aot", "numba", "numpy")
#: What :func:`simulator.mechanics.elements.springs.spring_kernel_backend` accepts.
BACKENDS = ("numba", "numpy")
#: The environment variables of the package, all read by :func:`environment`.
VARIABLES = ("ETORIGAMI_JIT", "ETORIGAMI_AOT", "ETORIGAMI_AOT_DIR", "ETORIGAMI_PARDISO",
             "ETORIGAMI_MKL_RT")
_OFF = ("0", "off", "no", "false", "never", "numpy")


@dataclasses.dataclass(frozen=True)
class Environment:
    """The ``ETORIGAMI_*`` variables, parsed (the table in ``docs/kernels.md``)."""

    #: ``ETORIGAMI_JIT``: False when off (``0``, ``off``, ``no``, ``false``, ``never``,
    #: ``numpy``): the numpy kernels everywhere; True when set otherwise (the CLI then uses
    #: numba's JIT kernels for every command); None when unset.
    jit: bool | None
    #: ``ETORIGAMI_AOT`` not off (also ``jit``): short CLI commands may use the ahead-of-time
    #: kernels.
    aot: bool
    #: ``ETORIGAMI_AOT_DIR``: the folder of the ahead-of-time module, or None (the default of
    #: :func:`simulator._aot.aot_dir`).
    aot_dir: str | None
    #: ``ETORIGAMI_PARDISO`` not ``0``/``false``/``no``/``off``: MKL PARDISO for large systems
    #: when installed.
    pardiso: bool
    #: ``ETORIGAMI_MKL_RT``: the path of MKL's runtime library, or None (searched).
    mkl_rt: str | None


_parsed: tuple = (None, None)


def environment() -> Environment:
    """The ``ETORIGAMI_*`` variables (:data:`VARIABLES`) of this process, parsed: the only
    place the package reads them. Parsed once and kept while the variables keep their values
    (set them before the process starts; a test that changes them is seen at the next call)."""
    global _parsed
    raw = tuple(os.environ.get(name) for name in VARIABLES)
    if raw != _parsed[0]:
        _parsed = (raw, _parse(*raw))
    return _parsed[1]


def _parse(jit, aot, aot_dir, pardiso, mkl_rt) -> Environment:
    def word(value):
        return (value or "").strip().lower()

    return Environment(jit=None if not word(jit) else word(jit) not in _OFF,
                       aot=word(aot) not in _OFF + ("jit",),
                       aot_dir=aot_dir or None,
                       pardiso=word(pardiso) not in ("0", "false", "no", "off"),
                       mkl_rt=mkl_rt or None)


#: The backend of a :func:`use` block: None (the default), "numba" or "numpy".
_backend = None
#: Ahead-of-time kernels asked for (a :func:`use` block of "aot", or
#: :func:`simulator._aot.enable`).
_aot = False


def default_backend() -> str:
    """``"numba"`` if installed and not switched off by ``ETORIGAMI_JIT``, else ``"numpy"``."""
    return "numba" if AVAILABLE and environment().jit is not False else "numpy"


def numba_selected() -> bool:
    """Whether compiled kernels run (tier "numba" or "aot"): the switch every compiled kernel
    asks; nothing is imported or compiled."""
    return (_backend or default_backend()) == "numba"


def aot_kernel(name: str):
    """The ahead-of-time compiled kernel ``name`` (``"fused"``, ``"thermal"``,
    ``"cholesky"``, ``"fold_angles"``, ``"quiet"``) when the tier is "aot" and the module
    loads (:mod:`simulator._aot`, no numba imported); else None (numba's kernel, or numpy)."""
    if not (_aot and numba_selected() and environment().aot):
        return None
    from . import _aot as aot

    return aot.module_kernel(name)


def tier() -> str:
    """The tier in force: ``"aot"`` (asked for and the module loaded: its kernels, numba's
    for the others), ``"numba"`` or ``"numpy"``."""
    if not numba_selected():
        return "numpy"
    return "aot" if aot_kernel("fused") is not None else "numba"


@contextlib.contextmanager
def use(name: str):
    """Run the kernels of tier ``name`` (:data:`TIERS`) inside the ``with`` block; the tier
    before is restored on exit. ``"aot"`` uses the ahead-of-time module where it loads and
    numba's kernels otherwise; ``"numba"`` numba's JIT kernels; ``"numpy"`` none."""
    global _backend, _aot
    if name not in TIERS:
        from .errors import ParameterError

        raise ParameterError(f"kernel tier {name!r}; use one of {', '.join(map(repr, TIERS))}.")
    before = _backend, _aot
    _backend, _aot = ("numpy", False) if name == "numpy" else ("numba", name == "aot")
    try:
        yield
    finally:
        _backend, _aot = before


def command_tier(short: bool) -> str:
    """The tier of a CLI command, the same on its first run and later ones: the default
    (:func:`default_backend`), except that short commands (one case, one gripper evaluation)
    use the ahead-of-time kernels when their module is built for these sources (checked from
    the files, nothing imported), unless ``ETORIGAMI_JIT`` or ``ETORIGAMI_AOT`` is set
    otherwise. The JIT and ahead-of-time kernels give the same floats, so whether the module
    is built yet changes the time of a run, not its results."""
    chosen, env = default_backend(), environment()
    if not short or chosen == "numpy" or env.jit is not None or not env.aot:
        return chosen
    from . import _aot as aot

    return "aot" if aot.available(log=True) else "numba"

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
    ("mechanics/elements/_springs_jit.py", ("cross", "dot", "element")),
    ("mechanics/elements/_fused_jit.py", ("_kernel", "_face", "_vertex_edge", "_contact_pair")),
    ("thermal/_thermal_jit.py", ("_kernel", "_point_triangle_distance")),
    ("_angles_jit.py", ("_kernel", "_quiet")),
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
    if not AVAILABLE:
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
    from . import _angles_jit
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


def compile_thermal_kernel_beside() -> bool:
    """On a cold numba cache, compile the thermal kernel in a second process while this one
    compiles the others (:func:`simulator.thermal._thermal_jit.compile_in_background`: about
    1 s of wall time saved on the first run after install); returns whether it started one.
    Only on request: the CLI calls it before a short command; no simulation does."""
    if not AVAILABLE or kernel_cache_warm():
        return False
    from .thermal import _thermal_jit

    return _thermal_jit.compile_in_background()


def warm_kernel_cache() -> bool:
    """Start a detached background process that compiles the kernels of a small model into
    numba's cache and then the ahead-of-time module of :mod:`simulator._aot` (several seconds
    of CPU, on another core), unless both are there already; returns whether it was
    started. The caller does not wait: its own run keeps the kernels it has, and the next
    process finds the cache warm (:func:`kernel_cache_warm`) and the module built. Any
    failure is logged at DEBUG and ignored (only the next run's speed depends on it).

    Only on request: the CLI calls it after a short command (:func:`command_tier`); no
    simulation does."""
    from . import _aot

    if not AVAILABLE or (kernel_cache_warm() and not _aot.wanted()):
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
