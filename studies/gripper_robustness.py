"""Origami micro-gripper: robustness of the power to the fabrication's residual fold.

Question
--------
Fabrication leaves the actuated creases of the gripper slightly folded (the *residual fold*;
negative: folded down towards the substrate). The paper optimises the gripper for a flat
start (residual 0). How do the power and the crease temperature of the start design and of
the optimised design change when the residual fold is between -20 and +10 deg, does the
optimised design keep its advantage and stay below the temperature limit, and what does a
design optimised for the worst case over residual folds look like?

Method
------
* Problem: :class:`studies.gripper_optimization.TimeLimitedGripperProblem` (the paper's
  gripper problem, bisect power search, temperature limit 1.2 T_g = 252 degC; no time limit
  unless ``gripper_optimization.TIME_LIMIT`` is set).
* Designs:

  - ``start``: the paper's start design (W 200, La 700, L1 1000, L2 1000 um);
  - ``our optimum``: the coordinate descent's final design of the study
    ``gripper_optimization`` (last ``cycles`` row of
    ``results/gripper_optimization/gripper_optimization.csv``). If that file does not exist,
    the coordinate descent is re-run here with a small budget (``FALLBACK_CD_BUDGET``
    evaluations, ``--quick``: 3); the ``source`` column says which;
  - ``fold-robust optimum``: NLopt SBPLX (60 evaluations, default options: exact penalty for the
    constraints) from the start design on :class:`~design.analysis.robustness.RobustGripperProblem`
    over the residual folds {-20, -10, 0} deg: objective = the largest total power over the
    three, every one of them must meet both stages and the temperature limit. SBPLX is the
    best method of the study ``gripper_optimization`` (lowest power, tied with COBYLA, with
    fewer evaluations). The paper's coordinate descent cannot be used from the start here:
    it only accepts feasible moves, and the start design and all its neighbours exceed the
    temperature limit at -20 deg (281 degC at the start). COBYLA, tried as well in an
    earlier version (with a 30 s time limit per evaluation), ended at W 300, La 1008,
    L1 555, L2 500 um with a worst case of 14.2 mW after 60 evaluations.

* Sweep: :func:`~design.analysis.robustness.sweep_residual_fold` of the three designs at residual
  folds -20, -15, ..., +10 deg (the same value on all four actuated creases), on a
  2-process executor.
* ``--quick``: serial; residual folds -10 and 0 deg (also those of the robust problem),
  SBPLX with 2 evaluations.

Outputs (``results/gripper_robustness/``)
-----------------------------------------
``gripper_robustness.csv``: one long table, the ``table`` column tells the row kind:

* ``sweep`` - one row per design and residual fold: ``design`` (label), ``source``,
  ``W [um]``, ``La [um]``, ``L1 [um]``, ``L2 [um]``, ``residual_fold [deg]``, ``success``
  (the point was evaluated: both stages met), ``status`` (``feasible``, ``infeasible``,
  ``not_met``: a criterion not met below the power cap, ``failed``: simulation failure or
  time limit), ``feasible`` (success and below the temperature limit),
  ``assembly_power [mW]``, ``grip_power [mW]``, ``total_power [mW]`` (empty when not
  met), ``temperature [degC]``
  (reference measure: centre-line mean of the heated creases, larger stage),
  ``temperature_limit [degC]``, ``assembly_temperature [degC]``,
  ``grip_temperature [degC]``, ``max_crease_temperature [degC]``, ``margin <constraint> [-]``
  (``-g``, positive when satisfied: ``temperature`` and the size bounds),
  ``temperature_margin [degC]``, ``simulations``, ``message``, ``wall_time [s]``.
* ``designs`` - one row per design: ``design``, ``source``, the variables (um), and for the
  optimised ones the run's ``method``, ``success`` (a feasible design was found),
  ``status``, ``message``, ``evaluations``, ``failed_evaluations``, ``wall_time [s]`` and
  ``objective [mW]`` (robust: worst-case power over the robust
  problem's residual folds, ``robust_residual_folds [deg]``).

Figure: ``gripper_robustness.png`` (total power and temperature vs residual fold per design;
open red circles: temperature limit exceeded, crosses at the top: criterion not met or
failed).
"""

from __future__ import annotations

import pathlib

import numpy as np
import pandas as pd

from design import (RobustGripperProblem, make_executor, optimize, residual_fold_grid,
                    sweep_residual_fold)
