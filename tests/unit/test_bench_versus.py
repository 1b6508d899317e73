"""benchmarks/bench_versus.py: options, task list and table, without running any task."""

import importlib.util
import sys
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_versus.py"
_spec = importlib.util.spec_from_file_location("bench_versus", _PATH)
bench = importlib.util.module_from_spec(_spec)
sys.modules.setdefault("bench_versus", bench)       # dataclasses look their module up
_spec.loader.exec_module(bench)


def test_task_list_covers_issue_13():
    assert bench.TASK_NAMES == ("startup_version", "startup_import", "first_run", "gripper_eval",
                                "cd_full", "single_crease", "miura_heat", "newton_1e3",
                                "newton_1e4", "newton_1e5")
    for task in bench.TASKS:                      # every snippet reports through the footer
        assert "_T" in task.old and "_T" in task.new
    newton = {t.name: t for t in bench.TASKS}["newton_1e4"]
    assert "simulator.newton import _solve_linear" in newton.old
    assert "simulator.linalg import solve as _solve_linear" in newton.new
    assert "m=30, n=30" in newton.new


def test_defaults_run_everything_and_quick_drops_the_heavy_tasks():
    args = bench.parse_args([])
    assert (args.repeat, args.quick, args.keep, args.commit) == (1, False, False, "b25f328")
    assert [t.name for t in bench.selected_tasks(args)] == list(bench.TASK_NAMES)
    quick = [t.name for t in bench.selected_tasks(bench.parse_args(["--quick"]))]
    assert "cd_full" not in quick and "newton_1e5" not in quick and "newton_1e4" in quick


def test_tasks_option_chooses_and_rejects_unknown_names(capsys):
    args = bench.parse_args(["--tasks", "newton_1e3", "gripper_eval", "--repeat", "3"])
    assert [t.name for t in bench.selected_tasks(args)] == ["gripper_eval", "newton_1e3"]
    assert args.repeat == 3
    with pytest.raises(SystemExit):
        bench.parse_args(["--tasks", "nonsense"])
    with pytest.raises(SystemExit):
        bench.parse_args(["--repeat", "0"])
    assert "--repeat = 0 must be >= 1" in capsys.readouterr().err


def test_table_speed_up_comparison_and_growth_exponent():
    rows = [{"task": f"newton_1e{k}", "old": 1e-3 * 10 ** k, "new": 5e-4 * 10 ** k,
             "old_result": [10 ** k, 1.0], "new_result": [10 ** k, 1.0 + 1e-9 * (k < 4)],
             "old_rss": 100.0, "new_rss": 90.0, "old_error": None, "new_error": None}
            for k in (3, 4)]
    for r in rows:
        r["same"] = bench._same_result(r["old_result"], r["new_result"])
    table = bench.format_table(rows)
    assert "| newton_1e3 | 1.000 | 0.500 | 2.00x | yes | 100 | 90 |" in table
    assert bench.growth_exponents(rows) == pytest.approx({"old": 1.0, "new": 1.0})
    assert bench._same_result([1.0], [1.1]) == "no"
    assert bench._same_result(None, [1.0]) == "-"
