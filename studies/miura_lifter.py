"""Miura-ori lifter: how a substrate's thermal boundary reduces the lift (paper section 6.2).

Question
--------
A Miura-ori beam (4 x 2 cells of 1 mm panels, gold/SU-8 creases) is anchored at its left
end; heating all creases folds the pattern and lifts the free right end. On a substrate the
creases near the anchored end lose heat to it, run cooler and fold less. How much lower is
the lift, and how is the crease temperature distributed along the beam? And how much of it
is the paper's fitted chain heat loss: the calibration-free integral model, which the 3-D FE
supports (``device_heat_models``), runs beside it.

Method
------
``get_case("miura_lifter", cells_x=4, cells_y=2, substrate=s)`` for s = False / True: the
first column of panels is clamped (and the substrate panel, 100 um below the sheet, is fixed
and is a room-temperature thermal boundary); every crease ramps to 9 mW in 250 staggered
thermo-mechanical increments. The lift is measured as in ``tests/integration/test_cases.py``: the mean z
of the sheet's corner nodes at the largest x (the free right edge) minus its initial value.
The normalised power is the crease power over its final value (9 mW), as in the paper's
figure. ``--quick`` uses 30 increments. Both variants run with the case's chains (the
paper's) and with ``loss_model="integral"`` (:class:`~simulator.IntegralLoss` at its defaults,
over the substrate panel's plane).

Outputs (``results/miura_lifter/``)
-----------------------------------
``miura_lifter.csv``: one long table, the ``table`` column tells the row kind, ``variant``
is ``free`` (no substrate) or ``on substrate``, with ``, integral loss`` appended for the
integral model's runs (``loss_model`` is ``chain`` or ``integral``):

* ``sweep`` - one row per record (the initial state, then every heating increment):
  ``step``, ``power [mW]`` (per crease), ``power_normalised [-]``, ``lift [um]``.
* ``crease`` - the creases at the final power: ``crease`` (edge id), ``x [um]`` and
  ``y [um]`` (the crease's centre node in the flat sheet), ``clamped`` (both panels in the
  clamped first column), ``power [mW]``, ``fold_angle [deg]``, ``temperature [degC]``
  (actuation temperature), ``temperature_centre [degC]`` (centre-line mean: the measure of
  the 1.2 T_g limit), ``temperature_max [degC]`` (hottest crease node).
* ``nodes`` - final node positions ``x [um]``, ``y [um]``, ``z [um]`` and
  ``temperature [degC]`` (``step``, ``stage``, ``increment``, ``node``).

Figures: ``miura_lifter.png`` (lift vs power, normalised power on the top axis, and crease
temperature vs the crease's x position at the final power), ``miura_lifter_shapes.png``
(final 3-D shapes of every run, coloured by temperature).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from simulator.cases import get_case
from studies._common import node_frame, run_case, shape_from_frame, study_main

NAME = "miura_lifter"
CELLS = dict(cells_x=4, cells_y=2)
THERMAL_STEPS_QUICK = 30
VARIANTS = {"free": False, "on substrate": True}
#: Every run: label -> (substrate, heat-loss model).
RUNS = {"free": (False, "chain"), "on substrate": (True, "chain"),
        "free, integral loss": (False, "integral"),
        "on substrate, integral loss": (True, "integral")}
Z_STRETCH_SHARED = 2.0   # 3-D shapes: z drawn 2 x (the same in both panels)
POWER, TEMP, TEMP_MAX, LIFT = ("power [mW]", "temperature [degC]", "temperature_max [degC]",
                               "lift [um]")
TEMP_CL = "temperature_centre [degC]"
#: What the 3-D FE says of the two heat-loss models on this lifter (``device_heat_models``).
FE_VERDICT = ("the 3-D FE (level 1) supports the integral loss on this lifter on its "
              "substrate: crease temperature rise +0.4 to +1.7 % against it on the mesh's sheet, "
              "the chains' -48 to -59 % (device_heat_models, at the heated shapes); here on the "
              "sheet refined r = 2 (theory 4.11)")


def _params(substrate: bool, quick: bool = False, loss_model: str = "chain") -> dict:
    p = dict(CELLS, substrate=substrate, loss_model=loss_model)
    if quick:
        p["thermal_steps"] = THERMAL_STEPS_QUICK
    return p


def right_edge_nodes(case) -> np.ndarray:
    """Corner nodes of the sheet (not the substrate) at its largest x (the free end)."""
    mesh = case.model.mesh
    n_sheet = case.parameters["cells_x"] * case.parameters["cells_y"]
    sheet = (mesh.node_vertex >= 0) & (mesh.node_panel < n_sheet)
    return np.flatnonzero(sheet & np.isclose(mesh.nodes[:, 0], mesh.nodes[sheet, 0].max()))


def lift_um(case, result) -> np.ndarray:
    """(m,) lift of the free end [um] of every record: mean z of the right edge - initial."""
    right = right_edge_nodes(case)
    z = case.model.mesh.nodes[right, 2] + result.history["u"][:, right, 2]
    return 1e6 * (z.mean(axis=1) - z[0].mean())


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Heat the lifter with and without substrate, with each heat-loss model; see the module
    docstring."""
    parts = []
    for variant, (substrate, loss_model) in RUNS.items():
        case, res = run_case(NAME, _params(substrate, quick, loss_model), progress, variant)
        h, mesh = res.history, case.model.mesh
        power = h["power"].max(axis=1) * 1e3                 # all heated creases share it
        parts.append(pd.DataFrame({"table": "sweep", "variant": variant,
                                   "loss_model": loss_model,
                                   "step": np.arange(len(power)), "stage": h["stage_name"],
                                   POWER: power, "power_normalised [-]": power / power[-1],
                                   LIFT: lift_um(case, res)}))
        centre = mesh.nodes[mesh.crease_nodes[:, 6]] * 1e6
        parts.append(pd.DataFrame({
            "table": "crease", "variant": variant, "loss_model": loss_model,
            "crease": mesh.crease_ids,
            "x [um]": centre[:, 0], "y [um]": centre[:, 1],
            "clamped": _clamped_creases(mesh, range(CELLS["cells_y"])),
            POWER: h["power"][-1] * 1e3, "fold_angle [deg]": np.degrees(res.fold_angle[-1]),
            TEMP: res.crease_temperature[-1], TEMP_MAX: res.crease_temperature_max[-1],
            TEMP_CL: res.crease_temperature_centre_line[-1]}))
        parts.append(node_frame(res, -1, variant=variant, loss_model=loss_model))
    return pd.concat(parts, ignore_index=True)


