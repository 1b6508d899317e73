"""The front doors (issue 31 item 1): at most 60 names at ``simulator`` and at ``design``, the
rest of each family in a namespace (``simulator.thermal``, ``simulator.fold``, ...,
``design.analysis``); every old spelling at the door still resolves for one release, to the
same object as its new spelling, with a deprecation warning naming the new place; the packages
import without a warning and the repository's own code and documentation use only the new
spellings."""

import ast
import importlib
import os
import pathlib
import pkgutil
import re
import subprocess
import sys

import pytest

import design
import simulator
from doors import moved, namespaces, public_names, renamed
from simulator.errors import EtorigamiDeprecationWarning

ROOT = pathlib.Path(__file__).resolve().parents[2]
PACKAGES = [simulator, design]
ENV = dict(os.environ, PYTHONPATH=str(ROOT))


def _run(code: str, *flags: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *flags, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, env=ENV)


@pytest.mark.parametrize("package", PACKAGES, ids=lambda p: p.__name__)
def test_the_door_has_at_most_60_names(package):
    assert len(package.__all__) <= 60
    assert len(namespaces(package)) >= 3


@pytest.mark.parametrize("package", PACKAGES, ids=lambda p: p.__name__)
def test_namespaces_publish_existing_names_and_no_submodule_name(package):
    """A namespace's public name that is also the name of one of its submodules would hide the
    submodule (``import pkg.ns.name as m`` would give the object); the door's names that a
    namespace also lists are the same objects."""
    for name, module in namespaces(package).items():
        names = module.__all__
        assert len(set(names)) == len(names), name
        objects = {n: getattr(module, n) for n in names}
        submodules = {m.name for m in pkgutil.iter_modules(getattr(module, "__path__", []))}
        assert not set(names) & submodules, name
        for n in set(names) & set(package.__all__):
            assert objects[n] is getattr(package, n), (name, n)


@pytest.mark.parametrize("package", PACKAGES, ids=lambda p: p.__name__)
def test_every_old_spelling_resolves_with_a_warning_to_the_new_object(package):
    table = moved(package)
    assert table and not set(table) & set(package.__all__)
    assert not set(table) & set(dir(package))        # not offered any more
    for old, (namespace, new) in table.items():
        module = importlib.import_module(namespace)
        assert new in module.__all__, (old, namespace)
        expected = rf"^{package.__name__}\.{old} is deprecated .*: use {namespace}\.{new} "
        with pytest.warns(EtorigamiDeprecationWarning, match=expected):
            obj = getattr(package, old)
        assert obj is getattr(module, new), old
    assert issubclass(EtorigamiDeprecationWarning, DeprecationWarning)


FACTORIES = {"simulator": {"make_model", "make_mesh"},
             "design": {"make_gripper_model", "make_miura_model", "make_executor"}}


@pytest.mark.parametrize("package", PACKAGES, ids=lambda p: p.__name__)
def test_factories_are_spelled_make_and_old_names_warn(package):
    """One spelling of the factories (``make_<thing>``); each renamed one resolves, at the door
    and in the namespaces that publish the new name, to the same object with a warning."""
    table = renamed(package)
    assert {new for new in table.values()} <= FACTORIES[package.__name__]
    assert {(package.__name__, "build_mesh"), ("simulator.model", "build_mesh"),
            (package.__name__, "gripper_model"), ("design.devices", "miura_model")} & \
        set(table)
    for (where, old), new in table.items():
        module = importlib.import_module(where)
        assert old not in module.__all__ and old not in dir(module)
        with pytest.warns(EtorigamiDeprecationWarning,
                          match=rf"^{where}\.{old} is deprecated .*: use {where}\.{new} "):
            obj = getattr(module, old)
        assert obj is getattr(module, new) is getattr(package, new), old
    for name in FACTORIES[package.__name__]:
        assert name in package.__all__ and callable(getattr(package, name))
    assert not [n for n in package.__all__ if n.startswith("build_") or n.endswith("_model")
                and not n.startswith("make_")]


