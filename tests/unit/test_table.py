"""Tables without pandas (simulator._table, design.cli._text_table) give pandas' own text: the
CSV files byte for byte as ``DataFrame.to_csv(index=False)``, the CLI's printed table as
``DataFrame.to_string(index=False)``; what they cannot write is left to pandas."""

import numpy as np
import pandas as pd
import pytest

from design.cli._text_table import format_table
from simulator import get_case
from simulator._table import step_array, writable, write_csv
from simulator.results import _step_column

#: Floats whose shortest repr, exponent form or rounding could go wrong.
AWKWARD = np.array([0.0, -0.0, 0.1, 1 / 3, 1e-5, 1e-4, 123456789.123, 1e16, 1.5e-300, -2.5,
                    np.nan, np.inf, -np.inf, 100.0, 18.700048123, 5e-324])


def _pandas_csv(tmp_path, columns) -> bytes:
    pd.DataFrame(columns).to_csv(tmp_path / "pandas.csv", index=False)
    return (tmp_path / "pandas.csv").read_bytes()


def _ours_csv(tmp_path, columns) -> bytes:
    assert write_csv(tmp_path / "ours.csv", columns)
    return (tmp_path / "ours.csv").read_bytes()


def test_csv_of_plain_columns_is_byte_identical_to_pandas(tmp_path):
    n = len(AWKWARD)
    columns = {"x [m]": AWKWARD, "x32": AWKWARD.astype(np.float32),
               "i": np.arange(n) - 3, "u": np.arange(n, dtype=np.uint8),
               "flag": np.arange(n) % 3 == 0,
               "stage": np.array(["heat", "self_fold", 'a "quoted", name', "x\ny"] * 4),
               "maybe": np.array([True, None, False, None] * 4, dtype=object),
               "note": np.array(["a,b", None, "", "c"] * 4, dtype=object),
               "nothing": np.array([None] * n, dtype=object)}
    assert _ours_csv(tmp_path, columns) == _pandas_csv(tmp_path, columns)


def test_csv_of_one_empty_column_and_of_no_rows_match_pandas(tmp_path):
    for columns in ({"a": np.array([np.nan, 1.0])}, {"a": np.zeros(0), "b": np.zeros(0, int)}):
        assert _ours_csv(tmp_path, columns) == _pandas_csv(tmp_path, columns)


@pytest.mark.parametrize("values", [
    [0.1, None, 2.0], [1, None, 3], [1, 2, 3], [True, False, True], [True, None, False],
    [None, None, None], ["a", None, "b,c"], [np.float64(0.25), 1, None], [np.int64(2), 3, 4],
    [np.array([1.0, 2.0]), None, np.array([0.5, np.nan])], [1e-7, 3.0, None]])
def test_step_columns_are_typed_and_written_as_pandas_types_them(tmp_path, values):
    C = 2
    ours = {"col": step_array(values, C)}
    theirs = {"col": _step_column(values, C)}
    assert _ours_csv(tmp_path, ours) == _pandas_csv(tmp_path, theirs)


@pytest.mark.parametrize("values", [[1, "a", None], [True, 1.0, None],
                                    [np.float32(0.5), 1.0, 2.0]])
def test_mixed_step_columns_are_left_to_pandas(tmp_path, values):
    columns = {"col": step_array(values, 2)}
    assert not writable(columns)
    assert not write_csv(tmp_path / "x.csv", columns) and not (tmp_path / "x.csv").exists()


def test_columns_of_different_lengths_or_not_arrays_are_left_to_pandas():
    assert not writable({"a": np.zeros(2), "b": np.zeros(3)})
    assert not writable({"a": [1.0, 2.0]})
    assert not writable({"a": np.zeros((2, 2))})


@pytest.mark.parametrize("name,settings", [
    ("single_fold", {"thermal_steps": 6, "residual_fold_deg": -10, "gravity": True}),
    ("single_fold_step_response", {"t_on": 0.004, "t_off": 0.004, "mechanics": "quasi_static"}),
])
def test_saved_creases_csv_is_the_pandas_file_and_to_columns_is_to_frame(tmp_path, name,
                                                                         settings):
    result = get_case(name, **settings).run()
    out = result.save(tmp_path / "run")
    frame = result.to_frame()
    frame.to_csv(tmp_path / "pandas.csv", index=False)
    assert (out / "creases.csv").read_bytes() == (tmp_path / "pandas.csv").read_bytes()
    columns = result.to_columns()
    assert list(columns) == list(frame.columns)
    for key, values in columns.items():
        expected = frame[key].to_numpy()
        if values.dtype.kind == "f":
            np.testing.assert_array_equal(values, expected.astype(float))
        else:
            assert [None if pd.isna(v) else v for v in expected] == list(values), key


# ------------------------------------------------------------------------- printed tables
@pytest.mark.parametrize("columns", [
    {"crease": np.array([2]), "power [mW]": np.array([100.0]),
     "fold_angle [deg]": np.array([18.700048123]), "temperature [degC]": np.array([60.4605])},
    {"crease": np.array([2, 10, 11]), "power [mW]": np.array([100.0, 5.5, 0.0]),
     "fold_angle [deg]": np.array([-3.2, 0.0, -0.0]),
     "t": np.array([np.nan, 1234.891, 2.0]), "u": np.array([123456.0, 1.0, 0.5]),
     "w": np.array([np.nan, np.nan, np.nan]), "z": np.array([1e-6, 2.0, 3.0])},
])
def test_printed_table_is_what_pandas_prints(columns):
    assert format_table(columns) == pd.DataFrame(columns).to_string(index=False)


@pytest.mark.parametrize("column", [np.array([1e-7, 2.0]), np.array([2e6, 1.0]),
                                    np.array([np.inf, 1.0]), np.array([True, False]),
                                    np.zeros(0)])
def test_tables_pandas_prints_otherwise_are_printed_by_pandas(column):
    columns = {"crease": np.arange(len(column)), "x": column}
    assert format_table(columns) == pd.DataFrame(columns).to_string(index=False)
