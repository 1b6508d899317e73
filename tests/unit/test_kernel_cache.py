"""The one place that chooses the kernels (simulator._jit): the environment read there only,
the tier of a CLI command the same whatever numba's cache holds (design.cli._common.kernel_backend),
numba's cache seen from the files (kernel_cache_warm) and the background compilation the CLI
asks for (warm_kernel_cache)."""

import importlib.util
import os

import pytest

from simulator import _jit

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
def test_short_commands_run_numba_whether_the_cache_is_warm_or_cold(monkeypatch, warm):
    """One tier whatever numba's cache holds (the same floats on the first and later runs);
    on a cold cache the CLI asks for the thermal kernel's compilation beside the run, and
    after the run for the ahead-of-time module."""
    from design.cli import _common
    from simulator import _aot
    from simulator.thermal import _thermal_jit

    asked = []
    monkeypatch.delenv("ETORIGAMI_JIT", raising=False)
    monkeypatch.delenv("ETORIGAMI_AOT", raising=False)
    monkeypatch.setattr(_aot, "available", lambda log=False: False)
    monkeypatch.setattr(_jit, "kernel_cache_warm", lambda *a: warm)
    monkeypatch.setattr(_jit, "warm_kernel_cache", lambda: asked.append("aot module"))
    monkeypatch.setattr(_thermal_jit, "compile_in_background", lambda: asked.append("thermal"))
    with _common.kernel_backend(short=True):
        assert _jit.tier() == "numba" and asked == ([] if warm else ["thermal"])
    assert asked[-1] == "aot module"                        # asked for after the run
    assert _jit._backend is None and not _jit._aot          # restored
    asked.clear()
    with _common.kernel_backend(short=False):
        assert _jit.tier() == "numba"
    assert asked == []                                      # long commands ask for nothing


def test_short_commands_use_the_aot_kernels_when_built(monkeypatch):
    from design.cli import _common
    from simulator import _aot

    monkeypatch.delenv("ETORIGAMI_JIT", raising=False)
    monkeypatch.delenv("ETORIGAMI_AOT", raising=False)
    monkeypatch.setattr(_aot, "available", lambda log=False: True)
    monkeypatch.setattr(_jit, "_aot", False)
    monkeypatch.setattr(_aot, "_module", False)            # as if it failed to load
    monkeypatch.setattr(_jit, "warm_kernel_cache", lambda: pytest.fail("started"))
    with _common.kernel_backend(short=True):
        assert _jit._aot and _jit.numba_selected()
        assert _jit.tier() == "numba"                      # it did not load: numba's kernels
    assert not _jit._aot                                   # only within the command
    with _common.kernel_backend(short=False):
        assert not _jit._aot


@pytest.mark.parametrize("env, short, tier", [
    ({}, True, "aot"), ({}, False, "numba"), ({"ETORIGAMI_JIT": "0"}, True, "numpy"),
    ({"ETORIGAMI_JIT": "1"}, True, "numba"), ({"ETORIGAMI_AOT": "0"}, True, "numba"),
])
def test_the_command_tier_follows_the_environment_only(monkeypatch, env, short, tier):
    from simulator import _aot

    for name in _jit.VARIABLES:
        monkeypatch.delenv(name, raising=False)
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    monkeypatch.setattr(_aot, "available", lambda log=False: True)   # the module is built
    assert _jit.command_tier(short) == (tier if _jit.AVAILABLE else "numpy")


def test_the_environment_is_read_in_one_place(monkeypatch):
    for name in _jit.VARIABLES:
        monkeypatch.delenv(name, raising=False)
    default = _jit.environment()
    assert (default.jit, default.aot, default.aot_dir, default.pardiso, default.mkl_rt) == (
        None, True, None, True, None)
    assert _jit.environment() is default                              # parsed once
    monkeypatch.setenv("ETORIGAMI_JIT", "off")
    monkeypatch.setenv("ETORIGAMI_AOT", "jit")
    monkeypatch.setenv("ETORIGAMI_PARDISO", "0")
    monkeypatch.setenv("ETORIGAMI_MKL_RT", "/opt/libmkl_rt.so.2")
    monkeypatch.setenv("ETORIGAMI_AOT_DIR", "/tmp/aot")
    env = _jit.environment()
    assert (env.jit, env.aot, env.aot_dir, env.pardiso, env.mkl_rt) == (
        False, False, "/tmp/aot", False, "/opt/libmkl_rt.so.2")
    assert _jit.default_backend() == "numpy" and _jit.tier() == "numpy"
    with _jit.use("numba" if _jit.AVAILABLE else "numpy"):
        assert _jit.numba_selected() == _jit.AVAILABLE
    with pytest.raises(Exception, match="kernel tier 'cuda'; use one of 'aot', 'numba', 'numpy'"):
        with _jit.use("cuda"):
            pass


def test_no_kernel_module_reads_the_environment():
    """ETORIGAMI_* appear in code (not docstrings or comments) of simulator/_jit.py only."""
    import ast
    import pathlib

    root = pathlib.Path(_jit.__file__).parent
    readers = set()
    for path in [*root.rglob("*.py"), *(root.parent / "design").rglob("*.py")]:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) \
                    and node.value.startswith("ETORIGAMI_") and " " not in node.value:
                readers.add(path.relative_to(root.parent).as_posix())
    assert readers == {"simulator/_jit.py"}


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
