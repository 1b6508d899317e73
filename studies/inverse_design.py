"""Inverse design with exact gradients, gradient-based against derivative-free optimisation at
equal wall time (issue 32, item 4): (a) a Miura sheet's heater powers, (b) the gripper's
dimensions, crease widths and heater powers.

Question
--------
A Miura sheet of 8 x 8 cells (112 creases, each with its own heater) is to fold into a target
shape: every crease's fold angle within 0.5 deg of its target, every crease below 1.2 T_g
(252 degC, centre-line mean), with the least total heater power. With 112 design variables,
how far does a gradient method with exact adjoint gradients (:mod:`simulator.sensitivity`)
get, and how far a derivative-free method, in the same wall time?

Method
------
* Model: :func:`~design.devices.miura.make_miura_model` of ``MiuraDesign(cells_x=8,
  cells_y=8, substrate=False, loss_model="chain")`` (a = b = 1 mm, gamma 60 deg, W 200 um; in
  air, first column of panels clamped; the chain heat loss, the one the sensitivities
  differentiate). Every crease is heated by its own power: 112 variables in [0, 8] mW.
* Targets: the fold angles of a known design, the *reference* powers
  ``p_c = 1.5 + 3 (0.5 + 0.5 sin(2 pi x_c / L) cos(pi y_c / H))`` mW (``x_c, y_c`` the
  crease's midpoint, ``L, H`` the sheet's extent), every crease's (those in the clamped
  column have targets near 0): a feasible design exists, with the reference's total power.
* Problem: :class:`~design.devices.fold_shape.FoldShapeProblem` (objective the total power;
  two constraints per crease, ``|fold - target| <= 0.5 deg``, and one per crease, the
  temperature limit), each evaluation one settled heating from the flat sheet in 10
  increments with tight Newton tolerances. In 2 increments the Newton iteration from the
  flat sheet (a bifurcation point of the Miura mechanism) lands for some designs on another
  folding mode (uniform 2.7 mW per crease: fold errors of 24 deg against 2.3 deg in 5 or 10
  increments), which derails the optimisers; 10 increments cost no more time.
* Optimisers, from the same start (1 mW per crease: folds too small, infeasible) with the same wall-time budget
  (``FULL["budget"]`` = 600 s each, stopped by a callback after the first evaluation past it): NLopt's
  MMA (``"mma"``) with the exact gradients of the objective and of all 336 constraints (one
  factorisation of the coupled Jacobian per design), and NLopt's COBYLA (``"cobyla"``,
  derivative-free, constraints native), both with ``xtol_rel`` 1e-6, ``xtol_abs`` 1e-8 and
  ``ftol_rel`` 1e-10 (``OPTIONS``). *Best*: the least total power among the feasible
  evaluations so far.
* ``--quick``: 3 x 3 cells (12 variables, powers in [0, 6] mW, reference 1-3 mW, 5
  increments), 20 s each.

Case (b), the gripper (:mod:`studies._inverse_design_gripper`)
--------------------------------------------------------------
The paper's gripper (section 6.3) assembles (base fold past 90 deg) and grips (arm tips
closer than 100 um, the base heat kept on). With its dimensions La, L1, L2, a width per crease
(W_2, W_3, W_5, W_9, the bounds of W: 100-300 um) and a heater power per crease (base 2, 5
heating from the assembly on, arms 3, 9 added for the grip; 0-40 mW): 11 variables
(:class:`~design.devices.GripperInverseProblem`, chain heat loss). Objective: the total power
of the four heaters; constraints: the base fold >= 90 deg at the assembly state (scaled by
0.5 deg), the tips <= 100 um at the grip state (scaled by 1 um), every crease <= 252 degC
(centre-line mean) at both states. Each evaluation: one simulation (self-weight, a settled
heating of the base creases, one of the arm creases on top, 2 increments each, snaps of the
grip followed by arc length) whose two steady states are differentiated (MMA's gradients:
powers by the adjoint, sizes by :class:`~simulator.sensitivity.Geometry`). MMA against COBYLA
from the same start (GRIPPER_SPACE's start, widths 200 um, 20 mW per base and 4 mW per arm
crease: the base folds 65 deg, infeasible), ``gripper.FULL["budget"]`` = 600 s each, the
same NLopt tolerances. *Reference*: the paper's design with each stage's power per crease from
:func:`~design.devices.evaluate_gripper`'s bisection (chain loss), evaluated by the problem.
``--quick``: one width W (8 variables), 15 s each.

Outputs (``results/inverse_design/``)
-------------------------------------
``inverse_design.csv``: one long table; the ``case`` column tells the case (``a``, ``b``;
no column in results written before case (b): all ``a``), the ``table`` column the row kind:

* ``history`` - one row per evaluation: ``method``, ``evaluation``, ``wall_time [s]`` (since
  the run's start), ``total_power [mW]``, ``feasible``, ``max_fold_error [deg]``,
  ``max_temperature [degC]``, ``best_power [mW]`` (best feasible so far, empty before the
  first), ``status``.
* ``crease`` - one row per method and crease: ``crease``, ``feasible`` (of the design),
  ``x [um]`` (midpoint), ``reference_power [mW]``, ``power [mW]`` (the method's returned
  design: the best feasible one, else the least violating; for ``method = reference`` the
  reference), ``target [deg]``, ``fold [deg]``, ``fold_error [deg]``,
  ``temperature [degC]``.
* ``summary`` - one row per method (and the reference): ``total_power [mW]`` (best feasible,
  empty if none), ``max_violation [-]`` (largest normalised constraint of the returned
  design, 0 if feasible), ``design_power [mW]`` (the returned design's total power, feasible
  or not), ``simulations`` (evaluations computed), ``wall_time [s]``,
  ``max_fold_error [deg]``, ``max_temperature [degC]`` (of the returned design),
  ``variables``, ``cells`` (per side), ``success``
  (a feasible design was found), ``status``, ``message``.

Case (b) has ``history`` and ``summary`` rows with ``base_fold [deg]`` (assembly state),
``tip_distance [um]`` (grip state) and ``max_temperature [degC]`` (both) in place of the fold
error, and ``design`` rows, one per method and variable: ``variable``, ``feasible``, ``size
[um]`` (dimensions, widths) or ``power [mW]`` of the returned design.

``inverse_design.png``: best feasible total power vs wall time for both methods (every
evaluation faint, infeasible ones as crosses), the reference's power; the fold-angle errors
per crease of the returned designs against the 0.5 deg band; their powers per crease.
``inverse_design_gripper.png`` (case b): best feasible total power vs wall time, the
returned designs' dimensions and widths, and their powers.

Run: ``python -m studies.inverse_design`` (``--quick``: the coarse version). A run is not
resumable: the wall-time budget makes each run depend on the machine's speed.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pandas as pd

from studies import _inverse_design_gripper as gripper
from studies._common import progress_bar, study_main

NAME = "inverse_design"
FULL = {"cells": 8, "budget": 600.0, "max_power": 8e-3, "reference": (1.5e-3, 3e-3),
        "increments": 10}
QUICK = {"cells": 3, "budget": 20.0, "max_power": 6e-3, "reference": (1e-3, 2e-3),
         "increments": 5}
#: NLopt tolerances of both methods, tighter than the defaults: the budget, not a tolerance,
#: ends a run that has not converged.
OPTIONS = {"xtol_rel": 1e-6, "xtol_abs": 1e-8, "ftol_rel": 1e-10}
START_POWER = 1e-3                  # W per crease, both methods
TOLERANCE_DEG = 0.5
METHODS = ("mma", "cobyla")


def problem_setup(cells: int, max_power: float, reference: tuple):
    """``(model, reference powers {crease: W}, midpoints (C, 3) [m])`` of the sheet."""
    from design.devices import MiuraDesign, make_miura_model

    model = make_miura_model(MiuraDesign(cells_x=cells, cells_y=cells, substrate=False,
                                         loss_model="chain"))
    mesh = model.mesh
    mid = mesh.nodes[mesh.crease_nodes].mean(axis=1)                      # (C, 3)
    lo, span = mid.min(axis=0), np.ptp(mid, axis=0)
    s = (mid - lo) / np.where(span > 0, span, 1.0)
    shape = 0.5 + 0.5 * np.sin(2 * math.pi * s[:, 0]) * np.cos(math.pi * s[:, 1])
    base, amplitude = reference
    powers = {int(c): float(base + amplitude * f) for c, f in zip(mesh.crease_ids, shape)}
    return model, powers, mid


def make_problem(cells: int, max_power: float, reference: tuple, increments: int = 10):
    """``(FoldShapeProblem, reference evaluation, midpoints)``: targets from the reference."""
    from design.devices import FoldShapeProblem
    from simulator.sensitivity import FoldAngle

    model, powers, mid = problem_setup(cells, max_power, reference)
    probe = FoldShapeProblem(model, {model.mesh.crease_ids[0]: 0.0}, max_power=max_power,
                             heat_increments=increments)
    state = probe.simulate({f"power_{c}": p for c, p in powers.items()}).steps[-1].state
    targets = {c: FoldAngle(c).terms(model, state.u, state.temperature)[0] for c in powers}
    problem = FoldShapeProblem(model, targets, tolerance=math.radians(TOLERANCE_DEG),
                               max_power=max_power, start_power=START_POWER,
                               heat_increments=increments,
                               label=f"miura {cells}x{cells} in air, chain loss")
    ref = problem.evaluate({f"power_{c}": p for c, p in powers.items()})
    return problem, ref, mid


class _Clock:
    """Callback of :func:`design.optimize`: records each evaluation's wall time and stops
    the run after the first evaluation past ``budget`` seconds."""

    def __init__(self, budget: float):
        self.budget, self.t0, self.rows = budget, time.perf_counter(), []

    def __call__(self, ev):
        from design import StopOptimization

        self.rows.append((time.perf_counter() - self.t0, ev))
        if self.rows[-1][0] > self.budget:
            raise StopOptimization(f"wall-time budget {self.budget:g} s reached")

    def history(self, method: str, metrics) -> list:
        """The ``history`` rows of the evaluations recorded, ``metrics(ev) -> dict`` the
        columns of each besides the power and the best feasible power so far."""
        out, best = [], None
        for k, (t, ev) in enumerate(self.rows, 1):
            power = 1e3 * ev.objective if ev.success else None
            if ev.feasible and (best is None or power < best):
                best = power
            out.append({"table": "history", "method": method, "evaluation": k,
                        "wall_time [s]": t, "total_power [mW]": power,
                        "feasible": ev.feasible, **metrics(ev), "best_power [mW]": best,
                        "status": ev.status})
        return out


def _fold_metrics(ev) -> dict:
    return {"max_fold_error [deg]": ev.metrics.get("max fold error [deg]"),
            "max_temperature [degC]": ev.metrics.get("max temperature [degC]")}


def _creases(method: str, problem, ev, reference, mid) -> list:
    ref_x = {c: reference.x[f"power_{c}"] for c in problem.creases}
    rows = []
    for i, c in enumerate(problem.all_creases):
        fold = ev.metrics[f"fold_{c} [deg]"] if ev is not None else None
        target = math.degrees(problem.targets[c])
        rows.append({"table": "crease", "method": method, "crease": c,
                     "feasible": ev is not None and ev.feasible,
                     "x [um]": 1e6 * mid[i, 0], "reference_power [mW]": 1e3 * ref_x[c],
                     "power [mW]": None if ev is None else 1e3 * ev.x[f"power_{c}"],
                     "target [deg]": target, "fold [deg]": fold,
                     "fold_error [deg]": None if fold is None else fold - target,
                     "temperature [degC]": None if ev is None
                     else ev.metrics[f"temperature_{c} [degC]"]})
    return rows


def _summary(method, ev, simulations, wall_time, n, status, message, cells) -> dict:
    feasible = ev is not None and ev.feasible
    return {"table": "summary", "method": method, "cells": cells,
            "total_power [mW]": 1e3 * ev.objective if feasible else None,
            "max_violation [-]": None if ev is None or not ev.success else ev.max_violation,
            "design_power [mW]": None if ev is None or not ev.success else 1e3 * ev.objective,
            "simulations": simulations, "wall_time [s]": wall_time,
            "max_fold_error [deg]": None if ev is None else ev.metrics["max fold error [deg]"],
            "max_temperature [degC]": None if ev is None
            else ev.metrics["max temperature [degC]"], "variables": n,
            "success": feasible, "status": status, "message": message}


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """The reference, then each method under the wall-time budget; the long table above."""
    from design import optimize

    s = QUICK if quick else FULL
    t0 = time.perf_counter()
    problem, ref, mid = make_problem(s["cells"], s["max_power"], s["reference"],
                                     s["increments"])
    n = len(problem.creases)
    rows = [_summary("reference", ref, 1, time.perf_counter() - t0, n,
                     ref.status, "the design the targets were made from", s["cells"]),
            *_creases("reference", problem, ref, ref, mid)]
    for method in progress_bar(METHODS, progress, desc=NAME, unit="method"):
        clock = _Clock(s["budget"])
        res = optimize(problem, method, max_evaluations=100000, callback=clock, **OPTIONS)
        rows += clock.history(method, _fold_metrics)
        rows += _creases(method, problem, res.best, ref, mid)
        rows.append(_summary(method, res.best, res.n_computed, res.wall_time, n, res.status,
                             res.message, s["cells"]))
    rows = [{"case": "a", **r} for r in rows]
    rows += gripper.run_case(quick, METHODS, _Clock, OPTIONS, progress_bar, progress)
    return pd.DataFrame(rows)


def plot(df: pd.DataFrame) -> dict:
    """Case (a): best feasible power vs wall time, final fold errors, and the powers per
    crease; case (b) (``inverse_design_gripper``, where the table has it): the gripper's."""
    case = df["case"] if "case" in df else pd.Series("a", index=df.index)
    figs = {NAME: _plot_miura(df[case == "a"])}
    if (case == "b").any():
        figs[f"{NAME}_gripper"] = gripper.plot_case(df[case == "b"], METHODS)
    return figs


