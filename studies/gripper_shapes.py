"""Origami micro-gripper: the shapes of the coordinate descent, at assembly and at grip
(paper section 6.3, Fig. 11 a, d, e of the LaTeX source, ``figure_opt``).

Question
--------
What do the start design, the paper's optimum and our optimum of the study
``gripper_optimization`` look like once assembled and once gripping, how hot are they, and
how does the shape change along the descent (the paper built devices near steps 4 and 9)?

Method
------
The designs and their stage powers (per heated crease, from the bisect power search) are read
from ``results/gripper_optimization/gripper_optimization.csv`` (``cycles`` rows; the current
directory's if a run wrote one, else the repository's committed one); the coordinate descent is
not re-run. For each design below, the gripper model of
:func:`design.devices.gripper.make_gripper_model` is loaded by its pre-steps (self-weight), then heated in
``INCREMENTS`` increments with iterated thermo-mechanical coupling to the assembly power on
the two base creases, then, with the base heat kept on, to the grip power on the two arm
creases. The measures of the stages (base fold, distance of the arm tips) are recomputed on
these states: heating in several increments from zero need not end on exactly the state of the
power search, which heated from saved states with staggered coupling (on the start design, 10
staggered increments end at a base fold of 88.9 deg, 40 at 89.7 deg, 10 iterated at 90.006
deg: the power search's crossing). Designs:

* ``start`` - cycle 0 (W 200, La 700, L1 = L2 = 1000 um, the paper's start, Fig. 11 d);
* ``paper's optimum`` - W 300, La 1300, L1 = L2 = 500 um, the reference script
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
per design and stage). Figures: ``gripper_shapes.png`` (start, paper's optimum and our
optimum at assembly and at grip) and ``gripper_descent.png`` (the grip shape at cycles 0,
4, 9, 12 and 15 on a grid, with a schematic of the design variables W, La, L1, L2 as in the
paper's Fig. 11a); all panels of a figure at one true scale and one colour scale, base, arm
and tip labelled.
"""

from __future__ import annotations

import math
import pathlib

import numpy as np
import pandas as pd

from design import GripperDesign, GripperHeatModel, make_gripper_model
from design.devices import ARM_CREASES, BASE_CREASES
from simulator import simulate
from simulator.steps import Heat
from studies._common import (RESULTS, TEMP, XYZ, default_out, progress_bar, shape_from_frame,
                             study_main)

__all__ = ["DESIGNS", "gripper_states", "main", "plot", "run"]

NAME = "gripper_shapes"
CD_CSV = pathlib.Path("gripper_optimization") / "gripper_optimization.csv"
INCREMENTS = 10
INCREMENTS_QUICK = 3
#: Design label -> CD cycle ("last" = the final cycle).
DESIGNS = {"start": 0, "cycle 4": 4, "cycle 9": 9, "paper's optimum": 12,
           "our optimum": "last"}
DESIGNS_QUICK = {"start": 0, "our optimum": "last"}
PAPER_LIKE = {"W": 300.0, "La": 1300.0, "L1": 500.0, "L2": 500.0}    # um
UM = ("W", "La", "L1", "L2")
#: The substrate under the gripper (150 um below): not drawn, it would dwarf the gripper.
SUBSTRATE_PANELS = (5,)
#: Named parts of the gripper pattern (panel ids of ``gripper_pattern``).
PARTS = {"central panel": 1, "base": 0, "arm": 3}


#: The heat model the optimisation's powers were found with (the paper's chains).
PAPER_HEAT = GripperHeatModel(loss_model="chain")


def _design(row) -> GripperDesign:
    """The design of a row of the optimisation's table."""
    return GripperDesign(**{v: float(row[f"{v} [um]"]) * 1e-6 for v in UM})


