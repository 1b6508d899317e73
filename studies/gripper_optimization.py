"""Origami micro-gripper: the paper's coordinate descent, and NLopt optimisers side by side
(paper section 6.3, Fig. 11 b-c of the LaTeX source, ``figure_opt``).

Question
--------
The gripper of the paper's section 6.3 assembles (base creases fold the base panels past
90 deg) and then grips (arm creases close the arm tips to under 100 um). Which crease width
``W``, arm length ``La`` and base panel sizes ``L1``, ``L2`` need the least power, subject to
the size bounds and a crease temperature of at most 1.2 T_g (252 degC)? Does our
coordinate descent reproduce the paper's trend (base panels shrink, arm creases lengthen,
power falls), and do general-purpose derivative-free optimisers (NLopt) find designs that
are at least as good from the same start and under the same constraints?

Method
------
* Problem: :class:`~design.GripperProblem` (bisect power search, objective = assembly
  + grip power per heated crease, constraints = normalised size bounds and the temperature
  limit), as :class:`TimeLimitedGripperProblem` with no time limit (``TIME_LIMIT = None``:
  a limit would make the results depend on the machine's speed). Every evaluation ends on
  its own: the solvers bound their step cuts, and a residual that stalls near contact kinks
  (e.g. W 300, La 1200, L1 = L2 = 500 um) is accepted below 1e-3 of the self-weight
  (``NewtonOptions.stall_rtol``). A normal evaluation takes 0.3-1.5 s. Set ``TIME_LIMIT`` to
  stop slow evaluations (they count as failed, see ``failed_evaluations``).
* Coordinate descent (``optimize(problem, "cd", max_cycles=15, parallel_candidates=True)``)
  from the paper's start W 200, La 700, L1 1000, L2 1000 um with steps 10 / 50 / 50 / 50 um;
  the minus and plus candidates of a coordinate are evaluated together on a 2-process
  executor (the run, its history included, is the sequential search's; a plus candidate
  computed while its minus one was accepted is dropped).
* NLopt from the same start, each with its evaluation budget and default options
  (normalised variables, initial step = the CD step, constraints native for COBYLA, by an
  exact penalty otherwise): ``cobyla``, ``bobyqa``, ``neldermead``, ``sbplx`` (60
  evaluations each) and ``direct`` (global DIRECT-L, 80). The NLopt runs are spread over
  the two worker processes, each run serial inside its worker.
* ``--quick``: serial, CD with 3 evaluations, COBYLA and SBPLX with 4 each.

Outputs (``results/gripper_optimization/``)
-------------------------------------------
``gripper_optimization.csv``: one long table, the ``table`` column tells the row kind:

* ``cycles`` - the coordinate descent, one row per cycle (0 = start, like Fig. 12 b-c):
  ``cycle``, ``moved`` (coordinates moved in the cycle, e.g. ``W+;La+;L1-``), ``complete``
  (false when the budget ended the cycle), design ``W [um]``, ``La [um]``, ``L1 [um]``,
  ``L2 [um]``, ``total_power [mW]``, ``assembly_power [mW]``, ``grip_power [mW]``,
  ``temperature [degC]`` (of the current design, the reference's measure),
  ``temperature_limit [degC]``, ``last_candidate_temperature [degC]`` (the reference
  script's history value), ``feasible`` (of the current design), ``evaluations``
  (cumulative).
* ``comparison`` - one row per method: ``method``, ``options`` (non-default options),
  ``budget`` (evaluations; empty: none, the CD stops by its cycles), ``status``,
  ``message``, ``success`` (a feasible design was found; ``status`` says why the run
  stopped), ``total_power [mW]`` (empty without a feasible design), ``assembly_power [mW]``,
  ``grip_power [mW]``, the design (um), ``start_power [mW]``,
  ``reduction [%]``, ``evaluations`` (distinct designs), ``failed_evaluations`` (not
  successful: criterion not met below the power cap, simulation failure, time limit),
  ``best_at_evaluation``, ``wall_time [s]`` (of the run), ``evaluation_time [s]`` (sum over
  its evaluations), ``workers`` (processes the run used), ``temperature [degC]``,
  ``temperature_limit [degC]``, ``temperature_margin [degC]`` (limit - temperature),
  ``margin temperature [-]`` (``-g``, normalised by the limit), ``margin size [-]`` (smallest
  normalised size-bound margin, 0 on a bound), ``reaches_cd`` (power at or below the CD's).
* ``history`` - every evaluation of every method, in order: ``method``, ``evaluation``,
  ``total_power [mW]`` (empty when the evaluation did not succeed), ``success``,
  ``status`` (``feasible``, ``infeasible``, ``not_met``, ``failed``), ``feasible``,
  ``best_so_far [mW]`` (best feasible power up to that evaluation).

Figures: ``gripper_optimization.png`` ((b) design variables, (c) power per heated crease
(the objective) and (c') the total electrical power of the full function vs CD cycle, with
the paper's two measured devices),
``gripper_optimization_methods.png`` ((d) best power, evaluations and wall time per method,
and the best feasible power vs evaluation).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from design import GripperHeatModel, GripperProblem, make_executor, optimize
from studies._common import (EvaluationTimeout, TimeLimited, progress_bar, study_main,
                             time_limit)

__all__ = [
    "EvaluationTimeout",
    "TimeLimitedGripperProblem",
    "cd_optimum",
    "main",
    "plot",
    "run",
    "time_limit",
]

NAME = "gripper_optimization"
#: Longest evaluation [s] before it is stopped and counted as failed (None: no limit).
TIME_LIMIT = None
WORKERS = 2
CD_OPTIONS = {"max_cycles": 15, "parallel_candidates": True}
CD_BUDGET_QUICK = 3
#: (method, budget, options) of the comparison; the CD row reuses the CD run.
NLOPT_RUNS = (("cobyla", 60, {}), ("bobyqa", 60, {}), ("neldermead", 60, {}),
              ("sbplx", 60, {}), ("direct", 80, {}))
NLOPT_RUNS_QUICK = (("cobyla", 4, {}), ("sbplx", 4, {}))
VARIABLES = ("W", "La", "L1", "L2")
#: The gripper studies reproduce the paper's optimisation: its chain heat loss (the paper
#: setting; ``GripperHeatModel``'s default is the integral loss since 7 Dec 2026), the integral
#: loss's powers stated beside (:data:`INTEGRAL_BESIDE`).
PAPER_HEAT = GripperHeatModel(loss_model="chain")
UM = [f"{v} [um]" for v in VARIABLES]
POWER, ASM, GRIP, TEMP = ("total_power [mW]", "assembly_power [mW]", "grip_power [mW]",
                          "temperature [degC]")


@dataclass(frozen=True)
class TimeLimitedGripperProblem(TimeLimited, GripperProblem):
    """:class:`~design.GripperProblem` whose evaluations stop (fail) after
    ``time_limit`` [s]; its heat model is :data:`PAPER_HEAT`, the paper's setting."""

    heat: GripperHeatModel = PAPER_HEAT
    time_limit: float | None = TIME_LIMIT


