"""Shared helpers of the FOLD modules: the namespace, errors naming field and index, and
per-element field access."""

from __future__ import annotations

from ...errors import FoldFormatError

#: Our namespace prefix.
NS = "etorigami:"


def fail(field: str, message: str):
    """Raise the one-line :class:`FoldFormatError` ``FOLD <field>: <message>``."""
    raise FoldFormatError(f"FOLD {field}: {message}") from None


def is_number(x) -> bool:
    """True for a JSON number (int or float, not bool)."""
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def index_list(value, field: str, n: int, length=None) -> list:
    """A list of integer indices in 0..n-1 (``length`` = exact count, or a minimum if negative)."""
    if not isinstance(value, list) or not all(isinstance(i, int) and not isinstance(i, bool)
                                              for i in value):
        fail(field, f"{value!r} is not a list of integer indices.")
    if length is not None and (len(value) != length if length > 0 else len(value) < -length):
        need = f"{length}" if length > 0 else f"at least {-length}"
        fail(field, f"{value!r} has {len(value)} entries; it needs {need}.")
    bad = [i for i in value if not 0 <= i < n]
    if bad:
        fail(field, f"index {bad[0]} is out of range: there are {n} vertices (0..{n - 1}).")
    return value


def array_field(data: dict, name: str, n: int, what: str):
    """A per-element list of length n, or None when absent."""
    value = data.get(name)
    if value is None:
        return None
    if not isinstance(value, list) or len(value) != n:
        got = f"{len(value)} entries" if isinstance(value, list) else f"a {type(value).__name__}"
        fail(name, f"has {got}; it needs one entry per {what} ({n}).")
    return value
