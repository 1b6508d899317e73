"""Tidy tables without pandas: columns as numpy arrays, written as CSV exactly as pandas would.

A short command (``etorigami run``) writes its ``creases.csv`` from here, so it does not pay for
importing pandas (about a quarter of a second). The text is pandas' own (``DataFrame.to_csv(
index=False)``, checked byte for byte in ``tests/unit/test_table.py``): floats as numpy writes
them (``astype(str)``, the shortest repr, ``nan`` empty), integers and booleans by ``str``,
strings as given, ``None`` empty, fields quoted by the ``csv`` module as needed. Columns whose types
pandas would infer otherwise (a mix of numbers and strings, say) are not written here:
:func:`write_csv` returns False and the caller uses pandas.
"""

from __future__ import annotations

import csv
import numbers
import os

import numpy as np

__all__ = ["step_array", "writable", "write_csv"]


def _is_number(v) -> bool:
    """A Python int or float, a numpy integer or a float64 (pandas keeps other float widths)."""
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
        return False
    return not isinstance(v, np.floating) or isinstance(v, np.float64)


def step_array(values, C: int) -> np.ndarray:
    """A step column (one value per record, ``None`` where a record's step lacks it) as
    ``(m C,)`` rows, typed as :class:`pandas.Series` would type ``values``.

    (C,) arrays are laid out per crease (float, NaN where missing); numbers are float64 with
    NaN for None (int64 when all are integers and none is missing); booleans are bool, or an
    object array when some are None; strings and all-None columns are object arrays; any
    other mix is an object array that :func:`writable` refuses.
    """
    if any(np.ndim(v) == 1 for v in values):
        return np.concatenate([np.full(C, np.nan) if v is None else
                               np.broadcast_to(np.asarray(v, float), (C,)) for v in values])
    present = [v for v in values if v is not None]
    missing = len(present) < len(values)
    if present and all(_is_number(v) for v in present):
        if not missing and all(isinstance(v, numbers.Integral) for v in present):
            column = np.array(values, dtype=np.int64)
        else:
            column = np.array([np.nan if v is None else v for v in values], dtype=float)
    elif present and not missing and all(isinstance(v, (bool, np.bool_)) for v in present):
        column = np.array(values, dtype=bool)
    else:
        column = np.empty(len(values), dtype=object)
        column[:] = list(values)
    return np.repeat(column, C)


def _plain_objects(column: np.ndarray) -> bool:
    """An object column pandas writes as ``str(v)`` and empty for None: all values None, or
    booleans and None, or strings and None."""
    present = [v for v in column if v is not None]
    return (not present or all(isinstance(v, (bool, np.bool_)) for v in present)
            or all(isinstance(v, str) for v in present))


def writable(columns: dict) -> bool:
    """Whether :func:`write_csv` writes these columns as pandas would (every column a 1-D
    numpy array of floats, integers, booleans or strings, or of objects that are all booleans
    or all strings, None allowed, and all of one length)."""
    lengths = {len(c) if isinstance(c, np.ndarray) else -1 for c in columns.values()}
    if len(lengths) > 1 or -1 in lengths:
        return False
    return all(c.ndim == 1 and (c.dtype.kind in "fiubU" or
                                (c.dtype.kind == "O" and _plain_objects(c)))
               for c in columns.values())


def _texts(column: np.ndarray) -> np.ndarray:
    """The CSV field texts of one column (pandas' ``get_values_for_csv`` with ``na_rep=""``)."""
    if column.dtype.kind == "f":
        text = column.astype(str).astype(object)
        text[np.isnan(column)] = ""
        return text
    if column.dtype.kind == "O":
        return np.array(["" if v is None else str(v) for v in column], dtype=object)
    return column.astype(str).astype(object)


def write_csv(path, columns: dict) -> bool:
    """Write ``columns`` (name -> 1-D array, one row per index) to ``path`` as
    ``pandas.DataFrame(columns).to_csv(path, index=False)`` would, byte for byte; False
    (nothing written) when :func:`writable` says the columns need pandas."""
    if not writable(columns):
        return False
    texts = [_texts(c) for c in columns.values()]
    rows = zip(*texts) if texts else ()
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh, lineterminator=os.linesep, quoting=csv.QUOTE_MINIMAL)
        writer.writerow(list(columns))
        writer.writerows(rows)
    return True
