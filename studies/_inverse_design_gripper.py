"""Case (b) of the study ``inverse_design``: the gripper's dimensions, crease widths and heater
powers (:class:`~design.devices.GripperInverseProblem`), gradient-based against
derivative-free at equal wall time. Rows of the study's long table with ``case = "b"``; the
figure ``inverse_design_gripper``. See :mod:`studies.inverse_design` for the question and
the outputs."""

from __future__ import annotations

import time

import pandas as pd

FULL = {"widths": True, "budget": 600.0, "increments": 2}
QUICK = {"widths": False, "budget": 15.0, "increments": 2}
#: The paper's design (GRIPPER_SPACE's start) with each stage's power per crease from
#: evaluate_gripper's bisection (chain loss): the per-crease powers of the reference row.
REFERENCE = "paper design, evaluate_gripper's powers"


def _reference(problem) -> tuple:
    """``(values, evaluation)``: the paper's design heated as evaluate_gripper finds."""
    from design.devices import evaluate_gripper
    from design.devices.gripper_heat import GripperHeatModel

    values = problem.space.to_mapping([v.start for v in problem.space.variables])
    res = evaluate_gripper(problem.design(values), heat=GripperHeatModel(loss_model="chain"))
    if res.success:
        values.update({f"power_{c}": res.assembly.power_per_crease for c in (2, 5)})
        values.update({f"power_{c}": res.grip.power_per_crease for c in (3, 9)})
    return values, problem.evaluate(values)


def _metrics(ev) -> dict:
    m = ev.metrics if ev is not None else {}
    return {"base_fold [deg]": m.get("base_fold [deg]"),
            "tip_distance [um]": m.get("tip_distance [um]"),
            "max_temperature [degC]": m.get("max temperature [degC]")}


def _design(method: str, problem, ev) -> list:
    """One row per variable of the returned design: ``size [um]`` or ``power [mW]``."""
    rows = []
    for v in problem.space.variables:
        power = v.name.startswith("power_")
        value = None if ev is None else ev.x[v.name]
        rows.append({"case": "b", "table": "design", "method": method, "variable": v.name,
                     "feasible": ev is not None and ev.feasible,
                     "size [um]": None if power or value is None else 1e6 * value,
                     "power [mW]": None if not power or value is None else 1e3 * value})
    return rows


def _summary(method, ev, simulations, wall_time, n, status, message) -> dict:
    feasible = ev is not None and ev.feasible
    done = ev is not None and ev.success
    return {"case": "b", "table": "summary", "method": method,
            "total_power [mW]": 1e3 * ev.objective if feasible else None,
            "max_violation [-]": ev.max_violation if done else None,
            "design_power [mW]": 1e3 * ev.objective if done else None,
            "simulations": simulations, "wall_time [s]": wall_time, **_metrics(ev),
            "variables": n, "success": feasible, "status": status, "message": message}


def run_case(quick: bool, methods, clock, options, progress_bar, progress: bool) -> list:
    """The reference, then each of ``methods`` under the budget (``clock(budget)`` the
    callback that stops a run); the case's rows."""
    from design import optimize
    from design.devices import GripperInverseProblem

    s = QUICK if quick else FULL
    t0 = time.perf_counter()
    problem = GripperInverseProblem(widths=s["widths"], heat_increments=s["increments"])
    n = len(problem.space)
    _, ref = _reference(problem)
    rows = [_summary("reference", ref, 1, time.perf_counter() - t0, n, ref.status, REFERENCE),
            *_design("reference", problem, ref)]
    for method in progress_bar(methods, progress, desc="inverse_design (b)", unit="method"):
        c = clock(s["budget"])
        res = optimize(problem, method, max_evaluations=100000, callback=c, **options)
        rows += [{"case": "b", **r} for r in c.history(method, _metrics)]
        rows += _design(method, problem, res.best)
        rows.append(_summary(method, res.best, res.n_computed, res.wall_time, n, res.status,
                             res.message))
    return rows