def gripper_states(design: GripperDesign, assembly_power: float, grip_power: float,
                   increments: int = INCREMENTS, heat=None):
    """Model and the two heated states of a gripper design.

    Parameters
    ----------
    design : GripperDesign
    assembly_power, grip_power : float
        Power per heated crease [W] of the base circuit (assembly, kept on while gripping)
        and of the arm circuit (grip).
    increments : int
        Heating increments per stage (iterated coupling).
    heat : GripperHeatModel, optional
        How the heat balance is modelled (default: the integral loss).

    Returns
    -------
    (model, {"assembly": SimulationResult, "grip": SimulationResult})
        Each result's last record is the state at the end of that stage.
    """
    model, pre = make_gripper_model(design, heat=heat)
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
                                        INCREMENTS_QUICK if quick else INCREMENTS, PAPER_HEAT)
        parts += _rows(label, int(row["cycle"]), row, model, results)
    df = pd.concat(parts, ignore_index=True)
    first = ["table", "design", "cycle", "stage"]
    return df[first + [c for c in df.columns if c not in first]]


# ----------------------------------------------------------------------------- plot
def _draw(fig, spec, d, nodes, t_range, colorbar):
    """One 3-D panel: the shape of design/stage row ``d`` from its node rows."""
    from studies.plotting import label_points, plot_shape

    ax = fig.add_subplot(spec, projection="3d")
    mesh = make_gripper_model(_design(d), heat=PAPER_HEAT)[0].mesh
    n = nodes[(nodes["design"] == d["design"]) & (nodes["stage"] == d["stage"])]
    shape = shape_from_frame(n, mesh)
    plot_shape(shape, ax=ax, t_range=t_range, colorbar=colorbar, hide_panels=SUBSTRATE_PANELS,
               panel_labels={k: v for k, v in PARTS.items() if k != "central panel"})
    x = n.sort_values("node")[XYZ].to_numpy(float) / 1e3
    label_points(ax, {"tip": x[15]})
    ax.view_init(elev=22, azim=-55)
    dims = ", ".join(f"{v} {d[f'{v} [um]']:.0f}" for v in UM)
    measure = (f"base fold {d['base_fold [deg]']:.0f} deg" if d["stage"] == "assembly"
               else f"tips {d['tip_distance [um]']:.0f} um apart")
    cycle = "" if d["design"].startswith("cycle") else f" (cycle {int(d['cycle'])})"
    ax.set_title(f"{d['design']}{cycle} at {d['stage']}\n{dims} um\n"
                 f"{d['electrical_power [mW]']:.1f} mW in all heated creases; {measure}",
                 fontsize="small")
    return ax, x[np.unique(mesh.triangles[~np.isin(mesh.triangle_panel, SUBSTRATE_PANELS)])]


