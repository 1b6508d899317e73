"""Figures of the CLI (the only CLI module that imports matplotlib)."""

from __future__ import annotations

__all__ = ["demo_figure"]


def demo_figure(table, threshold, what):
    """Fold angle and crease temperature vs power of the demo, the threshold marked.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`design.cli.simulate.heating_table` (``power [mW]``, ``fold_angle [deg]``,
        ``temperature [degC]``).
    threshold : float or None
        Threshold power [mW].
    what : str
        What the threshold marks (legend text).
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.2), layout="constrained")
    ax = fig.subplots()
    power = table["power [mW]"]
    ax.plot(power, table["fold_angle [deg]"], "C0.-", label="fold angle")
    ax.set_xlabel("crease power [mW]")
    ax.set_ylabel("fold angle [deg]", color="C0")
    ax.tick_params(axis="y", colors="C0")
    ax.grid(True, alpha=0.3)
    ax_t = ax.twinx()
    ax_t.plot(power, table["temperature [degC]"], "C3--", label="crease temperature")
    ax_t.set_ylabel("crease temperature [degC]", color="C3")
    ax_t.tick_params(axis="y", colors="C3")
    if threshold is not None:
        ax.axvline(threshold, color="k", lw=1, ls=":",
                   label=f"threshold {threshold:.1f} mW ({what})")
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax_t.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize="small", loc="upper left")
    ax.set_title("single crease on a substrate: heating until lift-off")
    return fig
