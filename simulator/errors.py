"""Exception hierarchy of etorigami.

Every error of the toolkit derives from :class:`EtorigamiError`. Bad user input raises a
:class:`ParameterError` (or :class:`PatternError`, :class:`FoldFormatError`), also a
:class:`ValueError`, whose message names the offending item, the value given and how to fix it
(see :mod:`simulator._validate`). A numerical method that fails on valid input raises a
:class:`SolverError` or, on request, a :class:`ConvergenceError` (both :class:`RuntimeError`):
changing the arguments is not the fix there. An old spelling kept for one release warns
with an :class:`EtorigamiDeprecationWarning` naming its replacement.
"""

from __future__ import annotations


class EtorigamiError(Exception):
    """Base class of all etorigami errors."""


class PatternError(EtorigamiError, ValueError):
    """The origami pattern (vertices, panels, crease data) is invalid."""


class ParameterError(EtorigamiError, ValueError):
    """A parameter, option or loading step was given an invalid value."""


class FoldFormatError(ParameterError):
    """A FOLD file is malformed; the message names the field and the index (one line)."""


class ConvergenceError(EtorigamiError, RuntimeError):
    """A solver did not converge and the caller asked for an exception.

    Attributes
    ----------
    result : object
        The partial result (status, message, iterations, last state).
    """

    def __init__(self, message: str, result: object = None):
        super().__init__(message)
        self.result = result


class SolverError(EtorigamiError, RuntimeError):
    """A numerical method failed although its input was valid: a factorisation that should
    succeed did not (LAPACK ``info != 0``), an LP found no solution, an eigensolver broke down.

    Not a :class:`ValueError`: changing the arguments is not the fix. The message names the
    method and its status.
    """


class EtorigamiDeprecationWarning(DeprecationWarning):
    """An old spelling that still works for one release and then goes (e.g. the flat
    ``ThermalParameters(env_thickness=...)`` keywords): the message names its replacement.
    A :class:`DeprecationWarning`, so Python shows it where a script (``__main__``) uses the
    old spelling; the test suite turns it into an error (``pyproject.toml``)."""