# ----------------------------------------------------------------------------- run
def design_um(x: dict) -> dict:
    return {f"{k} [um]": 1e6 * v for k, v in x.items()}


def _metric(ev, key):
    v = None if ev is None else ev.metrics.get(key)
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else math.nan


def cycles_table(result, limit: float) -> pd.DataFrame:
    """Rows ``table = "cycles"`` from a gripper CD result (stage powers looked up in its
    history); ``limit``: the temperature limit [degC]. Also ``studies.gripper_physics``'s."""
    h = result.history
    xcols = [f"x.{v} [m]" for v in VARIABLES]
    rows = []
    for _, c in result.cycles.iterrows():
        x = np.array([c[f"x.{v} [m]"] for v in VARIABLES])
        match = h[np.all(np.isclose(h[xcols].to_numpy(float), x, rtol=0, atol=1e-12), axis=1)]
        m = match.iloc[0] if len(match) else {}
        rows.append({"table": "cycles", "method": "cd", "cycle": int(c["cycle"]),
                     "moved": c["moved"],
                     "complete": bool(c["complete"]), **design_um(dict(zip(VARIABLES, x))),
                     POWER: 1e3 * c["objective"],
                     ASM: m.get("m.assembly_power [mW]", math.nan),
                     GRIP: m.get("m.grip_power [mW]", math.nan),
                     TEMP: c["current.temperature [degC]"],
                     "temperature_limit [degC]": limit,
                     "last_candidate_temperature [degC]":
                         c["last_candidate.temperature [degC]"],
                     "feasible": bool(c["feasible"]), "evaluations": int(c["n_evaluations"])})
    return pd.DataFrame(rows)


