"""Pattern robustness: does a crease pattern drawn by hand fold the same at any step count?

Question
--------
A flat sheet whose creases are heated together starts at a bifurcation (theory 6.12): load
control used to stay on the symmetric, unstable, nearly flat state while its increments were
small and to land on some folded branch when they were not, so the fold reached depended on
``thermal_steps``, and nothing said so. With every accepted state checked and an unstable one
left along its critical mode (``NewtonOptions(stability="switch")``, the default), do classic
patterns now give one answer, stable, at every step count, and at what cost?

Method
------
Six patterns drawn as plain FOLD crease patterns (``studies/_classic_patterns.py``, files in
``studies/patterns/``): the waterbomb base, the square twist, a Miura vertex, a 3 x 3 Miura-ori
sheet, a Huffman-style triangulated tessellation and the traditional flapping bird. Each is
heated on every crease as ``etorigami run FILE --heat all --power P`` does: the paper's SU-8/Au
layer stack (``su8-au``: 200 um creases, 10 um panels), the chain heat loss in air
(t_env = 1 mm, k = 0.026 W/(m K)), the central panel clamped, no gravity, panel contact on (the
plain patterns' default), at three powers per crease (``POWERS_MW``) and ``thermal_steps`` in
{25, 50, 100, 200, 400} with the stability check and branch switch (default), and at 25 and 200
without it (``stability="off"``, the behaviour before). Spread = the largest difference of a
crease's final fold angle between step counts, per pattern, power and setting.
``--quick``: the top power only, 25 and 50 steps, default setting only.

Outputs (``results/pattern_robustness/``)
------------------------------------------
``pattern_robustness.csv``: one row per run: ``pattern``, ``power [mW]`` (per crease),
``thermal_steps``, ``stability`` ("switch" or "off"), ``status``, ``success``, ``stable`` (the
final state's check; empty where not checked), ``events`` (kinds, ";"-joined),
``branch_switches``, ``fold_max [deg]`` (largest |final fold angle|), ``spread [deg]`` (over
the step counts of its pattern, power and setting), ``wall_time [s]``, and ``folds [deg]``
(the final fold angle of every crease, ";"-joined in crease-id order).
Figure ``pattern_robustness.png``: (a) the largest final |fold angle| at 200 steps with and
without the check, (b) the spread against power, per pattern (1 deg line), (c) wall time per
run against ``thermal_steps`` (default setting).
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from simulator import Heat, NewtonOptions, simulate
from simulator.fold import parse_fold
from simulator.model import get_stack, stack_model
from studies._classic_patterns import PATTERNS, POWERS_MW
from studies._common import progress_bar, study_main

NAME = "pattern_robustness"
STEPS = (25, 50, 100, 200, 400)
QUICK_STEPS, OFF_STEPS = (25, 50), (25, 200)
SETTINGS = ("switch", "off")
POWER, SPREAD, FOLDS, WALL = "power [mW]", "spread [deg]", "folds [deg]", "wall_time [s]"


def heated_model(fold: dict):
    """(model, heated crease ids) of a plain FOLD dict, built as ``etorigami run --heat all``
    builds it (layer stack ``su8-au``, central panel clamped, panel contact on)."""
    stack = get_stack("su8-au")
    geo = parse_fold(fold, crease_width=stack.crease_width,
                     crease_thickness=stack.crease_thickness,
                     panel_thickness=stack.panel_thickness)
    heated = geo.pattern.creases.tolist()
    return stack_model(geo.pattern, stack, heated, loss_model="chain"), heated


def heat(model, heated, power_mw: float, steps: int, stability: str = "switch"):
    """(SimulationResult, wall time [s]) of every crease heated to ``power_mw`` per crease."""
    t0 = time.perf_counter()
    res = simulate(model, [Heat({c: 1e-3 * power_mw for c in heated}, increments=steps,
                                coupling="staggered")],
                   options=NewtonOptions(stability=stability))
    return res, time.perf_counter() - t0


def _row(name, power, steps, stability, res, wall) -> dict:
    folds = np.degrees(res.fold_angle[-1]) if len(res.fold_angle) else np.zeros(0)
    kinds = [e.kind for e in res.events]
    return {"pattern": name, POWER: power, "thermal_steps": steps, "stability": stability,
            "status": res.status, "success": res.success, "stable": res.stable,
            "events": ";".join(kinds), "branch_switches": kinds.count("branch_switch"),
            "fold_max [deg]": float(np.abs(folds).max(initial=0.0)), WALL: wall,
            FOLDS: ";".join(f"{a:.6f}" for a in folds)}


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """One row per (pattern, power, thermal_steps, stability setting)."""
    cases = [(name, p, n, s) for name in PATTERNS
             for p in (POWERS_MW[name][-1:] if quick else POWERS_MW[name])
             for s in (SETTINGS[:1] if quick else SETTINGS)
             for n in (QUICK_STEPS if quick else STEPS if s == "switch" else OFF_STEPS)]
    models, rows = {}, []
    for name, p, n, s in progress_bar(cases, progress, desc=NAME, unit="run"):
        if name not in models:
            models[name] = heated_model(PATTERNS[name]())
        res, wall = heat(*models[name], p, n, s)
        rows.append(_row(name, p, n, s, res, wall))
    return with_spread(pd.DataFrame(rows))


def with_spread(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` with ``spread [deg]``: per pattern, power and setting, the largest difference of
    a crease's final fold angle between the step counts (runs that ended early included)."""
    df = df.copy()
    df[SPREAD] = np.nan
    for _, d in df.groupby(["pattern", POWER, "stability"]):
        folds = [np.array([float(x) for x in str(f).split(";") if x != ""]) for f in d[FOLDS]]
        if len({len(f) for f in folds}) == 1 and len(folds[0]):
            df.loc[d.index, SPREAD] = float(np.ptp(np.array(folds), axis=0).max())
    return df


