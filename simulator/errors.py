"""Exception hierarchy of etorigami.

Every error raised on bad user input derives from :class:`EtorigamiError` and
(for input errors) from :class:`ValueError`, so callers can catch either.
Messages name the offending item, the value given and how to fix it.
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