def _clamped_creases(mesh, clamped_panels) -> np.ndarray:
    """True for creases whose two panels are both clamped (the case clamps the first column,
    panels 0 .. cells_y - 1)."""
    # the four corner slots of a crease (N11, N12, N21, N22) belong to its two panels
    corner_panels = mesh.node_panel[mesh.crease_nodes[:, :4]]
    return np.all(np.isin(corner_panels, list(clamped_panels)), axis=1)


def plot(df: pd.DataFrame) -> dict:
    """``{"miura_lifter": lift and crease temperatures, "miura_lifter_shapes": 3-D shapes}``."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.ticker import MaxNLocator

    from studies.plotting import environment_note, heat_loss_note, mark_temperature_limit, \
        nodal_range, note_assumptions, plot_shape, share_3d_scale

    sweep = df[df["table"] == "sweep"]
    creases = df[df["table"] == "crease"]
    fig = Figure(figsize=(14, 5.4), layout="constrained")
    ax_l, ax_t = fig.subplots(1, 2)
    styles = {"free": dict(color="C0"), "on substrate": dict(color="C1", ls="--"),
              "free, integral loss": dict(color="C2", ls="-."),
              "on substrate, integral loss": dict(color="C3", ls=":")}
    p_max = sweep[POWER].max()
    for variant, d in sweep.groupby("variant", sort=False):
        d = d.sort_values("step")
        ax_l.plot(d[POWER], d[LIFT], lw=2, label=f"{variant} (final {d[LIFT].iloc[-1]:.0f} um)",
                  **styles.get(variant, {}))
    ax_l.set_xlabel("power per crease [mW]")
    ax_l.set_ylabel("lift of the free end [um]")
    top = ax_l.secondary_xaxis("top", functions=(lambda p: p / p_max, lambda s: s * p_max))
    top.set_xlabel("normalised power [-]")
    ax_l.set_title("(a) lift vs heating power")
    ax_l.axhline(0, color="k", lw=0.8)
    low = sweep[LIFT].min()
    if low < 0:
        ax_l.text(0.02, 0.78, f"lift < 0 (end moves down) at low power,\ndown to {low:.2f} um",
                  transform=ax_l.transAxes, fontsize="small", color="C3")
    ax_l.legend(fontsize="small", loc="upper left")

    measured = []
    for variant, d in creases.groupby("variant", sort=False):
        clamped = d["clamped"].astype(bool)
        color = styles.get(variant, {}).get("color")
        measured += ax_t.plot(d.loc[~clamped, "x [um]"] / 1e3, d.loc[~clamped, TEMP_CL], "o",
                              ms=7, color=color, ls="", label=variant)
        measured += ax_t.plot(d.loc[clamped, "x [um]"] / 1e3, d.loc[clamped, TEMP_CL], "x",
                              ms=8, color=color, ls="")
        ax_t.plot(d["x [um]"] / 1e3, d[TEMP_MAX], "_", ms=10, color=color, ls="")
    ax_t.set_xlabel("crease position x [mm] (anchored end at x = 0)")
    ax_t.set_ylabel("crease temperature, centre line [°C]")
    ax_t.set_title(f"(b) crease temperatures at {p_max:.1f} mW per crease")
    mark_temperature_limit(ax_t, lines=measured)
    keys = [Line2D([], [], color="0.4", marker=m, ls="", ms=8, label=text) for m, text in
            (("o", "centre line"), ("x", "centre line, crease inside the clamped column"),
             ("_", "hottest node"))]
    handles, labels = ax_t.get_legend_handles_labels()
    ax_t.legend(handles + keys, labels + [k.get_label() for k in keys], fontsize="small",
                loc="upper left", bbox_to_anchor=(1.01, 1.0))
    for ax in (ax_l, ax_t):
        ax.grid(True, alpha=0.3)

    runs = [v for v in RUNS if (sweep["variant"] == v).any()]
    models = dict.fromkeys(RUNS[v][1] for v in runs)
    fig.suptitle("Miura lifter: the substrate's thermal boundary with the paper's chains and "
                 "with the calibration-free integral heat loss", fontsize="medium")
    note = environment_note("air", 0.026, 0, None, extra=[
        "no gravity", "first column of panels clamped",
        "substrate 100 um below (room-temperature boundary) in the 'on substrate' runs"])
    losses = [f"{m}: " + heat_loss_note(get_case(NAME, **_params(True, loss_model=m)).model)
              for m in models]
    note_assumptions(fig, note, *losses, FE_VERDICT)

    nodes = df[df["table"] == "nodes"]
    rows = 2 if len(runs) > 2 else 1
    shapes = Figure(figsize=(12.5, 5.0 * rows), layout="constrained")
    t_range = nodal_range(nodes[TEMP])          # one colour scale: the comparison is the point
    axes, points = [], []
    for k, variant in enumerate(runs):
        ax = shapes.add_subplot(rows, 2, k + 1, projection="3d")
        on_substrate = RUNS[variant][0]
        mesh = get_case(NAME, **_params(on_substrate)).model.mesh
        n_sheet = CELLS["cells_x"] * CELLS["cells_y"]
        plot_shape(shape_from_frame(nodes[nodes["variant"] == variant], mesh), ax=ax,
                   t_range=t_range, colorbar=k % 2 == 1,
                   panel_labels={"clamped": list(range(CELLS["cells_y"]))}
                   | ({"substrate": n_sheet} if on_substrate else {}))
        ax.collections[0].set_zsort("max")     # keeps the large substrate triangles behind
        axes.append(ax)
        points.append(nodes.loc[nodes["variant"] == variant,
                                ["x [um]", "y [um]", "z [um]"]].to_numpy(float) / 1e3)
        lift = sweep[sweep["variant"] == variant][LIFT].iloc[-1]
        ax.set_title(f"{variant}: lift {lift:.0f} um at {p_max:.1f} mW per crease")
        ax.zaxis.set_major_locator(MaxNLocator(4))
        ax.view_init(elev=25, azim=-60)
    scale = share_3d_scale(axes, points, Z_STRETCH_SHARED)
    shapes.suptitle(f"Miura lifter, final shapes ({scale})")
    note_assumptions(shapes, note, *losses, FE_VERDICT)
    return {NAME: fig, f"{NAME}_shapes": shapes}


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