def _grid(designs, nodes, rows, stages, title, columns=None, schematic=False):
    """3-D panels of designs (rows) x stages (columns), or of designs on a grid of ``columns``
    for one stage; all at one true scale; a schematic in the first free cell if asked."""
    from matplotlib.figure import Figure

    from studies.plotting import GRIPPER_HEAT_LOSS, nodal_range, note_assumptions, \
        share_3d_scale

    chosen = designs[designs["design"].isin(rows) & designs["stage"].isin(stages)]
    t_range = nodal_range(nodes[nodes["design"].isin(rows)][TEMP])
    cells = [(label, stage) for label in rows for stage in stages
             if len(chosen[(chosen["design"] == label) & (chosen["stage"] == stage)])]
    n_c = len(stages) if len(stages) > 1 else (columns or len(cells))
    n_r = -(-(len(cells) + schematic) // n_c)
    fig = Figure(figsize=(5.0 * n_c, 4.4 * n_r + 0.6), layout="constrained")
    grid = fig.add_gridspec(n_r, n_c)
    axes, points = [], []
    for k, (label, stage) in enumerate(cells):
        d = chosen[(chosen["design"] == label) & (chosen["stage"] == stage)].iloc[0]
        ax, pts = _draw(fig, grid[k // n_c, k % n_c], d, nodes, t_range,
                        colorbar=k == len(cells) - 1)
        axes.append(ax)
        points.append(pts)
    scale = share_3d_scale(axes, points)
    if schematic:
        k = len(cells)
        draw_schematic(fig.add_subplot(grid[k // n_c, k % n_c]))
    fig.suptitle(f"{title}\n({scale}; facets coloured by their hottest node, one colour "
                 "scale; substrate, 150 um below, not drawn)", fontsize="medium")
    note_assumptions(fig, "environment: air, k_env = 0.026 W/(m K); residual fold 0 deg; "
                     "gravity x 1 (lumped self-weight); stage powers from the bisect search "
                     "of gripper_optimization (per heated crease)", GRIPPER_HEAT_LOSS)
    return fig


def draw_schematic(ax, design: GripperDesign = GripperDesign()):
    """The flat gripper pattern in 2-D with its design variables W, La, L1, L2 (paper
    Fig. 11a): panels grey, creases orange, the anchored base hatched; lengths in mm."""
    from matplotlib.patches import Polygon

    from simulator.example_patterns import gripper_pattern

    pat = gripper_pattern(w=design.W, la=design.La, l1=design.L1, l2=design.L2)
    v = np.asarray(pat.vertices)[:, :2] * 1e3
    names = {1: "central\npanel\n(anchored)", 0: "base", 2: "base", 3: "arm", 4: "arm"}
    for k, name in names.items():
        poly = v[list(pat.panels[k])]
        ax.add_patch(Polygon(poly, fc="0.85", ec="0.3", hatch="//" if k == 1 else None))
        ax.text(*poly.mean(axis=0), name, ha="center", va="center", fontsize="small")
    w = design.W * 1e3
    l1, l2, la = (1e3 * getattr(design, n) for n in ("L1", "L2", "La"))
    r = design.grip_range * 1e3
    strips = [((l1 - w / 2, 0), (l1 + w / 2, l2)), ((l1 + r - w / 2, 0), (l1 + r + w / 2, l2)),
              ((0, l2 - w / 2), (l1, l2 + w / 2)),
              ((l1 + r, l2 - w / 2), (2 * l1 + r, l2 + w / 2))]
    for (x0, y0), (x1, y1) in strips:
        ax.add_patch(Polygon([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], fc="#E69F00",
                             ec="none", alpha=0.8))
    arrow = dict(arrowstyle="<->", lw=1.0, color="k", shrinkA=0, shrinkB=0)

    def dim(a, b, text, offset):
        ax.annotate("", a, b, arrowprops=arrow)
        ax.text((a[0] + b[0]) / 2 + offset[0], (a[1] + b[1]) / 2 + offset[1], text,
                ha="center", va="center", fontsize="medium", fontweight="bold")

    dim((0, -0.15), (l1, -0.15), "L1", (0, -0.12))
    dim((-0.15, 0), (-0.15, l2), "L2", (-0.14, 0))
    dim((2 * l1 + r + 0.15, l2), (2 * l1 + r + 0.15, l2 + la), "La", (0.16, 0))
    dim((l1 - w / 2, l2 * 0.25), (l1 + w / 2, l2 * 0.25), "W", (0.22, 0))
    ax.annotate("tips", (0.75 * l1, l2 + la), (0.2 * l1, l2 + la + 0.25),
                arrowprops=dict(arrowstyle="->", lw=0.8), fontsize="small")
    ax.annotate("", (1.25 * l1 + r, l2 + la), (0.9 * l1, l2 + la + 0.22),
                arrowprops=dict(arrowstyle="->", lw=0.8))
    ax.set_xlim(-0.45, 2 * l1 + r + 0.45)
    ax.set_ylim(-0.4, l2 + la + 0.45)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title("design variables (flat pattern, start design; orange: creases, base "
                 "hinges heated at assembly, arm hinges at grip)", fontsize="small", wrap=True)


def plot(df: pd.DataFrame) -> dict:
    """``{"gripper_shapes": start / paper's / ours at assembly and grip,
    "gripper_descent": grip shapes along the descent}`` from the table alone."""
    designs = df[df["table"] == "designs"]
    nodes = df[df["table"] == "nodes"]
    present = list(dict.fromkeys(designs["design"]))
    main_rows = [d for d in ("start", "paper's optimum", "our optimum") if d in present]
    descent = designs[designs["stage"] == "grip"].sort_values("cycle")["design"].tolist()
    return {NAME: _grid(designs, nodes, main_rows, ["assembly", "grip"],
                        "Gripper at assembly (base circuit on) and at grip (both circuits on)"),
            "gripper_descent": _grid(designs, nodes, descent, ["grip"],
                                     "Gripper shape at grip along the coordinate descent "
                                     "(devices of the paper near cycles 4 and 9)", columns=3,
                                     schematic=True)}


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