def plot_evaluations(ax, h: pd.DataFrame, color) -> None:
    """Every evaluation of a run's ``history`` rows: its power against the wall time, a dot
    where feasible, a cross where not."""
    feas = h["feasible"].astype(str).str.lower() == "true"
    for mask, marker in ((feas, "."), (~feas, "x")):
        ax.plot(h["wall_time [s]"][mask], h["total_power [mW]"][mask], marker, color=color,
                alpha=0.3, ms=4)


def plot_case(df: pd.DataFrame, methods):
    """Best feasible total power vs wall time; the returned designs' sizes and powers."""
    from matplotlib.figure import Figure

    from design.devices import GripperDesign, make_gripper_model
    from design.devices.gripper_heat import GripperHeatModel
    from studies.figure_notes import environment_note, heat_loss_note, note_assumptions

    hist, design = df[df["table"] == "history"], df[df["table"] == "design"]
    summ = df[df["table"] == "summary"].set_index("method")
    fig = Figure(figsize=(14, 4.8), layout="constrained")
    ax_t, ax_s, ax_p = fig.subplots(1, 3)
    colors = {"mma": "C0", "cobyla": "C1", "reference": "0.4"}
    for method in methods:
        h = hist[hist["method"] == method]
        if h.empty:
            continue
        plot_evaluations(ax_t, h, colors[method])
        row = summ.loc[method]
        best = row["total_power [mW]"]
        ax_t.step(h["wall_time [s]"], h["best_power [mW]"], where="post", color=colors[method],
                  lw=2, label=f"{method}: best {best:.2f} mW, {int(row['simulations'])} "
                  "simulations" if pd.notna(best) else f"{method}: no feasible design in "
                  f"{int(row['simulations'])} simulations")
    ref = summ.loc["reference"] if "reference" in summ.index else None
    if ref is not None and pd.notna(ref["design_power [mW]"]):
        ax_t.axhline(ref["design_power [mW]"], color="0.4", ls="--",
                     label=f"paper design, power search: {ref['design_power [mW]']:.2f} mW"
                     + ("" if str(ref["success"]).lower() == "true" else " (infeasible)"))
    ax_t.set_xlabel("wall time [s]")
    ax_t.set_ylabel("total heater power [mW]")
    ax_t.set_title("gripper: best feasible power (x: infeasible evaluations)",
                   fontsize="medium")
    ax_t.legend(fontsize="x-small")
    ax_t.grid(True, alpha=0.3)
    labels = ["reference", *methods]
    for ax, column in ((ax_s, "size [um]"), (ax_p, "power [mW]")):
        d = design.dropna(subset=[column])
        names = list(dict.fromkeys(d["variable"]))
        width = 0.8 / len(labels)
        for j, method in enumerate(labels):
            m = d[d["method"] == method].set_index("variable")
            if m.empty:
                continue
            ax.bar([i + (j - (len(labels) - 1) / 2) * width for i in range(len(names))],
                   [m.loc[n, column] for n in names], width, color=colors[method],
                   label=method)
        ax.set_xticks(range(len(names)), names)
        ax.set_ylabel(column.replace("size", "dimension"))
        ax.legend(fontsize="x-small")
        ax.grid(True, axis="y", alpha=0.3)
    ax_s.set_title("dimensions and crease widths of the returned designs", fontsize="medium")
    ax_p.set_title("heater powers (base 2, 5: both stages; arms 3, 9: grip)",
                   fontsize="medium")
    note_assumptions(fig, environment_note("air", extra=[
        "gripper (paper section 6.3), chain heat loss, self-weight",
        "assembly: base fold >= 90 deg; grip: arm tips <= 100 um (base heat kept on)",
        "temperature limit 1.2 T_g = 252 degC on every crease (centre-line mean)"]),
        heat_loss_note(make_gripper_model(GripperDesign(),
                                          heat=GripperHeatModel(loss_model="chain"))[0]))
    return fig
