"""Layering rules: simulator/ imports neither matplotlib nor design/ or studies/."""

import ast
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


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


#: design/ imports from simulator through its door and namespaces (``from simulator import
#: ...``, ``from simulator.thermal import ...``) only; these are the justified exceptions, each
#: (file, module) with the reason.
#: Private helpers the two packages share (infrastructure, not simulation API): the lazy
#: exports, the validation checks (one message form for every field) and the result files.
SHARED_INFRASTRUCTURE = {"simulator._lazy", "simulator._validate", "simulator._result",
                         "simulator._deprecation"}

DESIGN_SIMULATOR_INTERNALS = set()


def _imports(path: pathlib.Path):
    """(line, absolute module name) of every import in ``path`` (relative ones resolved)."""
    package = ".".join(path.relative_to(ROOT).with_suffix("").parts[:-1])
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            yield from ((node.lineno, a.name) for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - node.level + 1]
                yield node.lineno, ".".join(base + ([node.module] if node.module else []))
            else:
                yield node.lineno, node.module or ""


def test_design_uses_simulator_through_its_doors_and_never_studies():
    """Arrows point down: design/ imports ``from simulator import ...`` or from one of its
    namespaces (allow-listed exceptions above) and never imports studies/ (at module level or
    inside functions)."""
    import simulator
    from doors import namespaces

    public = {"simulator"} | {f"simulator.{name}" for name in namespaces(simulator)}
    through_internals, upwards, used = [], [], set()
    for path in sorted((ROOT / "design").rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        for line, module in _imports(path):
            top = module.split(".")[0]
            if top == "studies":
                upwards.append(f"{rel}:{line}: {module}")
            elif top == "simulator" and module not in public:
                if module in SHARED_INFRASTRUCTURE:
                    continue
                if (rel, module) in DESIGN_SIMULATOR_INTERNALS:
                    used.add((rel, module))
                else:
                    through_internals.append(f"{rel}:{line}: {module}")
    assert upwards == []
    assert through_internals == [], "import these from simulator (make them public if a user " \
                                    "needs them) or allow-list them with the reason"
    assert used == DESIGN_SIMULATOR_INTERNALS, "stale allow-list entries"


def test_design_core_is_generic():
    """design/core (spaces, problems, logs, optimisers, executors) never imports the devices,
    the analyses or the CLI."""
    offenders = [f"{p.name}:{line}: {m}" for p in sorted((ROOT / "design" / "core").glob("*.py"))
                 for line, m in _imports(p)
                 if m.startswith(("design.devices", "design.analysis", "design.cli"))]
    assert offenders == []


def _message_reads(tree) -> list:
    """Lines where a result's ``.message`` is read as data: a membership test on it (``"x"
    in r.message``) or a string method on it (``r.message.split(...)``)."""
    def is_message(node):
        return isinstance(node, ast.Attribute) and node.attr == "message"
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare) and any(isinstance(op, (ast.In, ast.NotIn))
                                                 for op in node.ops):
            if any(is_message(c) for c in node.comparators):
                lines.append(node.lineno)
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                and is_message(node.func.value):
            lines.append(node.lineno)
    return lines


def test_design_reads_events_not_messages():
    """Issue 18 item 4: the design layer reads limit points and snaps from the event records
    (``simulator.steps.Event``), never out of a message: no module in ``design/`` imports ``re``,
    tests text in a ``.message`` or calls string methods on one."""
    offenders = []
    for path in (ROOT / "design").rglob("*.py"):
        tree = ast.parse(path.read_text())
        name = path.relative_to(ROOT)
        for node in ast.walk(tree):
            if isinstance(node, ast.Import) and any(a.name.split(".")[0] == "re"
                                                    for a in node.names):
                offenders.append(f"{name}:{node.lineno}: import re")
            elif isinstance(node, ast.ImportFrom) and node.module == "re":
                offenders.append(f"{name}:{node.lineno}: from re import")
        offenders += [f"{name}:{k}: reads a message" for k in _message_reads(tree)]
    assert offenders == []


def test_message_read_check_sees_what_it_forbids():
    """The check of :func:`test_design_reads_events_not_messages` catches both forms."""
    code = ('ok = "after a snap" in stage.message\n'
            'p = res.message.split("snap at ")[1]\n'
            'fine = res.message + "!"\n')
    assert _message_reads(ast.parse(code)) == [1, 2]
