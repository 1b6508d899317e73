"""What every study figure says about itself: its style (colour-blind-safe palette with line
styles), a footer with its assumptions, and a "full run" / "quick run" stamp.

The footer (bottom left) and the stamp (bottom right) live in a strip under the axes that a
constrained layout keeps free, so they never cover data. :mod:`studies.plotting` re-exports
these names.
"""

from __future__ import annotations

import contextlib
import textwrap

from cycler import cycler
from matplotlib.layout_engine import ConstrainedLayoutEngine

__all__ = ["PALETTE", "LINESTYLES", "figure_style", "environment_note", "note_assumptions",
           "heat_loss_note", "check_footer", "stamp_quick", "stamp_full", "QUICK_STAMP",
           "FULL_STAMP", "NO_HEAT"]

#: Colour-blind-safe colours (Okabe & Ito 2008), the default colour cycle of every study
#: figure (:func:`figure_style`); ``C0``... name them in this order.
PALETTE = ("#0072B2", "#E69F00", "#009E73", "#D55E00", "#CC79A7", "#56B4E9", "#000000",
           "#999999")
#: Line styles cycled with :data:`PALETTE`, so curves differ without colour too.
LINESTYLES = ("-", "--", "-.", ":", "-", "--", "-.", ":")


@contextlib.contextmanager
def figure_style():
    """Matplotlib settings of the study figures inside the block: the colour-blind-safe
    :data:`PALETTE` cycled with :data:`LINESTYLES`, legends on a white frame placed away from
    the data (``loc="best"``)."""
    import matplotlib

    with matplotlib.rc_context({"axes.prop_cycle": cycler(color=PALETTE)
                                + cycler(linestyle=LINESTYLES),
                                "legend.loc": "best", "legend.framealpha": 0.9}):
        yield


def environment_note(medium: str, k_env: float | None = None, residual_fold=None,
                     gravity=None, scenario: str | None = None, extra=()) -> str:
    """One line of a figure's assumptions: medium and k_env [W/(m K)], residual fold [deg],
    gravity factor, assumed scenario; ``extra`` strings appended."""
    parts = [f"environment: {medium}" + (f", k_env = {k_env:g} W/(m K)" if k_env else "")]
    if residual_fold is not None:
        parts.append(f"residual fold {residual_fold} deg" if isinstance(residual_fold, str)
                     else f"residual fold {residual_fold:g} deg")
    if gravity is not None:
        parts.append("no gravity" if gravity in (0, False) else f"gravity x {float(gravity):g}")
    if scenario:
        parts.append(f"assumed scenario: {scenario}")
    return "; ".join(parts + list(extra))


#: The footer line of a figure whose runs heat nothing (no heat-loss model in play).
NO_HEAT = "heat loss: none (nothing is heated)"


def heat_loss_note(thermal) -> str:
    """The footer line naming the heat-loss model, its settings, the medium and the
    substrate of a run: ``thermal.describe()`` of its
    :class:`~simulator.ThermalParameters` (or of a model, whose ``thermal`` it reads);
    :data:`NO_HEAT` for None."""
    mesh = getattr(thermal, "mesh", None)
    thermal = getattr(thermal, "thermal", thermal)
    if thermal is None:
        return NO_HEAT
    return thermal.describe(None if mesh is None else len(mesh.triangles))


_NOTE_GID, _STATUS_GID = "assumptions", "run-status"


def _reserve_bottom(fig, inches: float) -> None:
    """Keep a strip of ``inches`` under the axes free (constrained layout), at least as
    high as any strip reserved before."""
    engine = fig.get_layout_engine()
    if not isinstance(engine, ConstrainedLayoutEngine):
        return
    inches = max(inches, getattr(fig, "_etorigami_strip", 0.0))
    fig._etorigami_strip = inches
    strip = min(inches / fig.get_figheight(), 0.35)
    engine.set(rect=(0.0, strip, 1.0, 1.0 - strip))


def note_assumptions(fig, *lines: str) -> None:
    """State what a figure assumes in a footer under its axes (environment, residual fold,
    gravity factor, assumed scenario, missing reference data...): one call per figure,
    lines wrapped to the figure's width; the bottom-right corner stays free for the run
    status of :func:`save_figure`."""
    width = max(40, int(fig.get_figwidth() * 72 / 4.6) - 30)   # characters at 7 pt
    text = "\n".join(textwrap.fill(line, width) for line in lines if line)
    n = text.count("\n") + 1
    fig.text(0.005, 0.005, text, ha="left", va="bottom", fontsize=7, color="0.2",
             gid=_NOTE_GID, linespacing=1.25)
    _reserve_bottom(fig, 0.06 + n * 7 * 1.25 / 72 + 0.04)


def check_footer(fig, name: str = "figure") -> None:
    """Raise ValueError unless ``fig`` has a footer (:func:`note_assumptions`) that names its
    heat-loss model ("heat loss: ...", e.g. :func:`heat_loss_note`, or :data:`NO_HEAT`) and
    the medium ("medium" or "environment"; not needed with :data:`NO_HEAT`): every study
    figure says which physics made it."""
    text = " ".join(t.get_text() for t in fig.texts if t.get_gid() == _NOTE_GID)
    flat = " ".join(text.split()).lower()
    needed = (("the heat-loss model", ("heat loss:",)),) + (
        () if NO_HEAT in flat else (("the medium", ("medium", "environment")),))
    missing = [what for what, words in needed if not any(w in flat for w in words)]
    if missing:
        raise ValueError(f"{name}: its footer does not name {' and '.join(missing)} "
                         f"(footer: {text[:80]!r}); add heat_loss_note(model) to its "
                         "note_assumptions(...) call.")


#: Text of the stamp on the figures of a ``--quick`` study run (:func:`stamp_quick`).
QUICK_STAMP = "quick run: coarse settings,\nnot the published figure"
#: Text of the stamp on the figures of a full study run (:func:`save_figure`).
FULL_STAMP = "full run"
_STAMP_GID, _FULL_GID = "quick-stamp", "full-stamp"
_STAMP_HEIGHT = 0.32   # [inch] strip kept free for the stamp under the axes


def stamp_quick(fig) -> None:
    """Mark ``fig`` as the figure of a quick run: :data:`QUICK_STAMP` in its bottom-right
    corner, in a strip that a constrained layout keeps free of the axes (so the stamp never
    covers data; the bottom-left is the footer of :func:`note_assumptions`). Replaces a
    "full run" stamp; calling it again changes nothing."""
    if any(t.get_gid() == _STAMP_GID for t in fig.texts):
        return
    for t in [t for t in fig.texts if t.get_gid() == _FULL_GID]:
        t.remove()
    _reserve_bottom(fig, _STAMP_HEIGHT)
    fig.text(0.995, 0.005, QUICK_STAMP, ha="right", va="bottom", fontsize="x-small",
             color="darkred", fontweight="bold", gid=_STAMP_GID)


def stamp_full(fig) -> None:
    """Mark ``fig`` as the figure of a full run (bottom-right), unless it is stamped."""
    if any(t.get_gid() in (_STAMP_GID, _FULL_GID) for t in fig.texts):
        return
    _reserve_bottom(fig, 0.2)
    fig.text(0.995, 0.005, FULL_STAMP, ha="right", va="bottom", fontsize=7, color="0.35",
             gid=_FULL_GID)
