"""Rooms that do not reach into each other (issue 31 item 2): no module of ``simulator/`` or
``design/`` uses a private name (``_name``) of another module, and a private module
(``_name.py``) is used only inside its room, except for the documented handful below.

A *room* is the subpackage a module lives in, at the first level (``simulator.thermal`` for
``simulator/thermal/fe/_gmsh.py``); a private module directly in a package
(``simulator/_validate.py``) is that package's shared infrastructure and its room is the package.
Both ``from m import _x`` and ``m._x`` on an imported module count, at module level or inside
functions. A helper two modules share is public within its package (no underscore; it stays out
of the doors' ``__all__``) or lives where its users are.
"""

import ast
import pathlib
import re

from source_imports import imported_module

ROOT = pathlib.Path(__file__).resolve().parents[2]

KERNELS = ("the kernel tiers: simulator._jit chooses the tier and warms numba's cache, "
           "simulator._aot compiles the ahead-of-time module; both must name every room's "
           "compiled-kernel module (_*_jit.py) and its build function, and they share the "
           "tier flag (docs/kernels.md)")
SHARED = ("the infrastructure both packages share (test_architecture.SHARED_INFRASTRUCTURE): "
          "lazy exports, the validation checks, the result files, the deprecation warning")
CLI_KERNELS = ("the CLI chooses the compiled-kernel tier for its commands, compiles the thermal "
               "kernel in a second process and warms numba's cache (simulator._jit, docs/kernels.md): a command's choice, not a library call's")

#: (importer: a file or a folder ending in "/", target: a regular expression matched at the
#: start of the dotted name reached into) -> why it is allowed.
ALLOWED = {
    ("simulator/_jit.py", r"simulator(\.\w+)*\._\w+_jit\b"): KERNELS,
    ("simulator/_aot.py", r"simulator(\.\w+)*\._\w+_jit\b"): KERNELS,
    ("simulator/_aot.py", r"simulator\._jit\._aot$"): KERNELS,
    ("design/", r"simulator\._(lazy|validate|result|deprecation)\b"): SHARED,
    ("design/cli/_common.py", r"simulator\._jit$"): CLI_KERNELS,
    ("simulator/sensitivity/integral.py", r"simulator\.thermal\._single_layer\b"):
        "the single-layer operator's shape derivative differentiates its kernels pair by pair "
        "by the operator's own rules and thresholds (theory 12.6): one formula, not a copy",
}


def _is_module(dotted: str) -> bool:
    path = ROOT.joinpath(*dotted.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def _room(parts: list) -> str:
    """The room of the private part ``parts[-1]``: its package when that is a top package,
    else the first-level subpackage."""
    return ".".join(parts[:-1]) if len(parts) == 2 else ".".join(parts[:2])


def reaches(module: str, source: str, is_package: bool = False) -> list:
    """(line, dotted name) of every private name of another module, and every private module
    outside its room, that the module ``module`` (its source ``source``) uses."""
    package = module if is_package else module.rpartition(".")[0]
    tree = ast.parse(source)
    used, aliases = [], {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                used.append((node.lineno, a.name))
                aliases[a.asname or a.name.split(".")[0]] = a.name if a.asname else \
                    a.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom):
            source_module = imported_module(package, node)
            for a in node.names:
                target = f"{source_module}.{a.name}"
                used.append((node.lineno, target))
                if _is_module(target):
                    aliases[a.asname or a.name] = target
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) \
                and node.value.id in aliases and _private(node.attr):
            used.append((node.lineno, f"{aliases[node.value.id]}.{node.attr}"))
    found = []
    for line, target in used:
        parts = target.split(".")
        if parts[0] not in ("simulator", "design"):
            continue
        for k in range(1, len(parts)):
            if not _private(parts[k]):
                continue
            head = ".".join(parts[:k + 1])
            if not _is_module(head):                   # a private name of another module
                if ".".join(parts[:k]) != module:
                    found.append((line, target))
                break
            room = _room(parts[:k + 1])                # a private module: inside its room?
            if module != room and not module.startswith(room + "."):
                found.append((line, target))
                break
    return found


