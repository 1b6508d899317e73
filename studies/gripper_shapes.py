"""Origami micro-gripper: the shapes of the coordinate descent, at assembly and at grip
(paper section 6.3, Fig. 11 a, d, e of the LaTeX source, ``figure_opt``).

Question
--------
What do the start design, the paper-like optimum and our optimum of the study
``gripper_optimization`` look like once assembled and once gripping, how hot are they, and
how does the shape change along the descent (the paper built devices near steps 4 and 9)?

Method
------
The designs and their stage powers (per heated crease, from the bisect power search) are read
from ``results/gripper_optimization/gripper_optimization.csv`` (``cycles`` rows; the current
directory's if a run wrote one, else the repository's committed one); the coordinate descent is
not re-run. For each design below, the gripper model of
:func:`design.devices.gripper.gripper_model` is loaded by its pre-steps (self-weight), then heated in
``INCREMENTS`` increments with iterated thermo-mechanical coupling to the assembly power on
the two base creases, then, with the base heat kept on, to the grip power on the two arm
creases. The measures of the stages (base fold, distance of the arm tips) are recomputed on
these states: heating in several increments from zero need not end on exactly the state of the
power search, which heated from saved states with staggered coupling (on the start design, 10
staggered increments end at a base fold of 88.9 deg, 40 at 89.7 deg, 10 iterated at 90.006
deg: the power search's crossing). Designs:

* ``start`` - cycle 0 (W 200, La 700, L1 = L2 = 1000 um, the paper's start, Fig. 11 d);
* ``paper-like optimum`` - W 300, La 1300, L1 = L2 = 500 um, the reference script
  ``SingleGripper.m`` design (the paper's final shape, Fig. 11 e), our cycle 12;
* ``our optimum`` - the last cycle (15);
* ``cycle 4`` and ``cycle 9`` - near the paper's two fabricated devices.

``--quick`` uses 3 increments per stage and the start and last cycle only.

Outputs (``results/gripper_shapes/``)
-------------------------------------
``gripper_shapes.csv``: ``table`` = ``designs`` (one row per design and stage: ``design``,
``cycle``, ``stage`` (``assembly``/``grip``), ``W [um]``, ``La [um]``, ``L1 [um]``,
``L2 [um]``, ``assembly_power [mW]``, ``grip_power [mW]`` (per heated crease),
``electrical_power [mW]`` (all heated creases of the stage: 2 base (+ 2 arm at grip)),
``base_fold [deg]``, ``tip_distance [um]``, ``max_temperature [degC]`` (hottest node),
``success``, ``message``) and ``nodes`` (positions [um] and temperatures [degC] of every node,
per design and stage). Figures: ``gripper_shapes.png`` (start, paper-like optimum and our
optimum at assembly and at grip, one colour scale) and ``gripper_descent.png`` (the grip
shape at cycles 0, 4, 9 and 15, one colour scale).
"""

from __future__ import annotations

import math
import pathlib

import numpy as np
import pandas as pd

from design.devices.gripper import ARM_CREASES, BASE_CREASES, GripperDesign, gripper_model
from simulator.simulation import simulate
from simulator.steps import Heat
from studies._common import (RESULTS, TEMP, XYZ, default_out, progress_bar, shape_from_frame,
                             study_main)

__all__ = ["DESIGNS", "gripper_states", "main", "plot", "run"]

NAME = "gripper_shapes"
CD_CSV = pathlib.Path("gripper_optimization") / "gripper_optimization.csv"
INCREMENTS = 10
INCREMENTS_QUICK = 3
#: Design label -> CD cycle ("last" = the final cycle).
DESIGNS = {"start": 0, "cycle 4": 4, "cycle 9": 9, "paper-like optimum": 12,
           "our optimum": "last"}
DESIGNS_QUICK = {"start": 0, "our optimum": "last"}
PAPER_LIKE = {"W": 300.0, "La": 1300.0, "L1": 500.0, "L2": 500.0}    # um
UM = ("W", "La", "L1", "L2")
#: The substrate under the gripper (150 um below): not drawn, it would dwarf the gripper.
SUBSTRATE_PANELS = (5,)


