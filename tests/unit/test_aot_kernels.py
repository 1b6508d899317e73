"""The ahead-of-time compiled kernels (simulator._aot): the same floats as numba's JIT kernels,
a short CLI run that uses them imports no numba, and a stale or damaged module is ignored with
a log line (numba's kernels instead)."""

import json
import logging
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from simulator import _aot, _jit
from simulator.mechanics.elements import _fused_jit
from simulator.thermal import _thermal_jit

pytestmark = pytest.mark.skipif(not _jit.AVAILABLE, reason="numba not installed")

REPO = Path(__file__).resolve().parents[2]
RUN = ["run", "single-fold", "--set", "residual_fold_deg=-10", "--set", "gravity=true",
       "--set", "thermal_steps=250", "-q"]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """A folder holding the module built for the current sources (about 8 s of CPU)."""
    import sysconfig
    from shutil import which

    assert which((sysconfig.get_config_var("CC") or "cc").split()[0]) or which("cc"), \
        "numba.pycc needs a C compiler: install gcc (.ci/run apt-gets it where missing)"
    folder = tmp_path_factory.mktemp("aot")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("ETORIGAMI_AOT_DIR", str(folder))
        mp.delenv("ETORIGAMI_AOT", raising=False)
        path = _aot.build()
    assert path.exists() and path.parent == folder
    return folder


@pytest.fixture
def aot_env(built, monkeypatch):
    """This process pointed at the built module, with the AOT state of this process reset
    before and after."""
    monkeypatch.setenv("ETORIGAMI_AOT_DIR", str(built))
    monkeypatch.delenv("ETORIGAMI_AOT", raising=False)
    monkeypatch.setattr(_jit, "_aot", False)
    monkeypatch.setattr(_aot, "_module", None)
    return built


def _recorder(monkeypatch, module, jit, name="_compiled"):
    """Replace ``module.<name>`` by a wrapper of numba's kernel ``jit`` that keeps a copy of
    the arguments of every call and its return value; returns the list of (args, result)."""
    calls = []

    def record(*args):
        copied = tuple(a.copy() if isinstance(a, np.ndarray) else a for a in args)
        result = jit(*args)
        calls.append((copied, result))
        return result

    monkeypatch.setattr(module, name, record)
    return calls


def _same_results(jit, aot, calls):
    """Run both kernels on copies of each recorded call: the same return value and the same
    output arrays, bit for bit."""
    for args, _ in calls:
        a = [x.copy() if isinstance(x, np.ndarray) else x for x in args]
        b = [x.copy() if isinstance(x, np.ndarray) else x for x in args]
        assert jit(*a) == aot(*b)
        for x, y in zip(a, b):
            if isinstance(x, np.ndarray):
                assert np.array_equal(x, y, equal_nan=True)


def test_aot_kernels_give_the_jit_floats(aot_env, monkeypatch):
    """On a heated single fold (bars, springs, supports, thermal), the gripper (its sparse
    Cholesky solves) with active contact in all three distance zones and a Miura sheet with
    elastic supports."""
    from simulator.cases import get_case
    from simulator.linalg import _cholesky_jit
    from simulator import _angles_jit
    from tests.unit.test_fused_kernel import _gripper_with_contacts, _miura

    module = _aot._load()
    assert module is not None
    jit_fused = _fused_jit.fused_kernel()
    assert _thermal_jit.use_compiled()
    jit_thermal = _thermal_jit._compiled
    jit_cholesky = _cholesky_jit.cholesky_solve()
    jit_angles, jit_quiet = _angles_jit.fold_angles_kernel(), _angles_jit.quiet_kernel()
    for jit in (jit_fused, jit_thermal, jit_cholesky, jit_angles, jit_quiet):
        assert hasattr(jit, "py_func")                              # numba's
    fused_calls = _recorder(monkeypatch, _fused_jit, jit_fused)
    thermal_calls = _recorder(monkeypatch, _thermal_jit, jit_thermal)
    cholesky_calls = _recorder(monkeypatch, _cholesky_jit, jit_cholesky)
    angles_calls = _recorder(monkeypatch, _angles_jit, jit_angles)
    quiet_calls = _recorder(monkeypatch, _angles_jit, jit_quiet, "_compiled_quiet")
    get_case("single-fold", residual_fold_deg=-10, gravity=True, thermal_steps=40).run()
    for system, u, rest in (_gripper_with_contacts(), _miura()):    # the gripper: Cholesky
        system.evaluate(u, rest)
        system.evaluate(u, rest, hessian=False)
    assert len(fused_calls) > 100 and len(thermal_calls) > 10 and len(cholesky_calls) > 10
    assert len(angles_calls) > 10 and len(quiet_calls) > 10
    assert max(result for _, result in fused_calls) >= 6            # active contact pairs
    _same_results(jit_fused, module.fused, fused_calls)
    _same_results(jit_thermal, module.thermal, thermal_calls)
    _same_results(jit_cholesky, module.cholesky, cholesky_calls)
    _same_results(jit_angles, module.fold_angles, angles_calls)
    _same_results(jit_quiet, module.quiet, quiet_calls)


