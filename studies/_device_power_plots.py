"""Panels of the :mod:`studies.device_power_physics` figure, drawn from its CSV tables."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_powers", "plot_ratio", "GROUP_COLORS"]

#: Bar colours per variant group (Okabe-Ito names of the study style).
GROUP_COLORS = {"paper": "C7", "effect": "C0", "electrical": "C1", "combined": "C2",
                "resolution": "C4"}
POWER = "full_function_power [mW]"


def _bars(ax, labels, values, colors, hatches, left=0.0):
    """Horizontal bars top to bottom from ``left``, each labelled with its value (a missing
    value, a failed evaluation, says so at ``left``)."""
    y = np.arange(len(labels))[::-1]
    ok = np.isfinite(values)
    ax.barh(y[ok], values[ok] - left, left=left, color=np.array(colors)[ok],
            hatch=[h for h, k in zip(hatches, ok) if k], edgecolor="0.25", linewidth=0.5)
    for yi, v in zip(y, values):
        ax.text(v if np.isfinite(v) else left, yi,
                f" {v:.3g}" if np.isfinite(v) else " failed (see message)", va="center",
                fontsize="small")
    ax.set_yticks(y, labels)
    return y


def plot_powers(ax, power):
    """One design: full-function power per variant, the measured power and its +-10 % band,
    the combined range (low to high) as a bar across the central value."""
    labels = list(power["variant"])
    values = power[POWER].to_numpy(float)
    colors = [GROUP_COLORS[g] for g in power["group"]]
    hatches = ["//" if d == "V^2/R0" else None for d in power["power_definition"]]
    y = _bars(ax, labels, values, colors, hatches)
    measured = float(power["measured_power [mW]"].iloc[0])
    ax.axvspan(0.9 * measured, 1.1 * measured, color="C3", alpha=0.12, lw=0,
               label="measured +-10 %")
    ax.axvline(measured, color="C3", ls="--", label=f"measured {measured:g} mW")
    for suffix in ("", ", V^2/R0"):
        ends = {end: power[power["variant"] == f"all, {end}{suffix}"] for end in
                ("low", "central", "high")}
        if all(len(v) for v in ends.values()):
            yc = y[labels.index(f"all, central{suffix}")] - 0.25
            lo, hi = (float(ends[e][POWER].iloc[0]) for e in ("low", "high"))
            ax.plot([lo, hi], [yc, yc], color="k", lw=1.5, marker="|", ms=12,
                    label="range of the plausible values" if not suffix else None)
    paper = power[power["variant"] == "paper setting"][POWER]
    if len(paper):
        ax.axvline(float(paper.iloc[0]), color="0.4", ls=":", lw=1, label="paper setting")
    design = power["design"].iloc[0]
    ax.set_title(f"{design} (measured {measured:g} mW)")
    ax.set_xlabel("full-function power [mW]\n(V I of both circuits; hatched: V^2/R0)")
    ax.set_xlim(0, 1.2 * max(np.nanmax(values), 1.1 * measured))
    ax.grid(True, axis="x", alpha=0.3)
    ax.legend(fontsize="small", loc="upper right")


def plot_ratio(ax, ratio):
    """Cycle 4 / cycle 9 full-function power per variant beside the measured ratio."""
    labels = list(ratio["variant"])
    values = ratio["ratio [-]"].to_numpy(float)
    _bars(ax, labels, values, ["C5"] * len(labels), [None] * len(labels), left=1.0)
    measured = float(ratio["measured_ratio [-]"].iloc[0])
    ax.axvline(measured, color="C3", ls="--", label=f"measured {measured:.2f}")
    ax.set_title("design ratio cycle 4 / cycle 9")
    ax.set_xlabel("full-function power ratio [-]")
    ax.set_xlim(1.0, 1.1 * max(np.nanmax(values), measured))
    ax.grid(True, axis="x", alpha=0.3)
    ax.legend(fontsize="small", loc="upper right")
