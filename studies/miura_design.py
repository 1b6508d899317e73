"""Miura-ori lifter design: lift per power across the geometry, and the least-power design.

Question
--------
The Miura-ori lifter of the paper's section 6.2 (4 x 2 cells over a substrate, first column
clamped, every crease heated with the same power) lifts its free end. How does the lift per
unit of heating power depend on the panel side ``a``, the sector angle ``gamma`` and the
crease width ``W``? Which design lifts the free end by 200 um with the least total power,
keeping the creases below 1.2 T_g (252 degC)?

Method
------
* Grid: :func:`~design.devices.miura.lift_per_power_table` for the product of ``a`` in {0.5, 1.0,
  1.5} mm, ``gamma`` in {45, 60, 75} deg and ``W`` in {100, 200, 300} um (``b`` = 1 mm and
  the rest as :class:`~design.devices.miura.MiuraDesign`; the values span the bounds of
  :data:`~design.devices.miura.MIURA_SPACE`), each design heated to 4, 8 and 12 mW per crease
  (20 staggered increments per segment, from saved states). *Lift per power* = lift of the
  free end / total power of all heated creases [um/mW]. Designs whose creases collapse in
  the mesh, and designs whose heating fails, are listed with ``success = False`` and the
  reason. Heating follows snaps (limit points) by arc length in the power
  (``on_limit_point="continue"``, issue 9): a = 0.5 mm, W = 300 um snaps at 9.2 mW per
  crease (gamma 45 deg) and 10.8 mW (gamma 60 deg) and is followed past it; gamma 60 deg
  then fails at 12 mW on the unstable branch of a second snap (with two contact pairs
  active). No time limit by default (``TIME_LIMIT = None``; results must not depend on the
  machine's speed).
  Designs are spread over a 2-process executor.
* Optimum: :class:`~design.devices.miura.MiuraProblem` (target lift 200 um, bisect power search,
  objective = total power, constraints = size bounds and the hottest crease node below
  252 degC), as ``TimeLimitedMiuraProblem`` (no limit unless ``TIME_LIMIT`` is set),
  minimised by the paper's coordinate descent (``optimize(..., "cd",
  parallel_candidates=True)``: the
  variable steps of ``MIURA_SPACE`` (50 um, 50 um, 5 deg, 10 um), 15 cycles,
  ``CD_BUDGET`` = 80 evaluations) from the space's start (a = b = 1 mm, gamma 60 deg,
  W 200 um). Coordinate descent rather than an NLopt method: on the gripper (study
  ``gripper_optimization``) it came within 1% of the best NLopt runs (only its cycle limit
  stopped it short of the bound), its moves stay on the lattice of the variable steps, and
  it evaluates its candidates in parallel.
* The bisect power search heats each trial in one increment from a saved state, with
  staggered coupling (the temperature is solved on the shape at the start of the increment).
  On this lifter the lift feeds back strongly on the temperature (the thermal boundary is the
  substrate), so a state reached by a large increment lags behind, and any small further
  increment from it jumps past the target: the power found tends to sit 1/128 mW above one
  of the search's earlier trial powers (e.g. 11.5078 mW per crease at the start). The
  objective therefore has plateaus, and the coordinate descent stops where the neighbours
  lie on the same plateau. The start and the optimum are re-checked with the staircase
  search (0.1 mW steps) for comparison.
* ``--quick``: serial; two grid designs (W 150 and 200 um) at 8 mW per crease with 10
  increments, coordinate descent with 3 evaluations.

Outputs (``results/miura_design/``)
-----------------------------------
``miura_design.csv``: one long table, the ``table`` column tells the row kind:

* ``grid`` - one row per design and power: ``label``, ``a [um]``, ``b [um]``,
  ``gamma [deg]``, ``W [um]``, ``power [mW]`` (per crease), ``total_power [mW]``,
  ``n_creases``, ``lift [um]``, ``lift_per_power [um/mW]``,
  ``temperature [degC]`` (hottest crease, centre-line mean: the measure of the 1.2 T_g
  limit), ``max_crease_temperature [degC]`` (hottest crease node), ``success`` (the heating
  converged), ``status`` (``converged``, ``failed``), ``message``; lift and temperatures
  empty when it failed.
* ``optimum`` - two rows, ``label`` ``start`` and ``optimum``: the design, ``total_power [mW]``,
  ``power [mW]`` (per crease), ``lift [um]``, ``lift_per_power [um/mW]``,
  ``temperature [degC]``, ``max_crease_temperature [degC]``, ``temperature_limit [degC]``,
  ``margin temperature [-]``
  (``-g``), ``feasible``, ``power_staircase [mW]`` and ``total_power_staircase [mW]`` (the
  same design re-checked with the staircase search, 0.1 mW steps per crease; empty if the
  target is not reached), and the run's ``method``, ``success`` (a feasible design was
  found), ``status``, ``message``, ``evaluations``, ``failed_evaluations``,
  ``wall_time [s]``.
* ``cycles`` - the coordinate descent per cycle: ``cycle``, ``moved``, the design,
  ``total_power [mW]``, ``temperature [degC]`` (centre line), ``evaluations``.

Figures: ``miura_design.png`` (lift per power vs a, gamma and W: lines through the default
design, one per power; dots: every other grid design), ``miura_design_optimum.png`` (start vs
optimum: design variables within their bounds, and the power per cycle).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from design import make_executor
from simulator import ParameterError
from design.devices.miura import (
    MIURA_SPACE,
    MiuraDesign,
    MiuraProblem,
    design_columns,
    lift_per_power_table,
    lift_power,
)
from studies._common import progress_bar, study_main
from studies._common import EvaluationTimeout, TimeLimited, time_limit

NAME = "miura_design"
_DEG = math.pi / 180
WORKERS = 2
GRID = {"a": (0.5e-3, 1.0e-3, 1.5e-3), "gamma": (45 * _DEG, 60 * _DEG, 75 * _DEG),
        "W": (100e-6, 200e-6, 300e-6)}
GRID_QUICK = {"a": (1.0e-3,), "gamma": (60 * _DEG,), "W": (150e-6, 200e-6)}
POWERS_MW, POWERS_MW_QUICK = (4.0, 8.0, 12.0), (8.0,)
INCREMENTS, INCREMENTS_QUICK = 20, 10
TARGET_LIFT = 200e-6
#: Longest heating run of a design [s] before it is stopped (None: no limit).
TIME_LIMIT = None
CD_BUDGET, CD_BUDGET_QUICK = 80, 3
CD_OPTIONS = {"max_cycles": 15, "parallel_candidates": True,
              "metric": "temperature [degC]"}
#: Display columns of the design variables: name -> (column, scale from SI).
SHOW = {"a": ("a [um]", 1e6), "b": ("b [um]", 1e6), "gamma": ("gamma [deg]", 1 / _DEG),
        "W": ("W [um]", 1e6)}
LPP, TMAX = "lift_per_power [um/mW]", "max_crease_temperature [degC]"
#: The hottest crease's centre-line mean: the measure of the 1.2 T_g limit.
TEMP = "temperature [degC]"
#: The study keeps the case's chains (the paper setting; ``MiuraDesign``'s default heat loss
#: is the integral one since 7 Dec 2026), so its committed tables stay as they were.
PAPER_BASE = MiuraDesign(loss_model="chain")


@dataclass(frozen=True)
class TimeLimitedMiuraProblem(TimeLimited, MiuraProblem):
    """:class:`~design.devices.miura.MiuraProblem` whose evaluations stop (fail) after ``time_limit``
    [s]; its base design is the case's, with the case's chains (:data:`PAPER_BASE`)."""

    base: MiuraDesign = PAPER_BASE
    time_limit: float | None = TIME_LIMIT


# ----------------------------------------------------------------------------- run
def _label(values: dict) -> str:
    """``"a 1000 um, gamma 60 deg, W 200 um"`` from SI values."""
    return ", ".join(f"{k} {v * SHOW[k][1]:.4g} {SHOW[k][0].split('[')[1][:-1]}"
                     for k, v in values.items())


def _failed_rows(values: dict, powers, message: str) -> pd.DataFrame:
    """Grid rows of a design that could not be evaluated (``success = False``)."""
    base = PAPER_BASE
    v = {**{k: getattr(base, k) for k in SHOW}, **values}
    return pd.DataFrame([{"label": _label(values), **design_columns(v), "power [mW]": p,
                          "success": False, "status": "failed", "message": message}
                         for p in powers])


def _grid_task(task) -> pd.DataFrame:
    """Worker task (top level, picklable): ``(values, powers, increments) -> table``.

    A design that does not mesh, or whose heating runs longer than :data:`TIME_LIMIT`, gives
    rows with ``success = False`` and the reason.
    """
    values, powers, increments = task
    try:
        design = MiuraDesign(**{"loss_model": PAPER_BASE.loss_model, **values})
    except ParameterError as exc:
        return _failed_rows(values, powers, str(exc))
    try:
        with time_limit(TIME_LIMIT):
            return lift_per_power_table({_label(values): design}, list(powers),
                                        increments=increments)
    except EvaluationTimeout as exc:
        return _failed_rows(values, powers, str(exc))


def grid_table(grid: dict, powers, increments, executor, progress=None) -> pd.DataFrame:
    """Rows ``table = "grid"``: the product of ``grid`` {variable: values (SI)} at ``powers``."""
    names = list(grid)
    tasks = [(dict(zip(names, combo)), tuple(powers), increments)
             for combo in itertools.product(*grid.values())]
    parts = executor.map(_grid_task, tasks, progress)
    df = pd.concat(parts, ignore_index=True)
    df["n_creases"] = (df["total_power [mW]"] / df["power [mW]"]).round()
    df[LPP] = df["lift [um]"] / df["total_power [mW]"]
    df = df.drop(columns=[c for c in ("cells_x", "cells_y", "substrate") if c in df])
    df.insert(0, "table", "grid")
    return df


def _design_columns(x: dict) -> dict:
    return {col: x[name] * scale for name, (col, scale) in SHOW.items()}


def _nan(v) -> float:
    """A table cell: None (not met) becomes NaN, an empty CSV cell."""
    return math.nan if v is None else v


def _optimum_rows(problem, result) -> pd.DataFrame:
    h = result.history
    rows = []
    for label, ev in (("start", h.iloc[0]), ("optimum", None)):
        if ev is None:
            best = result.best
            x, m, g = best.x, best.metrics, best.constraints
            obj, feasible = best.objective, best.feasible
        else:
            x = {v.name: ev[f"x.{v.name} [{v.unit}]"] for v in MIURA_SPACE.variables}
            m = {k[2:]: ev[k] for k in h.columns if k.startswith("m.")}
            g = {k[2:]: ev[k] for k in h.columns if k.startswith("g.")}
            obj, feasible = ev["objective"], bool(ev["feasible"])
        total = 1e3 * obj if math.isfinite(obj) else math.nan
        check = lift_power(problem.design(x), problem.target_lift, mode="staircase",
                           step=problem.step, power_cap=problem.power_cap)
        rows.append({"table": "optimum", "label": label, **_design_columns(x),
                     "total_power [mW]": total,
                     "power [mW]": _nan(m.get("power_per_crease [mW]")),
                     "n_creases": m.get("n_creases", math.nan),
                     "lift [um]": m.get("lift [um]", math.nan),
                     LPP: m.get("lift [um]", math.nan) / total,
                     TEMP: m.get(TEMP, math.nan), TMAX: m.get(TMAX, math.nan),
                     "temperature_limit [degC]": problem.temperature_limit,
                     "margin temperature [-]": -g.get("temperature", math.nan),
                     "feasible": feasible,
                     "power_staircase [mW]": 1e3 * check.power_per_crease
                     if check.success else math.nan,
                     "total_power_staircase [mW]": 1e3 * check.total_power
                     if check.success else math.nan,
                     "method": result.method, "success": result.success,
                     "status": result.status, "message": result.message,
                     "evaluations": result.n_evaluations,
                     "failed_evaluations": int((~h["success"].astype(bool)).sum()),
                     "wall_time [s]": result.wall_time})
    return pd.DataFrame(rows)


def _cycles_rows(result) -> pd.DataFrame:
    c = result.cycles
    out = pd.DataFrame({"table": "cycles", "cycle": c["cycle"], "moved": c["moved"]})
    for name, (col, scale) in SHOW.items():
        out[col] = c[f"x.{name} [{MIURA_SPACE[name].unit}]"] * scale
    out["total_power [mW]"] = 1e3 * c["objective"]
    out[TEMP] = c[f"current.{CD_OPTIONS['metric']}"]
    out["evaluations"] = c["n_evaluations"]
    return out


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Lift-per-power grid, then the coordinate descent; see the module docstring."""
    grid = GRID_QUICK if quick else GRID
    powers = POWERS_MW_QUICK if quick else POWERS_MW
    problem = TimeLimitedMiuraProblem(target_lift=TARGET_LIFT)
    budget = CD_BUDGET_QUICK if quick else CD_BUDGET
    with make_executor("serial" if quick else "process",
                       None if quick else WORKERS) as executor:
        n = int(np.prod([len(v) for v in grid.values()]))
        bar = progress_bar(None, enabled=progress, desc="lift-per-power grid", total=n,
                           leave=False)
        shown = (lambda done, total: bar.update(done - bar.n)) if progress else None
        table = grid_table(grid, powers, INCREMENTS_QUICK if quick else INCREMENTS, executor,
                           shown)
        if progress:
            bar.close()
        bar = progress_bar(None, enabled=progress, desc="coordinate descent", total=budget,
                           leave=False)
        result = optimize_miura(problem, executor, budget,
                                (lambda ev: bar.update(1)) if progress else None)
        if progress:
            bar.close()
    return pd.concat([table, _optimum_rows(problem, result), _cycles_rows(result)],
                     ignore_index=True)


