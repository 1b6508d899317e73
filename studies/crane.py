"""Origami crane: folding with all creases active and with two creases deactivated (paper 6.1).

Question
--------
The crane pattern (14 panels, 17 electro-thermal creases of gold on SU-8, no gravity or
substrate) folds when all creases are heated at once. Real fabrication may leave some creases
passive: with creases 8 and 17 (reference numbering) unheated and half power on creases 9 and
11, does the crane still fold, thanks to its one-degree-of-freedom centre pattern, and by how
much less?

Method
------
``get_case("crane", deactivated=d)`` for d = False / True (reference Example04, theory 10.4):
every crease gets a multiple of the base power q (q, 1.5 q, 2 q, 4 q or q / 2 depending on
the crease) ramped to q = 4 mW in 500 staggered thermo-mechanical increments. The base power
``base_power [mW]`` of a record is the power of reference crease 6 (which gets q in both
variants). ``--quick`` uses 30 increments.

Heat loss: the case's chains (beta = 20 deg, t_env = 1 mm, the reference's t2RT = a), for
which the reference chose its 4 mW. The integral model (nothing fitted, theory 4.7) and the 3-D
FE put the flat crane's crease temperature rises at that power at 3.4-10.2 times the chains'
(``studies.heat_transfer_models``, flat crane); ``get_case("crane", loss_model="integral")``
runs the crane at 0.7 mW instead, where it folds as far as in this study's first run;
the study's third run does that (all creases active).

Crease ids: ``crease`` is our edge id (0-based), ``crease_ref`` = edge id + 1 is the
reference (and paper) numbering. Fold angles are signed (0 flat, positive = valley towards
+z, negative = mountain).

Outputs (``results/crane/``)
----------------------------
``crane.csv``: one long table, the ``table`` column tells the row kind, ``variant`` is
``all active`` or ``8 and 17 deactivated`` (the case's chains, q = 4 mW) or ``all active,
integral heat loss`` (q = 0.7 mW), ``loss_model`` its heat loss (``chain``, ``integral``):

* ``crease`` - the 17 creases at the end of heating: ``crease``, ``crease_ref``, ``heated``
  (final power > 0), ``power [mW]``, ``fold_angle [deg]``, ``temperature [degC]``
  (actuation temperature), ``temperature_centre [degC]`` (centre-line mean, the measure of
  the 1.2 T_g limit), ``temperature_max [degC]``.
* ``sweep`` - every crease, every record (every 5th in the full run, plus the last):
  ``crease``, ``crease_ref``, ``step``, ``base_power [mW]``, ``power [mW]``,
  ``fold_angle [deg]``, ``temperature [degC]``, ``temperature_centre [degC]``.
* ``nodes`` - final node positions ``x [um]``, ``y [um]``, ``z [um]`` and
  ``temperature [degC]`` (``step``, ``stage``, ``increment``, ``node``).

Figures: ``crane.png`` (fold angle and temperature vs base power for representative creases:
1 (4 q), 6 (q), 9 (q, or q / 2 when deactivated), and the deactivated 8 and 17),
``crane_creases.png`` (final fold and temperature of every crease, both variants),
``crane_shapes.png`` (the two final 3-D shapes side by side, coloured by temperature) and
``crane_heat_models.png`` (power, fold and temperature of every crease, all active, with the
chain and the integral heat loss).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from simulator.cases import get_case
from studies._common import node_frame, run_case, shape_from_frame, study_main

NAME = "crane"
THERMAL_STEPS_QUICK = 30
VARIANTS = {"all active": False, "8 and 17 deactivated": True}
#: The third run: all creases active with the integral heat loss (its case power, 0.7 mW).
INTEGRAL = "all active, integral heat loss"
#: Figure labels of the runs: the deactivated run (like the reference Example04) also
#: halves the power of creases 9 and 11, which the figures must say.
LABELS = {"all active": "all 17 creases heated",
          "8 and 17 deactivated": "8, 17 unheated; 9, 11 at half power",
          INTEGRAL: "all 17 heated, integral heat loss"}
REPRESENTATIVE = (1, 6, 9, 8, 17)       # reference ids
BASE_CREASE_REF = 6                     # gets exactly q in both variants
SWEEP_EVERY = 5                         # full run: keep every 5th record in the sweep rows
POWER, FOLD, TEMP, TEMP_MAX = ("power [mW]", "fold_angle [deg]", "temperature [degC]",
                               "temperature_max [degC]")
TEMP_CL = "temperature_centre [degC]"
#: Creases (reference numbers) left unheated, and halved, in the second run.
DEACTIVATED_REF, HALVED_REF = (8, 17), (9, 11)


def _params(deactivated: bool, quick: bool = False, loss_model: str = "chain") -> dict:
    return dict(deactivated=deactivated, loss_model=loss_model,
                **({"thermal_steps": THERMAL_STEPS_QUICK} if quick else {}))


#: The runs: (variant, deactivated, loss model)
RUNS = tuple((v, d, "chain") for v, d in VARIANTS.items()) + ((INTEGRAL, False, "integral"),)


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Fold the crane with all creases and with two creases deactivated (the case's chain
    heat loss at 4 mW), and with all creases and the integral heat loss (0.7 mW)."""
    parts = []
    for variant, deactivated, loss_model in RUNS:
        case, res = run_case(NAME, _params(deactivated, quick, loss_model), progress, variant)
        h, mesh = res.history, case.model.mesh
        ids = mesh.crease_ids
        C = len(ids)
        power = h["power"] * 1e3
        parts.append(pd.DataFrame({
            "table": "crease", "variant": variant, "loss_model": loss_model,
            "crease": ids, "crease_ref": ids + 1,
            "heated": power[-1] > 0, POWER: power[-1],
            FOLD: np.degrees(res.fold_angle[-1]), TEMP: res.crease_temperature[-1],
            TEMP_MAX: res.crease_temperature_max[-1],
            TEMP_CL: res.crease_temperature_centre_line[-1]}))
        m = len(power)
        recs = np.arange(0, m, 1 if quick else SWEEP_EVERY)
        if recs[-1] != m - 1:
            recs = np.r_[recs, m - 1]
        base = power[recs, mesh.crease_row_of(BASE_CREASE_REF - 1)]
        parts.append(pd.DataFrame({
            "table": "sweep", "variant": variant, "loss_model": loss_model,
            "crease": np.tile(ids, len(recs)), "crease_ref": np.tile(ids + 1, len(recs)),
            "step": np.repeat(recs, C), "base_power [mW]": np.repeat(base, C),
            POWER: power[recs].ravel(), FOLD: np.degrees(res.fold_angle[recs]).ravel(),
            TEMP: res.crease_temperature[recs].ravel(),
            TEMP_CL: res.crease_temperature_centre_line[recs].ravel()}))
        parts.append(node_frame(res, -1, variant=variant, loss_model=loss_model))
    return pd.concat(parts, ignore_index=True)


