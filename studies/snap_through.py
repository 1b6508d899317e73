"""Snap-through: equilibrium paths through limit points, stable and unstable branches.

Question
--------
Load control (force, rest angle or power increments) stops where an equilibrium path turns
back. What do the paths look like beyond those limit points, which parts are stable, and does
a Miura lifter from the design study (a = 0.5 mm, b = 1 mm, gamma = 45 deg, W = 300 um,
4 x 2 cells over a substrate), whose load-controlled heating stops at 9.2 mW per crease, lift
continuously past that power, and how hot do its creases get?

Method
------
* Roof (``get_case("snap_through")``): a shallow two-panel roof (span 1 mm, rise 40 um, 20 um
  SU-8 panels, 20 um x 5 um ridge crease) pinned along its eaves and pushed down at its ridge
  (reference load 1 mN). Three ways: MGDCM arc length (the case; load factor unknown, arc
  length 0.1, until the ridge centre has moved 2.5 rises), displacement control of the ridge centre
  (same reference load, 60 equal increments to 2 rises) and load control (``Load`` to 1.5
  times the first limit load in 30 increments, Newton from each increment).
  Stability = no negative eigenvalue of the reduced tangent at the converged point.
* Miura (``get_case("snap_through", variant="heated")``): every crease heated to 12 mW in 60
  staggered increments with ``on_limit_point="continue"``: load control up to the limit point,
  arc length in the power across the unstable branch, load control again once stable. Lift =
  mean z displacement of the sheet's free-end corner nodes; temperature = the hottest crease's
  centre-line mean (the measure of the 1.2 T_g limit) and the hottest crease node.
* ``--quick``: roof arc length with 80 increments at most and arc length 0.2, 20 displacement
  and load-control increments; the Miura with 30 increments.

Outputs (``results/snap_through/``)
-----------------------------------
``snap_through.csv``: one long table; ``table`` is ``roof`` or ``miura``, ``method`` is
``arc length``, ``displacement control``, ``load control`` or ``heating`` (the Miura's Heat
step, load control and arc length in one), ``increment``, ``load [mN]`` (roof: reference load
times load factor; empty for the Miura), ``power [mW]`` (per crease; Miura), ``displacement
[um]`` (roof: ridge centre, downwards; Miura: lift of the free end), ``stable`` (True/False;
empty where not computed, i.e. load-controlled increments), ``negative_eigenvalues``, and for
the Miura ``temperature_centre [degC]`` (hottest crease, centre line) and
``temperature_max [degC]`` (hottest crease node).
Figure ``snap_through.png``: (a) roof load vs ridge displacement, (b) Miura lift vs power,
(c) Miura crease temperature vs power with the 1.2 T_g limit; unstable branches dashed.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from simulator import DisplacementControl, Load, simulate
from studies._common import run_case, study_main

NAME = "snap_through"
LOAD, POWER, DISP = "load [mN]", "power [mW]", "displacement [um]"


TEMP_CL, TEMP_MAX = "temperature_centre [degC]", "temperature_max [degC]"
UNSTABLE = "#D55E00"          # vermillion (colour-blind-safe palette)


def _rows(structure, method, x, y, stable=None, negative=None) -> pd.DataFrame:
    n = len(y)
    none = [None] * n
    return pd.DataFrame({"table": structure, "method": method,
                         "increment": np.arange(1, n + 1),
                         LOAD: x if structure == "roof" else none,
                         POWER: x if structure == "miura" else none, DISP: y,
                         "stable": none if stable is None else list(stable),
                         "negative_eigenvalues": none if negative is None else list(negative)})


def _roof(quick: bool, progress: bool) -> list:
    params = dict(max_increments=80, arc_length=0.2) if quick else {}
    case, res = run_case(NAME, params, progress, "roof")
    step, load_mN = res.steps[0], case.parameters["load_mN"]
    rise = case.parameters["rise"]
    ridge = int(case.model.mesh.crease_nodes[0][6])
    forces = case.steps[0].forces
    parts = [_rows("roof", "arc length", load_mN * step.load_factor,
                   1e6 * step.columns["displacement [m]"], step.columns["stable"],
                   step.columns["negative_eigenvalues"])]
    n = 20 if quick else 60
    dc = simulate(case.model, [DisplacementControl(ridge, "-z", 2 * rise, increments=n,
                                                   forces=forces)]).steps[0]
    parts.append(_rows("roof", "displacement control", load_mN * dc.load_factor,
                       -1e6 * dc.u_history[:, ridge, 2], dc.columns["stable"],
                       dc.columns["negative_eigenvalues"]))
    lam = step.load_factor
    peak = float(lam[np.argmax(np.diff(lam) < 0)])
    lc = simulate(case.model, [Load({k: 1.5 * peak * np.asarray(f) for k, f in forces.items()},
                                    increments=20 if quick else 30)]).steps[0]
    parts.append(_rows("roof", "load control", 1.5 * peak * load_mN * lc.load_factor,
                       -1e6 * lc.u_history[:, ridge, 2]))
    return parts


def _miura(quick: bool, progress: bool) -> pd.DataFrame:
    params = dict(variant="heated", thermal_steps=30 if quick else 60)
    case, res = run_case(NAME, params, progress, "miura")
    mesh, step = case.model.mesh, res.steps[0]
    sheet = (mesh.node_vertex >= 0) & (mesh.node_panel < 8)
    free = np.flatnonzero(sheet & np.isclose(mesh.nodes[:, 0], mesh.nodes[sheet, 0].max()))
    lift = 1e6 * step.u_history[:, free, 2].mean(axis=1)
    cols = step.columns
    rows = _rows("miura", "heating", 1e3 * step.power_history.max(axis=1), lift,
                 cols.get("stable"), cols.get("negative_eigenvalues"))
    m = len(lift)                                  # the step's records end the history
    rows[TEMP_CL] = res.crease_temperature_centre_line[-m:].max(axis=1)
    rows[TEMP_MAX] = res.crease_temperature_max[-m:].max(axis=1)
    return rows


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Roof by three methods and the heated Miura; see the module docstring."""
    return pd.concat(_roof(quick, progress) + [_miura(quick, progress)], ignore_index=True)