from studies._common import RESULTS, progress_bar, study_main
from studies.gripper_optimization import (
    CD_OPTIONS,
    WORKERS,
    TimeLimitedGripperProblem,
    cd_optimum,
)

NAME = "gripper_robustness"
#: Output of the study ``gripper_optimization`` (source of our optimum).
OPTIMUM_CSV = RESULTS / "gripper_optimization" / "gripper_optimization.csv"
RESIDUALS = (-20.0, -15.0, -10.0, -5.0, 0.0, 5.0, 10.0)        # deg
RESIDUALS_QUICK = (-10.0, 0.0)
ROBUST_RESIDUALS = (-20.0, -10.0, 0.0)                          # deg
FALLBACK_CD_BUDGET, FALLBACK_CD_BUDGET_QUICK = 40, 3
#: Optimiser of the robust problem (see the module docstring) and its budgets.
ROBUST_METHOD = "sbplx"
ROBUST_BUDGET, ROBUST_BUDGET_QUICK = 60, 2
START, PAPER, ROBUST = "start", "our optimum", "fold-robust optimum"
POWER, TEMP = "total_power [mW]", "temperature [degC]"


def _bar(progress, desc, total):
    bar = progress_bar(None, enabled=progress, desc=desc, total=total, leave=False)
    return bar, ((lambda ev: bar.update(1)) if progress else None)


def _optimize(problem, method, budget, progress, desc, **kwargs):
    """``optimize`` from the start design with a progress bar over the evaluations."""
    bar, callback = _bar(progress, desc, budget)
    try:
        return optimize(problem, method, max_evaluations=budget, callback=callback, **kwargs)
    finally:
        if progress:
            bar.close()


def _design_row(label, source, x, result=None, **extra) -> dict:
    row = {"table": "designs", "design": label, "source": source,
           **{f"{k} [um]": 1e6 * v for k, v in x.items()}}
    if result is not None:
        row.update(method=result.method, status=result.status,
                   evaluations=result.n_evaluations,
                   failed_evaluations=int((~result.history["success"].astype(bool)).sum()),
                   **{"wall_time [s]": result.wall_time,
                      "objective [mW]": 1e3 * result.objective}, success=result.success,
                   message=result.message)
    return {**row, **extra}


def paper_optimum(problem, csv, budget, executor, progress):
    """(design, designs-table row): from the study ``gripper_optimization``'s CSV, or a CD."""
    csv = pathlib.Path(csv)
    if csv.exists():
        x = cd_optimum(pd.read_csv(csv))
        return x, _design_row(PAPER, f"{csv.parent.name}/{csv.name}: last CD cycle", x)
    res = _optimize(problem, "cd", budget, progress, "paper CD (fallback)", executor=executor,
                    **CD_OPTIONS)
    return res.x, _design_row(PAPER, f"CD re-run here ({csv.name} not found), "
                              f"budget {budget} evaluations", res.x, res)


def robust_optimum(problem, residuals_deg, budget, progress):
    """(design, designs-table row): :data:`ROBUST_METHOD` on the worst case over
    ``residuals_deg`` from the start design."""
    robust = RobustGripperProblem(problem, residual_fold_grid(residuals_deg))
    res = _optimize(robust, ROBUST_METHOD, budget, progress, f"robust {ROBUST_METHOD}")
    folds = ";".join(f"{r:g}" for r in residuals_deg)
    return res.x, _design_row(ROBUST, f"{ROBUST_METHOD} on the worst case over {folds} deg, "
                              f"budget {budget} evaluations", res.x, res,
                              **{"robust_residual_folds [deg]": folds})