def plot(df: pd.DataFrame):
    """(a) largest final |fold| at 200 steps with and without the check; (b) spread across step
    counts against power; (c) wall time per run against thermal_steps (default check)."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    from studies.plotting import environment_note, note_assumptions

    fig = Figure(figsize=(13.5, 5.4), layout="constrained")
    ax_f, ax_s, ax_t = fig.subplots(1, 3)
    patterns = list(dict.fromkeys(df["pattern"]))
    floor, handles = 1e-6, []
    for k, name in enumerate(patterns):
        d, label, c = df[df["pattern"] == name], name.replace("_", " "), f"C{k}"
        for setting, marker, fill, ls in (("switch", "o", c, "-"), ("off", "s", "none", ":")):
            e = d[d["stability"] == setting]
            f = e[e["thermal_steps"] == 200].groupby(POWER)["fold_max [deg]"].first()
            g = e.groupby(POWER)[SPREAD].first()
            if len(f):
                ax_f.plot(f.index, f.to_numpy(float), marker=marker, color=c, mfc=fill, ls=ls)
            if len(g):
                ax_s.plot(g.index, np.maximum(g.to_numpy(float), floor), marker=marker,
                          color=c, mfc=fill, ls=ls)
        t = d[d["stability"] == "switch"].groupby("thermal_steps")[WALL].mean()
        handles += ax_t.plot(t.index, t.to_numpy(float), marker="o", color=c, label=label)
    ax_s.axhline(1.0, color="0.3", lw=1, ls="--")
    ax_s.annotate("1 deg", (0.02, 1.0), xycoords=("axes fraction", "data"), va="bottom",
                  color="0.3", fontsize="small")
    ax_s.set_yscale("log")
    ax_f.set_ylabel("largest final |fold angle| at 200 steps [deg]")
    ax_f.set_title("(a) how far it folds")
    ax_s.set_ylabel(f"fold-angle spread over the step counts [deg] (>= {floor:g})")
    ax_s.set_title("(b) one answer at any step count?")
    for ax in (ax_f, ax_s):
        ax.set_xlabel("power per crease [mW]")
    steps = sorted(set(df["thermal_steps"]))
    ax_t.set_xscale("log")
    ax_t.set_yscale("log")
    ax_t.set_xticks(steps)
    ax_t.xaxis.set_major_formatter(ScalarFormatter())
    ax_t.xaxis.set_minor_formatter(NullFormatter())
    ax_t.set_xlabel("thermal_steps")
    ax_t.set_ylabel("wall time per run [s] (mean over the powers)")
    ax_t.set_title("(c) cost of a run (default check)")
    for ax in (ax_f, ax_s, ax_t):
        ax.grid(True, alpha=0.3, which="both")
    from matplotlib.lines import Line2D
    kinds = [Line2D([], [], color="0.3", marker="o", ls="-", label="default check (switch)"),
             Line2D([], [], color="0.3", marker="s", mfc="none", ls=":",
                    label="check off (before; 25 and 200 steps)")]
    ax_f.legend(handles=kinds, fontsize="x-small", loc="upper left")
    ax_t.legend(handles=handles, fontsize="x-small", loc="upper left")
    note_assumptions(fig, environment_note(
        "air", 0.026, gravity=0, extra=["heat loss: chain model (t_env = 1 mm, as the su8-au "
                                         "stack), SU-8/Au stack, 200 um creases, central panel "
                                         "clamped, panel contact on"]),
        f"every crease heated to the power; thermal_steps {', '.join(map(str, steps))}; "
        "check off = NewtonOptions(stability='off'), the behaviour before issue 28; wall "
        "times on a shared 2-core machine (indicative)")
    return fig


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