def test_old_from_import_warns_once_at_the_users_line():
    """``from simulator import read_fold`` (the import system looks the name up twice) shows
    one warning, attributed to the user's line, as Python shows DeprecationWarnings in
    ``__main__``; attribute access warns too, and unknown names still raise."""
    code = ("import simulator, design\n"
            "from simulator import read_fold, simulate\n"
            "x = design.wilson_interval\n"
            "try:\n"
            "    simulator.no_such_name\n"
            "except AttributeError:\n"
            "    print('raised')\n")
    out = _run(code)
    assert out.returncode == 0 and out.stdout == "raised\n"
    warned = [line for line in out.stderr.splitlines() if "Warning" in line]
    assert warned == [
        "<string>:2: EtorigamiDeprecationWarning: simulator.read_fold is deprecated (it goes in "
        "the next release): use simulator.fold.read_fold (from simulator.fold import "
        "read_fold).",
        "<string>:3: EtorigamiDeprecationWarning: design.wilson_interval is deprecated (it goes "
        "in the next release): use design.analysis.wilson_interval (from design.analysis "
        "import wilson_interval)."], out.stderr


def test_import_is_silent_and_uses_no_old_spelling():
    """``import simulator, design`` prints nothing; every name of the doors and namespaces, the
    CLI, the studies and the benchmarks import with deprecation warnings as errors."""
    out = _run("import simulator, design")
    assert out.returncode == 0 and out.stdout == "" and out.stderr == ""
    spaces = [f"{p.__name__}.{n}" for p in PACKAGES for n in namespaces(p)]
    studies = sorted(f"studies.{m.name}" for m in pkgutil.iter_modules([str(ROOT / "studies")]))
    code = ("import importlib, sys\n"
            "from simulator import *\nfrom design import *\nimport design.cli\n"
            f"for name in {spaces!r}:\n"
            "    module = importlib.import_module(name)\n"
            "    exec(f'from {name} import *', {})\n"
            f"for name in {studies!r}:\n"
            "    importlib.import_module(name)\n"
            "sys.path.insert(0, 'benchmarks')\n"
            "for name in ('bench_transient', 'bench_newton', 'bench_fold'):\n"
            "    importlib.import_module(name)\n")
    out = _run(code, "-W", "error::DeprecationWarning")
    assert out.returncode == 0, out.stderr[-2000:]


def _old_spellings(tree, moved_names) -> list:
    """(line, text) of every ``from simulator import <old>`` or ``simulator.<old>`` (and the
    same for design) in a parsed source."""
    aliases = {"simulator": "simulator", "design": "design"}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            aliases.update({a.asname: a.name for a in node.names
                            if a.asname and a.name in ("simulator", "design")})
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module in aliases:
            found += [(node.lineno, f"from {node.module} import {a.name}") for a in node.names
                      if (node.module, a.name) in moved_names]
        elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and \
                (aliases.get(node.value.id), node.attr) in moved_names:
            found.append((node.lineno, f"{node.value.id}.{node.attr}"))
    return found


def test_the_repository_uses_only_the_new_spellings():
    """Code (packages, studies, benchmarks, tests) and the code blocks of the README and the
    docs: no old spelling (the migration page shows one on purpose; this test names them)."""
    moved_names = {(p.__name__, old) for p in PACKAGES for old in moved(p)}
    moved_names |= {key for p in PACKAGES for key in renamed(p)}
    offenders = []
    for top in ("simulator", "design", "studies", "benchmarks", "tests"):
        for path in sorted((ROOT / top).rglob("*.py")):
            if path == pathlib.Path(__file__):
                continue
            rel = path.relative_to(ROOT)
            offenders += [f"{rel}:{line}: {text}"
                          for line, text in _old_spellings(ast.parse(path.read_text()),
                                                           moved_names)]
    block = re.compile(r"^```python[^\n]*\n(.*?)^```", re.M | re.S)
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        if path.name == "migration.md":
            continue
        for code in block.findall(path.read_text()):
            offenders += [f"{path.name}: {text}"
                          for _, text in _old_spellings(ast.parse(code), moved_names)]
    assert offenders == []


def test_public_names_are_the_doors_and_their_namespaces():
    """The helper the other tests use to ask "is this public?"."""
    assert {"simulate", "crease_temperatures", "solve_equilibrium", "read_fold",
            "thermal_model", "equilibrium_system", "StepPower", "StepSignal"} <= \
        public_names(simulator)
    assert {"optimize", "wilson_interval", "LoggedProblem", "GRIPPER_SPACE"} <= \
        public_names(design)