def _branches(ax, x, y, stable, **style):
    """Plot a path with unstable stretches dashed (runs of equal stability, joined)."""
    s = np.array([True if v is None or v != v else bool(v) for v in stable])
    start = 0
    for k in range(1, len(s) + 1):
        if k == len(s) or s[k] != s[start]:
            unstable = {} if s[start] else {"color": UNSTABLE}
            ax.plot(x[max(start - 1, 0):k], y[max(start - 1, 0):k],
                    ls="-" if s[start] else "--", **{**style, **unstable})
            style.pop("label", None)
            start = k


def plot(df: pd.DataFrame):
    """Figure: (a) roof load vs ridge displacement, (b) Miura lift vs power, (c) its crease
    temperatures vs power."""
    from matplotlib.figure import Figure

    from studies.plotting import mark_temperature_limit, note_assumptions

    fig = Figure(figsize=(15, 4.9), layout="constrained")
    ax_r, ax_m, ax_t = fig.subplots(1, 3)
    roof = df[df["table"] == "roof"]
    arc = roof[roof["method"] == "arc length"]
    _branches(ax_r, arc[DISP].to_numpy(), arc[LOAD].to_numpy(), arc["stable"].tolist(),
              color="k", lw=2, label="arc length (dashed: unstable)")
    dc = roof[roof["method"] == "displacement control"]
    ax_r.plot(dc[DISP], dc[LOAD], "o", ms=4, mfc="none", color="0.4", ls="",
              label="displacement control")
    lc = roof[roof["method"] == "load control"]
    ax_r.plot(lc[DISP], lc[LOAD], "x", ms=6, color="C0", ls="", label="load control")
    ax_r.axhline(0, color="0.7", lw=0.8)
    ax_r.set_xlabel("ridge displacement (down) [um]")
    ax_r.set_ylabel("ridge load [mN]")
    ax_r.set_title("(a) roof snap-through")
    ax_r.legend(fontsize="small", loc="upper left")

    miura = df[df["table"] == "miura"]
    power = miura[POWER].to_numpy(float)
    _branches(ax_m, power, miura[DISP].to_numpy(float), miura["stable"].tolist(), color="k",
              lw=1.5, label="heating (dashed: unstable)")
    ax_m.set_ylabel("lift of the free end [um]")
    ax_m.set_title("(b) Miura lifter a = 0.5 mm, 45 deg, W = 300 um")
    ax_m.legend(fontsize="small", loc="upper left")
    measured = []
    if TEMP_CL in miura.columns:
        measured = ax_t.plot(power, miura[TEMP_CL], "-", color="C0",
                             label="hottest crease, centre line")
        ax_t.plot(power, miura[TEMP_MAX], ":", color="C0", label="hottest crease node")
    ax_t.set_ylabel("temperature [°C]")
    ax_t.set_title("(c) Miura crease temperatures")
    ax_t.legend(fontsize="small", loc="upper left")
    mark_temperature_limit(ax_t, lines=measured)
    for ax in (ax_m, ax_t):
        ax.set_xlabel("power per crease [mW]")
    for ax in (ax_r, ax_m, ax_t):
        ax.grid(True, alpha=0.3)
    note_assumptions(fig, "(a): no heat, no gravity; pinned eaves, ridge pushed down. (b), "
                     "(c): environment: air, k_env = 0.026 W/(m K); heat loss: chain model "
                     "(the paper's; t_env = 750 um, 10 layers, beta = 20 deg); residual fold 0 "
                     "deg; no gravity; first column clamped over a substrate 100 um below. The "
                     "design runs far above 1.2 T_g: it shows the path-following, not a usable "
                     "operating point. Creases 14 and 13 (in the snap at 9.2 mW) and 10 (near "
                     "12 mW) fold past 180 deg with their panels apart (fold-past-flat events: "
                     "a 300 um crease holds them ~150 um apart, the 40 um contact acts later); "
                     "no panel passes through another.")
    return fig


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
