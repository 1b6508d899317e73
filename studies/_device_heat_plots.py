"""Panels of the :mod:`studies.device_heat_models` figure, drawn from its CSV tables."""

from __future__ import annotations

import math

import numpy as np

from studies.plotting import T_LIMIT           # 1.2 T_g of SU-8 [degC] (theory 5.4)

__all__ = ["plot_gripper", "plot_sweeps", "plot_parity", "STYLE"]

MODELS = ("chain", "integral")
POWER = "power [mW]"


STYLE = {"chain": dict(color="C0", ls="-"), "integral": dict(color="C3", ls="--")}


def plot_gripper(ax, gripper, comparison):
    """(a) Full-function power per design: chain, integral (its default m), FE-implied (mean
    of the estimates on both models' stopping shapes) and the paper's measured device."""
    from studies.device_heat_models import DEFAULT_M

    g = gripper[gripper["integral_refinement [-]"].fillna(DEFAULT_M) == DEFAULT_M]
    cycles = sorted(g["cycle"].dropna().unique())
    comp = comparison[comparison["quantity"] == "full-function power"]
    bars = [("chain", "C0"), ("integral", "C3"), ("FE-implied", "C2"), ("measured", "C6")]
    width = 0.2
    for k, (label, color) in enumerate(bars):
        vals = []
        for c in cycles:
            row = g[g["cycle"] == c]
            if label in MODELS:
                vals.append(float(row[row["model"] == label]["full_function_power [mW]"].iloc[0]))
            elif label == "measured":
                vals.append(float(row["measured_power [mW]"].iloc[0]))
            else:
                fe = comp[comp["case"] == f"gripper cycle {int(c)}"]
                vals.append(float(fe[["fe_chain_shape", "fe_integral_shape"]].mean(axis=1)
                                  .iloc[0]) if len(fe) else math.nan)
        x = np.arange(len(cycles)) + (k - 1.5) * width
        ax.bar(x, np.nan_to_num(vals), width, color=color, label=label,
               hatch="//" if label == "FE-implied" else None)
        for xi, v in zip(x, vals):
            ax.text(xi, np.nan_to_num(v), f"{v:.1f}" if np.isfinite(v) else "-", ha="center",
                    va="bottom", fontsize="small")
    ax.set_xticks(range(len(cycles)), [f"cycle {int(c)}" for c in cycles])
    ax.set_ylabel("full-function power [mW]\n(2 x assembly + 2 x grip per crease)")
    ax.set_title("(a) gripper: full-function power")
    ax.set_ylim(0, 1.35 * max(ax.get_ylim()[1], 1.0))
    ax.legend(fontsize="small", loc="upper right", ncols=2)
    ax.grid(True, axis="y", alpha=0.3)


def _hot(value: float) -> str:
    """A final centre-line temperature [degC] for a legend, flagged above the 1.2 T_g limit."""
    return f"{value:.0f} °C" + (f" > {T_LIMIT:.0f} °C limit" if value > T_LIMIT else "")


def plot_sweeps(ax_f, ax_l, sweep, comparison):
    """(b) Double-fold fold angles and (c) Miura lift vs power per crease, both models, with
    the final centre-line temperatures (``comparison`` rows) in the legends."""
    d = sweep[sweep["case"] == "double_fold"]
    for (model, fold), part in d.groupby(["model", "fold"], sort=False):
        part = part.sort_values("step")
        ax_f.plot(part[POWER], part["fold_angle [deg]"], color=STYLE[model]["color"],
                  ls=("-", "--")[model == "integral"], lw=2 if fold == 2 else 1.2,
                  label=f"{model}, fold {int(fold)}: {part['fold_angle [deg]'].iloc[-1]:.0f} "
                  f"deg, centre line {_hot(part['temperature_centre [degC]'].iloc[-1])}")
    ax_f.set_xlabel("power per crease [mW]")
    ax_f.set_ylabel("fold angle [deg]")
    ax_f.set_title("(b) double fold (thick: fold 2)")
    ax_f.legend(fontsize="small", loc="upper left")
    m = sweep[sweep["case"] == "miura_lifter"]
    hottest = comparison[(comparison["case"] == "miura_lifter")
                         & (comparison["quantity"] == "hottest centre-line temperature")]
    for model, part in m.groupby("model", sort=False):
        part = part.sort_values("step")
        hot = f", hottest centre line {_hot(float(hottest[model].iloc[0]))}" if len(hottest) \
            else ""
        ax_l.plot(part[POWER], part["lift [um]"], lw=2, **STYLE[model],
                  label=f"{model}: {part['lift [um]'].iloc[-1]:.0f} um{hot}")
    ax_l.set_xlabel("power per crease [mW]")
    ax_l.set_ylabel("lift of the free end [um]")
    ax_l.set_title("(c) Miura lifter on its substrate")
    ax_l.legend(fontsize="small", loc="upper left")
    for ax in (ax_f, ax_l):
        ax.grid(True, alpha=0.3)


def plot_parity(ax, fe, room=21.0):
    """(d) Each model's crease actuation temperature rise against the 3-D FE's on the same
    shapes and powers (``room`` [degC]), with the median |error| per model and device."""
    markers = {"gripper": "o", "double_fold": "s", "miura_lifter": "^"}
    top = 0.0
    for model in MODELS:
        for kind, marker in markers.items():
            d = fe[fe["case"].str.startswith(kind)]
            if not len(d):
                continue
            x, y = d["fe_temperature [degC]"] - room, d[f"{model}_temperature [degC]"] - room
            top = max(top, x.max(), y.max())
            err = np.median(np.abs(d[f"{model}_error [%]"]))
            ax.plot(x, y, marker, color=STYLE[model]["color"], ls="", ms=5,
                    mfc="none" if model == "chain" else STYLE[model]["color"], alpha=0.8,
                    label=f"{model}, {kind.replace('_', ' ')} (median |error| {err:.0f} %)")
    lim = 1.05 * top
    ax.plot([0, lim], [0, lim], "k:", lw=1, label="equal to the 3-D FE")
    ax.set_xlim(0, lim)
    ax.set_ylim(0, lim)
    ax.set_xlabel("3-D FE: crease actuation temperature rise [K]")
    ax.set_ylabel("model, same shape and power [K]")
    ax.set_title("(d) both models against the 3-D FE on the final shapes")
    ax.legend(fontsize="x-small", loc="upper left")
    ax.grid(True, alpha=0.3)
