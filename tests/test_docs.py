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

ROOT = pathlib.Path(__file__).resolve().parents[1]
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


def test_readme_imports_only_from_the_two_packages():
    imports = []
    for _, code in python_blocks(ROOT / "README.md"):
        imports += re.findall(r"^\s*(?:from|import)\s+([\w.]+)", code, re.M)
    ours = [m for m in imports if m.split(".")[0] in ("simulator", "design", "studies")]
    assert ours and all(m in ("simulator", "design") for m in ours), ours


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
                 "get_case", "ParameterError", "Step"):
        assert name in simulator.__all__, name
    for name in ("GripperDesign", "evaluate_gripper", "GripperProblem", "MiuraDesign",
                 "MiuraProblem", "miura_model", "heated_creases", "lift_power", "optimize",
                 "make_executor", "sweep_residual_fold", "allocate_heaters"):
        assert name in design.__all__, name


