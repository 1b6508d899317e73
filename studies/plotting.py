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

from studies.figure_notes import (FULL_STAMP, LINESTYLES, NO_HEAT, PALETTE,  # noqa: F401
                                  QUICK_STAMP, check_footer, environment_note, figure_style,
                                  heat_loss_note, note_assumptions, stamp_full, stamp_quick)

from design.cli._plots import set_3d_limits      # shared with the CLI's mode-shape figures
from design.devices.limits import SU8_LIMIT
from simulator.thermal import crease_limit_temperatures

__all__ = ["plot_shape", "plot_fold_vs_power", "plot_temperature_vs_power", "animate",
           "save_figure", "stamp_quick", "QUICK_STAMP", "mark_temperature_limit", "nodal_range",
           "T_LIMIT", "T_MEASURE", "PALETTE", "LINESTYLES", "figure_style", "note_assumptions",
           "environment_note", "heat_loss_note", "NO_HEAT", "GRIPPER_HEAT_LOSS", "centre_line_temperatures", "share_3d_scale", "label_points",
           "panel_centres"]

#: The footer line of the gripper studies' heat loss (``GripperDesign``'s default chain
#: model, whose t_env follows the design's arms).
GRIPPER_HEAT_LOSS = ("heat loss: chain model (the paper's; t_env = 1.5 x the mean arm length "
                     "(L1 + L2) / 2, 10 layers, beta = 20 deg); medium: air; t_env capped at "
                     "the substrate panel (5); sheet conduction T3")

CMAP = "plasma"
POWER, FOLD, TEMP, TEMP_MAX = ("power [mW]", "fold_angle [deg]", "temperature [degC]",
                               "temperature_max [degC]")
_T_LABEL = "temperature [°C]"
#: The paper's crease temperature limit, 1.2 T_g of SU-8 [deg C] (252 deg C): above it the
#: polymer softens. Every plot showing temperature marks values above it
#: (:data:`design.devices.limits.SU8_LIMIT`, judged on the crease centre-line mean).
T_LIMIT = SU8_LIMIT.value
_LIMIT_LABEL = f"above 1.2 T_g = {T_LIMIT:.0f} °C"
_FACE_LABEL = "temperature [°C] (facet: its hottest node)"
#: The one temperature the 1.2 T_g limit is checked on, in the design problems and in every
#: figure (theory 5.4): the mean of a crease's three
#: centre-line nodes (A, B, Ctr), the reference's measure; the hottest crease's value counts.
#: The hottest node is shown beside it where the two differ.
T_MEASURE = "centre-line mean of the hottest crease"



def centre_line_temperatures(temperature, mesh) -> np.ndarray:
    """Per crease the :data:`T_MEASURE` temperature [deg C]: mean of its centre-line nodes.

    Parameters
    ----------
    temperature : array (n_nodes,) or (m, n_nodes)
        Nodal temperatures [deg C].
    mesh : BarHingeMesh
        Its ``crease_nodes`` (C, 7) lists N11, N12, N21, N22, A, B, Ctr.

    Returns
    -------
    ndarray (C,) or (m, C)
    """
    t = np.asarray(temperature, float)
    return crease_limit_temperatures(t.T, mesh).T


def share_3d_scale(axes, points, z_stretch: float = 1.0) -> str:
    """Give side-by-side 3-D panels one length scale: every axis of every panel spans the
    largest extent over the panels (centred on its own points), z stretched by ``z_stretch``.

    Parameters
    ----------
    axes : sequence of 3-D axes
    points : sequence of arrays (..., 3) [mm], one per panel
    z_stretch : float
        Drawn height per unit of length, relative to x and y (1: true shape).

    Returns
    -------
    str
        What a caption should say ("true scale" or "z stretched 3x, same in every panel").
    """
    pts = [np.asarray(p, float).reshape(-1, 3) for p in points]
    span = np.max([p.max(axis=0) - p.min(axis=0) for p in pts], axis=0)
    span = np.maximum(span, 0.02 * span.max())
    for ax, p in zip(axes, pts):
        mid = (p.max(axis=0) + p.min(axis=0)) / 2
        ax.set_xlim(mid[0] - span[0] / 2, mid[0] + span[0] / 2)
        ax.set_ylim(mid[1] - span[1] / 2, mid[1] + span[1] / 2)
        ax.set_zlim(mid[2] - span[2] / 2, mid[2] + span[2] / 2)
        ax.set_box_aspect((span[0], span[1], span[2] * z_stretch))
    if z_stretch == 1:
        return "all panels at one true scale"
    return f"all panels at one scale, z stretched {z_stretch:g}x"


def label_points(ax, labels: dict, color="k") -> None:
    """Write ``{text: (x, y, z) [mm]}`` labels into a 3-D axes, in front of the facets."""
    ax.computed_zorder = False
    for text, (x, y, z) in labels.items():
        ax.text(x, y, z, text, fontsize="small", color=color, ha="center", va="bottom",
                zorder=20, bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none",
                                     alpha=0.75))


