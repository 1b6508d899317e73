"""Figures of :mod:`studies.heat_transfer_models` (re-created from its CSV alone): the strip's
errors against the 3-D FE vs W/L, and the crease temperatures per model on the folded shapes.
matplotlib is imported here only when a figure is drawn."""

from __future__ import annotations

import numpy as np

from studies.heat_transfer_models import (ACCEPTANCE, CRANE_BASE_POWER_MW, DOUBLE_FOLD_POWER,
                                          FE_BOX, GRIPPER_ASSEMBLY, GRIPPER_GRIP, GRIPPER_POWER,
                                          MEDIA, STRUCTURES)

__all__ = ["strip_figure", "folded_figure", "crane_figure"]


def _model_label(row) -> str:
    if row["model"] == "integral":
        extrapolated = str(row.get("integral_extrapolation [-]")) == "True"
        return (f"integral m = {int(row['integral_refinement [-]'])}"
                + (" extrapolated (default)" if extrapolated else ""))
    if row["model"].startswith("FE"):
        lv = row["FE level [-]"]
        return f"3-D FE, level {int(lv)}" if row["model"] == "FE" else \
            f"3-D FE, extrapolated (levels {int(lv) - 1}, {int(lv)})"
    return "chain (beta 20 deg, t_env 1.5 L)" if row["case"] == "strip" else \
        "chain (the model's beta, t_env)"


def _levels_note(df, kind) -> str:
    same = (df["case"] == "strip") == (kind == "strip")
    lv = sorted({int(v) for v in df.loc[same & df["model"].eq("FE"), "FE level [-]"].dropna()})
    ext = (same & df["model"].eq("FE extrapolated"))
    lv_txt = f"level {lv[-1]}" if lv else "not installed"
    return (f"3-D FE: mesh {lv_txt}" + (f", Richardson-extrapolated with level {lv[-1] - 1}"
                                        if ext.any() else " (no extrapolation)")
            + f", box_factor {FE_BOX:g}, Robin far field")


def strip_figure(df):
    """The strip's errors against the 3-D FE vs W/L: T_max and T_ave (rows), air and water
    (columns), one colour per model, SU-8 solid and Au dashed."""
    from matplotlib.figure import Figure

    d = df[df["case"] == "strip"].copy()
    d["label"] = d.apply(_model_label, axis=1)
    media = [m for m in MEDIA if m in set(d["medium"])]
    ref = "FE extrapolated" if d["model"].eq("FE extrapolated").any() else "FE"
    fig = Figure(figsize=(5.2 * len(media), 7.4), layout="constrained")
    axes = fig.subplots(2, len(media), sharex=True, squeeze=False)
    labels = list(dict.fromkeys(d.loc[d["model"] != ref, "label"]))
    for col, medium in enumerate(media):
        for row, m in enumerate(("T_max", "T_ave")):
            ax = axes[row, col]
            ax.axhspan(-ACCEPTANCE["strip"], ACCEPTANCE["strip"], color="0.85", zorder=0,
                       label=f"+-{ACCEPTANCE['strip']:g} %")
            for i, lab in enumerate(labels):
                color = "0.45" if lab.startswith("3-D FE") else f"C{i}"
                for s, (ls, mk) in zip(STRUCTURES, (("-", "o"), ("--", "s"))):
                    g = d[(d["label"] == lab) & (d["medium"] == medium)
                          & (d["structure"] == s)].sort_values("W/L [-]")
                    if len(g):
                        ax.plot(g["W/L [-]"], g[f"{m} error vs {ref} [%]"], ls=ls, marker=mk,
                                ms=4, color=color, mfc="none" if ls == "--" else color,
                                label=f"{lab}, {s}")
            ax.axhline(0, color="k", lw=0.8)
            ax.grid(True, alpha=0.3)
            ax.set_ylabel(f"error of the rise {m} - RT vs 3-D FE [%]")
            what = "T(Ctr)" if m == "T_max" else "mean of A, B, Ctr"
            ax.set_title(f"({'abcd'[row * len(media) + col]}) {m} = {what}, {medium}",
                         fontsize="medium")
        axes[-1, col].set_xlabel("W/L [-]")
    _legend(fig, axes)
    fig.suptitle("Strip (Fig. 6): error of the crease temperature against the 3-D FE "
                 f"({'extrapolated' if ref != 'FE' else 'finest level'}); SU-8 solid, "
                 "Au dashed" + ("; grey: the FE's finer level" if ref != "FE" else ""),
                 fontsize="medium")
    _note(fig, df, "strip", "strip: L = 1, t_p = 0.01, t_c = 0.001, Q = 10 W L t_c on the "
          "crease, far corners at RT = 0 (non-dimensional, Fig. 6); SU-8 k = 0.3, Au k = 315 "
          "W/(m K); air k_env = 0.026, water 0.6 W/(m K); chain beta = 20 deg, t_env = 1.5 L, "
          "N = 10; integral without substrate")
    return fig


