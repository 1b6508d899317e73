"""Single-crease micro-origami: the gravity-induced folding threshold (paper section 5.1).

Question
--------
A single electro-thermal crease (gold on SU-8) joins a thick anchor panel to a thin folding
panel that hangs 150 um above a substrate. With gravity the folding panel sags until it rests
on the substrate, so a power threshold must be passed before any visible folding. How does
the threshold depend on the fabrication-induced residual fold (0, -10, -20 deg), and does our
re-implementation still reproduce the reference Example01 curve (no gravity, residual 0)?

Method
------
* Threshold runs: ``get_case("single_fold", residual_fold_deg=r, gravity=True,
  thermal_steps=250, power_mW=150)`` for r = 0, -10, -20 deg (self-fold to the residual rest
  angle, gravity on the folding panel with substrate contact, then the crease power ramps
  linearly to 150 mW in 250 staggered thermo-mechanical increments). The threshold power is
  the first power at which the fold angle is 1 deg above its pre-heating value.
* The same threshold runs in air (``env_conductivity=0.026``, ramp to 7.5 mW): the case's
  default k_env = 0.6 W/(m K) is the reference script's, a water-like value 23 x air's. Heat
  leaves the crease mainly through the environment, so in air the same temperature, hence
  the same fold, needs about 20 x less power; the other studies (actuation speed, natural
  modes, the gripper) use air.
* Example01: ``get_case("single_fold")`` with its defaults (no gravity, residual 0, 500
  increments to 100 mW), overlaid on the MATLAB reference curve
  ``studies/reference/single_fold_res0.csv`` (``fold_angle_signed_deg`` vs ``power_mW``,
  interpolated at our powers); ``deviation [deg]`` = ours - reference.
* ``--quick``: residuals 0 and -10 deg only, 30 thermal increments, Example01 with 50.

Fold angles are signed: 0 flat, positive when the panel folds up (away from the substrate).

Outputs (``results/single_fold/``)
----------------------------------
``single_fold.csv``: one long table, the ``table`` column tells the row kind:

* ``sweep`` - one row per record from the last pre-heating state (power 0) through every
  heating increment: ``variant``, ``residual_fold [deg]``, ``gravity``,
  ``env_conductivity [W/(m K)]``, ``step`` (record),
  ``stage``, ``power [mW]``, ``fold_angle [deg]``, ``temperature [degC]`` (crease),
  and for the Example01 rows ``reference_fold_angle [deg]`` and ``deviation [deg]``. The
  reference curve itself is the variant ``Example01 reference``.
* ``threshold`` - one row per variant: ``threshold_power [mW]``, ``fold_start [deg]``
  (pre-heating), ``fold_final [deg]``, ``temperature_final [degC]``.
* ``nodes`` - node positions ``x [um]``, ``y [um]``, ``z [um]`` and ``temperature [degC]`` of
  the -10 deg run, every few records of the heating stage (``step``, ``stage``,
  ``increment``, ``node``); used for the 3-D shape and the animation.

Figures: ``single_fold.png`` (fold vs power with gravity, and Example01 ours vs reference with
the deviation), ``single_fold_shape.png`` (final 3-D shape of the -10 deg run, coloured by
temperature), ``single_fold_-10deg.gif`` (animation of the -10 deg heating stage).

The helpers :func:`node_frame` and :func:`shape_from_frame` (node rows of a result, and back
to an object that :func:`studies.plotting.plot_shape` / :func:`~studies.plotting.animate`
accept) are shared by the other device studies.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pandas as pd

from simulator.cases import get_case
from studies._common import (TEMP, heating_records, node_frame, run_case,
                             run_was_quick, shape_from_frame, study_main)

NAME = "single_fold"
REFERENCE = pathlib.Path(__file__).resolve().parent / "reference" / "single_fold_res0.csv"

RESIDUALS = (0.0, -10.0, -20.0)          # deg
RESIDUALS_QUICK = (0.0, -10.0)
POWER_MW = 150.0                         # end of the ramp of the threshold runs
K_REFERENCE, K_AIR = 0.6, 0.026          # W/(m K): the reference script's, and air
POWER_AIR_MW = 7.5                       # end of the ramp of the runs in air
THERMAL_STEPS, THERMAL_STEPS_QUICK = 250, 30
EXAMPLE01_STEPS_QUICK = 50
SHAPE_RESIDUAL = -10.0                   # the run drawn in 3-D and animated
THRESHOLD_RISE = 1.0                     # deg above the pre-heating fold
ANIMATION_FRAMES = 50                    # node records kept of the -10 deg run (about)
EXAMPLE01, EXAMPLE01_REF = "Example01 (ours)", "Example01 reference"
#: What the 3-D FE says of the two heat-loss models (this device is not in the FE studies).
FE_VERDICT = ("not checked against the 3-D FE on this device; on the strip, the double fold, "
              "the gripper and the Miura lifter the FE supports the integral loss on the mesh's "
              "sheet (heat_transfer_models, device_heat_models); here on the sheet refined r = 2 "
              "(theory 4.11)")

POWER, FOLD = "power [mW]", "fold_angle [deg]"


K_ENV = "env_conductivity [W/(m K)]"


#: Suffix of the variants run with the calibration-free integral heat loss.
INTEGRAL = ", integral loss"


def gravity_variant(residual_deg: float, air: bool = False, loss_model: str = "chain") -> str:
    return (f"{'air, ' if air else ''}gravity, residual {residual_deg:g} deg"
            f"{INTEGRAL if loss_model == 'integral' else ''}")


def _subsample(records, every):
    keep = list(records[::every])
    if keep[-1] != records[-1]:
        keep.append(records[-1])
    return np.array(keep)


def _mesh():
    return get_case(NAME).model.mesh


# ----------------------------------------------------------------------------- run
def _sweep(result, recs, **labels) -> pd.DataFrame:
    h = result.history
    return pd.DataFrame({"table": "sweep", **labels, "step": recs, "stage": h["stage_name"][recs],
                         POWER: h["power"][recs, 0] * 1e3,
                         FOLD: np.degrees(result.fold_angle[recs, 0]),
                         TEMP: result.crease_temperature[recs, 0]})


def threshold_power(power_mW, fold_deg, rise=THRESHOLD_RISE) -> float:
    """First power at which the fold is ``rise`` deg above its first value (NaN if never)."""
    fold_deg = np.asarray(fold_deg)
    above = np.flatnonzero(fold_deg - fold_deg[0] >= rise)
    return float(np.asarray(power_mW)[above[0]]) if len(above) else float("nan")


def _threshold_row(sweep: pd.DataFrame) -> dict:
    return {"table": "threshold", "variant": sweep["variant"].iloc[0],
            "loss_model": sweep["loss_model"].iloc[0],
            "residual_fold [deg]": sweep["residual_fold [deg]"].iloc[0],
            "gravity": sweep["gravity"].iloc[0], K_ENV: sweep[K_ENV].iloc[0],
            "threshold_power [mW]": threshold_power(sweep[POWER], sweep[FOLD]),
            "fold_start [deg]": sweep[FOLD].iloc[0], "fold_final [deg]": sweep[FOLD].iloc[-1],
            "temperature_final [degC]": sweep[TEMP].iloc[-1]}


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Threshold runs with gravity and the Example01 comparison; see the module docstring."""
    residuals = RESIDUALS_QUICK if quick else RESIDUALS
    steps = THERMAL_STEPS_QUICK if quick else THERMAL_STEPS
    parts, thresholds = [], []
    runs = [(k_env, power, r, loss) for loss in ("chain", "integral")
            for k_env, power in ((K_REFERENCE, POWER_MW), (K_AIR, POWER_AIR_MW))
            for r in residuals]
    for k_env, power, r, loss in runs:
        air = k_env == K_AIR
        _, res = run_case(NAME, dict(residual_fold_deg=r, gravity=True, thermal_steps=steps,
                                     power_mW=power, env_conductivity=k_env, loss_model=loss),
                          progress, f"residual {r:g} deg, k_env {k_env:g}, {loss} loss")
        recs = heating_records(res)
        sweep = _sweep(res, recs, variant=gravity_variant(r, air, loss),
                       **{"residual_fold [deg]": r}, gravity=True, **{K_ENV: k_env},
                       loss_model=loss)
        parts.append(sweep)
        thresholds.append(_threshold_row(sweep))
        if r == SHAPE_RESIDUAL and not air and loss == "chain":
            frames = 10 if quick else ANIMATION_FRAMES
            shape = node_frame(res, _subsample(recs, max(1, len(recs) // frames)),
                               variant=gravity_variant(r))

    _, res = run_case(NAME, {"thermal_steps": EXAMPLE01_STEPS_QUICK} if quick else {}, progress,
                    "Example01")
    ours = _sweep(res, heating_records(res), variant=EXAMPLE01,
                  **{"residual_fold [deg]": 0.0}, gravity=False, **{K_ENV: K_REFERENCE},
                  loss_model="chain")
    ref = pd.read_csv(REFERENCE).sort_values("power_mW")
    ours["reference_fold_angle [deg]"] = np.interp(ours[POWER], ref["power_mW"],
                                                   ref["fold_angle_signed_deg"])
    ours["deviation [deg]"] = ours[FOLD] - ours["reference_fold_angle [deg]"]
    thresholds.append(_threshold_row(ours))
    reference = pd.DataFrame({"table": "sweep", "variant": EXAMPLE01_REF, "loss_model": "chain",
                              "residual_fold [deg]": 0.0, "gravity": False,
                              K_ENV: K_REFERENCE, "step": ref["step"].to_numpy(), "stage": "reference",
                              POWER: ref["power_mW"].to_numpy(),
                              FOLD: ref["fold_angle_signed_deg"].to_numpy(),
                              TEMP: ref["T_crease_weighted_C"].to_numpy()})
    return pd.concat([*parts, ours, reference, pd.DataFrame(thresholds), shape],
                     ignore_index=True)


# ----------------------------------------------------------------------------- plot
def plot(df: pd.DataFrame) -> dict:
    """``{"single_fold": fold vs power, "single_fold_shape": 3-D shape of the -10 deg run}``."""
    from matplotlib.figure import Figure

    from studies.plotting import environment_note, heat_loss_note, note_assumptions, plot_shape

    sweep = df[df["table"] == "sweep"]
    thr = df[df["table"] == "threshold"].set_index("variant")
    fig = Figure(figsize=(16, 5.2), layout="constrained")
    ax_g, ax_a, ax_e = fig.subplots(1, 3)
    for ax, air in ((ax_g, False), (ax_a, True)):
        _threshold_panel(ax, sweep, thr, air)
    ax_g.set_title(f"(a) k_env = {K_REFERENCE:g} W/(m K) (reference script, water-like)",
                   fontsize="medium")
    ax_a.set_title(f"(b) in air, k_env = {K_AIR:g} W/(m K)", fontsize="medium")
    start = sweep[sweep["variant"].str.contains("gravity")].groupby("variant")[FOLD].first()
    ours = sweep[sweep["variant"] == EXAMPLE01]
    ref = sweep[sweep["variant"] == EXAMPLE01_REF]
    ax_e.plot(ref[POWER], ref[FOLD], "k-", lw=3, alpha=0.35, label="reference (MATLAB)")
    ax_e.plot(ours[POWER], ours[FOLD], "C3--", label="ours")
    ax_d = ax_e.twinx()
    ax_d.plot(ours[POWER], ours["deviation [deg]"], "C0:", label="ours - reference")
    ax_d.set_ylabel("deviation [deg]", color="C0")
    ax_d.tick_params(axis="y", colors="C0")
    lim = max(1e-3, 1.2 * float(np.abs(ours["deviation [deg]"]).max()))
    ax_d.set_ylim(-lim, lim)
    ax_e.set_title(f"(c) Example01: no gravity, residual 0 deg, k_env {K_REFERENCE:g}",
                   fontsize="medium")
    h1, l1 = ax_e.get_legend_handles_labels()
    h2, l2 = ax_d.get_legend_handles_labels()
    ax_e.legend(h1 + h2, l1 + l2, fontsize="small", loc="upper left")
    for ax in (ax_g, ax_a, ax_e):
        ax.set_xlabel("crease power [mW]")
        ax.set_ylabel("fold angle [deg]")
        ax.grid(True, alpha=0.3)
    note_assumptions(
        fig, f"(a), (b): gravity x 1, substrate 150 um below; every run starts near "
        f"{start.mean():.0f} deg whatever the residual fold: the panel sags onto the substrate, "
        "which stops it; the residual fold sets the rest angle, hence the power to lift off. "
        f"k_env = {K_REFERENCE:g} W/(m K) is the reference script's value, {K_REFERENCE / K_AIR:.0f}"
        " x air's; heat leaves the crease mainly through the environment, so in air the same "
        "fold needs about 20 x less power.", "chains (solid, (c)): "
        + heat_loss_note(get_case(NAME).model)
        + " (medium as the panels say: the reference script's or air)", "integral (dashed): "
        + heat_loss_note(get_case(NAME, loss_model="integral").model), FE_VERDICT,
        "The paper's measured threshold points (Fig. 7c) are not available here and not drawn.")

    nodes = df[df["table"] == "nodes"]
    shape = plot_shape(shape_from_frame(nodes, _mesh()), record=-1, panel_labels={
        "anchor panel": 0, "folding panel": 1, "substrate": 2})
    ax = shape.axes[0]
    ax.set_title(f"{nodes['variant'].iloc[0]}: end of heating "
                 f"({sweep[sweep['variant'] == nodes['variant'].iloc[0]][POWER].max():.0f} mW)")
    ax.view_init(elev=20, azim=-60)
    note_assumptions(shape, environment_note("water-like (reference script)", K_REFERENCE,
                                             SHAPE_RESIDUAL, 1.0),
                     heat_loss_note(get_case(NAME).model))
    return {NAME: fig, f"{NAME}_shape": shape}


def _threshold_panel(ax, sweep, thr, air: bool) -> None:
    """Fold vs power of the threshold runs at one k_env, thresholds circled: one colour per
    residual fold, solid the paper's chains, dashed the integral heat loss."""
    runs = [v for v in sweep["variant"].unique()
            if v.startswith("gravity") != air and "gravity" in v]
    residuals = list(dict.fromkeys(v.replace(INTEGRAL, "") for v in runs))
    for v in runs:
        d = sweep[sweep["variant"] == v]
        p_thr = thr.loc[v, "threshold_power [mW]"]
        integral = v.endswith(INTEGRAL)
        label = (v.replace("air, ", "").replace("gravity, ", "").replace(INTEGRAL, "")
                 + (", integral" if integral else ", chains"))
        (line,) = ax.plot(d[POWER], d[FOLD], ls="--" if integral else "-",
                          color=f"C{residuals.index(v.replace(INTEGRAL, ''))}",
                          label=f"{label} (threshold {p_thr:.2g} mW)")
        if np.isfinite(p_thr):
            ax.plot([p_thr], [np.interp(p_thr, d[POWER], d[FOLD])], "o", color=line.get_color(),
                    mfc="none")
    ax.legend(fontsize="x-small", title="o: threshold (fold +1 deg); solid: the paper's "
              "chains, dashed: integral loss", title_fontsize="x-small", loc="upper left")


def animation(df: pd.DataFrame, path, quick: bool = False) -> pathlib.Path:
    """GIF of the -10 deg run's heating stage from the ``nodes`` rows of the table
    (stamped as a quick run if ``quick``)."""
    from studies.plotting import animate

    return animate(shape_from_frame(df[df["table"] == "nodes"], _mesh()), path, every=1, fps=8,
                   quick=quick)


def main(argv=None):
    out = study_main(NAME, __doc__, run, plot, argv)
    animation(pd.read_csv(out / f"{NAME}.csv"), out / f"{NAME}_-10deg.gif",
              quick=run_was_quick(out))
    return out


if __name__ == "__main__":
    main()