def _comparison_row(label, result, budget, options, workers, problem, start_power) -> dict:
    best, h = result.best, result.history
    temp = _metric(best, "temperature [degC]")
    size = [-g for k, g in result.constraints.items() if k != "temperature"]
    power = 1e3 * result.objective if result.success else math.nan
    hist = _history_rows(label, result)
    reached = hist["evaluation"][hist["best_so_far [mW]"] <= power]
    best_at = int(reached.iloc[0]) if len(reached) else -1
    return {"table": "comparison", "method": label,
            "options": json.dumps(options, sort_keys=True), "budget": budget,
            "success": result.success, "status": result.status, "message": result.message,
            POWER: power, ASM: _metric(best, "assembly_power [mW]"),
            GRIP: _metric(best, "grip_power [mW]"), **design_um(result.x),
            "start_power [mW]": start_power, "reduction [%]": 100 * (1 - power / start_power),
            "evaluations": result.n_evaluations,
            "failed_evaluations": int((~h["success"].astype(bool)).sum()),
            "best_at_evaluation": best_at, "wall_time [s]": result.wall_time,
            "evaluation_time [s]": float(h["wall_time [s]"].sum()), "workers": workers,
            TEMP: temp, "temperature_limit [degC]": problem.temperature_limit,
            "temperature_margin [degC]": problem.temperature_limit - temp,
            "margin temperature [-]": -result.constraints.get("temperature", math.nan),
            "margin size [-]": min(size) + 0.0 if size else math.nan}     # no -0.0


def _history_rows(label, result) -> pd.DataFrame:
    h = result.history
    ok = h["feasible"].to_numpy(bool)
    success = h["success"].to_numpy(bool)
    power = np.where(success, 1e3 * h["objective"].to_numpy(float), np.nan)
    best = pd.Series(np.where(ok, power, np.nan)).cummin().ffill().to_numpy()
    return pd.DataFrame({"table": "history", "method": label,
                         "evaluation": h["eval"].to_numpy(int), POWER: power,
                         "success": success, "status": h["status"].to_numpy(str),
                         "feasible": ok, "best_so_far [mW]": best})


def _run_nlopt(task):
    """Worker task (top level, picklable): ``(problem, method, budget, options) -> result``."""
    problem, method, budget, options = task
    return optimize(problem, method, max_evaluations=budget, **options)


