"""numba's cache seen from the files (simulator._jit.kernel_cache_warm) and the CLI's choice of
kernels for short commands (design.cli._common.kernel_backend): compiled when the cache is
warm, numpy plus a background compilation when it is cold."""

import importlib.util
import os

import pytest

from simulator import _jit
from simulator.mechanics.elements import _springs_jit

pytestmark = pytest.mark.skipif(importlib.util.find_spec("numba") is None,
                                reason="numba not installed")

KERNELS = (("pkg/_k_jit.py", ("_kernel", "_helper")),)


def _source(root):
    src = root / "pkg" / "_k_jit.py"
    src.parent.mkdir(parents=True)
    src.write_text("def _kernel(): pass\n")
    return src


def _index(src, function, age=0.0):
    cache = src.parent / "__pycache__"
    cache.mkdir(exist_ok=True)
    index = cache / f"{src.stem}.{function}-1.py{_jit.sysconfig.get_config_var('py_version_nodot')}.nbi"
    index.write_bytes(b"")
    mtime = os.stat(src).st_mtime + age
    os.utime(index, (mtime, mtime))
    return index


def test_warm_only_when_every_kernel_has_an_index_at_least_as_new_as_its_source(tmp_path,
                                                                                 monkeypatch):
    monkeypatch.setattr(_jit, "_ROOT", tmp_path)
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "user-cache"))
    src = _source(tmp_path)
    assert not _jit.kernel_cache_warm(KERNELS)                  # nothing cached
    _index(src, "_kernel")
    assert not _jit.kernel_cache_warm(KERNELS)                  # one of two
    stale = _index(src, "_helper", age=-10.0)
    assert not _jit.kernel_cache_warm(KERNELS)                  # source edited after it
    stale.unlink()
    _index(src, "_helper", age=1.0)
    assert _jit.kernel_cache_warm(KERNELS)


def test_cache_in_numba_cache_dir_counts(tmp_path, monkeypatch):
    monkeypatch.setattr(_jit, "_ROOT", tmp_path / "src")
    src = _source(tmp_path / "src")
    cache_dir = tmp_path / "numba-cache"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache_dir))
    import hashlib                                     # numba's folder name in its cache dir

    folder = src.parent.resolve()
    mirror = cache_dir / f"{folder.name}_{hashlib.sha1(str(folder).encode()).hexdigest()}"
    mirror.mkdir(parents=True)
    tag = "py" + _jit.sysconfig.get_config_var("py_version_nodot")
    for f in ("_kernel", "_helper"):
        (mirror / f"{src.stem}.{f}-3.{tag}.nbi").write_bytes(b"")
    assert _jit.kernel_cache_warm(KERNELS)


def test_the_package_kernels_are_named_by_existing_functions():
    for rel, functions in _jit.SMALL_MODEL_KERNELS:
        text = (_jit._ROOT / rel).read_text()
        for f in functions:
            assert f"def {f}(" in text, (rel, f)


@pytest.mark.parametrize("warm", [True, False])
def test_short_commands_use_numba_only_with_a_warm_cache(monkeypatch, warm):
    import simulator
    from design.cli import _common
    from simulator import _aot

    started = []
    monkeypatch.delenv("ETORIGAMI_JIT", raising=False)
    monkeypatch.setattr(_aot, "available", lambda log=False: False)
    monkeypatch.setattr(simulator.kernels, "kernel_cache_warm", lambda: warm)
    monkeypatch.setattr(simulator.kernels, "warm_kernel_cache", lambda: started.append(1))
    with _common.kernel_backend(short=True):
        chosen = _springs_jit.backend
    assert chosen == (None if warm else "numpy")           # None: the default (numba)
    assert started == [1]                      # builds the AOT module (and the cache if cold)
    with _common.kernel_backend(short=False):
        assert _springs_jit.backend is None


def test_short_commands_use_the_aot_kernels_when_built(monkeypatch):
    import simulator
    from design.cli import _common
    from simulator import _aot

    monkeypatch.delenv("ETORIGAMI_JIT", raising=False)
    monkeypatch.setattr(_aot, "available", lambda log=False: True)
    monkeypatch.setattr(_aot, "_enabled", False)
    monkeypatch.setattr(_aot, "_module", False)            # as if it failed to load
    monkeypatch.setattr(simulator.kernels, "warm_kernel_cache", lambda: pytest.fail("started"))
    with _common.kernel_backend(short=True):
        assert _aot._enabled and _springs_jit.backend is None
    assert not _aot._enabled                               # only within the command
    with _common.kernel_backend(short=False):
        assert not _aot._enabled


def test_warm_cache_starts_nothing(monkeypatch):
    from simulator import _aot

    monkeypatch.setattr(_jit, "kernel_cache_warm", lambda *a: True)
    monkeypatch.setattr(_aot, "wanted", lambda: False)
    monkeypatch.setattr(_jit.subprocess, "Popen", lambda *a, **k: pytest.fail("started"))
    assert _jit.warm_kernel_cache() is False


def test_warm_cache_without_the_aot_module_builds_it(monkeypatch, tmp_path):
    from simulator import _aot

    calls = []
    monkeypatch.setattr(_jit, "kernel_cache_warm", lambda *a: True)
    monkeypatch.setattr(_aot, "wanted", lambda: True)
    monkeypatch.setattr(_jit, "_compile_lock", lambda: tmp_path / "compile.lock")
    monkeypatch.setattr(_jit.subprocess, "Popen", lambda argv, **kw: calls.append(argv))
    assert _jit.warm_kernel_cache() is True
    assert "compile_kernels_and_aot_module" in calls[0][-1]


def test_cold_cache_starts_one_detached_process(monkeypatch, tmp_path):
    calls = []
    monkeypatch.setattr(_jit, "kernel_cache_warm", lambda *a: False)
    monkeypatch.setattr(_jit, "_compile_lock", lambda: tmp_path / "compile.lock")
    monkeypatch.setattr(_jit.subprocess, "Popen", lambda argv, **kw: calls.append((argv, kw)))
    assert _jit.warm_kernel_cache() is True
    (argv, kw), = calls
    assert "compile_kernels_and_aot_module" in argv[-1] and kw["start_new_session"]
    assert _jit.warm_kernel_cache() is False and len(calls) == 1     # one is running
    os.utime(tmp_path / "compile.lock", (1.0, 1.0))                   # a stale marker
    assert _jit.warm_kernel_cache() is True and len(calls) == 2


def test_the_lock_depends_on_the_cache_dir(monkeypatch, tmp_path):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    default = _jit._compile_lock()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert _jit._compile_lock() != default
