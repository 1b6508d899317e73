"""Minimum-power heater allocation: which power on which crease gives a wanted shape?

Question
--------
The paper powers its crane with hand-picked multiples of a base power (0.5 q ... 4 q, 112 mW
in all at q = 4 mW). Given only the shape, can the powers be found again, on one heater per
crease and on the paper's five power classes as five circuits? How wrong is a design that
ignores that folding changes the heat loss and that creases meeting at a vertex move
together (one linear programme at the flat shape)? And how much power does a tolerance on
the fold angles save (double fold)?

Method
------
* Crane (``get_case("crane")``, 100 heating increments): the 17 final fold angles are the
  targets. :func:`design.analysis.heaters.allocate_heaters` (LP about the current state through the
  thermal influence matrices and the mechanical fold sensitivity, alternated with heating
  simulations of 50 increments, trust region on the powers, targets within 0.5 deg, the
  centre-line mean of every crease below 1.2 T_g = 252 degC: the documented measure of the
  limit, theory 5.4, as in every design problem and figure) with

  - ``per-crease heaters``: 17 independent heaters;
  - ``paper circuits``: the paper's power classes as 5 circuits (4 q: creases 1, 18;
    1.5 q: 3, 5, 14, 15; 2 q: 7, 8, 10, 12; q: 6, 9, 11, 13, 21; q / 2: 17, 19, reference
    numbering);
  - ``flat-shape LP``: :func:`design.analysis.heaters.linear_allocation`, one LP at the flat shape,
    then one heating simulation with its powers (no coupling rounds).

* Double fold (``get_case("double_fold")`` at 6 mW per crease, 30 increments, gravity): its
  two fold angles as targets, two heaters, tolerance band 0, 1, ..., 5 deg (``--quick``:
  0 and 3 deg).

Crease ids: ``crease`` is our edge id, ``crease_ref`` = edge id + 1 the paper's numbering.

Outputs (``results/heater_allocation/``)
---------------------------------------
``heater_allocation.csv``, the ``table`` column tells the row kind:

* ``summary`` - one row per run: ``case``, ``variant``, ``band [deg]``, ``success``
  (targets met; flat-shape LP: its heating simulation converged), ``status``,
  ``rounds``, ``total_power [mW]`` (empty if no round was simulated),
  ``reference_power [mW]`` (the powers that made the shape), ``worst_fold_error [deg]``,
  ``limit_temperature [degC]`` (what the 1.2 T_g limit bounds: the centre-line mean of the
  hottest crease, ``temperature_measure`` "centre_line"), ``max_crease_temperature [degC]``
  (the hottest crease node, shown beside it), ``temperature_measure``, ``wall_time [s]``,
  ``message``.
* ``crease`` - one row per run and crease: ``crease``, ``crease_ref``, ``heater``,
  ``power [mW]``, ``reference_power [mW]``, ``target_fold [deg]``, ``fold_angle [deg]``.
* ``rounds`` - every round of every run: ``round``, ``total_power [mW]``,
  ``worst_fold_error [deg]``, ``model_miss [deg]``, ``limit_temperature [degC]``,
  ``max_crease_temperature [degC]``.

Figure ``heater_allocation.png``: (a) crane powers per crease (reference, per-crease
heaters, paper circuits); (b) crane fold error per crease of the flat-shape LP and of the
allocation; (c) double fold total power vs tolerance band. Its footer names the measure the
allocation bounds and the hottest crease of the runs by it and by its hottest node.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pandas as pd

from design import HeaterAllocation, allocate_heaters
from design.analysis import linear_allocation
from simulator.cases import get_case
from simulator import Heat, simulate
from studies._common import progress_bar, study_main

NAME = "heater_allocation"
CRANE_STEPS, CRANE_STEPS_QUICK = 100, 40
INCREMENTS, INCREMENTS_QUICK = 50, 20
DOUBLE_FOLD_POWER_MW = 6.0
BANDS_DEG, BANDS_DEG_QUICK = (0, 1, 2, 3, 4, 5), (0, 3)
#: The paper's crane power classes (reference crease numbers) as circuits.
PAPER_CIRCUITS = {"4 q": (1, 18), "1.5 q": (3, 5, 14, 15), "2 q": (7, 8, 10, 12),
                  "q": (6, 9, 11, 13, 21), "q / 2": (17, 19)}


def _targets(case):
    """Fold angles [rad] the case reaches, per heated crease, and the powers that did it."""
    res = simulate(case.model, case.steps)
    if not res.success:
        raise RuntimeError(f"{case.name}: {res.message}")
    mesh, heat = case.model.mesh, case.steps[-1]
    power = {c: float(v) for k, v in dict(heat.power).items()
             for c in (k if isinstance(k, tuple) else (k,))}
    fold = res.fold_angle[-1]
    start = simulate(case.model, case.steps[:-1]).state if len(case.steps) > 1 else None
    return {c: float(fold[mesh.crease_row_of(c)]) for c in sorted(power)}, power, start


def _rows(case_name, variant, band, res, reference, targets, wall, achieved=None, power=None,
          heater_of=None):
    """Summary, crease and round rows of one run."""
    alloc = isinstance(res, HeaterAllocation)
    achieved = res.achieved if achieved is None else achieved
    power = res.power_by_crease() if power is None else power
    heater_of = heater_of or {c: n for n, cs in res.heaters.items() for c in cs}
    err = max(abs(achieved[c] - t) for c, t in targets.items()) if achieved else math.nan
    label = {"case": case_name, "variant": variant, "band [deg]": band}
    unheated = 0.0 if power else math.nan                    # no round simulated: unknown
    summary = {"table": "summary", **label, "success": bool(res.success),
               "status": res.status if alloc else
               ("simulated" if res.success else "failed"),
               "rounds": res.rounds if alloc else 1,
               "total_power [mW]": 1e3 * sum(power.values()) if power else math.nan,
               "reference_power [mW]": 1e3 * sum(reference.values()),
               "worst_fold_error [deg]": math.degrees(err),
               "limit_temperature [degC]": res.max_temperature if alloc else
               float(res.crease_temperature_centre_line[-1].max()),
               "max_crease_temperature [degC]": res.max_node_temperature if alloc else
               float(res.crease_temperature_max[-1].max()),
               "temperature_measure": res.temperature_measure if alloc else "centre_line",
               "wall_time [s]": wall, "message": res.message}
    creases = [{"table": "crease", **label, "crease": c, "crease_ref": c + 1,
                "heater": heater_of.get(c, ""), "power [mW]": 1e3 * power.get(c, unheated),
                "reference_power [mW]": 1e3 * reference.get(c, 0.0),
                "target_fold [deg]": math.degrees(t),
                "fold_angle [deg]": math.degrees(achieved[c]) if achieved else math.nan}
               for c, t in targets.items()]
    rounds = [{"table": "rounds", **label, **h} for h in (res.history if alloc else [])]
    return [summary] + creases + rounds


def _flat_lp(case, targets, reference, increments):
    """One LP at the flat shape, then heating with its powers."""
    t0 = time.perf_counter()
    heaters = {f"crease {c}": (c,) for c in targets}
    p = linear_allocation(case.model, targets, heaters=heaters)
    power = dict(zip(targets, map(float, p)))
    res = simulate(case.model, [Heat(power, increments=increments, coupling="staggered")])
    mesh = case.model.mesh
    fold = res.fold_angle[-1]
    achieved = {c: float(fold[mesh.crease_row_of(c)]) for c in targets}
    return _rows(case.name, "flat-shape LP", 0, res, reference, targets,
                 time.perf_counter() - t0, achieved, power,
                 {c: f"crease {c}" for c in targets})


def crane_rows(quick: bool, bar) -> list:
    case = get_case("crane", thermal_steps=CRANE_STEPS_QUICK if quick else CRANE_STEPS)
    targets, reference, _ = _targets(case)
    inc = INCREMENTS_QUICK if quick else INCREMENTS
    rows = []
    circuits = {name: tuple(r - 1 for r in refs) for name, refs in PAPER_CIRCUITS.items()}
    for variant, heaters in (("per-crease heaters", None), ("paper circuits", circuits)):
        t0 = time.perf_counter()
        res = allocate_heaters(case.model, targets, heaters=heaters, increments=inc,
                               coupling="staggered")              # the paper setting
        rows += _rows("crane", variant, 0, res, reference, targets, time.perf_counter() - t0)
        bar.update()
    rows += _flat_lp(case, targets, reference, inc)
    bar.update()
    return rows


def double_fold_rows(quick: bool, bar) -> list:
    case = get_case("double_fold", power_mW=DOUBLE_FOLD_POWER_MW, thermal_steps=30)
    targets, reference, start = _targets(case)
    rows = []
    for band in (BANDS_DEG_QUICK if quick else BANDS_DEG):
        t0 = time.perf_counter()
        res = allocate_heaters(case.model, targets, state=start, band=math.radians(band),
                               increments=30, coupling="staggered")
        rows += _rows("double_fold", "per-crease heaters", band, res, reference, targets,
                      time.perf_counter() - t0)
        bar.update()
    return rows


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Crane inverse design (three variants) and the double fold's tolerance sweep."""
    total = 3 + len(BANDS_DEG_QUICK if quick else BANDS_DEG)
    bar = progress_bar(None, enabled=progress, total=total, desc=NAME, unit="run")
    bar = bar if progress else _NoBar()
    rows = crane_rows(quick, bar) + double_fold_rows(quick, bar)
    if progress:
        bar.close()
    return pd.DataFrame(rows)