def run(quick: bool = False, progress: bool = True, optimum_csv=None) -> pd.DataFrame:
    """Designs, then the residual-fold sweep; see the module docstring.

    ``optimum_csv``: the study ``gripper_optimization``'s CSV (our optimum; default
    :data:`OPTIMUM_CSV`); when it does not exist the coordinate descent is re-run with a small
    budget.
    """
    optimum_csv = OPTIMUM_CSV if optimum_csv is None else optimum_csv
    problem = TimeLimitedGripperProblem()
    residuals = RESIDUALS_QUICK if quick else RESIDUALS
    with make_executor("serial" if quick else "process",
                       None if quick else WORKERS) as executor:
        x_start = problem.space.to_mapping(problem.space.start)
        designs = {START: (x_start, _design_row(START, "paper's start design", x_start))}
        designs[PAPER] = paper_optimum(
            problem, optimum_csv, FALLBACK_CD_BUDGET_QUICK if quick else FALLBACK_CD_BUDGET,
            executor, progress)
        designs[ROBUST] = robust_optimum(
            problem, RESIDUALS_QUICK if quick else ROBUST_RESIDUALS,
            ROBUST_BUDGET_QUICK if quick else ROBUST_BUDGET, progress)
        n = len(designs) * len(residuals)
        bar = progress_bar(None, enabled=progress, desc="residual-fold sweep", total=n,
                           leave=False)
        shown = (lambda done, total: bar.update(done - bar.n)) if progress else None
        sweep = sweep_residual_fold(problem, [x for x, _ in designs.values()],
                                    residual_fold_grid(residuals), executor=executor,
                                    progress=shown)
        if progress:
            bar.close()
    labels = np.repeat(list(designs), len(residuals))
    sources = np.repeat([row["source"] for _, row in designs.values()], len(residuals))
    sweep.insert(0, "table", "sweep")
    sweep.insert(1, "design", labels)
    sweep.insert(2, "source", sources)
    sweep["temperature_margin [degC]"] = sweep["temperature_limit [degC]"] - sweep[TEMP]
    table = pd.DataFrame([row for _, row in designs.values()])
    return pd.concat([sweep, table], ignore_index=True)


# ----------------------------------------------------------------------------- plot
def plot(df: pd.DataFrame):
    """Total power and temperature vs residual fold, one line per design."""
    from matplotlib.figure import Figure

    sweep = df[df["table"] == "sweep"].copy()
    for col in ("success", "feasible"):
        sweep[col] = sweep[col].astype(str).str.lower() == "true"
    fig = Figure(figsize=(12, 4.8), layout="constrained")
    ax_p, ax_t = fig.subplots(1, 2)
    hot = sweep[sweep["success"] & ~sweep["feasible"]]
    for i, (label, d) in enumerate(sweep.groupby("design", sort=False)):
        d = d.sort_values("residual_fold [deg]")
        x = d.iloc[0]
        name = (f"{label} (W {x['W [um]']:.0f}, La {x['La [um]']:.0f}, "
                f"L1 {x['L1 [um]']:.0f}, L2 {x['L2 [um]']:.0f} um)")
        style = {"color": f"C{i}", "marker": "osD^v"[i % 5], "ls": ("-", "--", ":")[i % 3],
                     "ms": 7 - 1.5 * i, "lw": 2 if i else 1.5}
        for ax, col in ((ax_p, POWER), (ax_t, TEMP)):
            ax.plot(d["residual_fold [deg]"], d[col], **style,
                    label=name if ax is ax_p else label)
            bad = d[~d["success"]]
            ax.plot(bad["residual_fold [deg]"], np.full(len(bad), 0.97), "x", color=f"C{i}",
                    ms=9, mew=2, transform=ax.get_xaxis_transform())
    for ax, col in ((ax_p, POWER), (ax_t, TEMP)):
        if len(hot):
            ax.plot(hot["residual_fold [deg]"], hot[col], "o", ms=11, mfc="none", mec="red",
                    label="temperature limit exceeded")
        ax.set_xlabel("residual fold of the actuated creases [deg]")
        ax.grid(True, alpha=0.3)
    limit = sweep["temperature_limit [degC]"].iloc[0]
    ax_t.axhline(limit, color="red", ls=":", lw=1.2, label=f"1.2 T_g = {limit:.0f} °C")
    ax_p.set_ylabel("assembly + grip power per heated crease [mW]")
    ax_t.set_ylabel("crease temperature [°C] (centre line)")
    ax_p.set_title("assembly + grip power (x at the top: criterion not met / failed)")
    ax_t.set_title("crease temperature at the stopping power")
    ax_p.legend(fontsize="small", loc="upper left", bbox_to_anchor=(0.0, -0.16))
    ax_t.legend(fontsize="small", loc="upper left", bbox_to_anchor=(0.0, -0.16), ncols=2)
    from studies.plotting import GRIPPER_HEAT_LOSS, note_assumptions

    note_assumptions(fig, "environment: air, k_env = 0.026 W/(m K); gravity x 1 (lumped "
                     "self-weight); the residual fold of all four actuated creases swept "
                     "together; temperature: centre-line mean of the hottest heated crease",
                     GRIPPER_HEAT_LOSS)
    return fig


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
