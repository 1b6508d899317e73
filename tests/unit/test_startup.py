"""Start-up stays light: ``import simulator``, ``import design`` and ``etorigami --version``
import no submodule and no heavy dependency; public names are imported on first use and are
the objects their submodules define; ``design.optimize`` is the function whatever the import
order. Each check runs in a fresh interpreter (this process has imported everything)."""

import json
import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
ENV = dict(os.environ, PYTHONPATH=str(ROOT))

#: Imported only inside the functions that use them.
HEAVY = ("matplotlib", "pandas", "cvxpy", "dask", "distributed", "nlopt", "numba", "llvmlite",
         "scipy.stats", "tqdm")


def _run(code: str) -> str:
    """stdout of ``code`` in a fresh interpreter with the worktree first on the path."""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, env=ENV)
    assert out.returncode == 0, out.stderr
    return out.stdout


def _loaded_after(code: str) -> dict:
    """{"heavy": heavy modules, "ours": simulator/design modules, "numpy": bool} after code."""
    probe = (f"{code}\nimport json, sys\n"
             f"print(json.dumps({{'heavy': [m for m in {HEAVY!r} if m in sys.modules],\n"
             "    'ours': sorted(m for m in sys.modules if m.split('.')[0] in "
             "('simulator', 'design')),\n"
             "    'numpy': 'numpy' in sys.modules, 'scipy': 'scipy' in sys.modules}))\n")
    return json.loads(_run(probe).strip().splitlines()[-1])


@pytest.mark.parametrize("code", ["import simulator", "import design",
                                  "import simulator, design"])
def test_package_import_loads_no_submodule_and_no_heavy_dependency(code):
    loaded = _loaded_after(code)
    assert loaded["heavy"] == []
    assert not loaded["numpy"] and not loaded["scipy"]
    assert set(loaded["ours"]) <= {"simulator", "simulator._lazy", "simulator._version",
                                   "design"}


@pytest.mark.parametrize("argv", [["--version"], ["--help"]])
def test_cli_version_and_help_import_no_simulator_stack(argv):
    code = ("import contextlib, io\nfrom design.cli import main\nbuf = io.StringIO()\n"
            "with contextlib.redirect_stdout(buf):\n"
            "    try:\n"
            f"        main({argv!r})\n"
            "    except SystemExit as exc:\n"
            "        assert exc.code == 0, exc.code\n"
            "assert buf.getvalue().strip(), 'nothing printed'")
    loaded = _loaded_after(code)
    assert loaded["heavy"] == [] and not loaded["numpy"] and not loaded["scipy"]
    assert not [m for m in loaded["ours"] if m.startswith("simulator.") and m not in (
        "simulator._lazy", "simulator._version", "simulator.errors")]


def test_cli_version_prints_the_version():
    from simulator import __version__

    out = subprocess.run([sys.executable, "-m", "design.cli", "--version"], capture_output=True,
                         text=True, cwd=ROOT, env=ENV)
    assert out.returncode == 0 and out.stdout.strip() == f"etorigami {__version__}"


def test_every_public_name_loads_no_optional_heavy_dependency():
    """All of both doors imported (every submodule behind them) still leaves matplotlib,
    pandas, cvxpy, Dask, NLopt, numba and scipy.stats unloaded."""
    loaded = _loaded_after("from simulator import *\nfrom design import *")
    assert loaded["heavy"] == []


@pytest.mark.parametrize("package", ["simulator", "design"])
def test_every_public_name_resolves_to_its_submodule_object(package):
    code = (f"import importlib, json, types, {package} as p\n"
            "names = list(p.__all__)\n"
            "bad = [n for n in names if n in p._lazy_where and getattr(p, n) is not getattr("
            "importlib.import_module(p._lazy_where[n], p.__name__), n)]\n"
            "missing = [n for n in names if not hasattr(p, n)]\n"
            "modules = [n for n in names if isinstance(getattr(p, n), types.ModuleType)]\n"
            "print(json.dumps({'bad': bad, 'missing': missing, 'lazy': sorted(p._lazy_where),"
            " 'all': sorted(names), 'dir': sorted(set(names) - set(dir(p))), 'modules': modules}))")
    got = json.loads(_run(code))
    assert got["missing"] == [] and got["bad"] == [] and got["dir"] == []
    eager = {"simulator": {"__version__"}, "design": set()}[package]
    assert set(got["lazy"]) == set(got["all"]) - eager - set(got["modules"])
    assert len(got["modules"]) >= 3                 # the namespaces


