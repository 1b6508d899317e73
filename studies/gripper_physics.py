"""The gripper optimisation again with the calibration-free heat loss and the device physics
(issue 30, item 5: "re-run the gripper studies with the new physics").

Question
--------
The paper's coordinate descent (section 6.3; ``gripper_optimization``) shrinks the base panels,
lengthens the arms and widens the creases, lowering the power of the gripper's full function,
all judged with its chain heat loss, which the 3-D FE finds 37-80 % too cool on these shapes
(``device_heat_models``). Does the same descent, from the same start under the same
constraints, take the same path and reach the same design when the heat transfer is the
calibration-free integral loss (theory 4.7, on the sheet refined r = 2, theory 4.11), and when
the device physics of issue 30 is added at literature values (the crease's gold layer
conducting, k_Au 150 W/(m K), theory 4.10; the air's conductivity rising with temperature,
Incropera's table, and radiation from both faces, polymer emissivity 0.7, gold 0.03, theory
4.12)? And how does each optimum fare under the physics the others leave out?

Method
------
* Three settings of :class:`~design.GripperProblem` (bisect power search, objective = assembly
  + grip power per heated crease, constraints = the size bounds and a crease centre-line
  temperature of at most 1.2 T_g = 252 degC): ``paper`` (the chains, the paper setting; the
  run of ``gripper_optimization``), ``integral`` (``GripperDesign()``'s default heat loss) and
  ``physics`` (``integral`` with the physics above; nothing fitted to the measured devices).
  The electrical knobs of ``device_power_physics`` (leads, the heaters' temperature
  coefficient) do not change the heat balance and are left out: the objective is heat.
* Coordinate descent (``optimize(problem, "cd", max_cycles=15, parallel_candidates=True)``,
  the start W 200, La 700, L1 1000, L2 1000 um, steps 10 / 50 / 50 / 50 um) in each setting,
  on a 2-process executor.
* Cross evaluation: the start and the three optima, each evaluated (``evaluate_gripper``,
  bisect) under each setting.
* ``--quick``: serial, 3 evaluations per descent; of the cross evaluation the start and the
  paper's (short) optimum under ``physics``, the physics' under ``paper``.

Outputs (``results/gripper_physics/``)
--------------------------------------
``gripper_physics.csv``, the ``table`` column tells the row kind:

* ``cycles`` - one row per setting and cycle: ``setting``, ``cycle``, ``moved``, ``complete``,
  the design ``W [um]``, ``La [um]``, ``L1 [um]``, ``L2 [um]``, ``total_power [mW]``
  (objective), ``assembly_power [mW]``, ``grip_power [mW]``, ``temperature [degC]``,
  ``feasible``, ``evaluations`` (cumulative), ``message`` (the descent's, last row).
* ``cross`` - one row per design and setting: ``design`` (``start`` or the setting whose
  optimum it is), ``setting`` (the one it is evaluated under), the design (um),
  ``total_power [mW]`` (assembly + grip per heated crease), ``full_function_power [mW]`` (2 x
  (assembly + grip): both circuits at grip, ``gripper_optimization``'s measure),
  ``temperature [degC]`` (the hottest heated crease's centre line at its stage's power),
  ``success``, ``status``, ``message``.

Figure ``gripper_physics.png``: (a) the objective along each descent, (b) the designs, (c)
each optimum's full-function power under each setting.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import pandas as pd

from design import GripperProblem, make_executor, optimize
from design.devices.gripper import (GripperDesign, GripperHeatModel, evaluate_gripper,
                                    make_gripper_model)
from studies._common import progress_bar, study_main
from studies.gripper_optimization import (ASM, GRIP, POWER, TEMP, UM, VARIABLES, cycles_table,
                                          design_um)

__all__ = ["main", "plot", "run", "SETTINGS", "PHYSICS"]

logger = logging.getLogger(__name__)

NAME = "gripper_physics"
FULL = "full_function_power [mW]"
#: The device physics at central literature values (``device_power_physics``'s "all,
#: central" without the electrical knobs, which do not enter the heat balance).
PHYSICS = dict(crease_conduction="layers", k_gold=150.0, temperature_dependent_air=True,
               emissivity_polymer=0.7, emissivity_gold=0.03)
#: The heat model of each setting (the dimensions are the descent's).
SETTINGS = {"paper": GripperHeatModel(loss_model="chain"),
            "integral": GripperHeatModel(),
            "physics": GripperHeatModel(**PHYSICS)}
LABELS = {"paper": "paper setting (chains)", "integral": "integral loss",
          "physics": "integral loss + device physics"}
CD_OPTIONS = {"max_cycles": 15, "parallel_candidates": True}
CD_BUDGET_QUICK = 3
WORKERS = 2


def _descent(setting: str, quick: bool, progress: bool):
    """The coordinate descent under ``setting``: its result."""
    problem = GripperProblem(mode="bisect", heat=SETTINGS[setting])
    budget = CD_BUDGET_QUICK if quick else None
    bar = progress_bar(None, enabled=progress, desc=f"descent, {setting}", unit="eval",
                       total=budget or 1 + 8 * CD_OPTIONS["max_cycles"], leave=False)
    callback = (lambda ev: bar.update(1)) if progress else None
    try:
        with make_executor("serial" if quick else "process",
                           None if quick else WORKERS) as executor:
            return optimize(problem, "cd", executor=executor, max_evaluations=budget,
                            callback=callback, **CD_OPTIONS)
    finally:
        if progress:
            bar.close()


def _cycles(setting: str, result) -> pd.DataFrame:
    """Rows ``table = "cycles"`` of one descent: ``gripper_optimization``'s cycle rows with the
    setting in place of the method and the descent's message on its last row."""
    rows = cycles_table(result, math.nan).drop(columns=[
        "method", "temperature_limit [degC]", "last_candidate_temperature [degC]"])
    rows.insert(1, "setting", setting)
    rows["message"] = ""
    rows.loc[rows.index[-1], "message"] = result.message
    return rows