def panel_centres(mesh, x_mm, panels: dict) -> dict:
    """``{name: centre [mm]}`` of named panels ``{name: panel id or ids}`` at positions
    ``x_mm`` (n_nodes, 3): the mean of their triangles' nodes."""
    out = {}
    for name, ids in panels.items():
        nodes = np.unique(mesh.triangles[np.isin(mesh.triangle_panel, np.atleast_1d(ids))])
        out[name] = x_mm[nodes].mean(axis=0)
    return out


def nodal_range(*temperatures) -> tuple:
    """(lowest, highest) nodal temperature [deg C] over arrays: a shared colour scale."""
    return (min(float(np.min(t)) for t in temperatures),
            max(float(np.max(t)) for t in temperatures))


def _temperature_norm(temperature) -> Normalize:
    """Colour limits of a temperature array (or a (lo, hi) range), widened to at least 1 deg C."""
    lo, hi = float(np.min(temperature)), float(np.max(temperature))
    if hi - lo < 1.0:
        mid = (hi + lo) / 2
        lo, hi = mid - 0.5, mid + 0.5
    return Normalize(lo, hi)


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


def _temperature_colorbar(fig, ax, mappable, shrink=0.7):
    """Colour bar in deg C with a dashed line at 1.2 T_g when the scale reaches it."""
    bar = fig.colorbar(mappable, ax=ax, shrink=shrink, label=_FACE_LABEL)
    lo, hi = mappable.norm.vmin, mappable.norm.vmax
    if lo <= T_LIMIT <= hi:
        bar.ax.axhline(T_LIMIT, color="k", ls="--", lw=1.2)
        bar.ax.text(1.05, T_LIMIT, "1.2 T_g", transform=bar.ax.get_yaxis_transform(),
                    va="bottom", fontsize="x-small")
    return bar


def _mark_hot_creases(ax, x_mm, temperature, mesh) -> int:
    """Circle the creases whose :data:`T_MEASURE` temperature is above 1.2 T_g (at their
    centre node) in a 3-D axes and state the verdict (the hottest crease's centre-line mean
    against the limit) with the hottest node as information; returns how many creases are
    above."""
    t = np.asarray(temperature, float)
    if not len(mesh.crease_nodes):
        return 0
    centre = centre_line_temperatures(t, mesh)
    hot = centre > T_LIMIT
    v = SU8_LIMIT.judge(t, mesh)
    text = (f"crease {v.crease}: centre-line mean {v.temperature:.0f} °C "
            f"{'≤' if v.success else '>'} 1.2 T_g = {T_LIMIT:.0f} °C; hottest node "
            f"{v.hottest_node:.0f} °C (information)")
    if hot.any():
        p = x_mm[np.asarray(mesh.crease_nodes)[hot, 6]]
        ax.computed_zorder = False          # the circles stay in front of the facets
        ax.scatter(p[:, 0], p[:, 1], p[:, 2], s=140, facecolors="none", edgecolors="c",
                   linewidths=2.0, depthshade=False, zorder=10)
        n = int(hot.sum())
        text += f"\n{n} crease{'s' if n > 1 else ''} {_LIMIT_LABEL} (cyan circles)"
    ax.text2D(0.0, 1.0, text, transform=ax.transAxes, fontsize="x-small", va="top",
              color="teal" if hot.any() else "0.25")
    return int(hot.sum())


