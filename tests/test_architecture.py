"""Layering rules: simulator/ imports neither matplotlib nor design/ or studies/."""

import ast
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_simulator_does_not_load_matplotlib():
    code = ("import pkgutil, importlib, sys, simulator\n"
            "for m in pkgutil.walk_packages(simulator.__path__, 'simulator.'):\n"
            "    importlib.import_module(m.name)\n"
            "bad = [m for m in sys.modules if m.split('.')[0] in ('matplotlib', 'design', 'studies')]\n"
            "print(','.join(bad))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_simulator_sources_import_only_downwards():
    offenders = []
    for path in (ROOT / "simulator").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module or ""]
            else:
                continue
            offenders += [f"{path.name}: {n}" for n in names
                          if n.split(".")[0] in ("matplotlib", "design", "studies")]
    assert offenders == []


def test_gravity_is_named_in_one_place():
    """9.8 / 9.81 / 9.80665 m/s^2 appear only as the named constants in simulator/model/model.py."""
    allowed = {"model.py"}
    offenders = []
    for pkg in ("simulator", "design", "studies"):
        for path in (ROOT / pkg).rglob("*.py"):
            if path.name in allowed and pkg == "simulator":
                continue
            offenders += [f"{pkg}/{path.name}:{node.lineno}"
                          for node in ast.walk(ast.parse(path.read_text()))
                          if isinstance(node, ast.Constant) and node.value in (9.8, 9.81, 9.80665)
                          and not isinstance(node.value, bool)]
    assert offenders == []


def test_imports_stay_light():
    """``import simulator`` / the CLI load no compiler, plotting, optimiser or cluster library;
    those are imported where they are used (numba only once the spring kernel is compiled)."""
    code = ("import sys, simulator, design.cli\n"
            "heavy = ('numba', 'llvmlite', 'matplotlib', 'cvxpy', 'dask', 'distributed',\n"
            "         'nlopt')\n"
            "print(','.join(sorted({m.split('.')[0] for m in sys.modules} & set(heavy))))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=ROOT)
    assert out.stdout.strip() == ""
