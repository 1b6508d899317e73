"""benchmarks/bench_scaling.py: the growth exponents and one small sheet run end to end."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

_PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_scaling.py"
_spec = importlib.util.spec_from_file_location("bench_scaling", _PATH)
bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench)


def test_exponents_fit_and_pairs():
    fit, pairs = bench.exponents([10, 100, 1000], [1.0, 10.0, 1000.0])
    assert pairs == pytest.approx([1.0, 2.0])
    assert fit == pytest.approx(1.5)


def test_one_sheet_in_a_subprocess_reports_its_figures(capsys):
    row = bench.run_size(bench.ROOT, 3, 1)
    assert row["nodes"] > 0 and row["dofs"] > 0 and row["rss"] > 0
    assert 0 < row["assembly"] <= row["iteration"] and np.isfinite(row["du_norm"])
    with pytest.raises(SystemExit):
        bench.main(["--repeat", "0"])
