"""A table of numbers printed as ``pandas.DataFrame.to_string(index=False)`` prints it, without
importing pandas (a quarter of a second of a short command such as ``etorigami run``).

Integer columns print with ``str``; float columns with six decimals, trailing zeros trimmed
equally down to one decimal, NaN as ``NaN``; headers of numeric columns get a leading space;
each column is right-justified to its widest cell; columns are joined by one space. A table
pandas would print otherwise (scientific notation for values below 1e-6 or above 1e6, other
column types) is printed by pandas itself. ``tests/unit/test_text_table.py`` compares both.
"""

from __future__ import annotations

import numpy as np

__all__ = ["format_table"]

#: pandas' ``display.precision``: decimals of a float column before trimming.
_DIGITS = 6
#: pandas' ``display.max_colwidth``: a longer cell is cut by pandas (left to pandas here).
_MAX_WIDTH = 50


def _float_cells(column: np.ndarray) -> list:
    """Six decimals, NaN as ``NaN``, trailing zeros trimmed equally (pandas'
    ``_trim_zeros_float``; ``inf`` is not a decimal number and is left alone)."""
    cells = ["NaN" if np.isnan(v) else f"{v:.{_DIGITS}f}" for v in column.tolist()]
    decimal = [c not in ("NaN", "inf", "-inf") for c in cells]
    while any(decimal) and all(c.endswith("0") for c, d in zip(cells, decimal) if d):
        cells = [c[:-1] if d else c for c, d in zip(cells, decimal)]
    return [c + "0" if d and c.endswith(".") else c for c, d in zip(cells, decimal)]


def _plain(column) -> bool:
    """Whether this module prints the column as pandas would: integers, or floats without
    values pandas prints in scientific notation."""
    if not isinstance(column, np.ndarray) or column.ndim != 1:
        return False
    if column.dtype.kind in "iu":
        return True
    if column.dtype.kind != "f":
        return False
    size = np.abs(column[~np.isnan(column)])
    return not (np.any(size > 1e6) or np.any((size > 0) & (size < 10.0 ** -_DIGITS)))


def format_table(columns: dict) -> str:
    """``columns`` (name -> 1-D array, all of one length) as pandas prints them with
    ``to_string(index=False)``."""
    lengths = {len(c) for c in columns.values() if isinstance(c, np.ndarray)}
    if (not columns or lengths == {0} or len(lengths) != 1
            or not all(_plain(c) for c in columns.values())):
        import pandas as pd

        return pd.DataFrame(columns).to_string(index=False)
    strcols = []
    for name, column in columns.items():
        cells = (_float_cells(column) if column.dtype.kind == "f"
                 else [str(v) for v in column.tolist()])
        header = " " + str(name)
        width = max([len(header)] + [len(c) for c in cells])
        if width > _MAX_WIDTH:
            import pandas as pd

            return pd.DataFrame(columns).to_string(index=False)
        strcols.append([header.rjust(width)] + [c.rjust(width) for c in cells])
    return "\n".join(" ".join(row) for row in zip(*strcols))