def _cross(design: str, x: dict, setting: str) -> dict:
    """One row ``table = "cross"``: the design ``x`` [m] evaluated under ``setting``."""
    res = evaluate_gripper(GripperDesign(**x), mode="bisect", heat=SETTINGS[setting])
    per = lambda p: math.nan if p is None else 1e3 * p          # noqa: E731
    a, g = per(res.assembly.power_per_crease), per(res.grip.power_per_crease)
    total = a + g if res.success else math.nan
    temps = [s.temperature for s in (res.assembly, res.grip) if s.temperature is not None]
    return {"table": "cross", "design": design, "setting": setting, **design_um(x),
            POWER: total, ASM: a, GRIP: g, FULL: 2 * total,
            TEMP: max(temps) if temps else math.nan, "success": res.success,
            "status": res.status, "message": res.message}


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """The three descents, then the cross evaluation; see the module docstring."""
    results = {s: _descent(s, quick, progress) for s in SETTINGS}
    for s, r in results.items():
        logger.info("descent %s: %s (%d evaluations) %s", s, r.status, r.n_evaluations,
                    {k: round(1e6 * v) for k, v in r.x.items()})
    start = {v: getattr(GripperDesign(), v) for v in VARIABLES}
    designs = {"start": start, **{s: dict(r.x) for s, r in results.items()}}
    tasks = [(d, s) for d in designs for s in SETTINGS]
    if quick:
        tasks = [("start", "physics"), ("paper", "physics"), ("physics", "paper")]
    cross = [_cross(d, designs[d], s)
             for d, s in progress_bar(tasks, enabled=progress, desc="cross evaluation",
                                      unit="eval", leave=False)]
    df = pd.concat([*(_cycles(s, r) for s, r in results.items()), pd.DataFrame(cross)],
                   ignore_index=True)
    first = ["table", "setting", "design", "cycle"]
    return df[first + [c for c in df.columns if c not in first]]