def plot(df: pd.DataFrame) -> dict:
    """Curves, per-crease bars and the two final shapes of the chain runs (``crane``,
    ``crane_creases``, ``crane_shapes``); both heat-loss models per crease
    (``crane_heat_models``)."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.ticker import MaxNLocator

    from studies.plotting import environment_note, heat_loss_note, label_points, \
        mark_temperature_limit, nodal_range, note_assumptions, plot_shape, share_3d_scale

    variants = list(VARIANTS)
    all_creases = df[df["table"] == "crease"]
    df = df[df["variant"].isin(variants)]            # the case's chains, the reference's 4 mW
    dashes = {variants[0]: "-", variants[1]: "--"}
    sweep = df[df["table"] == "sweep"].sort_values("step", kind="stable")
    fig = Figure(figsize=(11.5, 4.8), layout="constrained")
    ax_f, ax_t = fig.subplots(1, 2)
    for k, ref in enumerate(REPRESENTATIVE):
        for variant in variants:
            d = sweep[(sweep["crease_ref"] == ref) & (sweep["variant"] == variant)]
            for ax, col in ((ax_f, FOLD), (ax_t, TEMP_CL)):
                ax.plot(d["base_power [mW]"], d[col], dashes[variant], color=f"C{k}")
    handles = [Line2D([], [], color=f"C{k}", label=f"crease {ref}")
               for k, ref in enumerate(REPRESENTATIVE)]
    handles += [Line2D([], [], color="0.3", ls=dashes[v], label=LABELS[v]) for v in variants]
    ax_f.legend(handles=handles, fontsize="small", ncols=2, loc="upper left")
    ax_f.set_ylabel("fold angle [deg] (+ valley, - mountain)")
    ax_f.set_title("(a) fold angles (reference crease numbers)")
    ax_t.set_ylabel("crease temperature, centre line [°C]")
    ax_t.set_title("(b) crease temperatures")
    for ax in (ax_f, ax_t):
        ax.set_xlabel("base power q [mW] (crease power = 0.5 q ... 4 q)")
        ax.grid(True, alpha=0.3)
    mark_temperature_limit(ax_t)
    fig.suptitle("Crane: crease 9 gets q when all are heated but q / 2 in the second run (as in "
                 "the reference script), so its lower fold there is not only the deactivation's "
                 "effect", fontsize="medium")

    creases = df[df["table"] == "crease"]
    bars = _bars(creases, variants, "(9 and 11 halved in the second run)")
    note = environment_note("air", 0.026, 0, 0, extra=[
        heat_loss_note(get_case(NAME).model) + " (the reference's; crane_heat_models shows "
        "the calibration-free integral loss beside them)"])
    for f in (fig, bars):
        note_assumptions(f, note)
    figs = {NAME: fig, f"{NAME}_creases": bars}
    if (all_creases["variant"] == INTEGRAL).any():
        models = _bars(all_creases, ["all active", INTEGRAL], "",
                       {"all active": "chain heat loss (the case's)",
                        INTEGRAL: "integral heat loss"})
        models.suptitle("Crane, all creases heated: the integral heat loss folds it as far on "
                        "average at 0.7 mW as the case's chains at 4 mW", fontsize="medium")
        note_assumptions(models, environment_note("air", 0.026, 0, 0), "chain: "
                         + heat_loss_note(get_case(NAME).model) + " (the reference's)",
                         "integral: " + heat_loss_note(get_case(NAME, loss_model="integral").model)
                         + "; nothing fitted (theory 4.7), within 0.2 % of the 3-D FE in crease "
                         "temperature on the flat crane (heat_transfer_models)")
        figs[f"{NAME}_heat_models"] = models

    nodes = df[df["table"] == "nodes"]
    q = sweep["base_power [mW]"].max()
    shapes = Figure(figsize=(12.5, 5.6), layout="constrained")
    t_range = nodal_range(nodes[TEMP])             # one colour scale for both shapes
    axes, points = [], []
    for k, variant in enumerate(variants):
        ax = shapes.add_subplot(1, 2, k + 1, projection="3d")
        mesh = get_case(NAME, **_params(VARIANTS[variant])).model.mesh
        d = nodes[nodes["variant"] == variant]
        plot_shape(shape_from_frame(d, mesh), ax=ax, t_range=t_range,
                   colorbar=k == len(variants) - 1)
        x = d.sort_values("node")[["x [um]", "y [um]", "z [um]"]].to_numpy(float) / 1e3
        if VARIANTS[variant]:
            label_points(ax, {**{f"{r} off": x[mesh.crease_nodes[mesh.crease_row_of(r - 1), 6]]
                                 for r in DEACTIVATED_REF},
                              **{f"{r}: q/2": x[mesh.crease_nodes[mesh.crease_row_of(r - 1), 6]]
                                 for r in HALVED_REF}}, color="#D55E00")
        axes.append(ax)
        points.append(x)
        ax.set_title(f"{LABELS[variant]}\n(q = {q:.1f} mW)")
        for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
            axis.set_major_locator(MaxNLocator(5))
        ax.view_init(elev=30, azim=-60)
    scale = share_3d_scale(axes, points)
    shapes.suptitle(f"Crane, final shapes ({scale}; labels: reference crease numbers of the "
                    "deactivated and halved creases)", fontsize="medium")
    note_assumptions(shapes, note)
    return {**figs, f"{NAME}_shapes": shapes}


def _bars(creases, variants, halved, labels=None):
    """Final crease power, fold angle and centre-line temperature per crease (bars per
    variant, labelled by ``labels`` or :data:`LABELS`; hatched: unheated)."""
    from matplotlib.figure import Figure

    from studies.plotting import mark_temperature_limit

    bars = Figure(figsize=(11.5, 8.2), layout="constrained")
    ax_p, ax_b, ax_bt = bars.subplots(3, 1, sharex=True)
    refs = np.sort(creases["crease_ref"].unique())
    pos = np.arange(len(refs))
    for k, variant in enumerate(variants):
        d = creases[creases["variant"] == variant].set_index("crease_ref").loc[refs]
        heated = d["heated"].astype(bool).to_numpy()
        for ax, col in ((ax_p, POWER), (ax_b, FOLD), (ax_bt, TEMP_CL)):
            b = ax.bar(pos + (k - 0.5) * 0.4, d[col], width=0.4, color=f"C{k}",
                       label=(labels or LABELS)[variant])
            for patch, h in zip(b, heated):
                if not h:
                    patch.set_hatch("//")
                    patch.set_edgecolor("k")
    q = " and ".join(dict.fromkeys(f"{creases.loc[creases['variant'] == v, POWER].max() / 4:.3g}"
                                   for v in variants))
    ax_p.set_ylabel("final crease power [mW]")
    ax_p.set_title(f"(a) heating at q = {q} mW: crease powers {halved}".rstrip())
    ax_p.legend(fontsize="small", title="hatched: unheated crease", title_fontsize="small",
                loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax_b.set_ylabel("final fold angle [deg]")
    ax_b.set_title("(b) fold angles")
    ax_b.axhline(0, color="k", lw=0.8)
    ax_bt.set_ylabel("final crease temperature,\ncentre line [°C]")
    ax_bt.set_xlabel("crease (reference numbering)")
    ax_bt.set_title("(c) crease temperatures")
    ax_bt.set_xticks(pos, [str(int(r)) for r in refs])
    for ax in (ax_p, ax_b, ax_bt):
        ax.grid(True, axis="y", alpha=0.3)
    mark_temperature_limit(ax_bt)
    return bars


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
