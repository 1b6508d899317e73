r"""Heat conduction within the structure: bar-and-hinge strip against the 1-D solution (Fig. 5 d-f).

Question
--------
The bar-and-hinge (BH) model meshes a crease with only six T3 triangles and each panel with a
four-triangle fan. How far are its crease temperatures from the exact temperature of the
equivalent 1-D conduction problem, as a function of the crease aspect W/L, the thickness ratio
t_c/t_p, the panel aspect L1/L (L1 = L2) and the panel asymmetry L1/L2 (paper section 4.1,
Fig. 5 d-f)?

Method
------
*Bar-and-hinge side.* ``simulator.cases.verification_strip(variant="within")`` (theory 10.7): two
panels of lengths L1, L2 and thickness t_p joined by one crease of width W, length L and
thickness t_c; k = 1 everywhere, no environment (k_env = 0), the four far corners held at
RT = 0, heat Q = q''' W L t_c with q''' = 10 on the crease (distributed 1/8 to the four edge
nodes, 1/12 to the centre-line ends A, B and 1/3 to the centre Ctr). Measured as in the paper:
T_max^BH = T(Ctr) (0-based node 10) and T_ave^BH = mean of the centre line A, B, Ctr (nodes 8,
9, 10). Everything is non-dimensional (lengths in units of L, k = 1, q''' = 10).

Grid (that of the reference CSV ``studies/reference/verification01_within_structure.csv``):
L = 1, t_p = 0.01, W/L in {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0} and

* sweep ``tc/tp``:  t_c in {0.0005, 0.001, 0.002} (t_c/t_p = 0.05, 0.1, 0.2), L1 = L2 = 1;
* sweep ``L1/L``:   L1 = L2 in {0.5, 1, 2}, t_c = 0.001;
* sweep ``L1/L2``:  (L1, L2) in {(1, 2), (1, 1), (2, 1)}, t_c = 0.001.

The base case (t_c/t_p = 0.1, L1 = L2 = 1) appears once in every sweep. ``--quick``: W/L in
{0.2, 0.4} and the two extreme values of each sweep (0.05 and 0.2; 0.5 and 2; 0.5 and 2).

*1-D analytical side (derivation).* The strip is uniform across its length L, so heat flows
only along x (the direction across the crease). Per unit length L, a panel of length L_i and
thickness t_p conducts like a bar of crease thickness t_c and length

    r_i = L_i t_c / t_p      (same conductance k t_p / L_i = k t_c / r_i),

so the problem is a single bar of thickness t_c on -r1 <= s <= W + r2 with generation only on
the crease 0 <= s <= W and T = 0 at both ends. With s measured from the panel-1 edge of the
crease, and theta = T / (q'''/k):

* panels (no generation): T is linear, T(-r1) = 0, T(W + r2) = 0;
* crease: k T'' = -q''', so T(s) = (q'''/k) (-s^2/2 + alpha s + beta);
* panel 1 (s = 0): continuity of T and of the heat flow per unit width,
  k t_c T'(0) = (k t_p / L1) T(0)  =>  beta = alpha r1;
* panel 2 (s = W): -k t_c T'(W) = (k t_p / L2) T(W)  =>
  (W - alpha) r2 = theta(W) = -W^2/2 + alpha (W + r1),

hence

    alpha = W (W/2 + r2) / (r1 + W + r2),     T(s) = (q'''/k) (-s^2/2 + alpha s + alpha r1).

``0 <= alpha <= W`` always, so the peak lies in the crease at s = alpha:

    T_1D,max = (q'''/k) alpha (alpha/2 + r1),
    T_1D,ave = (1/W) int_0^W T ds = (q'''/k) [alpha (W/2 + r1) - W^2/6].

Energy balance: the heat leaving through panel 1 per unit width is (k t_p/L1) T(0) =
q''' t_c alpha and through panel 2 q''' t_c (W - alpha); together q''' t_c W, i.e. Q over the
length L. Symmetric strip (r1 = r2 = r): alpha = W/2, T_1D,max = (q'''/k)(W^2/8 + W r/2),
T_1D,ave = (q'''/k)(W^2/12 + W r/2); with t_c = t_p this is (q'''/k)(W^2/8 + W L1/2).

Both solutions are linear in q''' and depend on L1, L2, t_c, t_p only through r1, r2 (the
reference shows the same: t_c = 0.0005 and L1 = L2 = 0.5 give identical BH temperatures, and
L1/L2 = 0.5 and 2 are mirror images with identical curves). For L1 = L2 the BH model
reproduces the panel term W r/2 exactly (T^BH - T^1D does not depend on r) and errs only on
the crease term, so T^BH/T^1D tends to 1 as t_c/t_p (or L1/L) grows and the panels dominate
the thermal resistance.

*Which 1-D temperature.* Both BH measures are taken on the crease CENTRE LINE (T_ave^BH
averages A, B, Ctr along the line s = W/2, not across the width). Their 1-D counterpart is
the centre-line temperature, which for L1 = L2 is exactly T_1D,max; the paper, too, plots both
BH values against a single T^1D. So the plotted ratios are T_max^BH/T_1D,max and
T_ave^BH/T_1D,max. The width average T_1D,ave is reported as well, with the ratio
T_ave^BH/T_1D,ave, but that compares a centre-line value with a width average and so grows
with W/L by construction (up to 1.34 on this grid).

Findings (full run)
-------------------
All 72 rows have a reference row; ours agree to 4.7e-10 at most (relative 4.3e-10, the
10-digit rounding of the reference CSV). T_max^BH/T_1D,max lies in 1.04-1.17 (the coarse
crease mesh overestimates the peak, most for thin creases or short panels, t_c/t_p = 0.05 or
L1/L = 0.5, near W/L = 0.3-0.4); T_ave^BH/T_1D,max lies in 0.94-0.99. Both deviations shrink
as t_c/t_p or L1/L grows; t_c/t_p and L1/L give identical curves (only r = L1 t_c/t_p
matters); the asymmetric strips (L1/L2 = 0.5, 2, identical) sit between the symmetric ones.
This is the paper's statement: the maximum is slightly overestimated, the average is close.

Outputs (``results/heat_within_structure/``)
--------------------------------------------
``heat_within_structure.csv``, one row per (sweep, sweep value, W/L); all quantities are
non-dimensional:

* ``sweep``: ``tc/tp``, ``L1/L`` or ``L1/L2``; ``value [-]``: the swept ratio of that row;
* ``W/L [-]``, ``W [-]``, ``L [-]``, ``tc [-]``, ``tp [-]``, ``L1 [-]``, ``L2 [-]``,
  ``tc/tp [-]``, ``L1/L [-]``, ``L1/L2 [-]``: the geometry;
* ``T_max_BH [-]``, ``T_ave_BH [-]``: bar-and-hinge T(Ctr) and mean of A, B, Ctr;
* ``T_max_1D [-]``, ``T_ave_1D [-]``: closed forms above; ``s_peak_1D [-]``: alpha;
* ``T_max_BH/T_max_1D [-]``, ``T_ave_BH/T_max_1D [-]``: the plotted ratios;
  ``T_ave_BH/T_ave_1D [-]``: centre-line BH average over the 1-D width average (see above);
* ``T_max_ref [-]``, ``T_ave_ref [-]``: the reference implementation's values for the same
  geometry (empty if the reference has no such row) and ``T_max_BH - ref [-]``,
  ``T_ave_BH - ref [-]``: our value minus the reference's.

``heat_within_structure.png``: panels (d) t_c/t_p, (e) L1/L, (f) L1/L2; T_max^BH/T_1D,max
(solid) and T_ave^BH/T_1D,max (dashed) against W/L, one colour per ratio value.
``meta.json``: settings, row count, wall time.
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass

import numpy as np
import pandas as pd

from simulator.cases import verification_strip
from studies._common import progress_bar, study_main

NAME = "heat_within_structure"
REFERENCE_CSV = pathlib.Path(__file__).parent / "reference" / "verification01_within_structure.csv"

#: Heat generation per unit crease volume and conductivity of the verification (non-dimensional).
Q_VOLUME, K = 10.0, 1.0
L, TP, TC = 1.0, 0.01, 0.001
W_OVER_L = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0)
W_OVER_L_QUICK = (0.2, 0.4)
#: sweep -> [(value, tc, L1, L2), ...]
SWEEPS = {
    "tc/tp": [(0.05, 0.0005, 1.0, 1.0), (0.1, 0.001, 1.0, 1.0), (0.2, 0.002, 1.0, 1.0)],
    "L1/L": [(0.5, TC, 0.5, 0.5), (1.0, TC, 1.0, 1.0), (2.0, TC, 2.0, 2.0)],
    "L1/L2": [(0.5, TC, 1.0, 2.0), (1.0, TC, 1.0, 1.0), (2.0, TC, 2.0, 1.0)],
}
QUICK_VALUES = {"tc/tp": (0.05, 0.2), "L1/L": (0.5, 2.0), "L1/L2": (0.5, 2.0)}
PANEL = {"tc/tp": ("(d)", "$t_c/t_p$"), "L1/L": ("(e)", "$L_1/L$ ($L_1 = L_2$)"),
         "L1/L2": ("(f)", "$L_1/L_2$")}

RATIO_MAX, RATIO_AVE = "T_max_BH/T_max_1D [-]", "T_ave_BH/T_max_1D [-]"


@dataclass(frozen=True)
class Strip1D:
    """Exact steady 1-D temperature of the strip (derivation in the module docstring).

    Parameters: crease width ``W``, panel lengths ``L1``, ``L2``, crease and panel thicknesses
    ``tc``, ``tp``, generation ``q`` per unit crease volume and conductivity ``k`` (any
    consistent units; the study is non-dimensional).
    """

    W: float
    L1: float
    L2: float
    tc: float
    tp: float
    q: float = Q_VOLUME
    k: float = K

    def __post_init__(self):
        for name in ("W", "L1", "L2", "tc", "tp", "q", "k"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"Strip1D.{name} = {v!r} must be a positive number.")

    @property
    def r1(self) -> float:
        """Panel 1 as an equivalent length of crease-thickness bar, L1 tc / tp."""
        return self.L1 * self.tc / self.tp

    @property
    def r2(self) -> float:
        """Panel 2 as an equivalent length of crease-thickness bar, L2 tc / tp."""
        return self.L2 * self.tc / self.tp

    @property
    def alpha(self) -> float:
        """Position of the peak, measured from the panel-1 edge of the crease."""
        return self.W * (self.W / 2 + self.r2) / (self.r1 + self.W + self.r2)

    @property
    def t_max(self) -> float:
        """Peak temperature (inside the crease)."""
        a = self.alpha
        return self.q / self.k * a * (a / 2 + self.r1)

    @property
    def t_ave(self) -> float:
        """Mean temperature over the crease width."""
        return self.q / self.k * (self.alpha * (self.W / 2 + self.r1) - self.W ** 2 / 6)

    @property
    def end_fluxes(self) -> tuple:
        """Heat per unit length L leaving through the far ends of panel 1 and panel 2.

        k t_p |dT/dx| of the (linear) panels; the two add up to q t_c W.
        """
        g1, g2 = self.k * self.tp / self.L1, self.k * self.tp / self.L2
        return (float(g1 * self.temperature(self.L1)),
                float(g2 * self.temperature(self.L1 + self.W)))

    def temperature(self, x):
        """Temperature at x in [0, L1 + W + L2] (x = 0: far end of panel 1)."""
        x = np.asarray(x, float)
        s = x - self.L1                                    # crease coordinate
        c = self.q / self.k
        a, r1 = self.alpha, self.r1
        t0 = c * a * r1                                    # at the panel-1 edge of the crease
        tw = c * (-self.W ** 2 / 2 + a * self.W + a * r1)  # at the panel-2 edge
        inside = c * (-s ** 2 / 2 + a * s + a * r1)
        left = t0 * x / self.L1
        right = tw * (self.L1 + self.W + self.L2 - x) / self.L2
        return np.where(s < 0, left, np.where(s > self.W, right, inside))


def _reference() -> dict:
    """{(W, tc, L1, L2): (T_max, T_ave)} of the reference implementation."""
    ref = pd.read_csv(REFERENCE_CSV)
    return {_key(r.W, r.tc, r.L1, r.L2): (r.T_max, r.T_ave) for r in ref.itertuples()}


def _key(W, tc, L1, L2):
    return tuple(round(float(v), 9) for v in (W, tc, L1, L2))


def bar_hinge(W, tc, L1, L2, L_=L, tp=TP) -> tuple:
    """(T_max, T_ave) of the bar-and-hinge strip: node Ctr and the mean of A, B, Ctr."""
    res = verification_strip("within", W=W, L=L_, L1=L1, L2=L2, tc=tc, tp=tp).run()
    if not res.success:
        raise RuntimeError(f"strip W={W}, tc={tc}, L1={L1}, L2={L2}: {res.message}")
    t = res.state.temperature
    return float(t[10]), float(np.mean(t[[8, 9, 10]]))


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Sweep the grid (coarse with ``quick``); one row per (sweep, value, W/L), no file I/O."""
    w_grid = W_OVER_L_QUICK if quick else W_OVER_L
    jobs = [(sweep, value, tc, L1, L2, wl)
            for sweep, rows in SWEEPS.items()
            for value, tc, L1, L2 in rows if not quick or value in QUICK_VALUES[sweep]
            for wl in w_grid]
    ref = _reference()
    out = []
    for sweep, value, tc, L1, L2, wl in progress_bar(jobs, progress, desc=NAME):
        W = wl * L
        t_max, t_ave = bar_hinge(W, tc, L1, L2)
        exact = Strip1D(W, L1, L2, tc, TP)
        r_max, r_ave = ref.get(_key(W, tc, L1, L2), (np.nan, np.nan))
        out.append({
            "sweep": sweep, "value [-]": value, "W/L [-]": wl, "W [-]": W, "L [-]": L,
            "tc [-]": tc, "tp [-]": TP, "L1 [-]": L1, "L2 [-]": L2, "tc/tp [-]": tc / TP,
            "L1/L [-]": L1 / L, "L1/L2 [-]": L1 / L2,
            "T_max_BH [-]": t_max, "T_ave_BH [-]": t_ave,
            "T_max_1D [-]": exact.t_max, "T_ave_1D [-]": exact.t_ave,
            "s_peak_1D [-]": exact.alpha,
            RATIO_MAX: t_max / exact.t_max, RATIO_AVE: t_ave / exact.t_max,
            "T_ave_BH/T_ave_1D [-]": t_ave / exact.t_ave,
            "T_max_ref [-]": r_max, "T_ave_ref [-]": r_ave,
            "T_max_BH - ref [-]": t_max - r_max, "T_ave_BH - ref [-]": t_ave - r_ave,
        })
    return pd.DataFrame(out)


