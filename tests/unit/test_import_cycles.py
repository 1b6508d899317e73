"""No import cycle among simulator's rooms (issue 31 item 2).

A *room* is a subpackage of ``simulator`` (``model``, ``mechanics``, ``thermal``, ``solvers``,
``steps``, ``linalg``, ``geometry``, ``io``) or a module directly in it (``state``, ``events``,
``results``, ``cases``, ``_jit``, ...). The graph has an edge from room A to room B when a module
of A imports from B (``from ..model.mesh import ...``, ``import simulator.thermal``).

* Imports at module level (what Python runs when a module is loaded, including those under
  ``if``/``try`` there) must form an acyclic graph: the rooms have an order, from
  ``geometry`` and ``linalg`` through ``model``, ``mechanics``, ``state``, ``solvers`` to
  ``thermal`` and ``steps``.
* Imports inside functions are lazy: they run when called and cannot break loading. They are
  counted separately: a lazy import against that order (one that closes a cycle with the
  module-level graph) must be listed in :data:`LAZY_UPWARDS` with its reason.

The lazy maps of the packages' ``__init__`` (their public names) are strings, not imports, and
are not edges: a namespace may publish a name defined in another room.
"""

import ast
import pathlib

from source_imports import imported_module

ROOT = pathlib.Path(__file__).resolve().parents[2]

KERNELS = ("the kernel tiers: simulator._jit and simulator._aot import the compiled-kernel "
           "modules of every room when asked to warm or build them; the kernels ask _jit for "
           "the tier at module level (docs/kernels.md)")
#: (importing room, imported room) of lazy imports against the order -> the reason.
LAZY_UPWARDS = {
    ("_jit", "_aot"): KERNELS,
    ("_jit", "_angles_jit"): KERNELS,
    ("_jit", "mechanics"): KERNELS,
    ("_jit", "thermal"): KERNELS,
}


def _room(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if parts[0] == "simulator" and len(parts) > 1 else None


def imports(path: pathlib.Path):
    """(line, imported module, lazy) of every import of ``path`` (relative ones resolved; for
    ``from m import a`` both ``m`` and ``m.a``, since ``a`` may be a submodule)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    package = ".".join(parts[:-1])
    tree = ast.parse(path.read_text())
    out = []

    def visit(nodes, lazy):
        for node in nodes:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                visit(ast.iter_child_nodes(node), True)
                continue
            if isinstance(node, ast.Import):
                out.extend((node.lineno, a.name, lazy) for a in node.names)
            elif isinstance(node, ast.ImportFrom):
                module = imported_module(package, node)
                if node.module:
                    out.append((node.lineno, module, lazy))
                out.extend((node.lineno, f"{module}.{a.name}", lazy) for a in node.names)
            visit(ast.iter_child_nodes(node), lazy)

    visit(tree.body, False)
    return out


def graph():
    """``(edges, lazy)``: {room: {room: [where]}} of module-level and of lazy imports."""
    edges, lazy = {}, {}
    for path in sorted((ROOT / "simulator").rglob("*.py")):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        source = _room(module)
        if source in (None, "__init__"):            # simulator/__init__.py: the door
            continue
        for line, target, is_lazy in imports(path):
            room = _room(target)
            if room is None or room == source or room == "__init__":
                continue
            where = f"{path.relative_to(ROOT).as_posix()}:{line}"
            (lazy if is_lazy else edges).setdefault(source, {}).setdefault(room, []).append(where)
    return edges, lazy


def cycles(edges) -> list:
    """The strongly connected components of more than one room (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def connect(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in edges.get(v, {}):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in list(edges):
        if v not in index:
            connect(v)
    return found


def reaches(edges, start, goal) -> bool:
    seen, todo = set(), [start]
    while todo:
        v = todo.pop()
        if v == goal:
            return True
        if v not in seen:
            seen.add(v)
            todo.extend(edges.get(v, {}))
    return False


def test_rooms_import_each_other_without_a_cycle():
    """The module-level imports among simulator's rooms form no cycle (each cycle is named
    with the imports that make it)."""
    edges, _ = graph()
    found = cycles(edges)
    detail = [f"{a} -> {b}: {edges[a][b]}" for c in found for a in c for b in edges.get(a, {})
              if b in c]
    assert found == [], detail


def test_lazy_imports_against_the_order_are_the_documented_ones():
    """A lazy import whose target room imports the importing room back (directly or not, at
    module level) is in :data:`LAZY_UPWARDS`, and every entry there is still needed."""
    edges, lazy = graph()
    upwards = {(a, b): where for a in lazy for b, where in lazy[a].items()
               if reaches(edges, b, a)}
    assert set(upwards) - set(LAZY_UPWARDS) == set(), upwards
    assert set(LAZY_UPWARDS) - set(upwards) == set(), "stale entries"


def test_the_cycle_check_sees_a_cycle():
    """:func:`cycles` finds a two-room and a three-room cycle and nothing in a chain."""
    assert cycles({"a": {"b": []}, "b": {"a": []}}) == [["a", "b"]]
    assert cycles({"a": {"b": []}, "b": {"c": []}, "c": {"a": []}, "d": {"a": []}}) \
        == [["a", "b", "c"]]
    assert cycles({"a": {"b": []}, "b": {"c": []}}) == []
