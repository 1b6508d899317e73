"""FOLD files whose panels are not one sheet joined by creases (issue 20 corpus check): check
and run refuse them in one line naming the free panels, instead of a 'singular' failure."""

import importlib.util
import pathlib

import pytest

from design.cli import main
from simulator import ParameterError
from simulator.fold import read_fold
from simulator.model import check_supported, unsupported_panels

ROOT = pathlib.Path(__file__).resolve().parents[2]
TOUCHING = str(ROOT / "tests" / "data" / "fold" / "sheets_touching_at_a_vertex.fold")
MM = {"crease_width": 2e-4, "crease_thickness": 1e-6, "panel_thickness": 1e-5}


def test_unsupported_panels_of_one_sheet_is_empty_and_of_two_names_the_other():
    miura = read_fold(ROOT / "tests" / "data" / "fold" / "miura_3x3_plain.fold", **MM)
    assert unsupported_panels(miura, 0) == []
    two = read_fold(TOUCHING, **MM)
    assert unsupported_panels(two, 0) == [2, 3]
    assert unsupported_panels(two, 3) == [0, 1]
    with pytest.raises(ParameterError, match=r"panels \[2, 3\] are joined to it by no crease"):
        check_supported(two, 0)


@pytest.mark.parametrize("args", [
    ["check", TOUCHING],
    ["run", TOUCHING, "--heat", "all", "--power", "1"],
    ["run", TOUCHING, "--crease-model", "sharp", "--fold", "all=30"],
    ["run", TOUCHING, "--heat", "all", "--power", "1", "--fix-panel", "0"],
], ids=["check", "heat", "sharp", "fix-panel"])
def test_sheets_touching_at_a_vertex_are_refused_in_one_line(args, tmp_path, capsys):
    if args[0] == "run":
        args = args + ["--out", str(tmp_path / "r"), "-q"]
    assert main(args) == 2
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in out + err and "singular" not in out + err
    assert "joined to it by no crease" in lines[0] and "panels [" in lines[0]


def _corpus_module():
    spec = importlib.util.spec_from_file_location("fold_corpus",
                                                  ROOT / "benchmarks" / "fold_corpus.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_corpus_script_classifies_outcomes(tmp_path):
    classify = _corpus_module().classify
    ok = (0, "", "")
    assert classify(ok, (0, "converged", ""))[0] == "ran"
    assert classify(ok, (2, "", "etorigami: error: x\n"))[0] == "refused"
    assert classify(ok, (2, "", "etorigami: error: x\nmore\n"))[0] == "refused-multiline"
    gave_up = "p: failed (step 'heat': gave up ... no convergence in 30 iterations) in 1 s"
    assert classify(ok, (1, gave_up, "")) == ("exit1-no-cause", gave_up)
    assert classify(ok, (1, "p: failed (a limit point at 3 mW) in 1 s", ""))[0] == "failed-named"
    tb = "Traceback (most recent call last):\nValueError: v"
    assert classify(ok, (1, "", tb))[0] == "traceback"
    crash = (1, "", "Traceback (most recent call last):\nValueError: zero-size")
    assert classify(crash, (2, "", "etorigami: error: x")) == ("traceback", "ValueError: zero-size")
    assert classify((None, "", ""), ok) == ("timeout", "check")
    assert classify(ok, (0, "fold angle nan", ""))[0] == "nan"
    assert classify(ok, (0, "Nanami.fold converged", ""))[0] == "ran"
    (tmp_path / "creases.csv").write_text("crease,fold_angle [deg]\n0,nan\n")
    assert classify(ok, (0, "", ""), tmp_path)[0] == "nan"


def test_corpus_script_reads_stability_from_meta_defensively(tmp_path):
    mod = _corpus_module()
    assert not mod.final_state_unstable({"status": "converged", "steps": [{"name": "heat"}]})
    assert not mod.final_state_unstable({"steps": []})
    assert mod.final_state_unstable({"steps": [{"stability": {"stable": False}}]})
    assert mod.final_state_unstable({"steps": [{"stable": True}, {"stability": "unstable"}]})
    assert mod.final_state_unstable({"steps": [{"n_negative_eigenvalues": 1}]})
    assert not mod.final_state_unstable({"steps": [{"stable": False}, {"stable": True}]})
    (tmp_path / "meta.json").write_text('{"status": "converged", "steps": [{"stable": false}]}')
    assert mod.classify((0, "", ""), (0, "", ""), tmp_path)[0] == "unstable-converged"


def test_corpus_script_runs_a_folder(tmp_path, capsys):
    import shutil
    shutil.copy(TOUCHING, tmp_path / "a.fold")
    csv = tmp_path / "t.csv"
    assert _corpus_module().main(["--dir", str(tmp_path), "--out", str(tmp_path / "o"),
                                  "--csv", str(csv)]) == 0
    out = capsys.readouterr().out
    assert "a.fold" in out and "refused" in out and "1 files, 0 bad outcomes" in out
    assert "refused by run after check passed: 0" in out
    assert csv.read_text().splitlines()[1].startswith("a.fold,refused,2,2,")
