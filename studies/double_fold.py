"""Double-crease micro-origami: thermo-mechanical coupling of two identical creases (paper 5.2).

Question
--------
An anchor panel, two 450 um folding panels and two identical gold/SU-8 creases hang 60 um
above a substrate; both creases receive the same power. Fold 2 moves away from the substrate
as the device folds, so it should lose less heat, run hotter and fold more than fold 1. How
large is the difference in temperature and fold angle over the power ramp?

Method
------
``get_case("double_fold")`` with its defaults (reference Example02, theory 10.2): self-fold to
the residual fold 0, gravity at 0.9 x the panel weight with substrate contact, then both
creases ramp together to 10 mW each in 250 staggered thermo-mechanical increments.
Fold 1 is crease 2 (anchor - panel 1, reference crease 3), fold 2 is crease 5 (panel 1 -
panel 2, reference crease 6). ``--quick`` uses 30 increments.

Fold angles are signed (0 flat, positive = folding up, away from the substrate); the paper
(and the reference script) report them relative to the pre-heating state, hence
``fold_change [deg]``.

Outputs (``results/double_fold/``)
----------------------------------
``double_fold.csv``: one long table, the ``table`` column tells the row kind:

* ``sweep`` - one row per record (the last pre-heating record, power 0, then every heating
  increment) and fold: ``fold`` (1 or 2), ``crease`` (edge id), ``step``, ``stage``,
  ``power [mW]`` (power of that crease = power per crease), ``fold_angle [deg]``,
  ``fold_change [deg]`` (relative to the pre-heating record), ``temperature [degC]``
  (actuation temperature of the crease), ``temperature_centre [degC]`` (mean of its
  centre-line nodes: the measure of the 1.2 T_g limit) and ``temperature_max [degC]``
  (hottest crease node).
* ``nodes`` - final node positions ``x [um]``, ``y [um]``, ``z [um]`` and
  ``temperature [degC]`` (``step``, ``stage``, ``increment``, ``node``).

Figures: ``double_fold.png`` (fold angles and crease temperatures vs power per crease) and
``double_fold_shape.png`` (final 3-D shape coloured by temperature).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from simulator.cases import get_case
from studies._common import heating_records, node_frame, run_case, shape_from_frame, study_main

NAME = "double_fold"
THERMAL_STEPS_QUICK = 30
FOLDS = {1: 2, 2: 5}          # fold number -> crease (edge) id
POWER, FOLD, TEMP, TEMP_MAX = ("power [mW]", "fold_angle [deg]", "temperature [degC]",
                               "temperature_max [degC]")
TEMP_CL = "temperature_centre [degC]"


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Heat both creases of the double fold; see the module docstring."""
    case, res = run_case(NAME, {"thermal_steps": THERMAL_STEPS_QUICK} if quick else {},
                         progress, "double fold")
    h, mesh = res.history, case.model.mesh
    recs = heating_records(res)
    parts = []
    for fold, crease in FOLDS.items():
        row = mesh.crease_row_of(crease)
        angle = np.degrees(res.fold_angle[recs, row])
        parts.append(pd.DataFrame({
            "table": "sweep", "fold": fold, "crease": crease, "step": recs,
            "stage": h["stage_name"][recs], POWER: h["power"][recs, row] * 1e3, FOLD: angle,
            "fold_change [deg]": angle - angle[0],
            TEMP: res.crease_temperature[recs, row], TEMP_MAX: res.crease_temperature_max[recs, row],
            TEMP_CL: res.crease_temperature_centre_line[recs, row],
        }))
    return pd.concat([*parts, node_frame(res, -1)], ignore_index=True)


def plot(df: pd.DataFrame) -> dict:
    """``{"double_fold": folds and temperatures vs power, "double_fold_shape": final shape}``."""
    from matplotlib.figure import Figure

    from studies.plotting import environment_note, mark_temperature_limit, note_assumptions, \
        plot_shape

    sweep = df[df["table"] == "sweep"].sort_values("step", kind="stable")
    fig = Figure(figsize=(11.5, 4.9), layout="constrained")
    ax_f, ax_t = fig.subplots(1, 2)
    measured = []
    for fold, d in sweep.groupby("fold"):
        label = f"fold {int(fold)} (crease {int(d['crease'].iloc[0])})"
        color, style = f"C{int(fold) - 1}", ("-", "-.")[int(fold) - 1]
        ax_f.plot(d[POWER], d[FOLD], color=color, ls=style, label=label)
        measured += ax_t.plot(d[POWER], d[TEMP_CL], color=color, ls=style,
                              label=f"{label}, centre line")
        ax_t.plot(d[POWER], d[TEMP_MAX], ":", color=color, lw=1.2,
                  label=f"{label}, hottest node")
    ax_f.set_ylabel("fold angle [deg]")
    ax_f.set_title("(a) fold angles (positive: folding up)")
    ax_t.set_ylabel("temperature [°C]")
    ax_t.set_title("(b) crease temperatures (limit on the centre line)")
    for ax in (ax_f, ax_t):
        ax.set_xlabel("power per crease [mW]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small", loc="upper left")
    mark_temperature_limit(ax_t, lines=measured)
    note = environment_note("air", 0.026, 0, 0.9, extra=["substrate 60 um below"])
    missing = ("the paper's measured fold angles (Fig. 8c-d) are not available here and not "
               "drawn")
    note_assumptions(fig, note, missing)

    nodes = df[df["table"] == "nodes"]
    shape = plot_shape(shape_from_frame(nodes, get_case(NAME).model.mesh), record=-1,
                       panel_labels={"anchor": 0, "panel 1": 1, "panel 2": 2, "substrate": 3})
    ax = shape.axes[0]
    ax.set_title(f"double fold at {sweep[POWER].max():.1f} mW per crease (true scale)")
    ax.view_init(elev=20, azim=-70)
    note_assumptions(shape, note)
    return {NAME: fig, f"{NAME}_shape": shape}


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