def _offenders():
    """{(file, line, target)} of the whole of simulator/ and design/."""
    out = set()
    for top in ("simulator", "design"):
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT)
            parts = list(rel.with_suffix("").parts)
            is_package = parts[-1] == "__init__"
            module = ".".join(parts[:-1] if is_package else parts)
            out |= {(rel.as_posix(), line, target)
                    for line, target in reaches(module, path.read_text(), is_package)}
    return out


def _allowed_by(table, rel, target):
    return [key for key in table
            if (rel == key[0] or key[0].endswith("/") and rel.startswith(key[0]))
            and re.match(key[1], target)]


def test_no_room_reaches_into_another():
    """Every private name used across modules and every private module used outside its room
    is in the allow-list with its reason; no simulator entry of the list is stale."""
    bad, used = [], set()
    for rel, line, target in sorted(_offenders()):
        keys = _allowed_by(ALLOWED, rel, target)
        if keys:
            used.update(keys)
        else:
            bad.append(f"{rel}:{line}: {target}")
    assert bad == [], "make the helper public within its package (or move it to where its " \
                      "users live), or allow-list it here with the reason"
    assert set(ALLOWED) <= used, f"stale allow-list entries: {set(ALLOWED) - used}"


def test_the_check_sees_what_it_forbids():
    """:func:`reaches` finds a private name of another module (imported or read as an
    attribute) and a private module outside its room, and lets a module use its room's private
    modules and the public names of other modules."""
    code = ("from ..model.mesh import crease_up, _helper\n"          # 1: _helper
            "from ..linalg import _cholesky_jit\n"                   # 2: another room's
            "from . import _thermal_jit\n"                           # 3: own room: fine
            "from .. import _jit\n"                                  # 4: simulator's: fine
            "from ..model import mesh\n"
            "x = mesh._private_thing\n"                              # 6: attribute
            "def f():\n"
            "    from simulator.mechanics.elements import _springs_jit\n")   # 8: lazy
    assert sorted(reaches("simulator.thermal.steady", code)) == [
        (1, "simulator.model.mesh._helper"), (2, "simulator.linalg._cholesky_jit"),
        (6, "simulator.model.mesh._private_thing"),
        (8, "simulator.mechanics.elements._springs_jit")]
    assert reaches("simulator.thermal.fe.solve2d", "from . import _gmsh\n") == []
    assert reaches("design.cli.main", "from simulator import _jit\n") == [(1, "simulator._jit")]


def re_exports(source: str) -> list:
    """The names a module's ``__all__`` lists that it imports rather than defines."""
    tree = ast.parse(source)
    imported = {a.asname or a.name for node in tree.body if isinstance(node, ast.ImportFrom)
                for a in node.names}
    listed = [e.value for node in tree.body if isinstance(node, ast.Assign)
              and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets)
              for e in node.value.elts]
    return [name for name in listed if name in imported]


def test_no_module_is_an_old_home_re_exporting_names():
    """Inside simulator/ a module publishes what it defines: no module re-exports names
    defined elsewhere (an "old home" left by a move or a split), except the packages'
    ``__init__`` and the namespace modules at simulator's door (``simulator.fold``,
    ``simulator.materials``, ...), whose job that is. Old spellings at the door go through
    ``simulator/_moved.py``."""
    import simulator
    from doors import namespaces

    doors = {f"simulator/{name}.py" for name in namespaces(simulator)}
    found = {}
    for path in sorted((ROOT / "simulator").rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if path.name != "__init__.py" and rel not in doors:
            if names := re_exports(path.read_text()):
                found[rel] = names
    assert found == {}
    assert re_exports("from .a import b, c\nd = 1\n__all__ = ['b', 'd']\n") == ["b"]
