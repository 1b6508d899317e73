"""Figures and animations of simulation results.

Display units only live here: lengths in mm, angles in degrees, powers in mW and
temperatures in deg C (the simulator works in SI units and radians). Figures are built
with :class:`matplotlib.figure.Figure` (no pyplot, so no GUI backend is ever selected);
every function returns a figure or writes a file.
"""

from __future__ import annotations

import pathlib

import numpy as np
from matplotlib.animation import FuncAnimation, PillowWriter
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

__all__ = ["plot_shape", "plot_fold_vs_power", "plot_temperature_vs_power", "animate",
           "save_figure"]

CMAP = "plasma"
POWER, FOLD, TEMP, TEMP_MAX = ("power [mW]", "fold_angle [deg]", "temperature [degC]",
                               "temperature_max [degC]")
_T_LABEL = "temperature [°C]"


# ----------------------------------------------------------------------------- 3-D shape
def _temperature_norm(temperature) -> Normalize:
    """Colour limits of a temperature array, widened to at least 1 deg C."""
    lo, hi = float(np.min(temperature)), float(np.max(temperature))
    if hi - lo < 1.0:
        mid = (hi + lo) / 2
        lo, hi = mid - 0.5, mid + 0.5
    return Normalize(lo, hi)


def _set_limits(ax, points_mm) -> None:
    """Axis limits to the bounding box of ``points_mm`` (..., 3) with equal aspect."""
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


def _title(result, record: int) -> str:
    h = result.history
    return f"{h['stage_name'][record]}, increment {int(h['increment'][record])} (record {record})"


def _shape_axes(ax):
    if ax is None:
        fig = Figure(figsize=(6.4, 5.0), layout="constrained")
        ax = fig.add_subplot(projection="3d")
    elif getattr(ax, "name", None) != "3d":
        raise ValueError("plot_shape needs a 3-D axes (add_subplot(projection='3d')).")
    for axis in "xyz":
        getattr(ax, f"set_{axis}label")(f"{axis} [mm]")
    return ax.figure, ax


def plot_shape(result, record=-1, ax=None, color_by="temperature", show_reference=False) -> Figure:
    """Deformed shape of one record in 3-D, faces coloured by temperature.

    Parameters
    ----------
    result : SimulationResult
    record : int
        Record of ``result.history`` (0 = initial state, -1 = last).
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D, optional
        Axes to draw into; a new figure is created if omitted.
    color_by : {"temperature", None}
        Colour every triangle by the mean temperature of its nodes (with a colorbar in
        deg C), or draw panels grey and crease triangles orange.
    show_reference : bool
        Also draw the undeformed mesh as a dashed wireframe.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if color_by not in ("temperature", None):
        raise ValueError(f"color_by must be 'temperature' or None, got {color_by!r}.")
    h, mesh = result.history, result.model.mesh
    record = range(len(h["u"]))[record]  # IndexError for a bad record, negatives allowed
    fig, ax = _shape_axes(ax)
    x = (mesh.nodes + h["u"][record]) * 1e3
    coll = Poly3DCollection(x[mesh.triangles], edgecolors="0.2", linewidths=0.3)
    if color_by == "temperature":
        face_t = h["temperature"][record][mesh.triangles].mean(axis=1)
        coll.set(array=face_t, cmap=CMAP, norm=_temperature_norm(face_t))
        fig.colorbar(coll, ax=ax, shrink=0.7, label=_T_LABEL)
    else:
        coll.set_facecolor(np.where(mesh.triangle_panel[:, None] >= 0,
                                    (0.75, 0.78, 0.82, 1.0), (0.95, 0.55, 0.2, 1.0)))
    ax.add_collection3d(coll)
    points = [x]
    if show_reference:
        x0 = mesh.nodes * 1e3
        ax.add_collection3d(Poly3DCollection(x0[mesh.triangles], facecolors="none",
                                             edgecolors="0.5", linewidths=0.4, linestyles="--"))
        points.append(x0)
    _set_limits(ax, np.concatenate(points))
    ax.set_title(_title(result, record))
    return fig


# ----------------------------------------------------------------------------- curves
def _frame(frame_or_result, columns):
    """The long table of a result (or the given DataFrame), checked for ``columns``."""
    df = frame_or_result.to_frame() if hasattr(frame_or_result, "to_frame") else frame_or_result
    missing = [c for c in ("crease", *columns) if c not in df.columns]
    if missing:
        raise ValueError(f"table lacks column(s) {missing}; expected SimulationResult.to_frame().")
    return df.sort_values("step", kind="stable") if "step" in df.columns else df


def _crease_groups(df, creases):
    available = sorted(df["crease"].unique().tolist())
    creases = available if creases is None else [int(c) for c in np.atleast_1d(creases)]
    unknown = sorted(set(creases) - set(available))
    if unknown:
        raise ValueError(f"unknown crease(s) {unknown}; the table has {available}.")
    return [(c, df[df["crease"] == c]) for c in creases]


def _curve_axes(ax, ylabel):
    if ax is None:
        fig = Figure(figsize=(6.4, 4.4), layout="constrained")
        ax = fig.add_subplot()
    ax.set_xlabel("power [mW]")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    return ax.figure, ax


def plot_fold_vs_power(frame_or_result, creases=None, ax=None) -> Figure:
    """Fold angle [deg] against crease power [mW], one line per crease.

    Parameters
    ----------
    frame_or_result : pandas.DataFrame or SimulationResult
        The long table of :meth:`SimulationResult.to_frame` (also as read back from
        ``creases.csv``) or a result. Points are joined in record order.
    creases : int or sequence of int, optional
        Crease (edge) ids to plot; all by default.
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    df = _frame(frame_or_result, (POWER, FOLD))
    fig, ax = _curve_axes(ax, "fold angle [deg]")
    for c, d in _crease_groups(df, creases):
        ax.plot(d[POWER].to_numpy(), d[FOLD].to_numpy(), marker=".", label=f"crease {c}")
    ax.legend(fontsize="small")
    return fig