class _NoBar:
    def update(self, n=1):
        pass


def plot(df: pd.DataFrame):
    """The three panels described in the module docstring."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(13, 4.6), layout="constrained")
    ax_p, ax_e, ax_b = fig.subplots(1, 3, gridspec_kw={"width_ratios": [2.2, 2.2, 1]})
    cr = df[(df["table"] == "crease") & (df["case"] == "crane")]
    refs = np.sort(cr["crease_ref"].unique())
    pos = np.arange(len(refs))
    first = cr[cr["variant"] == "per-crease heaters"].set_index("crease_ref").loc[refs]
    bars = [("reference (paper)", first["reference_power [mW]"], "0.6")]
    for k, variant in enumerate(("per-crease heaters", "paper circuits")):
        d = cr[cr["variant"] == variant].set_index("crease_ref").loc[refs]
        bars.append((variant, d["power [mW]"], f"C{k}"))
    for k, (label, values, color) in enumerate(bars):
        ax_p.bar(pos + (k - 1) * 0.27, values, width=0.27, color=color, label=label)
    ax_p.set_xticks(pos, [str(int(r)) for r in refs])
    ax_p.set_xlabel("crease (paper numbering)")
    ax_p.set_ylabel("power [mW]")
    ax_p.set_title("(a) crane: powers that give the paper's shape")
    ax_p.legend(fontsize="small")
    for k, variant in enumerate(("flat-shape LP", "per-crease heaters")):
        d = cr[cr["variant"] == variant].set_index("crease_ref").loc[refs]
        ax_e.bar(pos + (k - 0.5) * 0.4, d["fold_angle [deg]"] - d["target_fold [deg]"],
                 width=0.4, color=("C3", "C0")[k], label=variant)
    ax_e.axhline(0, color="k", lw=0.8)
    ax_e.set_xticks(pos, [str(int(r)) for r in refs])
    ax_e.set_xlabel("crease (paper numbering)")
    ax_e.set_ylabel("fold angle - target [deg]")
    ax_e.set_title("(b) crane: one LP at the flat shape vs coupled rounds")
    ax_e.legend(fontsize="small")
    s = df[(df["table"] == "summary") & (df["case"] == "double_fold")]
    ax_b.plot(s["band [deg]"], s["total_power [mW]"], "o-")
    ax_b.axhline(s["reference_power [mW]"].iloc[0], color="0.5", ls="--", label="reference")
    ax_b.set_xlabel("tolerance band [deg]")
    ax_b.set_ylabel("total power [mW]")
    ax_b.set_title("(c) double fold")
    ax_b.legend(fontsize="small")
    for ax in (ax_p, ax_e, ax_b):
        ax.grid(True, alpha=0.3)
    from studies.plotting import environment_note, heat_loss_note, note_assumptions

    note_assumptions(fig, "crane: " + environment_note("air", 0.026, 0, 0) + "; "
                     + heat_loss_note(get_case("crane").model) + ". double fold: "
                     + environment_note("air", 0.026, 0, 0.9) + "; "
                     + heat_loss_note(get_case("double_fold").model), _limit_note(df))
    return fig


def _limit_note(df: pd.DataFrame) -> str:
    """The footer line on the temperature limit: what it bounds and the hottest crease of the
    allocations (by that measure and by its hottest node)."""
    from studies.plotting import T_LIMIT

    s = df[df["table"] == "summary"]
    line = (f"Temperature bound of the allocation: the centre-line mean (nodes A, B, Ctr) of "
            f"every crease <= 1.2 T_g = {T_LIMIT:.0f} °C, the measure of every design problem "
            "and figure (theory 5.4)")
    if "limit_temperature [degC]" not in s:
        return line + "."
    flat = s["variant"] == "flat-shape LP"
    for what, rows in (("the allocations", s[~flat]), ("the flat-shape LP", s[flat])):
        if rows["limit_temperature [degC]"].notna().any():
            line += (f"; hottest crease of {what} {rows['limit_temperature [degC]'].max():.0f} °C"
                     f" (centre line), hottest node "
                     f"{rows['max_crease_temperature [degC]'].max():.0f} °C")
    return line + "."


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