def _run_cd(problem, executor, budget, progress):
    bar = progress_bar(None, enabled=progress, desc="coordinate descent", unit="eval",
                       total=budget or 1 + 8 * CD_OPTIONS["max_cycles"], leave=False)
    callback = (lambda ev: bar.update(1)) if progress else None
    try:
        return optimize(problem, "cd", executor=executor, max_evaluations=budget,
                        callback=callback, **CD_OPTIONS)
    finally:
        if progress:
            bar.close()


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Coordinate descent, then the NLopt methods; see the module docstring."""
    problem = TimeLimitedGripperProblem()
    runs = NLOPT_RUNS_QUICK if quick else NLOPT_RUNS
    with make_executor("serial" if quick else "process",
                       None if quick else WORKERS) as executor:
        cd = _run_cd(problem, executor, CD_BUDGET_QUICK if quick else None, progress)
        bar = progress_bar(None, enabled=progress, desc="NLopt methods", unit="run",
                           total=len(runs), leave=False)
        shown = (lambda done, total: bar.update(done - bar.n)) if progress else None
        results = executor.map(_run_nlopt, [(problem, m, b, o) for m, b, o in runs], shown)
        if progress:
            bar.close()
    start = cd.history.iloc[0]
    start_power = 1e3 * start["objective"] if start["success"] else math.nan
    rows = [_comparison_row("cd", cd, cd.options["max_evaluations"],
                            {k: cd.options[k] for k in CD_OPTIONS}, executor.workers, problem,
                            start_power)]
    rows += [_comparison_row(m, r, b, o, 1, problem, start_power)
             for (m, b, o), r in zip(runs, results)]
    comparison = pd.DataFrame(rows)
    comparison["reaches_cd"] = comparison[POWER] <= comparison[POWER].iloc[0] + 1e-9
    history = [_history_rows("cd", cd)] + [_history_rows(m, r)
                                           for (m, _, _), r in zip(runs, results)]
    df = pd.concat([cycles_table(cd, problem.temperature_limit), comparison, *history],
                   ignore_index=True)
    first = ["table", "method", "cycle", "evaluation"]
    return df[first + [c for c in df.columns if c not in first]]


def cd_optimum(df: pd.DataFrame) -> dict:
    """The coordinate descent's final design {W, La, L1, L2} [m] from this study's table."""
    cycles = df[df["table"] == "cycles"].sort_values("cycle")
    last = cycles.iloc[-1]
    return {v: float(last[f"{v} [um]"]) * 1e-6 for v in VARIABLES}


# ----------------------------------------------------------------------------- plot
#: The paper's two fabricated grippers: (CD cycle near their geometry, measured electrical
#: power of the full function [mW]) (section 6.3, Fig. 11 f-g of the LaTeX source).
PAPER_DEVICES = ((4, 29.8), (9, 21.6))


_NOTE = ("environment: air, k_env = 0.026 W/(m K); residual fold 0 deg; gravity x 1 (lumped "
         "self-weight); temperature: centre-line mean of the hottest heated crease, limit "
         "1.2 T_g = 252 °C; the paper's simulated curves are not re-drawn here")


#: The calibration-free loss beside the chains on this problem (``device_heat_models``).
INTEGRAL_BESIDE = ("the calibration-free integral loss, which the 3-D FE supports on these "
                   "shapes (within 3.2 %; the chains 37-80 % cool), needs 22.2 / 12.7 mW full "
                   "function at cycles 4 / 9 against the chains' 42.4 / 23.4 mW; measured 29.8 / "
                   "21.6 mW (device_heat_models)")


def _plot_cycles(cycles, stop_message=""):
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    from studies.plotting import mark_temperature_limit

    fig = Figure(figsize=(16, 4.8), layout="constrained")
    ax_x, ax_p, ax_e = fig.subplots(1, 3)
    same = np.allclose(cycles["L1 [um]"], cycles["L2 [um]"])
    styles = {"W": ("o", "-", 4, "W"), "La": ("s", "-", 4, "La"), "L1": ("D", "-", 4, "L1"),
              "L2": ("o", "--", 9, "L2 (= L1 in every cycle)" if same else "L2")}
    for col, color in zip(UM, ("C0", "C1", "C2", "C3")):
        marker, ls, ms, label = styles[col.split()[0]]
        ax_x.plot(cycles["cycle"], cycles[col], marker=marker, ls=ls, ms=ms, color=color,
                  mfc="none" if ms > 4 else color, label=label)
    ax_x.set_ylabel("design variable [um]")
    ax_x.set_title("(b) design variables during the coordinate descent")
    ax_x.legend(fontsize="small", ncol=2)

    ax_p.plot(cycles["cycle"], cycles[POWER], "k-o", ms=4, label="objective: assembly + grip")
    ax_p.plot(cycles["cycle"], cycles[ASM], "C0--", label="assembly")
    ax_p.plot(cycles["cycle"], cycles[GRIP], "C1:", label="grip")
    ax_p.set_ylabel("power per heated crease [mW]")
    ax_p.set_ylim(bottom=0)
    ax_t = ax_p.twinx()
    ax_t.plot(cycles["cycle"], cycles[TEMP], "C3-.", alpha=0.7, lw=1,
              label="crease temperature (centre line)")
    ax_t.set_ylabel("crease temperature, centre line [°C]", color="C3")
    ax_t.tick_params(axis="y", colors="C3")
    ax_t.set_ylim(0, 270)
    mark_temperature_limit(ax_t, axis="y")
    p0, p1 = cycles[POWER].iloc[0], cycles[POWER].iloc[-1]
    ax_p.set_title(f"(c) objective per heated crease: {p0:.1f} -> {p1:.1f} mW "
                   f"({100 * (1 - p1 / p0):.0f}% less)\n{stop_message}", fontsize="medium")
    h1, l1 = ax_p.get_legend_handles_labels()
    h2, l2 = ax_t.get_legend_handles_labels()
    ax_p.legend(h1 + h2, l1 + l2, fontsize="small", loc="upper center",
                bbox_to_anchor=(0.5, -0.16), ncols=2)

    full = 2 * cycles[ASM] + 2 * cycles[GRIP]
    ax_e.plot(cycles["cycle"], full, "k-o", ms=4,
              label="simulated: 2 base creases x assembly\n+ 2 arm creases x grip power")
    for k, (cycle, mw) in enumerate(PAPER_DEVICES):
        ours = full[cycles["cycle"] == cycle]
        ax_e.plot([cycle], [mw], "*", ms=14, color=f"C{k + 4}",
                  label=f"paper's device near step {cycle}: {mw} mW measured"
                        + (f" (ours {float(ours.iloc[0]):.1f} mW)" if len(ours) else ""))
    ax_e.text(0.98, 0.97, "The paper measures its first device below\nits simulation: residual "
              "curvature of the thin\npanels, one dissipation angle for creases\nsharing the "
              "air, fabrication variations", transform=ax_e.transAxes, ha="right", va="top",
              fontsize="small")
    ax_e.set_ylabel("total electrical power of the full function [mW]")
    ax_e.set_ylim(bottom=0)
    ax_e.set_title("(c') every heated crease of both circuits at grip", fontsize="medium")
    ax_e.legend(fontsize="small", loc="lower left")
    for ax in (ax_x, ax_p, ax_e):
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_xlabel("cycle")
        ax.grid(True, alpha=0.3)
    from studies.plotting import GRIPPER_HEAT_LOSS, note_assumptions

    note_assumptions(fig, _NOTE, GRIPPER_HEAT_LOSS, INTEGRAL_BESIDE)
    return fig


def _plot_methods(comp, hist):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(13, 7.5), layout="constrained")
    axes = fig.subplot_mosaic([["power", "evals", "time"], ["hist", "hist", "hist"]])
    methods = list(comp["method"])
    y = np.arange(len(methods))
    colors = [f"C{i}" for i in range(len(methods))]
    for key, col, label in (("power", POWER, "best feasible power per heated crease [mW]"),
                            ("evals", "evaluations", "evaluations (distinct designs)"),
                            ("time", "wall_time [s]", "wall time [s]")):
        ax, vals = axes[key], comp[col].to_numpy(float)
        ax.barh(y, np.nan_to_num(vals), color=colors)
        for yi, v in zip(y, vals):
            ax.text(np.nan_to_num(v), yi, f" {v:.4g}" if np.isfinite(v) else " none",
                    va="center", fontsize="small")
        ax.set_xlim(0, 1.25 * np.nanmax(vals) if np.any(np.isfinite(vals)) else 1)
        ax.set_yticks(y, methods)
        ax.invert_yaxis()
        ax.set_xlabel(label)
        ax.set_ylabel("method")
        ax.grid(True, axis="x", alpha=0.3)
    axes["power"].axvline(comp[POWER].iloc[0], color="k", ls=":", lw=1)
    axes["power"].set_title("(d) best feasible power (dotted: CD)")
    axes["evals"].set_title("evaluations used")
    n = int(comp["workers"].iloc[0])
    axes["time"].set_title(f"wall time (CD on {n} process{'es' if n > 1 else ''})")
    ax_h = axes["hist"]
    for m, c in zip(methods, colors):
        d = hist[hist["method"] == m]
        ax_h.plot(d["evaluation"], d["best_so_far [mW]"], color=c, lw=2, label=m)
        ax_h.plot(d["evaluation"], d[POWER], ".", color=c, ms=3, alpha=0.4)
        bad = d[~d["success"]]
        ax_h.plot(bad["evaluation"], np.full(len(bad), 0.97), "x", color=c,
                  transform=ax_h.get_xaxis_transform())
    ax_h.set_xlabel("evaluation")
    ax_h.set_ylabel("assembly + grip power per heated crease [mW]")
    ax_h.set_title("best feasible power vs evaluation (dots: every evaluation, x at the top: "
                   "failed, e.g. time limit)")
    ax_h.legend(fontsize="small", ncol=3, loc="upper right")
    ax_h.grid(True, alpha=0.3)
    from studies.plotting import GRIPPER_HEAT_LOSS, note_assumptions

    note_assumptions(fig, _NOTE, GRIPPER_HEAT_LOSS, INTEGRAL_BESIDE)
    return fig


def plot(df: pd.DataFrame) -> dict:
    """``{"gripper_optimization": Fig. 12 b-c, "gripper_optimization_methods": comparison}``."""
    cycles = df[df["table"] == "cycles"].sort_values("cycle")
    comp = df[df["table"] == "comparison"]
    hist = df[df["table"] == "history"].copy()
    for col in ("feasible", "success"):
        hist[col] = hist[col].astype(str).str.lower() == "true"
    cd = comp[comp["method"] == "cd"]
    stop = f"stopped: {cd['message'].iloc[0]}" if len(cd) else ""
    return {NAME: _plot_cycles(cycles, stop), f"{NAME}_methods": _plot_methods(comp, hist)}


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