def plot_shape(result, record=-1, ax=None, color_by="temperature", show_reference=False,
               t_range=None, colorbar=True, hide_panels=(), panel_labels=None) -> Figure:
    """Deformed shape of one record in 3-D, faces coloured by temperature.

    Parameters
    ----------
    result : SimulationResult
    record : int
        Record of ``result.history`` (0 = initial state, -1 = last).
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D, optional
        Axes to draw into; a new figure is created if omitted.
    color_by : {"temperature", None}
        Colour every triangle by the temperature of its hottest node [deg C], on a scale that
        spans the nodal range (so the colour bar reaches the hottest node), with a colour
        bar; creases whose centre-line mean (:data:`T_MEASURE`) is above 1.2 T_g
        (:data:`T_LIMIT`) are circled, and the hottest crease and node are stated. ``None``: panels grey and
        crease triangles orange.
    show_reference : bool
        Also draw the undeformed mesh as a dashed wireframe.
    t_range : (float, float), optional
        Colour scale (lowest, highest) [deg C], e.g. :func:`nodal_range` of several shapes
        drawn side by side; default the record's nodal range.
    colorbar : bool
        Draw the colour bar (leave it out on all but one of several panels sharing a scale).
    hide_panels : sequence of int
        Panels not drawn (e.g. a large substrate that would dwarf the structure); the axis
        limits then follow the drawn triangles.
    panel_labels : dict, optional
        ``{text: panel id or ids}``: names written at the panels' centres (base, arm, ...).

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
    tri = mesh.triangles[~np.isin(mesh.triangle_panel, list(hide_panels))]
    coll = Poly3DCollection(x[tri], edgecolors="0.2", linewidths=0.3)
    if color_by == "temperature":
        t = np.asarray(h["temperature"][record], float)
        coll.set(array=t[tri].max(axis=1), cmap=CMAP,
                 norm=_temperature_norm(t if t_range is None else t_range))
        if colorbar:
            _temperature_colorbar(fig, ax, coll)
    else:
        coll.set_facecolor(np.where(mesh.triangle_panel[~np.isin(mesh.triangle_panel,
                                                                 list(hide_panels)), None] >= 0,
                                    (0.75, 0.78, 0.82, 1.0), (0.95, 0.55, 0.2, 1.0)))
    ax.add_collection3d(coll)
    if color_by == "temperature":
        _mark_hot_creases(ax, x, t, mesh)
    points = [x[np.unique(tri)]]
    if show_reference:
        x0 = mesh.nodes * 1e3
        ax.add_collection3d(Poly3DCollection(x0[mesh.triangles], facecolors="none",
                                             edgecolors="0.5", linewidths=0.4, linestyles="--"))
        points.append(x0)
    set_3d_limits(ax, np.concatenate(points))
    if panel_labels:
        label_points(ax, panel_centres(mesh, x, panel_labels))
    ax.set_title(_title(result, record))
    return fig


def mark_temperature_limit(ax, limit=T_LIMIT, axis="y", lines=None) -> int:
    """Mark temperatures above 1.2 T_g on a 2-D plot whose ``axis`` is a temperature [deg C].

    Draws a dotted red line at ``limit`` when the plotted values reach 80 % of it, rings every
    plotted point above it in red, outlines bars above it in red, and adds both to the
    legend (if the axes has one). Call it after plotting. ``lines``: the curves of the
    limit's measure (:data:`T_MEASURE`) whose points are ringed; default every line (give
    them when the axes also shows another measure, e.g. the hottest node).

    Returns
    -------
    int
        Number of plotted points and bars above the limit.
    """
    k = 1 if axis == "y" else 0
    values, hot = [], []
    for line in ax.get_lines() if lines is None else lines:
        xy = np.column_stack([np.asarray(line.get_xdata(), float),
                              np.asarray(line.get_ydata(), float)])
        if line.get_transform() != ax.transData or len(xy) == 0:
            continue
        values.append(xy[:, k])
        hot.append(xy[xy[:, k] > limit])
    n_bars = 0
    for patch in ax.patches:
        top = patch.get_y() + patch.get_height() if axis == "y" else patch.get_x() + patch.get_width()
        values.append(np.array([top]))
        if top > limit:
            patch.set_edgecolor("r")
            patch.set_linewidth(1.5)
            n_bars += 1
    vals = np.concatenate(values) if values else np.array([])
    vals = vals[np.isfinite(vals)]
    if not len(vals) or vals.max() < 0.8 * limit:
        return 0
    line_fn = ax.axhline if axis == "y" else ax.axvline
    handles = [line_fn(limit, color="r", ls=":", lw=1.2, label=f"1.2 T_g = {limit:.0f} °C")]
    pts = np.concatenate(hot) if hot else np.empty((0, 2))
    if len(pts):
        handles += ax.plot(pts[:, 0], pts[:, 1], "o", ms=6, mfc="none", mec="r", mew=1.2,
                           label=_LIMIT_LABEL)
    legend = ax.get_legend()
    if legend is not None:
        old = list(legend.legend_handles)
        ax.legend(old + handles, [t.get_text() for t in legend.texts]
                  + [h.get_label() for h in handles], fontsize="small")
    return len(pts) + n_bars


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
    mark_temperature_limit(ax)
    return fig


# ----------------------------------------------------------------------------- files
def animate(result, path, every=1, fps=10, quick=False) -> pathlib.Path:
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
    quick : bool
        The result comes from a ``--quick`` run: stamp every frame (:func:`stamp_quick`).

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
    temp = h["temperature"][:, mesh.triangles].max(axis=2)  # (m, nt) hottest node per face

    fig, ax = _shape_axes(Figure(figsize=(6.4, 5.0), layout="constrained")
                          .add_subplot(projection="3d"))
    coll = Poly3DCollection(x_all[0][mesh.triangles], edgecolors="0.2", linewidths=0.3,
                            array=temp[0], cmap=CMAP, norm=_temperature_norm(h["temperature"]))
    ax.add_collection3d(coll)
    _temperature_colorbar(fig, ax, coll)
    set_3d_limits(ax, x_all)
    if quick:
        stamp_quick(fig)

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


def save_figure(fig, path, dpi=150, quick=False) -> pathlib.Path:
    """Save a figure (PNG unless ``path`` has another suffix), creating the parent folder.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or pathlib.Path
    dpi : float
    quick : bool
        The figure comes from a ``--quick`` run: stamp it as such (:func:`stamp_quick`);
        otherwise it is stamped "full run".

    Returns
    -------
    pathlib.Path
        The written file.
    """
    path = pathlib.Path(path)
    if not path.suffix:
        path = path.with_suffix(".png")
    check_footer(fig, path.name)
    path.parent.mkdir(parents=True, exist_ok=True)
    if quick:
        stamp_quick(fig)
    else:
        stamp_full(fig)
    fig.savefig(path, dpi=dpi)
    return path