@pytest.mark.parametrize("package", ["simulator", "design"])
def test_star_import_gives_all_and_only_all(package):
    code = (f"import json, {package} as p\nns = {{}}\nexec('from {package} import *', ns)\n"
            "print(json.dumps([sorted(set(ns) - {'__builtins__'}), sorted(p.__all__)]))")
    names, public = json.loads(_run(code))
    assert names == public


def test_submodules_are_reachable_as_attributes_and_unknown_names_raise():
    out = _run("import simulator, design\n"
               "print(simulator.thermal.__name__, simulator.example_patterns.__name__,"
               " design.analysis.__name__)\n"
               "for p, n in ((simulator, 'no_such_name'), (design, 'no_such_name'),"
               " (simulator, '__no_such_dunder__')):\n"
               "    try:\n"
               "        getattr(p, n)\n"
               "    except AttributeError as exc:\n"
               "        print(type(exc).__name__, n in str(exc))\n")
    lines = out.split("\n")
    assert lines[0] == "simulator.thermal simulator.example_patterns design.analysis"
    assert lines[1:4] == ["AttributeError True"] * 3


@pytest.mark.parametrize("code", [
    # the function first, then the submodule
    "from design import optimize as f\nimport design.core.optimize\nimport design",
    # the submodule first (as the CLI and other design modules do), then the function
    "import design.core.optimize\nfrom design import optimize as f\nimport design",
    "from design.core.optimize import optimize as f\nimport design",
    "import design\nf = design.optimize\nimport design.core.optimize",
    # a sibling module importing the submodule first
    "import design.analysis.robustness, design.analysis.uncertainty_sweep\nimport design\nf = design.optimize",
])
def test_design_optimize_is_the_function_in_any_import_order(code):
    out = _run(code + "\nimport sys, types\n"
               "from design.core.optimize import optimize as g, OptimizationResult\n"
               "m = sys.modules['design.core.optimize']\n"
               "print(isinstance(f, types.FunctionType), f is g, design.optimize is g,"
               " isinstance(m, types.ModuleType), m.optimize is g,"
               " design.OptimizationResult is OptimizationResult)")
    assert out.split() == ["True"] * 6


#: Not needed by ``etorigami run`` of a small case (issue 21: the CLI at library speed).
NOT_ON_THE_RUN_PATH = ("pandas", "tqdm", "matplotlib", "scipy.sparse.linalg",
                       "scipy.sparse.csgraph", "scipy.optimize", "scipy.stats", "cvxpy", "nlopt")


def test_cli_run_imports_no_pandas_tqdm_or_unused_scipy(tmp_path):
    """``etorigami run single-fold ... -q --out DIR`` (numpy kernels, so that the check does
    not depend on numba's cache) writes its files and prints its table without pandas, tqdm,
    scipy.sparse.linalg or scipy.sparse.csgraph."""
    out = tmp_path / "run"
    code = ("import contextlib, io, json, sys\nfrom design.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()) as buf:\n"
            "    code = main(['run', 'single-fold', '--set', 'thermal_steps=4', '--set',"
            f" 'gravity=true', '-q', '--out', {str(out)!r}])\n"
            f"print(json.dumps({{'code': code, 'text': buf.getvalue(), 'loaded': [m for m in"
            f" {NOT_ON_THE_RUN_PATH!r} if m in sys.modules]}}))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, env=dict(ENV, ETORIGAMI_JIT="0"))
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout.strip().splitlines()[-1])
    assert got["code"] == 0 and got["loaded"] == []
    assert "fold_angle [deg]" in got["text"] and (out / "creases.csv").stat().st_size > 0
