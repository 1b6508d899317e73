"""Documentation that runs: every code block of README.md and docs/*.md executes and writes
nothing into the repository, and every public name is exported.

Code blocks (docs/development.md, "Code blocks in the README and the docs"): the blocks of one
file run in order inside a temporary working folder that holds copies of ``docs/examples/``;
``python`` blocks in one namespace (later blocks may use earlier names), ``bash`` blocks whose
lines are all ``etorigami ...`` commands through the CLI's ``main()`` (``~`` is a temporary
home folder). ``text`` blocks are output, ``json`` blocks are parsed; a fence without a
language is an error. A block is left out by a comment on the line before its fence:
``<!-- no-run: why -->`` (it cannot run here: an installation, a cluster) or
``<!-- slow: why -->`` (it runs only with ``-m slow``). Afterwards ``git status --porcelain``
of the repository must show nothing new.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import types

import pytest

import design
import simulator
from doors import moved, namespaces

ROOT = pathlib.Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: The most blocks all pages may mark ``no-run``: installations, builds, a cluster.
MAX_NO_RUN = 6
_FENCE = re.compile(r"^```(?P<info>[^\n`]*)\n(?P<code>.*?)^```[ \t]*$", re.M | re.S)
_MARK = re.compile(r"<!--\s*(?P<kind>no-run|slow)\s*:\s*(?P<why>[^>]*?)\s*-->\s*\Z")
_SHELL = ("bash", "sh", "shell", "console")
_KINDS = ("python", "json", "text", *_SHELL)


@dataclasses.dataclass(frozen=True)
class Block:
    """One fenced block of a Markdown file: its language, its code, the line of its fence and
    its mark (``""``, ``"no-run"`` or ``"slow"``) with the reason given."""

    path: pathlib.Path
    line: int
    language: str
    info: str
    code: str
    mark: str = ""
    why: str = ""

    @property
    def where(self) -> str:
        return f"{self.path.name}:{self.line}"


def blocks(path: pathlib.Path) -> list[Block]:
    """Every fenced block of a Markdown file, in order."""
    text = path.read_text()
    found = []
    for m in _FENCE.finditer(text):
        info = m.group("info").strip()
        before = text[:m.start()].rstrip("\n").rsplit("\n", 1)[-1]
        mark = _MARK.search(before)
        found.append(Block(path, text.count("\n", 0, m.start()) + 1, info.split(" ")[0], info,
                           m.group("code"), mark.group("kind") if mark else "",
                           mark.group("why") if mark else ""))
    return found


def python_blocks(path: pathlib.Path) -> list[tuple[int, str]]:
    """(line number, code) of every ``python`` block of a Markdown file that runs."""
    return [(b.line, b.code) for b in blocks(path) if b.language == "python" and not b.mark]


def etorigami_commands(code: str) -> list[list[str]]:
    """The commands of a shell block as argument lists (continued lines joined, comments
    dropped); every command must be ``etorigami ...``."""
    commands = []
    for line in code.replace("\\\n", " ").splitlines():
        words = shlex.split(line, comments=True)
        if words:
            if words[0] != "etorigami":
                raise ValueError(f"{line.strip()!r} is not an etorigami command")
            commands.append(words[1:])
    return commands


def _git_status() -> str | None:
    git = shutil.which("git")
    if git is None:
        return None
    out = subprocess.run([git, "status", "--porcelain", "--untracked-files=all"], cwd=ROOT,
                         capture_output=True, text=True)
    return out.stdout if out.returncode == 0 else None


def _run_shell(block: Block, home: pathlib.Path) -> None:
    from design.cli import main

    for args in etorigami_commands(block.code):
        args = [str(home / a[2:]) if a.startswith("~/") else a for a in args]
        try:
            code = main(args)
        except SystemExit as exc:                       # argparse's errors and --help
            code = exc.code
        assert code in (0, None), f"{block.where}: etorigami {shlex.join(args)} exited {code}"


def _run_blocks(path: pathlib.Path, tmp_path, monkeypatch, slow: bool) -> int:
    """Run the blocks of ``path`` (the slow ones too when ``slow``) in a temporary working
    folder; check that the repository shows nothing new. Returns how many blocks ran."""
    work, home = tmp_path / "work", tmp_path / "home"
    shutil.copytree(ROOT / "docs" / "examples", work)
    home.mkdir()
    (tmp_path / "tmp").mkdir()
    monkeypatch.chdir(work)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))   # tempfile.mkdtemp()
    module = types.ModuleType("_docs_namespace")       # dataclasses need a real module
    monkeypatch.setitem(sys.modules, module.__name__, module)
    namespace = module.__dict__
    before = _git_status()
    ran = 0
    for block in blocks(path):
        if block.mark == "no-run" or (block.mark == "slow" and not slow):
            continue
        try:
            if block.language == "python":
                exec(compile(block.code, block.where, "exec"), namespace)
            elif block.language in _SHELL:
                _run_shell(block, home)
            else:
                continue
        except Exception as exc:  # pragma: no cover - the message is the point
            raise AssertionError(f"{block.where}: code block failed: {type(exc).__name__}: "
                                 f"{exc}") from exc
        ran += 1
    after = _git_status()
    new = sorted(set((after or "").splitlines()) - set((before or "").splitlines()))
    assert new == [], f"the code blocks of {path.name} wrote into the repository: {new}"
    return ran


@pytest.mark.parametrize("path", DOCS, ids=lambda p: p.name)
def test_code_blocks_run(path, tmp_path, monkeypatch):
    ran = _run_blocks(path, tmp_path, monkeypatch, slow=False)
    if path.name == "README.md":
        assert ran >= 3, "the README lost its examples"


@pytest.mark.slow
@pytest.mark.parametrize("path", [p for p in DOCS if any(b.mark == "slow" for b in blocks(p))],
                         ids=lambda p: p.name)
def test_slow_code_blocks_run(path, tmp_path, monkeypatch):
    """The files with blocks marked slow, every block in order (the slow ones included)."""
    ran = _run_blocks(path, tmp_path, monkeypatch, slow=True)
    assert ran >= sum(b.mark == "slow" for b in blocks(path))


def test_every_block_says_what_it_is():
    """Every fence names its language, shell blocks are etorigami commands or marked, json
    blocks parse, and the blocks left out are marked with a reason and few."""
    every = [b for path in DOCS for b in blocks(path)]
    assert len(every) > 40
    wrong = [f"{b.where}: ```{b.info}" for b in every
             if b.language not in _KINDS or b.info != b.language]
    assert wrong == [], "name the block's language (python, bash, json or text): " + str(wrong)
    for b in every:
        if b.language in _SHELL and not b.mark:
            etorigami_commands(b.code)                  # raises on another command
        if b.language == "json":
            json.loads(b.code)
        if b.mark:
            assert b.language in ("python", *_SHELL) and len(b.why) > 10, b.where
    no_run = [b.where for b in every if b.mark == "no-run"]
    assert len(no_run) <= MAX_NO_RUN, f"{len(no_run)} blocks not run: {no_run}"


def test_a_mark_stands_right_before_its_fence():
    for path in DOCS:
        text = path.read_text()
        marked = {b.line for b in blocks(path) if b.mark}
        for i, line in enumerate(text.splitlines(), 1):
            if _MARK.search(line):
                assert i + 1 in marked, f"{path.name}:{i}: a mark must be on the line before a fence"


def test_block_parser(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("text\n\n```python\nx = 1\n```\n\n<!-- no-run: needs a cluster here -->\n"
                    "```bash\npip install x\n```\n\n<!-- slow: about a minute -->\n```python\n"
                    "y = 2\n```\n\n```\nplain\n```\n")
    found = blocks(page)
    assert [(b.line, b.language, b.mark) for b in found] == [
        (3, "python", ""), (8, "bash", "no-run"), (13, "python", "slow"), (17, "", "")]
    assert found[1].why == "needs a cluster here" and python_blocks(page) == [(3, "x = 1\n")]
    assert etorigami_commands("etorigami run a \\\n  --out b   # c\n\n") == [["run", "a", "--out",
                                                                             "b"]]
    with pytest.raises(ValueError, match="not an etorigami command"):
        etorigami_commands("pip install x\n")


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
                 "MiuraProblem", "make_miura_model", "heated_creases", "lift_power", "optimize",
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
