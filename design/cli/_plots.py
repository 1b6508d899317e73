"""Figures of the CLI (the only CLI module that imports matplotlib, inside its functions): the
demo's heating curve and natural mode shapes (:func:`simulator.natural_modes`).

Built without pyplot (no GUI backend is selected); lengths in mm, frequencies in Hz. A mode is
drawn as the state's shape (grey wireframe) plus the scaled mode shape, faces coloured by the
modal displacement magnitude (the colours of ``studies.plotting``).
"""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["demo_figure", "plot_mode_shape", "plot_modes", "save_mode_plots", "set_3d_limits"]


def demo_figure(table, threshold, what, physics: str = ""):
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
    physics : str
        The footer: the heat-loss model and medium
        (:meth:`~simulator.ThermalParameters.describe`).
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
    if physics:
        import textwrap

        fig.text(0.005, 0.005, textwrap.fill(physics, 110), ha="left", va="bottom", fontsize=6,
                 color="0.2")
        fig.get_layout_engine().set(rect=(0, 0.07, 1, 0.93))
    return fig


def set_3d_limits(ax, points_mm) -> None:
    """Axis limits of a 3-D axes to the bounding box of ``points_mm`` (..., 3) with equal
    aspect (also used by ``studies.plotting``)."""
    pts = np.asarray(points_mm).reshape(-1, 3)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = hi - lo
    span = np.maximum(span, 0.02 * span.max() if span.max() > 0 else 1.0)  # flat: keep z visible
    mid = (hi + lo) / 2
    lo, hi = mid - span / 2, mid + span / 2
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(span)


def _mode_title(modes, k: int) -> str:
    f = modes.frequency[k]
    tag = " (zero mode)" if modes.zero_mode[k] else ""
    return f"mode {k + 1}: {f:.4g} Hz{tag}"


def plot_mode_shape(modes, mode: int = 0, scale: float | None = None, ax=None) -> Figure:
    """One mode shape over the state it was computed about.

    Parameters
    ----------
    modes : ModesResult
    mode : int
        0-based mode index (negative counts from the last).
    scale : float, optional
        Largest drawn modal displacement as a fraction of the model size (default 0.1).
    ax : 3-D axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    k = range(modes.count)[mode]
    mesh = modes.model.mesh
    if ax is None:
        fig = Figure(figsize=(6.4, 5.0), layout="constrained")
        ax = fig.add_subplot(projection="3d")
    elif getattr(ax, "name", None) != "3d":
        raise ValueError("plot_mode_shape needs a 3-D axes (add_subplot(projection='3d')).")
    fig = ax.figure
    x0 = (mesh.nodes + modes.state.u) * 1e3
    phi = modes.shapes[k]
    peak = float(np.abs(phi).max()) or 1.0
    size = float(np.max(np.ptp(x0, axis=0)))
    x = x0 + phi * ((0.1 if scale is None else scale) * size / peak)
    amp = np.linalg.norm(phi, axis=1)[mesh.triangles].mean(axis=1) / peak
    coll = Poly3DCollection(x[mesh.triangles], edgecolors="0.2", linewidths=0.3)
    coll.set(array=amp, cmap="plasma", norm=Normalize(0, max(float(amp.max()), 1e-12)))
    ax.add_collection3d(coll)
    ax.add_collection3d(Poly3DCollection(x0[mesh.triangles], facecolors="none",
                                         edgecolors="0.6", linewidths=0.3, linestyles="--"))
    fig.colorbar(coll, ax=ax, shrink=0.6, label="modal displacement [-]")
    for axis in "xyz":
        getattr(ax, f"set_{axis}label")(f"{axis} [mm]")
    set_3d_limits(ax, np.concatenate([x, x0]))
    ax.set_title(_mode_title(modes, k))
    return fig


def plot_modes(modes, count: int = 6, scale: float | None = None) -> Figure:
    """The first ``count`` modes side by side (3 per row)."""
    from matplotlib.figure import Figure

    count = min(count, modes.count)
    cols = min(3, count)
    rows = -(-count // cols)
    fig = Figure(figsize=(4.2 * cols, 3.6 * rows), layout="constrained")
    for k in range(count):
        plot_mode_shape(modes, k, scale, fig.add_subplot(rows, cols, k + 1, projection="3d"))
    return fig


def save_mode_plots(modes, directory, count: int = 6, scale: float | None = None) -> list:
    """Write ``modes.png`` (overview) and ``mode_<k>.png`` for the first ``count`` modes;
    returns the written paths."""
    out = pathlib.Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    figures = {"modes.png": plot_modes(modes, count, scale)}
    figures.update({f"mode_{k + 1}.png": plot_mode_shape(modes, k, scale)
                    for k in range(min(count, modes.count))})
    for name, fig in figures.items():
        fig.savefig(out / name, dpi=150)
    return [out / name for name in figures]
