"""benchmarks/bench_fold.py: a small folding sheet run end to end with both solver settings."""

import importlib.util
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_fold.py"
_spec = importlib.util.spec_from_file_location("bench_fold", _PATH)
bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench)


def test_a_small_sheet_folds_alike_with_either_setting():
    rows = [bench.run(3, 1.0, 0.9, pardiso) for pardiso in (True, False)]
    for row in rows:
        assert row["success"] and row["iterations"] >= 2 and row["rss"] > 0
        assert 0 < row["solve"] < row["wall"]
        assert row["umax"] > 1e-7                      # the sheet folds [m]
    assert rows[0]["umax"] == pytest.approx(rows[1]["umax"], rel=1e-9)
