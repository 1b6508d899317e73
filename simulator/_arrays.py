"""Read-only arrays for the immutable stages (Pattern, BarHingeMesh)."""

from __future__ import annotations

import numpy as np


def read_only(a) -> np.ndarray:
    """``a`` if it is already a read-only array, else a read-only copy.

    A copy, not a view, so that nobody holding the original can change a frozen object.
    """
    if isinstance(a, np.ndarray) and not a.flags.writeable:
        return a
    out = np.array(a)
    out.setflags(write=False)
    return out
