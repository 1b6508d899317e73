"""Deprecated spellings: one warning, attributed to the user's line (not to the toolkit's own
frames, nor to ``dataclasses.replace``, which calls ``__init__``, nor to the ``__init__`` that
:mod:`dataclasses` generates, which calls ``__post_init__``, nor to the import system, which
looks a name up once more in ``from package import name``)."""

from __future__ import annotations

import dataclasses
import sys
import warnings

from .errors import EtorigamiDeprecationWarning

__all__ = ["warn_deprecated"]


def warn_deprecated(message: str) -> None:
    """Warn with an :class:`~simulator.errors.EtorigamiDeprecationWarning` ``message`` at the
    first frame outside the calling module, :mod:`dataclasses` and the import system (Python
    shows it once per such line)."""
    frame, level = sys._getframe(1), 2
    skip = {frame.f_code.co_filename, dataclasses.__file__}
    while frame.f_back is not None and (frame.f_code.co_filename in skip or
                                        frame.f_code.co_filename.startswith("<frozen importlib")
                                        or _generated_init(frame)):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, EtorigamiDeprecationWarning, stacklevel=level)


def _generated_init(frame) -> bool:
    """The frame is the ``__init__`` that :mod:`dataclasses` wrote (no source file) of a
    dataclass instance."""
    code = frame.f_code
    return (code.co_name == "__init__" and code.co_filename.startswith("<")
            and dataclasses.is_dataclass(frame.f_locals.get("self")))
