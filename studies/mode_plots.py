"""Figures of natural modes (:func:`simulator.natural_modes`).

Each mode is drawn as the state's shape (grey wireframe) plus the scaled mode shape, faces
coloured by the modal displacement magnitude; lengths in mm, frequencies in Hz. Like
:mod:`studies.plotting`, figures are built without pyplot.
"""

from __future__ import annotations

import pathlib

import numpy as np
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from .plotting import CMAP, _set_limits, save_figure

__all__ = ["plot_mode_shape", "plot_modes", "save_mode_plots"]


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
    coll.set(array=amp, cmap=CMAP, norm=Normalize(0, max(float(amp.max()), 1e-12)))
    ax.add_collection3d(coll)
    ax.add_collection3d(Poly3DCollection(x0[mesh.triangles], facecolors="none",
                                         edgecolors="0.6", linewidths=0.3, linestyles="--"))
    fig.colorbar(coll, ax=ax, shrink=0.6, label="modal displacement [-]")
    for axis in "xyz":
        getattr(ax, f"set_{axis}label")(f"{axis} [mm]")
    _set_limits(ax, np.concatenate([x, x0]))
    ax.set_title(_mode_title(modes, k))
    return fig


def plot_modes(modes, count: int = 6, scale: float | None = None) -> Figure:
    """The first ``count`` modes side by side (3 per row)."""
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
    paths = [save_figure(plot_modes(modes, count, scale), out / "modes.png")]
    for k in range(min(count, modes.count)):
        paths.append(save_figure(plot_mode_shape(modes, k, scale), out / f"mode_{k + 1}.png"))
    return paths