def _legend(fig, axes):
    """One legend right of the axes with every labelled artist of ``axes`` (once each)."""
    found = {}
    for ax in axes.ravel():
        for h, lab in zip(*ax.get_legend_handles_labels()):
            found.setdefault(lab, h)
    fig.legend(found.values(), found.keys(), loc="outside right center", fontsize="small")


def _note(fig, df, kind, what):
    from studies.plotting import note_assumptions

    note_assumptions(fig, what, _levels_note(df, kind) + "; same shape, same nodal heat and "
                     "same sheet conduction for every model: only the loss to the medium "
                     "differs; errors of the rise above RT", HEAT_LOSSES)


#: The footer line naming the heat-loss models compared (theory 4.3, 4.7; the FE: 4.8).
HEAT_LOSSES = ("heat loss: chain model (the paper's: beta = 20 deg, N = 10, t_env as each "
               "panel says) against the integral model (calibration-free, m as labelled) and "
               "the 3-D FE reference")


def folded_figure(df):
    """Crease temperatures per model on each folded shape (bars from room temperature) and
    below them each model's error against the 3-D FE (the double fold, the gripper)."""
    fig = _crease_bars(df[~df["case"].isin(["strip", "crane"])], 4.6)
    fig.suptitle("Folded shapes: 7-node crease temperature per model on the same shape and "
                 f"heat (bars from RT); below, the error against the 3-D FE "
                 f"({_ref_name(df)}), +-{ACCEPTANCE['folded']:g} % shaded", fontsize="medium")
    _note(fig, df, "folded", "environment: air, k_env = 0.026 W/(m K); double fold: shape "
          f"after heating at {1e3 * DOUBLE_FOLD_POWER:g} mW per crease (gravity x 0.9, substrate "
          "plane of its anchor panel); gripper (default design, self-weight): shapes at the "
          f"end of assembly ({1e3 * GRIPPER_ASSEMBLY:.2f} mW per base crease) and grip "
          f"(+ {1e3 * GRIPPER_GRIP:.2f} mW per arm crease), then {1e3 * GRIPPER_POWER:g} mW per "
          "heated crease on the fixed shape; integral and FE over the substrate plane of the "
          "thermal boundary panel; chain at the models' own beta, t_env; the 1.2 T_g limit "
          "(252 °C) applies to the centre-line mean T_ave (in the CSV), not to T_crease")
    return fig


