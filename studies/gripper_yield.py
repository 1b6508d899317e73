"""Origami micro-gripper: yield and power spread under fabrication uncertainty.

Question
--------
Fabricated grippers differ from the drawing: each actuated crease keeps its own residual
fold, the gold and SU-8 layers vary in thickness, the bimorph mismatch and the air's heat
loss vary. Which share of the devices works (both stages met with the crease temperature
``T <= 1.2 T_g`` = 252 degC: the *yield*), how much power do they need, which inputs matter
most, and does a design chosen for yield do better than our (power-optimal) optimum?

Method
------
* Scenario: :data:`design.analysis.uncertainty.SCENARIOS` ``["default"]``, an *assumed* fabrication
  spread (not measured): residual fold of each of the four actuated creases normal, mean
  -5 deg, std 4 deg, truncated to [-20, 10] deg, correlated between the creases of one
  device (Gaussian copula, rho 0.7); gold 0.2 um and SU-8 0.8 um thick, each normal with a
  5 % standard deviation, truncated at 3 std; bimorph mismatch uniform on [34, 42] ppm/K; air
  conductivity uniform on [0.024, 0.030] W/(m K).
* Problem: the paper's gripper problem (:class:`design.GripperProblem`, bisect
  power search).
* Designs: ``start`` (the paper's start), ``our optimum`` (the coordinate descent's final
  design of the study ``gripper_optimization``, read from its CSV; re-run with a small
  budget if the CSV is missing, see :func:`studies.gripper_robustness.paper_optimum`),
  ``yield-robust optimum``: NLopt SBPLX (``ROBUST_BUDGET`` evaluations) from our optimum
  design on
  :class:`design.analysis.uncertainty_sweep.RobustYieldProblem`: minimise the 90 % quantile of the
  total power subject to a yield of at least 90 %, both estimated on the same
  ``ROBUST_SAMPLES`` Latin-hypercube samples for every design (common random numbers, seed
  ``SEED``; the robust problem evaluates a design's samples one after the other, so its
  budget is kept small), and ``path 1/3``, ``path 2/3``: designs on the straight line from
  the start to the robust design (yield vs design).
* Yield sweep: :func:`design.analysis.uncertainty_sweep.sweep_uncertainty` of the five designs at
  ``SAMPLES`` Latin-hypercube samples (seed ``SEED + 1``, independent of the optimiser's
  samples, so the robust design's yield is not judged on the samples it was tuned on), on a
  2-process executor; :func:`design.analysis.uncertainty_sweep.summarize_yield`: yield with its 95 %
  Wilson interval, power quantiles, Spearman rank correlations of every input with the
  total power and the temperature (95 % Fisher-z intervals).
* ``--quick``: serial, 3 samples, robust problem on 2 samples with 2 SBPLX evaluations.

Outputs (``results/gripper_yield/``)
------------------------------------
``gripper_yield.csv``, one long table; ``table`` tells the row kind:

* ``samples``: one row per design and sample (``design``, design [um], ``sample``, the
  sampled inputs in deg, um, ppm/K, W/(m K), ``success``, ``status``, ``works``, powers
  [mW], ``temperature [degC]``, ``message``, ``wall_time [s]``);
* ``summary``: one row per design (``yield [-]`` with ``yield_low [-]``, ``yield_high [-]``,
  ``power_q0.5 [mW]``, ``power_q0.9 [mW]`` (empty when more than 10 % are not met),
  ``power_mean [mW]``, ``power_std [mW]``, ``temperature_max [degC]``);
* ``sensitivity``: per design, input and output (``total_power [mW]``,
  ``temperature [degC]``): ``spearman [-]``, ``low [-]``, ``high [-]``;
* ``designs``: per design its ``source`` and, for the robust one, the optimiser's
  ``status``, ``evaluations``, ``objective [mW]`` and ``message``.

Figures: ``gripper_yield.png`` (yield with its interval per design, and the total power of
every sample), ``gripper_yield_inputs.png`` (rank correlations of the inputs with the total
power and the temperature, per design).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from design.analysis import SCENARIOS, summarize_yield
from design import GripperProblem, RobustYieldProblem, make_executor, sweep_uncertainty
from studies._common import RESULTS, progress_bar, study_main
from studies.gripper_optimization import PAPER_HEAT
from studies.gripper_robustness import FALLBACK_CD_BUDGET_QUICK, _design_row, _optimize, \
    paper_optimum

NAME = "gripper_yield"
OPTIMUM_CSV = RESULTS / "gripper_optimization" / "gripper_optimization.csv"
SCENARIO = SCENARIOS["default"]
SEED = 2026
SAMPLES, SAMPLES_QUICK = 30, 3
ROBUST_SAMPLES, ROBUST_SAMPLES_QUICK = 5, 2
ROBUST_BUDGET, ROBUST_BUDGET_QUICK = 15, 2
ROBUST_Q, ROBUST_YIELD = 0.9, 0.9
WORKERS = 2
START, PAPER, ROBUST = "start", "our optimum", "yield-robust optimum"
#: Power-search steps of the retry of samples whose simulation failed [W per crease]: half
#: the first step and a quarter of the largest step of the default search.
RETRY_STEPS = (0.05e-3, 0.1e-3)
PATH = ("path 1/3", "path 2/3")
#: How the figures name the assumed scenario.
SCENARIO_TEXT = ("fabrication spread assumed, not measured: residual fold per crease "
                 "N(-5, 4) deg, layer thicknesses +-5 %, mismatch 34-42 ppm/K, "
                 "k_env 0.024-0.030 W/(m K)")


def robust_optimum(problem, x0, samples, budget, progress):
    """(design, designs row): SBPLX on :class:`RobustYieldProblem` from ``x0``."""
    robust = RobustYieldProblem(problem, SCENARIO, samples=samples, seed=SEED, method="lhs",
                                q=ROBUST_Q, yield_target=ROBUST_YIELD)
    res = _optimize(robust, "sbplx", budget, progress, "robust yield sbplx", x0=x0)
    return res.x, _design_row(
        ROBUST, f"sbplx from the our optimum: min power q{ROBUST_Q:g} s.t. yield >= "
        f"{ROBUST_YIELD:g} on {samples} LHS samples (seed {SEED}), budget {budget} "
        "evaluations", res.x, res)


def _path(a: dict, b: dict, t: float) -> dict:
    return {k: a[k] + t * (b[k] - a[k]) for k in a}


def run(quick: bool = False, progress: bool = True, optimum_csv=None) -> pd.DataFrame:
    """Designs, then the yield sweep; see the module docstring."""
    problem = GripperProblem(mode="bisect", heat=PAPER_HEAT)     # the paper setting (chains)
    x_start = problem.space.to_mapping(problem.space.start)
    with make_executor("serial" if quick else "process",
                       None if quick else WORKERS) as executor:
        designs = {START: (x_start, _design_row(START, "paper's start design", x_start))}
        designs[PAPER] = paper_optimum(problem, OPTIMUM_CSV if optimum_csv is None
                                       else optimum_csv, FALLBACK_CD_BUDGET_QUICK, executor,
                                       progress)
        designs[ROBUST] = robust_optimum(
            problem, designs[PAPER][0], ROBUST_SAMPLES_QUICK if quick else ROBUST_SAMPLES,
            ROBUST_BUDGET_QUICK if quick else ROBUST_BUDGET, progress)
        for label, t in zip(PATH, (1 / 3, 2 / 3)):
            x = _path(x_start, designs[ROBUST][0], t)
            designs[label] = (x, _design_row(label, f"start + {t:.3g} (robust - start)", x))
        samples = SCENARIO.sample(SAMPLES_QUICK if quick else SAMPLES, SEED + 1, "lhs")
        total = len(designs) * len(samples)
        bar = progress_bar(None, enabled=progress, desc="yield sweep", total=total, leave=False)
        shown = (lambda done, n: bar.update(done - bar.n)) if progress else None
        retry = replace(problem, power_step=RETRY_STEPS[0], max_power_step=RETRY_STEPS[1])
        table = sweep_uncertainty(problem, SCENARIO, samples, [x for x, _ in designs.values()],
                                  executor=executor, progress=shown, retry=retry)
        if progress:
            bar.close()
    labels = list(designs)
    table.insert(0, "design", np.repeat(labels, len(samples)))
    summary, sens = summarize_yield(table, SCENARIO, by=["design"])
    parts = [table.assign(table="samples"), summary.assign(table="summary"),
             sens.assign(table="sensitivity"),
             pd.DataFrame([row for _, row in designs.values()])]
    df = pd.concat(parts, ignore_index=True)
    return df[["table"] + [c for c in df.columns if c != "table"]]


# ----------------------------------------------------------------------------- plot
#: Marker and meaning of each sample category in the power panel.
_MARKS = {"works": ("o", "works"), "too hot": ("x", "too hot (T > 1.2 T_g)"),
          "target not met": ("v", "target not met\n(top row)"),
          "solver failed": ("s", "solver failed twice\n(retried with smaller\nsteps; top row;\nnot counted)")}


def _plot_yield(df):
    from matplotlib.figure import Figure

    from studies.plotting import GRIPPER_HEAT_LOSS, T_LIMIT, T_MEASURE, environment_note, \
        note_assumptions

    summary = df[df["table"] == "summary"]
    samples = df[df["table"] == "samples"]
    fig = Figure(figsize=(12, 5.2), layout="constrained")
    ax_y, ax_p = fig.subplots(1, 2)
    pos = np.arange(len(summary))
    y = summary["yield [-]"].to_numpy(float)
    err = np.vstack([y - summary["yield_low [-]"], summary["yield_high [-]"] - y])
    ax_y.bar(pos, y, color=[f"C{i}" for i in pos], alpha=0.7)
    ax_y.errorbar(pos, y, yerr=err, fmt="none", ecolor="k", capsize=5,
                  label="95 % Wilson interval")
    failed = summary["solver_failed"].to_numpy(int)
    for i, (v, n, f) in enumerate(zip(y, summary["samples"].to_numpy(int), failed)):
        ax_y.text(i, 0.03, f"{int(round(v * (n - f)))}/{n - f}" + (f"\n+{f} failed" if f else ""),
                  ha="center", va="bottom", fontsize="small")
    ax_y.set_xticks(pos, summary["design"], rotation=20)
    ax_y.set_ylim(0, 1.12)
    ax_y.set_ylabel("yield among evaluated samples [-]")
    ax_y.set_title(f"yield: both stages met, T <= 1.2 T_g ({int(summary['samples'].iloc[0])} "
                   "samples per design)", fontsize="medium")
    ax_y.legend(fontsize="small", loc="upper left")
    cap = 1.08 * np.nanmax(samples["total_power [mW]"].to_numpy(float))
    for i, label in enumerate(summary["design"]):
        d = samples[samples["design"] == label]
        jitter = i + np.linspace(-0.25, 0.25, len(d)) if len(d) > 1 else np.full(len(d), i)
        p = d["total_power [mW]"].to_numpy(float)
        for cat, (marker, _) in _MARKS.items():
            hit = (d["category"] == cat).to_numpy()
            shown = p[hit] if cat in ("works", "too hot") else np.full(hit.sum(), cap)
            ax_p.plot(jitter[hit], shown, marker, color=f"C{i}" if cat in ("works", "too hot")
                      else "0.3", ms=6, mew=1.8, mfc="none" if cat != "works" else None, ls="")
    for cat, (marker, text) in _MARKS.items():
        ax_p.plot([], [], marker, color="0.3", mfc="none" if cat != "works" else None, ls="",
                  label=text)
    ax_p.set_xticks(pos, summary["design"], rotation=20)
    ax_p.set_ylabel("total power per heated crease [mW]")
    ax_p.set_title("power of every sample, by category", fontsize="medium")
    ax_p.grid(True, alpha=0.3)
    ax_p.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    note_assumptions(fig, environment_note(
        "air", scenario=SCENARIO_TEXT, extra=["gravity x 1 (lumped self-weight)"]),
        GRIPPER_HEAT_LOSS + " (air's conductivity varied as the scenario says)", f"T = {T_MEASURE} (limit {T_LIMIT:.0f} °C); a sample whose simulation "
        f"failed is retried once with power steps {1e3 * RETRY_STEPS[0]:g}/"
        f"{1e3 * RETRY_STEPS[1]:g} mW; failures left after it are not counted in the yield.")
    return fig


def _plot_inputs(df):
    from matplotlib.figure import Figure

    sens = df[df["table"] == "sensitivity"]
    outputs = list(dict.fromkeys(sens["output"]))
    designs = list(dict.fromkeys(sens["design"]))
    fig = Figure(figsize=(12, 5), layout="constrained")
    for ax, out in zip(fig.subplots(1, len(outputs), sharey=True), outputs):
        for j, label in enumerate(designs):
            d = sens[(sens["output"] == out) & (sens["design"] == label)]
            pos = np.arange(len(d)) + (j - (len(designs) - 1) / 2) * 0.8 / len(designs)
            rho = d["spearman [-]"].to_numpy(float)
            err = np.vstack([rho - d["low [-]"], d["high [-]"] - rho])
            ax.barh(pos, rho, height=0.8 / len(designs), color=f"C{j}", label=label)
            ax.errorbar(rho, pos, xerr=err, fmt="none", ecolor="k", lw=0.8, capsize=2)
        inputs = list(dict.fromkeys(sens["input"]))
        ax.set_yticks(np.arange(len(inputs)), inputs)
        ax.axvline(0, color="k", lw=0.8)
        ax.set_xlim(-1, 1)
        ax.set_xlabel(f"Spearman rank correlation with {out} (95 % CI)")
        ax.grid(True, axis="x", alpha=0.3)
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    from studies.plotting import GRIPPER_HEAT_LOSS, environment_note, note_assumptions

    note_assumptions(fig, environment_note("air", scenario=SCENARIO_TEXT,
                                           extra=["gravity x 1 (lumped self-weight)"]),
                     GRIPPER_HEAT_LOSS + " (air's conductivity varied as the scenario says)")
    return fig


def plot(df: pd.DataFrame) -> dict:
    """Yield and power per design; which inputs matter."""
    return {NAME: _plot_yield(df), f"{NAME}_inputs": _plot_inputs(df)}


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