def optimize_miura(problem, executor, budget, callback=None):
    """The coordinate descent on ``problem`` from the space's start."""
    from design import optimize

    return optimize(problem, "cd", executor=executor, max_evaluations=budget,
                    callback=callback, **CD_OPTIONS)


# ----------------------------------------------------------------------------- plot
def _grid_figure(grid):
    from matplotlib.figure import Figure

    from studies.plotting import T_LIMIT

    defaults = _design_columns({n: v.start for n, v in zip(MIURA_SPACE.names,
                                                            MIURA_SPACE.variables)})
    params = [("a [um]", "panel side a [um]"), ("gamma [deg]", "sector angle gamma [deg]"),
              ("W [um]", "crease width W [um]")]
    fig = Figure(figsize=(13, 4.4), layout="constrained")
    axes = fig.subplots(1, 3, sharey=True)
    ok = grid[grid["success"]]
    powers = sorted(ok["power [mW]"].unique())
    for ax, (col, label) in zip(axes, params):
        others = [c for c, _ in params if c != col]
        for i, p in enumerate(powers):
            d = ok[ok["power [mW]"] == p]
            ax.plot(d[col], d[LPP], ".", color=f"C{i}", alpha=0.35, ms=6)
            base = d[np.all([np.isclose(d[c], defaults[c]) for c in others], axis=0)]
            base = base.sort_values(col)
            ax.plot(base[col], base[LPP], "-o", color=f"C{i}", ms=5,
                    label=f"{p:g} mW per crease")
        hot = ok[ok[TEMP] > T_LIMIT]
        if len(hot):
            ax.plot(hot[col], hot[LPP], "o", ms=9, mfc="none", mec="r", mew=1.2,
                    label=f"hottest crease (centre line) above 1.2 T_g = {T_LIMIT:.0f} °C "
                          f"(up to {ok[TEMP].max():.0f} °C; hottest node "
                          f"{ok[TMAX].max():.0f} °C)")
        down = ok[ok["lift [um]"] < 0]
        if len(down):
            ax.plot(down[col], down[LPP], "v", ms=9, mfc="none", mec="k", mew=1.2,
                    label=f"negative lift (end moves down, {down['lift [um]'].min():.1f} um)")
        ax.axhline(0, color="k", lw=0.8)
        bad = grid[~grid["success"]].drop_duplicates(subset=["a [um]", "gamma [deg]",
                                                               "W [um]"])
        if len(bad):
            ax.plot(bad[col], np.full(len(bad), 0.03), "kx", ms=7,
                    transform=ax.get_xaxis_transform(),
                    label="not evaluated (no mesh or time limit)")
        ax.set_xlabel(label)
        ax.set_ylabel("lift per total power [um/mW]")
        ax.grid(True, alpha=0.3)
        ax.set_title(f"vs {col.split()[0]} (others: " + ", ".join(
            f"{c.split()[0]} {defaults[c]:.0f}" for c in others) + ")", fontsize="medium")
    entries = {}
    for ax in axes:
        for h, label in zip(*ax.get_legend_handles_labels()):
            entries.setdefault(label, h)
    fig.legend(entries.values(), entries.keys(), loc="outside upper center", ncols=3,
               fontsize="small")
    _note(fig)
    return fig