def plot_temperature_vs_power(frame_or_result, creases=None, ax=None) -> Figure:
    """Crease temperature (solid) and hottest crease node (dashed) [deg C] against power [mW].

    Parameters
    ----------
    frame_or_result : pandas.DataFrame or SimulationResult
        As for :func:`plot_fold_vs_power`.
    creases : int or sequence of int, optional
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    df = _frame(frame_or_result, (POWER, TEMP, TEMP_MAX))
    fig, ax = _curve_axes(ax, _T_LABEL)
    for c, d in _crease_groups(df, creases):
        (line,) = ax.plot(d[POWER].to_numpy(), d[TEMP].to_numpy(), "-", marker=".",
                          label=f"crease {c}")
        ax.plot(d[POWER].to_numpy(), d[TEMP_MAX].to_numpy(), "--", color=line.get_color(),
                label=f"crease {c} (max)")
    ax.legend(fontsize="small")
    return fig


# ----------------------------------------------------------------------------- files
def animate(result, path, every=1, fps=10) -> pathlib.Path:
    """Write a GIF of the deformed, temperature-coloured shape over the whole history.

    Colour limits and axis limits are fixed over the run (all temperatures, bounding box
    of all records), so frames are comparable.

    Parameters
    ----------
    result : SimulationResult
    path : str or pathlib.Path
        Output file (``.gif``); parent folders are created.
    every : int
        Use every ``every``-th record (the last record is always included).
    fps : float
        Frames per second.

    Returns
    -------
    pathlib.Path
    """
    if int(every) != every or every < 1:
        raise ValueError(f"every must be a positive integer, got {every!r}.")
    if not fps > 0:
        raise ValueError(f"fps must be positive, got {fps!r}.")
    h, mesh = result.history, result.model.mesh
    m = len(h["u"])
    frames = list(range(0, m, int(every)))
    if frames[-1] != m - 1:
        frames.append(m - 1)
    x_all = (mesh.nodes + h["u"]) * 1e3
    temp = h["temperature"][:, mesh.triangles].mean(axis=2)  # (m, nt) face temperatures

    fig, ax = _shape_axes(Figure(figsize=(6.4, 5.0), layout="constrained")
                          .add_subplot(projection="3d"))
    coll = Poly3DCollection(x_all[0][mesh.triangles], edgecolors="0.2", linewidths=0.3,
                            array=temp[0], cmap=CMAP, norm=_temperature_norm(temp))
    ax.add_collection3d(coll)
    fig.colorbar(coll, ax=ax, shrink=0.7, label=_T_LABEL)
    _set_limits(ax, x_all)

    def update(k):
        coll.set_verts(x_all[k][mesh.triangles])
        coll.set_array(temp[k])
        ax.set_title(_title(result, k))
        return (coll,)

    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    anim = FuncAnimation(fig, update, frames=frames, blit=False, repeat=False)
    anim.save(path, writer=PillowWriter(fps=fps))
    return path


def save_figure(fig, path, dpi=150) -> pathlib.Path:
    """Save a figure (PNG unless ``path`` has another suffix), creating the parent folder.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or pathlib.Path
    dpi : float

    Returns
    -------
    pathlib.Path
        The written file.
    """
    path = pathlib.Path(path)
    if not path.suffix:
        path = path.with_suffix(".png")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path