# ----------------------------------------------------------------------------- plot
def _footer() -> list[str]:
    from studies.figure_notes import heat_loss_note

    notes = [f"{s}: {heat_loss_note(make_gripper_model(GripperDesign(), heat=h)[0])}"
             for s, h in SETTINGS.items()]
    return ["objective: assembly + grip power per heated crease (bisect search); limit: centre-"
            "line mean of the hottest heated crease <= 1.2 T_g = 252 °C; size bounds of the "
            "paper; coordinate descent from W 200, La 700, L1 = L2 = 1000 um (steps 10 / 50 "
            "um), at most 15 cycles",
            "device physics: gold layer conducting (k_Au 150 W/(m K), theory 4.10), air k(T) "
            "(Incropera A.4) and radiation (polymer 0.7, gold 0.03; theory 4.12); nothing "
            "fitted to the measured devices; the paper's measured devices (29.8 / 21.6 mW near "
            "its cycles 4 / 9) are other designs: device_power_physics", *notes]


def plot(df: pd.DataFrame) -> dict:
    """``{"gripper_physics": figure}``."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    from studies.figure_notes import note_assumptions

    cycles, cross = df[df["table"] == "cycles"], df[df["table"] == "cross"]
    fig = Figure(figsize=(17, 5.6), layout="constrained")
    ax_p, ax_x, ax_c = fig.subplots(1, 3)
    colors = {"paper": "0.45", "integral": "C0", "physics": "C3", "start": "0.8"}
    for s in SETTINGS:
        c = cycles[cycles["setting"] == s].sort_values("cycle")
        if not len(c):
            continue
        p0, p1 = c[POWER].iloc[0], c[POWER].iloc[-1]
        ax_p.plot(c["cycle"], c[POWER], "-o", ms=4, color=colors[s],
                  label=f"{LABELS[s]}: {p0:.1f} -> {p1:.1f} mW ({100 * (1 - p1 / p0):.0f} % "
                        "less)")
    ax_p.set_xlabel("cycle")
    ax_p.set_ylabel("objective: assembly + grip power per heated crease [mW]")
    ax_p.set_ylim(bottom=0)
    ax_p.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax_p.set_title("(a) the descent in each setting, judged by its own model", fontsize="medium")
    ax_p.legend(fontsize="small", loc="lower left")

    names = ["start", *SETTINGS]
    final = {"start": cycles.sort_values("cycle").groupby("setting").first().iloc[0]}
    final.update({s: g.sort_values("cycle").iloc[-1] for s, g in cycles.groupby("setting")})
    width = 0.8 / len(names)
    for k, n in enumerate(n for n in names if n in final):
        ax_x.bar(np.arange(len(UM)) + (k - (len(names) - 1) / 2) * width,
                 [final[n][u] for u in UM], width, color=colors[n],
                 label="start" if n == "start" else f"optimum, {LABELS[n]}")
    ax_x.set_xticks(np.arange(len(UM)), VARIABLES)
    ax_x.set_ylabel("design variable [um]")
    ax_x.set_title("(b) the designs", fontsize="medium")
    ax_x.legend(fontsize="small")

    shown = [d for d in names if d in set(cross["design"])]
    settings = [s for s in SETTINGS if s in set(cross["setting"])]
    width = 0.8 / max(len(settings), 1)
    for k, s in enumerate(settings):
        rows = cross[cross["setting"] == s].set_index("design")
        vals = [rows[FULL].get(d, math.nan) for d in shown]
        bars = ax_c.bar(np.arange(len(shown)) + (k - (len(settings) - 1) / 2) * width, vals,
                        width, color=colors[s], label=f"evaluated with {LABELS[s]}")
        ax_c.bar_label(bars, fmt="%.1f", fontsize="x-small")
    ax_c.set_xticks(np.arange(len(shown)),
                    ["start" if d == "start" else f"optimum,\n{d}" for d in shown])
    ax_c.set_ylabel("full-function power: 2 x (assembly + grip) [mW]")
    ax_c.set_title("(c) each design under each setting", fontsize="medium")
    ax_c.legend(fontsize="small", loc="upper right")
    for ax in (ax_p, ax_x, ax_c):
        ax.grid(True, alpha=0.3)
    fig.suptitle("Gripper optimisation with the paper's chains, the calibration-free heat loss, "
                 "and the device physics")
    note_assumptions(fig, *_footer())
    return {NAME: fig}


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
