"""Documentation that runs: every ``python`` code block of README.md and docs/*.md executes,
and every public name is exported.

The blocks of one file run in order in one namespace (later blocks may use earlier names),
inside a temporary working directory so that files they write land there. A block fenced
as ```python no-test is shown to readers but not run (used only for commands that need a
cluster or take minutes; each one says so in the text around it).
"""

from __future__ import annotations

import pathlib
import re
import sys
import types

import pytest

import design
import simulator
from doors import moved, namespaces

ROOT = pathlib.Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
_BLOCK = re.compile(r"^```python[ \t]*(?P<info>[^\n]*)\n(?P<code>.*?)^```", re.M | re.S)


def python_blocks(path: pathlib.Path) -> list[tuple[int, str]]:
    """(line number, code) of every runnable ``python`` block of a Markdown file."""
    text = path.read_text()
    return [(text.count("\n", 0, m.start()) + 1, m.group("code"))
            for m in _BLOCK.finditer(text) if "no-test" not in m.group("info")]


@pytest.mark.parametrize("path", DOCS, ids=lambda p: p.name)
def test_code_blocks_run(path, tmp_path, monkeypatch):
    blocks = python_blocks(path)
    if path.name == "README.md":
        assert len(blocks) >= 3, "the README lost its examples"
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    module = types.ModuleType("_docs_namespace")       # dataclasses need a real module
    monkeypatch.setitem(sys.modules, module.__name__, module)
    namespace = module.__dict__
    for line, code in blocks:
        try:
            exec(compile(code, f"{path.name}:{line}", "exec"), namespace)
        except Exception as exc:  # pragma: no cover - the message is the point
            raise AssertionError(f"{path.name}, code block at line {line} failed: "
                                 f"{type(exc).__name__}: {exc}") from exc


def test_readme_imports_only_from_the_doors_and_namespaces():
    imports = []
    for _, code in python_blocks(ROOT / "README.md"):
        imports += re.findall(r"^\s*(?:from|import)\s+([\w.]+)", code, re.M)
    ours = [m for m in imports if m.split(".")[0] in ("simulator", "design", "studies")]
    public = {"simulator", "design"} | {f"{p.__name__}.{n}" for p in (simulator, design)
                                        for n in namespaces(p)}
    assert ours and all(m in public for m in ours), ours


@pytest.mark.parametrize("package", [simulator, design], ids=lambda p: p.__name__)
def test_public_names_exist(package):
    names = package.__all__
    assert len(names) == len(set(names)), "duplicate names in __all__"
    missing = [n for n in names if not hasattr(package, n)]
    assert missing == []


def test_issue_names_are_public():
    for name in ("simulate", "make_model", "Supports", "ContactParameters", "BarHingeParameters",
                 "ThermalParameters", "Actuators", "Bimorph", "Material", "Pattern", "SelfFold",
                 "Gravity", "Heat", "AmbientTemperature", "NewtonOptions", "SimulationResult",
                 "get_case", "ParameterError"):
        assert name in simulator.__all__, name
    assert "Step" in simulator.steps.__all__
    for name in ("GripperDesign", "evaluate_gripper", "GripperProblem", "MiuraDesign",
                 "MiuraProblem", "miura_model", "heated_creases", "lift_power", "optimize",
                 "make_executor", "sweep_residual_fold", "allocate_heaters"):
        assert name in design.__all__, name




# ------------------------------------------------ citations of docs/theory.md in the code
# The code cites the method as "theory 4.3" (section), "theory 4" (chapter), "theory 4.3-4.4"
# (range), "theory 6.4, 6.5" or "theory 8.6 and 8.4" (lists); docs/theory.md section 1.1.
THEORY = ROOT / "docs" / "theory.md"
_SOURCES = ("simulator", "design", "studies", "tests", "benchmarks")
_NUMBER = r"\d+(?:\.\d+)?"
_CITATION = re.compile(rf"\btheory ({_NUMBER}(?:(?:-|, | and ){_NUMBER}(?![\d.]))*)", re.I)
_HEADING = re.compile(r"^#{2,3} (\d+(?:\.\d+)?)\.? ", re.M)


def source_files() -> list[pathlib.Path]:
    """Every Python and Markdown file of the source trees, plus the README."""
    files = [ROOT / "README.md"]
    for top in _SOURCES:
        files += sorted(p for p in (ROOT / top).rglob("*") if p.suffix in (".py", ".md"))
    return files


def theory_sections() -> set[str]:
    """Section numbers of docs/theory.md: "4" for "## 4. Heat transfer", "4.3" for "### 4.3 ..."."""
    return set(_HEADING.findall(THEORY.read_text()))