def _design(row) -> GripperDesign:
    return GripperDesign(**{v: float(row[f"{v} [um]"]) * 1e-6 for v in UM})


def gripper_states(design: GripperDesign, assembly_power: float, grip_power: float,
                   increments: int = INCREMENTS):
    """Model and the two heated states of a gripper design.

    Parameters
    ----------
    design : GripperDesign
    assembly_power, grip_power : float
        Power per heated crease [W] of the base circuit (assembly, kept on while gripping)
        and of the arm circuit (grip).
    increments : int
        Heating increments per stage (iterated coupling).

    Returns
    -------
    (model, {"assembly": SimulationResult, "grip": SimulationResult})
        Each result's last record is the state at the end of that stage.
    """
    model, pre = gripper_model(design)
    start = simulate(model, pre)
    assembly = simulate(model, [Heat({BASE_CREASES: assembly_power}, increments=increments,
                                              coupling="iterated")],
                        state=start.state)
    grip = simulate(model, [Heat({ARM_CREASES: grip_power}, increments=increments,
                                          coupling="iterated")],
                    state=assembly.state)
    return model, {"assembly": assembly, "grip": grip}


def _measures(x) -> tuple:
    """(base fold [deg], arm tip distance [um]) of node positions ``x`` [m] (theory 10.6)."""
    a, b = x[1] - x[0], x[5] - x[4]
    cos = float(np.clip(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)), -1, 1))
    fold = float(np.sign(x[0, 2] - x[5, 2])) * math.degrees(math.acos(cos))
    return fold, 1e6 * float(np.linalg.norm(x[15] - x[18]))


def _cd_csv() -> pathlib.Path:
    """The descent's table: ``./results/gripper_optimization`` of the current directory if a
    run wrote one there, else the repository's committed copy."""
    here = default_out("gripper_optimization").parent / CD_CSV
    return here if here.is_file() else RESULTS / CD_CSV


def _cd_cycles(csv: pathlib.Path) -> pd.DataFrame:
    if not csv.is_file():
        raise FileNotFoundError(f"{csv} is missing: run `python -m studies.gripper_optimization` "
                                "first (its coordinate descent gives the designs).")
    df = pd.read_csv(csv)
    return df[df["table"] == "cycles"].sort_values("cycle").reset_index(drop=True)


def _rows(label, cycle, row, model, results) -> list:
    rows = []
    for stage, res in results.items():
        st = res.state
        x = model.mesh.nodes + st.u
        fold, tips = _measures(x)
        p_asm, p_grip = float(row["assembly_power [mW]"]), float(row["grip_power [mW]"])
        meta = {"design": label, "cycle": cycle, "stage": stage}
        rows.append(pd.DataFrame([{
            "table": "designs", **meta, **{f"{v} [um]": float(row[f"{v} [um]"]) for v in UM},
            "assembly_power [mW]": p_asm, "grip_power [mW]": p_grip,
            "electrical_power [mW]": len(BASE_CREASES) * p_asm
            + (len(ARM_CREASES) * p_grip if stage == "grip" else 0.0),
            "base_fold [deg]": fold, "tip_distance [um]": tips,
            TEMP.replace("temperature", "max_temperature"): float(st.temperature.max()),
            "success": bool(res.success), "message": res.message}]))
        nodes = pd.DataFrame(1e6 * x, columns=XYZ)
        nodes.insert(0, "node", np.arange(len(x)))
        rows.append(nodes.assign(table="nodes", **meta, step=0, increment=0,
                                 **{TEMP: st.temperature}))
    return rows