def crane_figure(df):
    """The flat crane at the end of its case's heating: crease temperatures per model and
    their errors against the 3-D FE."""
    fig = _crease_bars(df[df["case"] == "crane"], 13.0)
    fig.suptitle(f"Flat crane heated as the crane case at q = {CRANE_BASE_POWER_MW:g} mW "
                 "(0.5 q ... 4 q per crease): 7-node crease temperature per model (bars from "
                 f"RT); below, the error against the 3-D FE ({_ref_name(df)}), "
                 f"+-{ACCEPTANCE['folded']:g} % shaded", fontsize="medium")
    _note(fig, df, "folded", "environment: air, k_env = 0.026 W/(m K), no substrate; the "
          "crane case's chains: beta = 20 deg, t_env = 1 mm (the reference's t2RT = a); its "
          "power of 4 mW was chosen for them: with the integral model the case uses 0.7 mW "
          "(simulator.cases.CRANE_POWER_MW), where it folds as far")
    return fig


def _ref_name(df) -> str:
    return "extrapolated" if df["model"].eq("FE extrapolated").any() else "finest level"


def _crease_bars(d, width):
    """Bars per crease and model on each (case, shape) of ``d``: temperatures above, errors
    against the (extrapolated) FE below; ``width`` [in] per shape."""
    from matplotlib.figure import Figure

    d = d.copy()
    d["label"] = d.apply(_model_label, axis=1)
    shapes = d.drop_duplicates(["case", "shape"])[["case", "shape"]].to_numpy()
    labels = list(dict.fromkeys(d["label"]))
    ref = "FE extrapolated" if d["model"].eq("FE extrapolated").any() else "FE"
    fig = Figure(figsize=(width * len(shapes) + 2.6, 7.4), layout="constrained")
    axes = fig.subplots(2, len(shapes), squeeze=False, height_ratios=[1.5, 1])
    ref_label = d.loc[d["model"] == ref, "label"].iloc[0] if (d["model"] == ref).any() else None
    below = [lab for lab in labels if lab != ref_label]
    hatches = {"FE": "..", "FE extrapolated": "//"}
    for col, (case, shape) in enumerate(shapes):
        g = d[(d["case"] == case) & (d["shape"] == shape)]
        creases = g.drop_duplicates("crease [-]")
        xs = np.arange(len(creases))
        rt = float(g["room temperature [degC]"].iloc[0])
        top, bottom = axes[0, col], axes[1, col]
        for i, lab in enumerate(labels):
            s = g[g["label"] == lab].set_index("crease [-]").reindex(creases["crease [-]"])
            kw = dict(color=f"C{i}", edgecolor="k", lw=0.4, label=lab,
                      hatch=hatches.get(g.loc[g["label"] == lab, "model"].iloc[0]))
            top.bar(xs + (i - (len(labels) - 1) / 2) * 0.8 / len(labels),
                    s["T_crease [degC]"] - rt, 0.8 / len(labels), bottom=rt, **kw)
            if lab in below:
                j = below.index(lab)
                bottom.bar(xs + (j - (len(below) - 1) / 2) * 0.8 / len(below),
                           s[f"T_crease error vs {ref} [%]"], 0.8 / len(below), **kw)
        names = [f"{r['crease name']} ({int(r['crease [-]'])})"
                 + ("" if r["crease power [W]"] > 0 else "\nunheated")
                 for _, r in creases.iterrows()]
        p = 1e3 * creases.loc[creases["crease power [W]"] > 0, "crease power [W]"]
        p = f"{p.max():g} mW" if p.min() == p.max() else f"{p.min():g}-{p.max():g} mW"
        top.set_title(f"({'abc'[col]}) {case}, {shape}: {p} per heated crease",
                      fontsize="medium")
        top.set_ylabel("crease temperature T_crease [°C]")
        top.axhline(rt, color="k", lw=0.8)
        bottom.axhspan(-ACCEPTANCE["folded"], ACCEPTANCE["folded"], color="0.85", zorder=0)
        bottom.axhline(0, color="k", lw=0.8)
        bottom.set_ylabel("error of the rise T_crease - RT\nvs 3-D FE [%]")
        for ax in (top, bottom):
            ax.set_xticks(xs, names, fontsize="small")
            ax.grid(True, axis="y", alpha=0.3)
    _legend(fig, axes)
    return fig
