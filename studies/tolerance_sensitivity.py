"""Which fabrication tolerance matters: the double fold's sensitivity report, first order
against Monte Carlo.

Question
--------
The double fold (both creases heated, chains, air, gravity) is built with tolerances on its
heater powers, residual folds, bimorph layers and the air's conductivity. Which of them moves
the fold angles and the crease temperatures most, how wide is the spread of the outputs, how
likely is the device to fold far enough while staying below the temperature limit, and does
the first-order (FOSM) propagation of the exact gradients agree with full simulations?

Method
------
* Design: ``get_case("double_fold")`` at 10 mW per crease (self-fold 20 increments, gravity 20,
  heating 5 increments with ``coupling="settled"``: a steady coupled state).
* Tolerances (1 sigma, independent normals; *assumed*, not measured): :data:`TOLERANCES`,
  heater power 2 %, residual fold 2 deg per crease, bimorph mismatch 5 % per crease, gold
  (t1) and SU-8 (t2) thickness 5 %, SU-8 modulus (E2) 10 %, the air's conductivity 10 %.
* Outputs: the fold angles of creases 2 and 5 and the centre-line temperatures of both (the
  limit's measure, theory 5.4). Limits: fold 5 at least :data:`FOLD_TARGET_DEG`, crease 5's
  centre line at most 1.2 T_g = 252 degC.
* :func:`design.analysis.sensitivity_report`: the gradients by one adjoint solve per output,
  the effects ``g sigma``, the FOSM standard deviation and the probabilities (each limit,
  and both at once with the outputs jointly normal).
* :func:`design.analysis.monte_carlo_comparison`: :data:`SAMPLES` samples of the same
  normals (seed :data:`SEED`) through full simulations; the sample standard deviation with
  its 95 % chi-square interval, the fraction meeting the limits with its 95 % Wilson
  interval, and the linearisation's error per sample.
* ``--quick``: 20 samples.

Outputs (``results/tolerance_sensitivity/``)
------------------------------------------
``tolerance_sensitivity.csv``, ``table`` tells the row kind: ``parameters`` (the report's
table: ``parameter``, ``unit``, ``nominal``, ``tolerance``, ``d <output> [<unit>] per
tolerance``, ``<output> variance share [-]``), ``outputs`` (per output and ``all limits``:
FOSM and Monte Carlo standard deviations and probabilities, with intervals) and ``samples``
(every sample's parameter changes, outputs and first-order predictions).

Figures: ``tolerance_sensitivity.png`` (tornado plot of fold 5 and crease 5's temperature,
the FOSM and Monte Carlo standard deviations marked), ``tolerance_sensitivity_mc.png``
(histograms of the Monte Carlo outputs against the first-order normal, limits marked).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd

from design.analysis import monte_carlo_comparison, plot_tornado, sensitivity_report
from simulator import Heat, SelfFold, simulate
from simulator.cases import get_case
from simulator.sensitivity import CreaseTemperature, FoldAngle
from studies._common import progress_bar, study_main

NAME = "tolerance_sensitivity"
SEED = 2026
SAMPLES, SAMPLES_QUICK = 200, 20
POWER = 0.010                      # W per crease
FOLD_TARGET_DEG = 95.0
T_LIMIT = 252.0                    # degC, 1.2 T_g on the centre line (theory 5.4)
#: 1-sigma tolerances [SI] (assumed).
TOLERANCES = {"power[2]": 0.02 * POWER, "power[5]": 0.02 * POWER,
              "rest_offset[2]": math.radians(2.0), "rest_offset[5]": math.radians(2.0),
              "delta_alpha[2]": 0.05 * 38e-6, "delta_alpha[5]": 0.05 * 38e-6,
              "t1": 0.05 * 0.2e-6, "t2": 0.05 * 0.9e-6, "E2": 0.10 * 2e9,
              "medium_conductivity": 0.10 * 0.026}
OUTPUTS = {"fold_2": FoldAngle(2), "fold_5": FoldAngle(5),
           "temperature_2": CreaseTemperature(2, "centre_line"),
           "temperature_5": CreaseTemperature(5, "centre_line")}
LIMITS = {"fold_5": (math.radians(FOLD_TARGET_DEG), None), "temperature_5": (None, T_LIMIT)}
TOLERANCE_TEXT = ("tolerances assumed, not measured (1 sigma, independent normals): power 2 %, "
                  "residual fold 2 deg per crease, mismatch 5 %, t_Au and t_SU8 5 %, E_SU8 "
                  "10 %, k_env 10 %")


def design_steps() -> list:
    """The double fold's steps: self-fold, gravity, heating to a steady coupled state."""
    gravity = get_case("double_fold").steps[1]
    return [SelfFold({2: 0.0, 5: 0.0}, increments=20),
            dataclasses.replace(gravity, increments=20),
            Heat({2: POWER, 5: POWER}, increments=5, coupling="settled")]


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """The report, then the Monte Carlo comparison; see the module docstring."""
    model, steps = get_case("double_fold").model, design_steps()
    result = simulate(model, steps)
    if not result.success:
        raise RuntimeError(f"double fold: {result.message}")
    report = sensitivity_report(result, TOLERANCES, outputs=OUTPUTS, limits=LIMITS)
    if not report.success:
        raise RuntimeError(f"sensitivity report: {report.message}")
    n = SAMPLES_QUICK if quick else SAMPLES
    bar = progress_bar(None, enabled=progress, total=n, desc=NAME, unit="sample")
    mc = monte_carlo_comparison(report, steps, n_samples=n, seed=SEED,
                                progress=(lambda k: bar.update(k - bar.n)) if progress
                                else None)
    if progress:
        bar.close()
    fosm = report.summary().drop(columns=["sigma (FOSM)", "P(meet) (FOSM) [-]", "nominal"])
    outputs = mc.table.merge(fosm, on=["output", "unit"], how="left")
    return pd.concat([report.to_frame(sort_by="fold_5").assign(table="parameters"),
                      outputs.assign(table="outputs", n_samples=n, seed=SEED),
                      mc.samples.assign(table="samples")], ignore_index=True)


