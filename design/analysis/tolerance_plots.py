"""Figures of a sensitivity report (the only module of :mod:`design.analysis` that imports
matplotlib, inside its function): the tornado plot of which tolerance matters.

Built without pyplot (no GUI backend is selected); changes in the display units of the
report's table (deg, K, um).
"""

from __future__ import annotations

import math
import textwrap
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["plot_tornado"]

_HEAD, _TAIL = "d ", "] per tolerance"


def _effect_column(column: str) -> tuple | None:
    """``(output, unit)`` of a column ``d <output> [<unit>] per tolerance``, else None."""
    if not (column.startswith(_HEAD) and column.endswith(_TAIL)) or " [" not in column:
        return None
    output, _, unit = column[len(_HEAD):-len(_TAIL)].rpartition(" [")
    return output, unit


def plot_tornado(report, outputs=None, footer: str | None = None, mc_sigma: dict | None = None,
                 top: int | None = None) -> Figure:
    """Tornado plot: per output, the change of +1 and -1 sigma of each parameter's tolerance
    (first order), the largest at the top, with the first-order standard deviation of the
    output marked.

    Parameters
    ----------
    report : SensitivityReport or pandas.DataFrame
        The report, or its table (:meth:`SensitivityReport.to_frame`, e.g. read back from a
        CSV): ``parameter``, ``unit``, ``tolerance`` and ``d <output> [<unit>] per
        tolerance`` columns.
    outputs : sequence of str, optional
        The outputs to draw, one panel each (default: every output of the table).
    footer : str, optional
        The physics the report assumes (the heat-loss model and medium); default the
        report's ``physics`` (a table's ``attrs["physics"]``).
    mc_sigma : dict {output: float}, optional
        Standard deviations of a Monte Carlo run, in the table's units, marked beside the
        first-order ones.
    top : int, optional
        Draw only the ``top`` largest effects of each output.
    """
    from matplotlib.figure import Figure

    frame = report.to_frame() if hasattr(report, "to_frame") else report
    if footer is None:
        footer = getattr(report, "physics", None) or frame.attrs.get("physics", "")
    columns = {m[0]: (c, m[1]) for c in frame.columns if (m := _effect_column(str(c)))}
    outputs = list(columns) if outputs is None else list(outputs)
    unknown = [o for o in outputs if o not in columns]
    if unknown or not outputs:
        raise ValueError(f"outputs = {outputs!r}: the table has {list(columns)}.")
    fig = Figure(figsize=(4.6 * len(outputs) + 1.0, 0.9 + 0.32 * min(len(frame), top or
                                                                      len(frame)) + 1.4),
                 layout="constrained")
    axes = fig.subplots(1, len(outputs), squeeze=False)[0]
    for ax, o in zip(axes, outputs):
        column, unit = columns[o]
        _panel(ax, frame, column, o, unit, None if mc_sigma is None else mc_sigma.get(o),
               top)
    axes[0].legend(fontsize="small", loc="upper center", bbox_to_anchor=(0.5, -0.13),
                   ncol=2)
    fig.suptitle("first-order effect of each fabrication tolerance (+-1 sigma)")
    if footer:
        fig.text(0.005, 0.005, textwrap.fill(footer, int(22 * fig.get_figwidth())),
                 ha="left", va="bottom", fontsize=6.5, color="0.2")
        fig.get_layout_engine().set(rect=(0, 0.1, 1, 0.9))
    return fig


def _panel(ax, frame, column, output, unit, mc_sigma, top) -> None:
    """One output's bars, the largest effect at the top."""
    order = frame[column].abs().sort_values(ascending=False, kind="stable").index
    rows = frame.loc[order[:top] if top else order]
    effect = rows[column].to_numpy(float)
    y = range(len(rows))[::-1]
    labels = [_label(r) for _, r in rows.iterrows()]
    ax.barh(y, effect, color="C3", alpha=0.8, label="+1 sigma")
    ax.barh(y, -effect, color="C0", alpha=0.8, label="-1 sigma")
    ax.set_yticks(list(y), labels, fontsize="small")
    ax.axvline(0, color="k", lw=0.8)
    sigma = math.sqrt(float((frame[column].to_numpy(float) ** 2).sum()))
    title = f"{output}: FOSM sigma {sigma:.3g} {unit}"
    for s in (-sigma, sigma):
        ax.axvline(s, color="k", ls="--", lw=1, label="first-order (FOSM) +-sigma"
                   if s > 0 else None)
    if mc_sigma is not None:
        title += f"\nMonte Carlo sigma {mc_sigma:.3g} {unit}"
        for s in (-mc_sigma, mc_sigma):
            ax.axvline(s, color="C2", ls=":", lw=1.5, label="Monte Carlo +-sigma"
                       if s > 0 else None)
    reach = 1.08 * max([sigma, abs(mc_sigma or 0.0), *abs(effect)])
    ax.set_xlim(-reach, reach)
    ax.set_title(title, fontsize="small")
    ax.set_xlabel(f"change of {output} [{unit}]")
    ax.grid(True, axis="x", alpha=0.3)


def _label(row) -> str:
    """``power[5] +-0.24 mW``."""
    unit = row.get("unit", "")
    tol = row.get("tolerance")
    if tol is None or (isinstance(tol, float) and math.isnan(tol)):
        return str(row["parameter"])
    return f"{row['parameter']} +-{tol:.3g} {unit}"