def _note(fig):
    from design import make_miura_model
    from studies.plotting import environment_note, heat_loss_note, note_assumptions

    note_assumptions(fig, environment_note("air", 0.026, 0, 0, extra=[
        "4 x 2 cells over a substrate 100 um below", "first column clamped",
        "temperature: hottest crease, centre-line mean"]),
        heat_loss_note(make_miura_model(PAPER_BASE)) + " (t_env of the design's case)")


def _optimum_figure(opt, cycles):
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    from studies.plotting import mark_temperature_limit

    fig = Figure(figsize=(12, 4.6), layout="constrained")
    ax_x, ax_p = fig.subplots(1, 2)
    names = list(SHOW)
    y = np.arange(len(names))
    lo = np.array([MIURA_SPACE[n].lower * SHOW[n][1] for n in names])
    hi = np.array([MIURA_SPACE[n].upper * SHOW[n][1] for n in names])
    for k, (label, color) in enumerate((("start", "0.6"), ("optimum", "C3"))):
        row = opt[opt["label"] == label].iloc[0]
        vals = np.array([row[SHOW[n][0]] for n in names])
        z = (vals - lo) / (hi - lo)
        ax_x.barh(y + (k - 0.5) * 0.38, z, height=0.36, color=color,
                  label=f"{label}: {row['total_power [mW]']:.1f} mW, "
                        f"lift {row['lift [um]']:.0f} um, {row[TEMP]:.0f} °C")
        for yi, zi, v, n in zip(y, z, vals, names):
            ax_x.text(zi, yi + (k - 0.5) * 0.38, f" {v:.4g} {SHOW[n][0].split('[')[1][:-1]}",
                      va="center", fontsize="small")
    ax_x.set_yticks(y, [f"{n}\n[{l:.4g}, {h:.4g}]" for n, l, h in zip(names, lo, hi)])
    ax_x.set_xlim(0, 1.35)
    ax_x.invert_yaxis()
    ax_x.set_xlabel("position within the bounds [-] (0: lower, 1: upper)")
    ax_x.set_ylabel("design variable [bounds]")
    ax_x.set_title("start vs optimum")
    ax_x.legend(fontsize="small", loc="upper center", bbox_to_anchor=(0.5, -0.16))
    ax_x.grid(True, axis="x", alpha=0.3)

    ax_p.plot(cycles["cycle"], cycles["total_power [mW]"], "k-o", ms=4)
    ax_p.set_xlabel("cycle")
    ax_p.set_ylabel("total power for a 200 um lift [mW]")
    ax_p.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax_t = ax_p.twinx()
    ax_t.plot(cycles["cycle"], cycles[TEMP], "C3--", alpha=0.8)
    ax_t.set_ylabel("hottest crease, centre line [°C] (dashed)", color="C3")
    ax_t.tick_params(axis="y", colors="C3")
    mark_temperature_limit(ax_t)
    for _, c in cycles.iterrows():
        if isinstance(c["moved"], str) and c["moved"]:
            ax_p.annotate(c["moved"], (c["cycle"], c["total_power [mW]"]), fontsize="x-small",
                          xytext=(3, 4), textcoords="offset points")
    ax_p.set_title("coordinate descent (labels: moves of the cycle)")
    ax_p.grid(True, alpha=0.3)
    _note(fig)
    return fig


def plot(df: pd.DataFrame) -> dict:
    """``{"miura_design": lift per power vs parameters, "miura_design_optimum": ...}``."""
    grid = df[df["table"] == "grid"].copy()
    grid["success"] = grid["success"].astype(str).str.lower() == "true"
    return {NAME: _grid_figure(grid),
            f"{NAME}_optimum": _optimum_figure(df[df["table"] == "optimum"],
                                               df[df["table"] == "cycles"].sort_values("cycle"))}


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
