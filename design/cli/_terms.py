"""The library's FOLD messages in CLI spelling.

The FOLD reader and the model builders name what fixes a refusal in Python, for Python users
(``pass unit_scale=<metres per unit>``, ``frame='creasePattern'``, ``lay_flat=True``). At the
command line each of those is an option in CLI units. :data:`TERMS` is the one map from the
first spelling to the second; :func:`cli_spelling` applies it to every library error, note
and log line of a FOLD file's ``check`` or ``run`` (a built-in case keeps its ``--set name=``
spelling, so the map is not applied there).
"""

from __future__ import annotations

import contextlib
import logging

from ._common import CLIError

__all__ = ["TERMS", "cli_terms", "cli_spelling"]

#: (Python spelling, CLI spelling), in the order applied: specific forms (with the value) first.
TERMS = (
    ("unit_scale=<metres per unit>", "--unit-scale METRES"),
    ("lay_flat=True", "--lay-flat"),
    ("lay_flat=False", "--no-lay-flat"),
    ("merge_collinear=False", "--keep-collinear"),
    ("frame='creasePattern'", "--frame creasePattern"),
    ("NewtonOptions(branch='other')", "--branch other"),
    ("NewtonOptions(branch='lower')", "--branch lower"),
    ("NewtonOptions.stability='check'", "--stability check"),
    ("crease_model='sharp'", "--crease-model sharp"),
    ("fold_stiffness=<N m/rad/m>", "--fold-stiffness N_M_PER_RAD_M"),
    ("panel_bending_width=<m>", "--panel-bending-width UM"),
    ("crease_width=<m>", "--crease-width UM"),
    ("crease_thickness=<m>", "--crease-thickness UM"),
    ("panel_thickness=<m>", "--panel-thickness UM"),
    ("(crease_width)", "(--crease-width UM, or the file's edges_etorigami:width where it has "
                       "them)"),
    ("SharpHingeParameters.panel_bending_width", "--panel-bending-width"),
    ("frame=", "--frame"),
    *((name, "--" + name.replace("_", "-")) for name in (
        "unit_scale", "lay_flat", "crease_model", "fold_stiffness", "panel_bending_width",
        "panel_mesh", "crease_width", "crease_thickness", "panel_thickness")),
)


def _word(ch: str) -> bool:
    return ch.isalnum() or ch == "_"


def _at(message: str, i: int, py: str) -> bool:
    """True if ``py`` stands at ``message[i]`` as a whole word (where it starts or ends with
    one: ``crease_width`` is not in ``my_crease_width``)."""
    if not message.startswith(py, i):
        return False
    before = i > 0 and _word(message[i - 1]) and _word(py[0])
    j = i + len(py)
    after = j < len(message) and _word(message[j]) and _word(py[-1])
    return not (before or after)


def cli_terms(message: str) -> str:
    """``message`` with every Python spelling of :data:`TERMS` replaced by its CLI option
    (the first term that stands at a place wins, so the specific forms go first)."""
    out, i = [], 0
    while i < len(message):
        hit = next(((py, cli) for py, cli in TERMS if _at(message, i, py)), None)
        out.append(message[i] if hit is None else hit[1])
        i += 1 if hit is None else len(hit[0])
    return "".join(out)


class _TermsFilter(logging.Filter):
    """Log lines in CLI spelling (the reader's warnings reach the terminal)."""

    def filter(self, record: logging.LogRecord) -> bool:
        record.msg, record.args = cli_terms(record.getMessage()), ()
        return True


@contextlib.contextmanager
def cli_spelling():
    """Within: library errors become one-line :class:`CLIError` in CLI spelling, and log
    lines are spelled so too."""
    from simulator import EtorigamiError

    handlers = logging.getLogger().handlers
    terms = _TermsFilter()
    for handler in handlers:
        handler.addFilter(terms)
    try:
        yield
    except EtorigamiError as exc:
        raise CLIError(cli_terms(str(exc))) from None
    finally:
        for handler in handlers:
            handler.removeFilter(terms)