def test_enabled_kernels_are_the_aot_ones(aot_env, monkeypatch):
    monkeypatch.setattr(_fused_jit, "_compiled", None)
    monkeypatch.setattr(_thermal_jit, "_compiled", None)
    assert _aot.kernel("fused") is None                 # not enabled: numba's kernels
    with _aot.enabled():
        aot = _aot.kernel("fused")
        assert aot is not None and not hasattr(aot, "py_func")
        assert _fused_jit.fused_kernel() is aot and not _fused_jit.needs_compiling()
        assert _thermal_jit.use_compiled() and _thermal_jit._compiled is None
        from simulator.linalg import _cholesky_jit
        assert _cholesky_jit.cholesky_solve() is _aot.kernel("cholesky")
        from simulator import _angles_jit
        assert _angles_jit.fold_angles_kernel() is _aot.kernel("fold_angles") is not None
        assert _angles_jit.quiet_kernel() is _aot.kernel("quiet") is not None
    assert hasattr(_fused_jit.fused_kernel(), "py_func")  # numba's again


def _cli(env, out):
    code = ("import sys, runpy\n"
            "sys.argv = ['etorigami'] + sys.argv[1:]\n"
            "try:\n    runpy.run_module('design.cli', run_name='__main__')\n"
            "except SystemExit as e:\n    code = e.code\n"
            "print('NUMBA' if any(m.split('.')[0] in ('numba', 'llvmlite') for m in sys.modules)"
            " else 'NO-NUMBA')\n")
    res = subprocess.run([sys.executable, "-c", code, *RUN, "--out", str(out)], env=env,
                         cwd=REPO, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    return res.stdout.strip().splitlines()[-1]


def test_a_short_cli_run_with_the_module_imports_no_numba(aot_env, tmp_path):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(REPO)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    env.pop("ETORIGAMI_JIT", None)
    assert _cli(env, tmp_path / "aot") == "NO-NUMBA"
    off = dict(env, ETORIGAMI_AOT="0", NUMBA_CACHE_DIR=os.environ.get("NUMBA_CACHE_DIR", ""))
    if not off["NUMBA_CACHE_DIR"]:
        off.pop("NUMBA_CACHE_DIR")
    _cli(off, tmp_path / "jit")                     # numba's kernels (or numpy if cold)
    for name in ("creases.csv", "nodes.npz"):        # the same results
        assert (tmp_path / "aot" / name).read_bytes() == (tmp_path / "jit" / name).read_bytes()


def _copy(built, folder):
    """The built module and manifest copied to ``folder``; (module file, manifest file)."""
    import shutil

    folder.mkdir()
    for f in built.iterdir():
        if f.name.startswith("_etorigami_kernels_"):
            shutil.copy(f, folder / f.name)
    so, = [f for f in folder.iterdir() if not f.name.endswith(".json")]
    manifest, = folder.glob("*.json")
    return so, manifest


def _falls_back(caplog, monkeypatch, expected) -> bool:
    """True if the AOT module is refused, numba's fused kernel is used instead and
    ``expected`` is logged."""
    monkeypatch.setattr(_fused_jit, "_compiled", None)
    with caplog.at_level(logging.INFO, logger="simulator._aot"):
        enabled = _aot.enable()
        kernel = _fused_jit.fused_kernel()
    return (not enabled and kernel is not None and hasattr(kernel, "py_func")
            and any(expected in r.getMessage() for r in caplog.records))


def test_a_stale_module_is_ignored_with_a_log_line(aot_env, tmp_path, monkeypatch, caplog):
    so, manifest = _copy(aot_env, tmp_path / "stale")
    monkeypatch.setenv("ETORIGAMI_AOT_DIR", str(tmp_path / "stale"))
    data = json.loads(manifest.read_text())
    manifest.write_text(json.dumps(dict(data, key="0" * 64)))
    with caplog.at_level(logging.INFO, logger="simulator._aot"):
        assert not _aot.available(log=True)
    assert "is stale" in caplog.text
    assert _falls_back(caplog, monkeypatch, "stale"), caplog.text


def test_a_damaged_module_is_ignored_with_a_log_line(aot_env, tmp_path, monkeypatch, caplog):
    so, manifest = _copy(aot_env, tmp_path / "damaged")
    monkeypatch.setenv("ETORIGAMI_AOT_DIR", str(tmp_path / "damaged"))
    blob = bytearray(so.read_bytes())
    blob[len(blob) // 2] ^= 0xFF
    so.write_bytes(bytes(blob))
    assert _falls_back(caplog, monkeypatch, "do not match their manifest"), caplog.text


def test_an_unloadable_module_is_ignored_with_a_log_line(aot_env, tmp_path, monkeypatch,
                                                         caplog):
    so, manifest = _copy(aot_env, tmp_path / "garbage")
    monkeypatch.setenv("ETORIGAMI_AOT_DIR", str(tmp_path / "garbage"))
    so.write_bytes(b"not a shared object")
    data = json.loads(manifest.read_text())
    manifest.write_text(json.dumps(dict(data, sha256=_aot._file_sha256(so))))
    assert _falls_back(caplog, monkeypatch, "could not load"), caplog.text


def test_no_module_means_numba_with_a_log_line(tmp_path, monkeypatch, caplog):
    monkeypatch.setenv("ETORIGAMI_AOT_DIR", str(tmp_path / "empty"))
    monkeypatch.setattr(_jit, "_aot", False)
    monkeypatch.setattr(_aot, "_module", None)
    with caplog.at_level(logging.INFO, logger="simulator._aot"):
        assert not _aot.available(log=True) and _aot.wanted()
    assert "not built yet" in caplog.text
    assert _falls_back(caplog, monkeypatch, "no ahead-of-time kernels"), caplog.text
    monkeypatch.setenv("ETORIGAMI_AOT", "0")
    assert not _aot.wanted() and not _aot.available()


def test_the_key_follows_the_sources(tmp_path, monkeypatch):
    before = _aot.key()
    assert before is not None and len(before) == 64
    for rel in _aot.SOURCES:
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_bytes((_aot._ROOT / rel).read_bytes())
    monkeypatch.setattr(_aot, "_ROOT", tmp_path)
    assert _aot.key() == before
    with open(tmp_path / _aot.SOURCES[1], "a") as fh:
        fh.write("\n# edited\n")
    assert _aot.key() != before


def test_only_the_newest_modules_are_kept(tmp_path):
    for i in range(5):
        for suffix in (".json", ".so"):
            f = tmp_path / f"_etorigami_kernels_{i:024d}{suffix}"
            f.write_text("x")
            os.utime(f, (1000.0 + i, 1000.0 + i))
    (tmp_path / "other.txt").write_text("kept")
    _aot._prune(tmp_path, keep=2)
    kept = [f"_etorigami_kernels_{i:024d}{s}" for i in (3, 4) for s in (".json", ".so")]
    assert sorted(f.name for f in tmp_path.iterdir()) == sorted(["other.txt"] + kept)


def test_no_build_is_wanted_from_a_numba_without_pycc(tmp_path, monkeypatch):
    """numba marks pycc pending deprecation: once it is gone, short commands keep numba's
    kernels and start no build (looked for without importing numba)."""
    import importlib.machinery

    package = tmp_path / "numba"
    (package / "pycc").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    spec = importlib.machinery.ModuleSpec("numba", None, origin=str(package / "__init__.py"))
    monkeypatch.setattr(_aot.importlib.util, "find_spec",
                        lambda name, *a: spec if name == "numba" else None)
    monkeypatch.setattr(_aot, "available", lambda log=False: False)
    monkeypatch.delenv("ETORIGAMI_AOT", raising=False)
    assert not _aot.wanted()                           # pycc/ without its __init__.py
    (package / "pycc" / "__init__.py").write_text("")
    assert _aot.wanted()
    monkeypatch.setenv("ETORIGAMI_AOT", "0")
    assert not _aot.wanted()