def run(quick: bool = False, progress: bool = True, csv=None) -> pd.DataFrame:
    """Re-simulate the chosen descent designs at their stage powers; see the docstring.

    ``csv``: the gripper_optimization table (default: ``./results/gripper_optimization/``
    of the current directory if present, else the repository's committed one)."""
    cycles = _cd_cycles(_cd_csv() if csv is None else pathlib.Path(csv))
    designs = DESIGNS_QUICK if quick else DESIGNS
    parts = []
    for label, cycle in progress_bar(designs.items(), enabled=progress, desc="gripper shapes"):
        row = cycles.iloc[-1] if cycle == "last" else cycles[cycles["cycle"] == cycle].iloc[0]
        model, results = gripper_states(_design(row), 1e-3 * float(row["assembly_power [mW]"]),
                                        1e-3 * float(row["grip_power [mW]"]),
                                        INCREMENTS_QUICK if quick else INCREMENTS)
        parts += _rows(label, int(row["cycle"]), row, model, results)
    df = pd.concat(parts, ignore_index=True)
    first = ["table", "design", "cycle", "stage"]
    return df[first + [c for c in df.columns if c not in first]]


# ----------------------------------------------------------------------------- plot
def _draw(fig, spec, d, nodes, t_range, colorbar):
    """One 3-D panel: the shape of design/stage row ``d`` from its node rows."""
    from studies.plotting import plot_shape

    ax = fig.add_subplot(spec, projection="3d")
    mesh = gripper_model(_design(d))[0].mesh
    n = nodes[(nodes["design"] == d["design"]) & (nodes["stage"] == d["stage"])]
    plot_shape(shape_from_frame(n, mesh), ax=ax, t_range=t_range, colorbar=colorbar,
               hide_panels=SUBSTRATE_PANELS)
    ax.view_init(elev=22, azim=-55)
    dims = ", ".join(f"{v} {d[f'{v} [um]']:.0f}" for v in UM)
    measure = (f"base fold {d['base_fold [deg]']:.0f} deg" if d["stage"] == "assembly"
               else f"tips {d['tip_distance [um]']:.0f} um apart")
    ax.set_title(f"{d['design']} (cycle {int(d['cycle'])}) at {d['stage']}\n{dims} um\n"
                 f"{d['electrical_power [mW]']:.1f} mW in all heated creases; {measure}",
                 fontsize="small")
    return ax


def _grid(designs, nodes, rows, stages, title):
    from matplotlib.figure import Figure

    from studies.plotting import nodal_range

    chosen = designs[designs["design"].isin(rows) & designs["stage"].isin(stages)]
    t_range = nodal_range(nodes[nodes["design"].isin(rows)][TEMP])
    n_r, n_c = (len(rows), len(stages)) if len(stages) > 1 else (1, len(rows))
    fig = Figure(figsize=(5.6 * n_c, 4.6 * n_r), layout="constrained")
    grid = fig.add_gridspec(n_r, n_c)
    k = 0
    for i, label in enumerate(rows):
        for j, stage in enumerate(stages):
            d = chosen[(chosen["design"] == label) & (chosen["stage"] == stage)]
            if not len(d):
                continue
            spec = grid[i, j] if len(stages) > 1 else grid[0, i]
            k += 1
            _draw(fig, spec, d.iloc[0], nodes, t_range, colorbar=k == len(chosen))
    fig.suptitle(title, fontsize="medium")
    return fig


def plot(df: pd.DataFrame) -> dict:
    """``{"gripper_shapes": start / paper-like / ours at assembly and grip,
    "gripper_descent": grip shapes along the descent}`` from the table alone."""
    designs = df[df["table"] == "designs"]
    nodes = df[df["table"] == "nodes"]
    present = list(dict.fromkeys(designs["design"]))
    main_rows = [d for d in ("start", "paper-like optimum", "our optimum") if d in present]
    descent = designs[designs["stage"] == "grip"].sort_values("cycle")["design"].tolist()
    note = ("stage powers from the bisect search of gripper_optimization\n"
            "facets coloured by their hottest node, one scale per figure; substrate not drawn")
    return {NAME: _grid(designs, nodes, main_rows, ["assembly", "grip"],
                        f"Gripper at assembly (base circuit on) and at grip (both circuits on)\n"
                        f"{note}"),
            "gripper_descent": _grid(designs, nodes, descent, ["grip"],
                                     f"Gripper shape at grip along the coordinate descent "
                                     f"(devices of the paper near cycles 4 and 9)\n{note}")}


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