def _same_as(a: pd.DataFrame, b: pd.DataFrame) -> bool:
    """True when two sweeps' ratio columns are equal to 1e-12 (value by value, in order)."""
    cols = [RATIO_MAX, RATIO_AVE]
    a, b = (x.sort_values(["value [-]", "W/L [-]"])[cols] for x in (a, b))
    return a.shape == b.shape and bool(np.allclose(a.to_numpy(float), b.to_numpy(float),
                                                   rtol=1e-12, atol=0))


def plot(df: pd.DataFrame):
    """Three panels like Fig. 5 d-f: T^BH/T_1D,max against W/L, one colour per ratio value.

    Returns a matplotlib Figure (matplotlib is imported here only: ``run`` never loads it).
    """
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    sweeps = [s for s in SWEEPS if s in set(df["sweep"])]
    fig = Figure(figsize=(4.2 * len(sweeps), 4.4), layout="constrained")
    axes = fig.subplots(1, len(sweeps), sharey=True, squeeze=False)[0]
    for ax, sweep in zip(axes, sweeps):
        d = df[df["sweep"] == sweep]
        tag, label = PANEL[sweep]
        groups = list(d.groupby("value [-]", sort=True))
        handles = []
        for i, (value, g) in enumerate(groups):
            g = g.sort_values("W/L [-]")
            color = f"C{i}"
            lw = 1.3 + 0.9 * (len(groups) - 1 - i)        # earlier curves wider: overlaps show
            ax.plot(g["W/L [-]"], g[RATIO_MAX], "-o", color=color, ms=4, lw=lw)
            ax.plot(g["W/L [-]"], g[RATIO_AVE], "--s", color=color, ms=4, mfc="none", lw=lw)
            handles.append(Line2D([], [], color=color, lw=lw, label=f"{value:g}"))
        if sweep == "L1/L2" and len(groups) > 1:
            ax.text(0.03, 0.97, "0.5 and 2 are mirror images:\ntheir curves coincide",
                    transform=ax.transAxes, ha="left", va="top", fontsize="small")
        if sweep == "L1/L" and _same_as(d, df[df["sweep"] == "tc/tp"]):
            ax.text(0.03, 0.80, "identical to (d) to every digit (see below)",
                    transform=ax.transAxes, ha="left", va="top", fontsize="small")
        ax.axhline(1.0, color="k", lw=0.8, ls=":")
        ax.set_title(f"{tag} {label}")
        ax.set_xlabel("W/L [-]")
        ax.grid(True, alpha=0.3)
        ax.legend(handles=handles, title=label, fontsize="small", title_fontsize="small",
                  loc="upper right", ncols=len(handles))
    lo, hi = axes[0].get_ylim()
    axes[0].set_ylim(lo, hi + 0.25 * (hi - lo))              # headroom for the legends
    axes[0].set_ylabel(r"$T^{BH}/T_{max}^{1D}$ [-]")
    styles = [Line2D([], [], color="0.3", ls="-", marker="o", ms=4,
                     label=r"$T_{max}^{BH}/T_{max}^{1D}$ (BH: centre node Ctr)"),
              Line2D([], [], color="0.3", ls="--", marker="s", ms=4, mfc="none",
                     label=r"$T_{ave}^{BH}/T_{max}^{1D}$ (BH: mean of centre line A, B, Ctr)"),
              Line2D([], [], color="k", ls=":", lw=0.8, label="exact 1-D")]
    fig.legend(handles=styles, loc="outside upper center", ncols=3, fontsize="small",
               title="Heat within the structure: bar-and-hinge strip vs exact 1-D conduction "
                     "(k = 1, q''' = 10, far ends at 0)", title_fontsize="medium",
               frameon=False)
    from studies.plotting import note_assumptions

    note_assumptions(fig, "(e) = (d), not a bug: the ratios depend on t_c L1 / (t_p L) only, so "
                     "L1/L = 0.5, 1, 2 (at t_c/t_p = 0.1) is t_c/t_p = 0.05, 0.1, 0.2 (at "
                     "L1/L = 1).", "environment: none (k_env = 0); heat loss: none (insulated sheet); no mechanics; the "
                     "paper's FE reference curves (Fig. 5) are not re-computed: the exact 1-D "
                     "solution stands in for them")
    return fig


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
