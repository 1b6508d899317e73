"""Ahead-of-time compiled kernels of a small model, loaded without numba.

A short command (one case, one gripper evaluation) spends more time importing numba and
setting up its compiler (about 0.55 s of CPU, even when every kernel comes from numba's cache)
than in its kernels. So the kernels such a run calls, the fused mechanics evaluation
(:mod:`simulator.mechanics.elements._fused_jit`), the thermal element data
(:mod:`simulator.thermal._thermal_jit`), the sparse Cholesky of models from 64 free DOFs
(:mod:`simulator.linalg._cholesky_jit`) and the crossing watch's fold angles
(:mod:`simulator._angles_jit`), are also compiled ahead of time with ``numba.pycc``
into one extension module in the user cache (:func:`aot_dir`). Loading it costs well under a
millisecond and imports nothing from numba.

* **Same floats.** The module is compiled by numba from the same sources and signatures as the
  JIT kernels; without ``fastmath`` LLVM neither reorders nor contracts floating-point
  operations, so its results are those of the JIT kernels bit for bit (the tests compare them
  on a real run).
* **Keyed.** The module's name and its manifest (a JSON file beside it) carry a hash of the
  kernel sources, the numba, numpy and Python versions and the CPU (:func:`key`); the manifest
  also holds the SHA-256 of the module file. A module whose manifest does not match (stale, or
  a file damaged or replaced) is ignored, with an INFO line saying why.
* **Built in the background.** :func:`build` compiles it (about 7 s of CPU); the CLI starts it
  in a detached process after a short command when it is missing
  (:func:`simulator._jit.warm_kernel_cache`), so only the next run profits.
* **Chosen in one place.** Its kernels run where :mod:`simulator._jit` says the tier is
  ``"aot"`` (the CLI's short commands, :func:`simulator._jit.command_tier`, or a block of
  :func:`simulator._jit.use`); the kernels ask :func:`simulator._jit.aot_kernel` at each call,
  so leaving the block restores numba's. ``ETORIGAMI_AOT=0`` switches it off. Any failure
  falls back to the JIT kernels (the same floats).
* **Deprecated upstream.** numba marks ``numba.pycc`` pending deprecation (a warning on its
  import): it is imported by :func:`build` only, with that warning silenced, never by
  ``import simulator``. The plan, with the first-run times it buys: ``docs/kernels.md``.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.machinery
import importlib.util
import json
import logging
import os
import pathlib
import platform
import sys
import sysconfig

from . import _jit

__all__ = ["aot_dir", "available", "build", "disable", "enable", "enabled", "kernel", "key",
           "module_kernel", "wanted"]

logger = logging.getLogger(__name__)

_ROOT = pathlib.Path(__file__).resolve().parent
#: Exported name, module under ``simulator``, its Python function, its signature attribute.
EXPORTS = (
    ("fused", "mechanics.elements._fused_jit", "_kernel", "SIGNATURE"),
    ("thermal", "thermal._thermal_jit", "_kernel", "_SIGNATURE"),
    ("cholesky", "linalg._cholesky_jit", "_kernel", "SIGNATURE"),
    ("fold_angles", "_angles_jit", "_kernel", "SIGNATURE"),
    ("quiet", "_angles_jit", "_quiet", "QUIET_SIGNATURE"),
)
#: Every source the compiled code comes from (the fused kernel calls the spring element of
#: ``_springs_jit``), and this file (how it is built).
SOURCES = ("mechanics/elements/_fused_jit.py", "mechanics/elements/_springs_jit.py",
           "thermal/_thermal_jit.py", "linalg/_cholesky_jit.py", "_angles_jit.py",
           "_aot.py")
_PREFIX = "_etorigami_kernels_"

#: The loaded module; False after a failed attempt in this process (not tried again).
_module = None


def aot_dir() -> pathlib.Path:
    """Folder of the compiled module: ``ETORIGAMI_AOT_DIR`` if set, else ``etorigami-aot`` in
    ``NUMBA_CACHE_DIR`` if that is set, else ``<XDG_CACHE_HOME or ~/.cache>/etorigami/aot``
    (beside numba's user-wide cache)."""
    if _jit.environment().aot_dir:
        return pathlib.Path(_jit.environment().aot_dir)
    if os.environ.get("NUMBA_CACHE_DIR"):
        return pathlib.Path(os.environ["NUMBA_CACHE_DIR"]) / "etorigami-aot"
    cache_home = os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache")
    return pathlib.Path(cache_home) / "etorigami" / "aot"


def _cpu() -> str:
    """The CPU: architecture and, on Linux, the model name and feature flags."""
    info = [platform.machine()]
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as fh:
            for line in fh:
                if line.startswith(("model name", "flags")):
                    info.append(line.strip())
                if len(info) == 3:
                    break
    except OSError:
        info.append(platform.processor())
    return "|".join(info)


def _version_file(package: str, name: str):
    """The text of ``package``'s version file ``name`` (read, not imported: a usage error of
    the CLI stays quick), else its distribution's version; None if it is not installed."""
    spec = importlib.util.find_spec(package)
    if spec is None or not spec.origin:
        return None
    try:
        return (pathlib.Path(spec.origin).parent / name).read_text(encoding="utf-8")
    except OSError:
        from importlib import metadata

        try:
            return metadata.version(package)
        except metadata.PackageNotFoundError:
            return None


def key():
    """Hex SHA-256 of the kernel sources (:data:`SOURCES`), the numba, numpy and Python
    versions and the CPU; None if numba is not installed or a source cannot be read. Computed
    without importing numba or numpy."""
    numba_version = _version_file("numba", "_version.py")
    if numba_version is None:
        return None
    hasher = hashlib.sha256()
    for part in (numba_version, _version_file("numpy", "version.py") or "", sys.version,
                 sysconfig.get_config_var("EXT_SUFFIX") or "", _cpu()):
        hasher.update(part.encode() + b"\0")
    try:
        for rel in SOURCES:
            hasher.update((_ROOT / rel).read_bytes() + b"\0")
    except OSError:
        return None
    return hasher.hexdigest()


def _paths(k: str):
    """(module name, module file, manifest file) for key ``k``."""
    name = _PREFIX + k[:24]
    folder = aot_dir()
    return name, folder / (name + (sysconfig.get_config_var("EXT_SUFFIX") or ".so")), \
        folder / (name + ".json")


def _switched_off() -> bool:
    return not _jit.environment().aot


def _file_sha256(path) -> str:
    return hashlib.sha256(pathlib.Path(path).read_bytes()).hexdigest()


def _load():
    """Import the compiled module if it is present and its manifest matches; None (with an
    INFO or DEBUG line saying why) otherwise."""
    if _switched_off():
        logger.debug("ahead-of-time kernels switched off (ETORIGAMI_AOT)")
        return None
    k = key()
    if k is None:
        logger.debug("no ahead-of-time kernels: numba is not installed or a source is missing")
        return None
    name, module_file, manifest_file = _paths(k)
    if not manifest_file.exists():
        logger.info("no ahead-of-time kernels for these sources yet (%s); using numba",
                    manifest_file)
        return None
    try:
        manifest = json.loads(manifest_file.read_text(encoding="utf-8"))
        if manifest.get("key") != k:
            logger.info("ahead-of-time kernels %s are stale (built for other sources or "
                        "versions); ignored, using numba", module_file)
            return None
        if manifest.get("sha256") != _file_sha256(module_file):
            logger.info("ahead-of-time kernels %s do not match their manifest (damaged or "
                        "replaced); ignored, using numba", module_file)
            return None
        spec = importlib.util.spec_from_file_location(
            name, module_file, loader=importlib.machinery.ExtensionFileLoader(name,
                                                                              str(module_file)))
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    except Exception as exc:  # noqa: BLE001 - an accelerator: numba's kernels instead
        logger.info("could not load the ahead-of-time kernels %s (%s: %s); using numba",
                    module_file, type(exc).__name__, exc)
        return None
    missing = [export for export, *_ in EXPORTS if not callable(getattr(module, export, None))]
    if missing:
        logger.info("ahead-of-time kernels %s lack %s; ignored, using numba", module_file,
                    ", ".join(missing))
        return None
    logger.debug("loaded the ahead-of-time kernels %s", module_file)
    return module


def enable() -> bool:
    """Use the ahead-of-time kernels in this process from now on, if they load (tier "aot" of
    :mod:`simulator._jit` wherever numba's kernels would run); returns whether they did."""
    _jit._aot = True
    return module_kernel(EXPORTS[0][0]) is not None


def disable() -> None:
    """Stop using the ahead-of-time kernels: numba's from the next kernel call on."""
    _jit._aot = False


@contextlib.contextmanager
def enabled():
    """Context in which the kernels are the ahead-of-time ones when they load (:func:`enable`);
    the previous choice is restored on exit."""
    before = _jit._aot
    enable()
    try:
        yield
    finally:
        _jit._aot = before


def kernel(name: str):
    """The ahead-of-time compiled kernel ``name`` where the tier is "aot"
    (:func:`simulator._jit.aot_kernel`), else None."""
    return _jit.aot_kernel(name)


def module_kernel(name: str):
    """The kernel ``name`` of the module (``"fused"``, ``"thermal"``, ``"cholesky"``,
    ``"fold_angles"``, ``"quiet"``), loaded on the first call; None if it does not load
    (logged once, not tried again in this process)."""
    global _module
    if _module is None:
        _module = _load() or False
    return getattr(_module, name, None) if _module else None


def available(log: bool = False) -> bool:
    """Whether a module for the current sources is present with a matching manifest (the
    files only: nothing is imported); with ``log``, say at INFO why not."""
    why = None
    if _switched_off():
        why = "switched off (ETORIGAMI_AOT)"
    elif (k := key()) is None:
        why = "numba is not installed or a kernel source is missing"
    else:
        _, module_file, manifest_file = _paths(k)
        try:
            manifest = json.loads(manifest_file.read_text(encoding="utf-8"))
            if manifest.get("key") != k:
                why = f"{manifest_file} is stale"
            elif not module_file.exists():
                why = f"{module_file} is missing"
        except FileNotFoundError:
            why = f"not built yet for these sources ({manifest_file})"
        except (OSError, ValueError) as exc:
            why = f"unreadable manifest {manifest_file} ({type(exc).__name__}: {exc})"
    if why and log:
        logger.info("no ahead-of-time kernels: %s", why)
    return why is None


def wanted() -> bool:
    """Whether a build would be useful and possible: switched on, numba installed with its
    ``pycc`` (looked for without importing numba: numba marks it pending deprecation), no
    module for the current sources yet."""
    return not _switched_off() and _pycc_shipped() and not available()


def _pycc_shipped() -> bool:
    """Whether the installed numba has ``numba.pycc`` (its folder; nothing imported)."""
    spec = importlib.util.find_spec("numba") if _jit.AVAILABLE else None
    return bool(spec and spec.origin
                and (pathlib.Path(spec.origin).parent / "pycc" / "__init__.py").is_file())


#: Modules kept in :func:`aot_dir` (other checkouts or versions share it); older ones are
#: removed after a build.
KEEP = 8


def _prune(folder: pathlib.Path, keep: int = KEEP) -> None:
    """Remove all but the ``keep`` newest modules (and their manifests) from ``folder``."""
    manifests = sorted(folder.glob(_PREFIX + "*.json"), key=lambda f: f.stat().st_mtime,
                       reverse=True)
    for manifest in manifests[keep:]:
        stem = manifest.name[:-len(".json")]
        for f in folder.glob(stem + "*"):
            f.unlink(missing_ok=True)


def build() -> pathlib.Path:
    """Compile the kernels of :data:`EXPORTS` with ``numba.pycc`` into the module of the
    current key (several seconds of CPU; imports numba), write its manifest, and keep the
    :data:`KEEP` newest modules (other checkouts or versions share the folder); returns the
    module file. Raises if compilation fails."""
    import importlib
    import shutil
    import tempfile
    import warnings

    k = key()
    if k is None:
        raise RuntimeError("numba is not installed (or a kernel source is missing)")
    name, module_file, manifest_file = _paths(k)
    folder = module_file.parent
    folder.mkdir(parents=True, exist_ok=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")            # numba.pycc is deprecated (still works)
        from numba.pycc import CC

        from .linalg import _cholesky_jit
        from .mechanics.elements import _fused_jit
        from .thermal import _thermal_jit

        _fused_jit._compile()                      # the compiled helpers the kernels call
        _thermal_jit._build()
        _cholesky_jit._build()
        with tempfile.TemporaryDirectory(dir=folder, prefix=".build-") as tmp:
            cc = CC(name)
            cc.output_dir = tmp
            cc.verbose = False
            for export, module, function, signature in EXPORTS:
                mod = importlib.import_module(f"{__package__}.{module}")
                cc.export(export, getattr(mod, signature))(getattr(mod, function))
            cc.compile()
            built = pathlib.Path(tmp) / module_file.name
            if not built.exists():
                found = [p for p in pathlib.Path(tmp).iterdir() if p.name.startswith(name)]
                if not found:
                    raise RuntimeError(f"numba.pycc wrote no module {module_file.name}")
                built = found[0]
            staged = pathlib.Path(tmp) / "staged"
            shutil.copyfile(built, staged)
            manifest = {"key": k, "sha256": _file_sha256(staged),
                        "exports": [e[0] for e in EXPORTS]}
            os.replace(staged, module_file)
            (pathlib.Path(tmp) / "manifest").write_text(json.dumps(manifest), encoding="utf-8")
            os.replace(pathlib.Path(tmp) / "manifest", manifest_file)
    _prune(folder)
    logger.info("compiled the ahead-of-time kernels into %s", module_file)
    return module_file
