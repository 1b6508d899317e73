"""A library call has no process-wide side effects unless asked (issue 31): importing
``simulator``, building a small model and simulating it start no process, and the dense
LAPACK factorisations leave BLAS's thread count as they found it."""

import os
import pathlib
import subprocess
import sys
import textwrap

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]

#: Every way of starting a process is made to fail before anything of ours is imported.
_NO_PROCESS = textwrap.dedent("""
    import os, subprocess, sys
    started = []

    def refuse(name):
        def call(*args, **kwargs):
            started.append(name)
            raise OSError(f"{name} called: a library call started a process")
        return call

    subprocess.Popen = refuse("subprocess.Popen")        # run, call, check_output use it
    for name in ("system", "fork", "forkpty", "posix_spawn", "posix_spawnp", "spawnv",
                 "spawnve", "execv", "execve"):
        if hasattr(os, name):
            setattr(os, name, refuse("os." + name))
    assert not [m for m in sys.modules if m.split(".")[0] in ("simulator", "design")]
""")


def test_import_model_and_simulate_start_no_process(tmp_path):
    """With numba's compiled kernels (the default) and nothing asked for: a heated single
    fold simulated and its result saved (meta.json's commit is read without git)."""
    code = _NO_PROCESS + textwrap.dedent(f"""
        import simulator
        from simulator import get_case, simulate
        case = get_case("single_fold", gravity=True, thermal_steps=3)
        result = simulate(case.model, case.steps)
        assert result.success, result.message
        result.save({str(tmp_path / "out")!r})
        from simulator import _jit
        print(_jit.tier(), started)
    """)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    for name in ("ETORIGAMI_JIT", "ETORIGAMI_AOT"):
        env.pop(name, None)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=tmp_path, env=env, timeout=600)
    assert out.returncode == 0, out.stderr
    tier, started = out.stdout.split(maxsplit=1)
    assert started.strip() == "[]"
    assert tier == ("numba" if _numba() else "numpy")
    assert (tmp_path / "out" / "meta.json").exists()


def test_the_git_commit_is_read_without_git(monkeypatch):
    from simulator import _result

    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: pytest.fail("git started"))
    commit = _result.git_hash()
    if (ROOT / ".git").exists():
        assert commit is not None and len(commit) == 40 and int(commit, 16) >= 0
    else:
        assert commit is None


def _numba() -> bool:
    import importlib.util

    return importlib.util.find_spec("numba") is not None


def _blas_threads():
    from threadpoolctl import threadpool_info

    return [(i["internal_api"], i["num_threads"]) for i in threadpool_info()
            if i["user_api"] == "blas"]


def test_blas_thread_limit_is_scoped_to_the_call():
    """The limit to one BLAS thread holds inside a factorisation only."""
    pytest.importorskip("threadpoolctl")
    from simulator.linalg import dense_lapack
    from simulator.linalg.thresholds import DENSE_ONE_THREAD_MIN

    if not dense_lapack.available():
        pytest.skip("threadpoolctl cannot see BLAS")
    before = _blas_threads()
    n = max(DENSE_ONE_THREAD_MIN, 8)
    rng = np.random.default_rng(0)
    A = rng.standard_normal((n, n))
    S, M = A @ A.T + n * np.eye(n), rng.standard_normal((n, 3))
    with dense_lapack.one_blas_thread(n):
        assert all(threads == 1 for _, threads in _blas_threads())
    C, W, L = dense_lapack.cholesky_loss(S, M)
    dense_lapack.back_substitute(C, M[:, 0])
    solve, _ = dense_lapack.lu_loss(S - 2 * n * np.eye(n), M)
    solve(M[:, 0])
    assert _blas_threads() == before


def test_blas_thread_limit_reaches_mkl_loaded_later():
    """PARDISO's MKL, loaded after the limit's first use, is limited with the other BLAS (in a
    fresh process: the limit's controller made first, then MKL loaded)."""
    code = textwrap.dedent("""
        from threadpoolctl import threadpool_info
        from simulator.linalg import dense_lapack, pardiso
        from simulator.linalg.thresholds import DENSE_ONE_THREAD_MIN
        assert dense_lapack.available()
        assert pardiso.available(), "no MKL PARDISO"
        with dense_lapack.one_blas_thread(max(DENSE_ONE_THREAD_MIN, 8)):
            inside = [(i["internal_api"], i["num_threads"]) for i in threadpool_info()
                      if i["user_api"] == "blas"]
        print(inside)
        assert any(api == "mkl" for api, _ in inside), inside
        assert all(n == 1 for _, n in inside), inside
        """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert out.returncode == 0, out.stderr[-2000:]


def test_import_and_kernel_choice_raise_no_warning():
    """numba.pycc warns on import (pending deprecation): neither importing the packages nor
    choosing a command's kernels imports it, even with warnings as errors."""
    code = ("import simulator, design\nfrom simulator import _aot, _jit\n"
            "_jit.command_tier(short=True); _aot.wanted(); _aot.available()\n"
            "import sys\nprint('numba.pycc' in sys.modules)")
    out = subprocess.run([sys.executable, "-W", "error", "-c", code], capture_output=True,
                         text=True, cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert out.returncode == 0 and out.stderr == "", out.stderr
    assert out.stdout.strip() == "False"