def _plot_miura(df: pd.DataFrame):
    from matplotlib.figure import Figure

    from studies.figure_notes import environment_note, heat_loss_note, note_assumptions

    hist, crease = df[df["table"] == "history"], df[df["table"] == "crease"]
    summ = df[df["table"] == "summary"].set_index("method")
    fig = Figure(figsize=(14, 4.8), layout="constrained")
    ax_t, ax_e, ax_p = fig.subplots(1, 3)
    ref_power = summ.loc["reference", "total_power [mW]"]
    colors = {"mma": "C0", "cobyla": "C1", "reference": "0.4"}
    for method in METHODS:
        h = hist[hist["method"] == method]
        if h.empty:
            continue
        gripper.plot_evaluations(ax_t, h, colors[method])
        row = summ.loc[method]
        best = row["total_power [mW]"]
        ax_t.step(h["wall_time [s]"], h["best_power [mW]"], where="post",
                  color=colors[method], lw=2,
                  label=f"{method}: best {best:.1f} mW, {int(row['simulations'])} simulations"
                  if pd.notna(best) else f"{method}: no feasible design in "
                  f"{int(row['simulations'])} simulations\n(least violating: "
                  f"{row['design_power [mW]']:.1f} mW, g = {row['max_violation [-]']:.1g})")
    ax_t.axhline(ref_power, color="0.4", ls="--", label=f"reference {ref_power:.1f} mW")
    ax_t.set_xlabel("wall time [s]")
    ax_t.set_ylabel("total heater power [mW]")
    ax_t.set_title("best feasible power (dots: feasible, x: infeasible evaluations)",
                   fontsize="medium")
    ax_t.legend(fontsize="x-small", loc="center right")
    ax_t.grid(True, alpha=0.3)
    for method in METHODS:
        c = crease[crease["method"] == method].dropna(subset=["fold_error [deg]"])
        if c.empty:
            continue
        feasible = str(c["feasible"].iloc[0]).lower() == "true"
        label = method if feasible else f"{method} (least violating: no feasible design)"
        marker = "o" if feasible else "x"
        ax_e.plot(c["crease"], c["fold_error [deg]"], marker, ms=3, color=colors[method],
                  label=label)
        ax_p.plot(c["crease"], c["power [mW]"], marker, ms=3, color=colors[method],
                  label=label)
    ax_e.axhspan(-TOLERANCE_DEG, TOLERANCE_DEG, color="g", alpha=0.12,
                 label=f"|error| <= {TOLERANCE_DEG} deg")
    ax_e.set_xlabel("crease")
    ax_e.set_ylabel("fold angle - target [deg]")
    ax_e.set_title("fold-angle errors of the returned designs", fontsize="medium")
    ax_e.legend(fontsize="small")
    ax_e.grid(True, alpha=0.3)
    r = crease[crease["method"] == "reference"]
    ax_p.plot(r["crease"], r["reference_power [mW]"], "_", color="0.3", ms=6,
              label="reference")
    ax_p.set_xlabel("crease")
    ax_p.set_ylabel("heater power [mW]")
    ax_p.set_title("powers of the returned designs", fontsize="medium")
    ax_p.legend(fontsize="small")
    ax_p.grid(True, alpha=0.3)
    cells = int(summ["cells"].iloc[0])
    model = problem_setup(cells, FULL["max_power"], FULL["reference"])[0]
    note_assumptions(fig, environment_note("air", extra=[
        f"Miura {cells} x {cells} cells, first column clamped, no substrate",
        "temperature limit 1.2 T_g = 252 degC on every crease (centre-line mean)"]),
        heat_loss_note(model))
    return fig


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