def plot(df: pd.DataFrame) -> dict:
    """The tornado plot and the Monte Carlo histograms (from the CSV alone)."""
    from studies.figure_notes import heat_loss_note
    from studies.plotting import note_assumptions

    params = df[df["table"] == "parameters"].dropna(axis=1, how="all")
    outputs = df[df["table"] == "outputs"].set_index("output")
    samples = df[df["table"] == "samples"]
    n = int(outputs["n_samples"].iloc[0])
    physics = heat_loss_note(get_case("double_fold").model)
    tornado = plot_tornado(params, ["fold_5", "temperature_5"], footer="",
                           mc_sigma={o: outputs.loc[o, "sigma (MC)"]
                                     for o in ("fold_5", "temperature_5")})
    note_assumptions(tornado, physics, TOLERANCE_TEXT,
                     f"double fold, {1e3 * POWER:g} mW per crease, gravity; Monte Carlo: {n} "
                     "full simulations")
    hist = _histograms(outputs, samples, n)
    note_assumptions(hist, physics, TOLERANCE_TEXT)
    return {NAME: tornado, f"{NAME}_mc": hist}


def _histograms(outputs, samples, n):
    from matplotlib.figure import Figure
    from scipy.stats import norm

    fig = Figure(figsize=(10, 5.0), layout="constrained")
    for ax, (o, unit) in zip(fig.subplots(1, 2), (("fold_5", "deg"), ("temperature_5",
                                                                       "degC"))):
        row = outputs.loc[o]
        y = samples[f"{o} [{unit}]"].dropna().to_numpy(float)
        ax.hist(y, bins=max(8, int(np.sqrt(len(y)))), density=True, color="C0", alpha=0.6,
                label=f"Monte Carlo ({len(y)} of {n})")
        grid = np.linspace(y.min() - row["sigma (FOSM)"], y.max() + row["sigma (FOSM)"], 200)
        ax.plot(grid, norm.pdf(grid, row["nominal"], row["sigma (FOSM)"]), "k-",
                label="first order (FOSM) normal")
        limit = row["low"] if pd.notna(row["low"]) else row["high"]
        ax.axvline(limit, color="C3", ls="--",
                   label=f"limit {limit:.0f} {unit}: P FOSM {row['P(meet) (FOSM) [-]']:.2f}, "
                   f"MC {row['P(meet) (MC) [-]']:.2f} [{row['P_low (MC) [-]']:.2f}, "
                   f"{row['P_high (MC) [-]']:.2f}]")
        ax.set_xlabel(f"{o} [{unit}]")
        ax.set_ylabel("density")
        ax.set_title(f"sigma FOSM {row['sigma (FOSM)']:.3g}, MC {row['sigma (MC)']:.3g} "
                     f"[{row['sigma_low (MC)']:.3g}, {row['sigma_high (MC)']:.3g}] {unit}",
                     fontsize="small")
        ax.set_ylim(0, 1.15 * ax.get_ylim()[1])
        ax.legend(fontsize="x-small", loc="upper center", bbox_to_anchor=(0.5, -0.16))
    both = outputs.loc["all limits"]
    fig.suptitle(f"both limits met: FOSM {both['P(meet) (FOSM) [-]']:.3f}, Monte Carlo "
                 f"{both['P(meet) (MC) [-]']:.3f} [{both['P_low (MC) [-]']:.3f}, "
                 f"{both['P_high (MC) [-]']:.3f}] (95 %)")
    return fig


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