def cited_sections(text: str) -> list[str]:
    """Every section number a text cites as "theory X.Y" (each end of a range, each list item)."""
    return [n for m in _CITATION.finditer(text) for n in re.findall(_NUMBER, m.group(1))]


def test_citation_parser():
    text = ("(theory 4.3) theory 10; (theory 4.3-4.4), (Theory 6.4, 6.5) theory 8.6 and 8.4; "
            "theory 6.4, 10.6: tol 5e-7 N")
    assert cited_sections(text) == ["4.3", "10", "4.3", "4.4", "6.4", "6.5", "8.6", "8.4",
                                    "6.4", "10.6"]
    assert {"1.1", "4", "4.3", "10.9", "11"} <= theory_sections()


def test_no_digest_citations_left():
    """The code once cited a "method digest" that is not in the repository; it cites theory.md.

    This file is exempt: it has to name the word it looks for."""
    stale = [f"{p.relative_to(ROOT)}:{i}" for p in source_files() if p != pathlib.Path(__file__)
             for i, line in enumerate(p.read_text().splitlines(), 1)
             if re.search(r"(?<!hex)digest", line, re.I)]
    assert stale == [], "cite docs/theory.md as 'theory X.Y' instead: " + ", ".join(stale)


def test_theory_citations_name_existing_sections():
    sections = theory_sections()
    cited = {(str(p.relative_to(ROOT)), n) for p in source_files()
             for n in cited_sections(p.read_text())}
    assert len(cited) > 80, "the code lost its citations of docs/theory.md"
    missing = sorted(f"{f}: theory {n}" for f, n in cited if n not in sections)
    assert missing == [], "no such section in docs/theory.md: " + ", ".join(missing)


# ------------------------------------------------ the API reference (mkdocs.yml, docs/_ext/api.py)
def _api_module():
    import importlib.util

    spec = importlib.util.spec_from_file_location("_docs_api", ROOT / "docs" / "_ext" / "api.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault(spec.name, module)            # its dataclasses need a real module
    spec.loader.exec_module(sys.modules[spec.name])
    return sys.modules[spec.name]


@pytest.mark.parametrize("package", [simulator, design], ids=lambda p: p.__name__)
def test_api_pages_document_every_public_name(package):
    """The static reading of the sources that makes the API pages agrees with the runtime:
    the door and every namespace, each name the object it stands for; every public name has
    one entry (a namespace's name that is also at the door has the door's)."""
    import importlib

    api = _api_module()
    names = api.public_names(package.__name__)
    assert [n.name for n in names] == package.__all__
    spaces = namespaces(package)
    assert [n.name for n in api.namespaces(package.__name__)] == list(spaces)
    for ns in api.namespaces(package.__name__):
        items = api.namespace_names(ns)
        assert [n.name for n in items] == spaces[ns.name].__all__, ns.name
        names += items
    for item in names:
        owner = importlib.import_module(item.package)
        defined = importlib.import_module(item.module)
        obj = defined if item.is_module else getattr(defined, item.source or item.name)
        assert obj is getattr(owner, item.name), item
    pages = api._pages(package.__name__)
    entries = {line[4:] for module, items, at_door in pages.values()
               for line in api._page(module, items, at_door).splitlines()
               if line.startswith("::: ") and line[4:] not in (module, package.__name__)}
    door = {n for n in package.__all__ if n not in spaces}
    documented = {f"{package.__name__}.{n}" for n in door}
    for name, module in spaces.items():
        documented |= {f"{package.__name__}.{name}.{n}" for n in module.__all__
                       if not (n in door and getattr(module, n) is getattr(package, n))}
    assert entries == documented


def test_migration_table_lists_every_moved_name():
    api = _api_module()
    for package in (simulator, design):
        rows = api.migration_table(package.__name__).splitlines()[2:]
        assert len(rows) == len(moved(package)) > 0
        assert all(f"`{package.__name__}." in row for row in rows)


def test_api_theory_anchors_are_mkdocs_slugs():
    pytest.importorskip("markdown")
    anchors = _api_module().theory_anchors()
    assert anchors["4.3"] == "43-environment-chains" and anchors["4"] == "4-heat-transfer"
    assert set(anchors) == theory_sections()


def test_api_unknown_public_name_is_an_error(tmp_path, monkeypatch):
    api = _api_module()
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "__init__.py").write_text(
        "__getattr__, __dir__ = _attach(__name__, {'.a': ('f',)})\n__all__ = ['f', 'g']\n")
    monkeypatch.setattr(api, "ROOT", tmp_path)
    with pytest.raises(RuntimeError, match="'g'.*add it there"):
        api.public_names("pkg")
