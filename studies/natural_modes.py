"""Natural frequencies vs heating power and fold state: single crease and gripper.

Question
--------
How do the natural frequencies of an electro-thermal single crease change as it is heated
and folds? Without power the thin panel sags under gravity onto the substrate's contact
layer; heating lifts it off and folds it up. Which mode sets the mechanical time scale of the
actuator in each state?

Method
------
* Single crease: ``get_case("single_fold_step_response")`` (gravity, substrate with contact,
  the chip a heat sink, in air), self-fold to the residual fold (0 and -10 deg) and gravity;
  gripper (``design.devices.gripper``, reference design): self-weight, then the base circuit heated to
  28 mW per crease (assembly: the base folds past 90 deg at 26.4 mW), then with the base held
  there the arm circuit to 6 mW (grip: the tips close to 40 um; they touch above ~6.2 mW).
* Static heating (:class:`~simulator.steps.Heat`, iterated coupling) to each power in turn,
  every power from the previous one's state; at every power the ``MODES`` lowest natural
  modes (:func:`~simulator.natural_modes`) about the heated equilibrium (with its stresses
  and contact), the fold angle (base fold for the gripper) or the arm tip distance, and the
  mean temperature of the heated creases.
* ``--quick``: residual 0 with three powers, the gripper at 0 and full power per stage.

Outputs (``results/natural_modes/``)
------------------------------------
``natural_modes.csv``: one row per state and mode: ``device`` (single crease with its residual
fold, gripper assembly, gripper grip), ``power [mW]`` (per heated crease of the circuit),
``fold_angle [deg]`` or ``tip_distance [um]``, ``temperature [degC]``, ``mode`` (1 = lowest),
``frequency [Hz]``, ``success``. Figure ``natural_modes.png``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from simulator import Heat, natural_modes, simulate
from studies._common import TEMP, progress_bar, study_main
from studies.actuation_speed import gripper, heat_loss_lines, single_crease

NAME = "natural_modes"
MODES = 4
POWERS_MW = tuple(np.round(np.arange(0.0, 6.01, 0.5), 2))
POWERS_QUICK = (0.0, 2.0, 4.0)
RESIDUALS, RESIDUALS_QUICK = (0.0, -10.0), (0.0,)
#: Gripper: base circuit 0 -> 28 mW per crease (assembly), then the arms 0 -> 6 mW (grip).
ASSEMBLY_MW, ASSEMBLY_QUICK = tuple(range(0, 29, 4)), (0, 28)
GRIP_MW, GRIP_QUICK = (0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 5.5, 6.0), (0.0, 6.0)
FREQ, FOLD, POWER = "frequency [Hz]", "fold_angle [deg]", "power [mW]"


def modes_vs_power(device, powers_mW, progress: bool = False) -> pd.DataFrame:
    """Rows per power and mode: the device's circuit heated (static, iterated coupling) to
    each power [mW per crease] in turn; natural modes about every equilibrium."""
    state, previous, rows = device.state, 0.0, []
    mesh, crease_rows = device.model.mesh, [device.model.mesh.crease_row_of(c)
                                            for c in device.creases]
    ok = True
    for p in progress_bar(powers_mW, progress, desc=device.label):
        if p != previous:
            res = simulate(device.model, [Heat({device.creases: (p - previous) * 1e-3},
                                               increments=10, coupling="iterated")],
                           state=state)
            ok = res.success
            if not ok:
                break
            state, previous = res.state, p
        modes = natural_modes(device.model, state, MODES)
        temp = float(np.mean(state.temperature[mesh.crease_nodes[crease_rows]]))
        for k, f in enumerate(modes.frequency, start=1):
            rows.append({"device": device.label, POWER: float(p),
                         device.column: device.measure(mesh.nodes + state.u), TEMP: temp,
                         "mode": k, FREQ: float(f), "success": bool(ok and modes.success)})
    return pd.DataFrame(rows)


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Modes vs power for the single crease (every residual fold) and the gripper."""
    parts = []
    for r in (RESIDUALS_QUICK if quick else RESIDUALS):
        device = dataclasses.replace(single_crease(r), label=f"single crease, residual {r:g} deg")
        parts.append(modes_vs_power(device, POWERS_QUICK if quick else POWERS_MW, progress))
    parts.append(modes_vs_power(gripper("assembly"), ASSEMBLY_QUICK if quick else ASSEMBLY_MW,
                                progress))
    parts.append(modes_vs_power(gripper("grip", ASSEMBLY_MW[-1] * 1e-3),
                                GRIP_QUICK if quick else GRIP_MW, progress))
    return pd.concat(parts, ignore_index=True)


def plot(df: pd.DataFrame):
    """Single crease: frequencies vs power (a) and vs fold angle (b); gripper vs the power of
    the stage's circuit (c). One line per mode and run."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(15, 6.2), layout="constrained")
    ax_p, ax_f, ax_g = fig.subplots(1, 3)
    styles = ("-", "--", ":", "-.")
    for j, (device, d) in enumerate(df.groupby("device", sort=False)):
        crease = device.startswith("single crease")
        for k, m in d.groupby("mode"):
            kw = dict(color=f"C{k - 1}", ls=styles[j % 2 if crease else j % 4], marker="o",
                      ms=3, label=f"mode {k}, {device}")
            if crease:
                ax_p.plot(m[POWER], m[FREQ], **kw)
                ax_f.plot(m[FOLD], m[FREQ], **kw)
            else:
                ax_g.plot(m[POWER], m[FREQ], **kw)
    ax_p.set(xlabel="crease power [mW]", title="(a) single crease vs heating power")
    ax_f.set(xlabel="fold angle [deg]", title="(b) single crease vs fold state")
    ax_g.set(xlabel="power per heated crease [mW]",
             title="(c) gripper: base circuit (assembly), then arms (grip)")
    for ax in (ax_p, ax_f, ax_g):
        ax.set(ylabel="natural frequency [Hz]", yscale="log")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="xx-small", ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.18))
    from studies.plotting import environment_note, note_assumptions

    note_assumptions(fig, environment_note("air", 0.026, "0 and -10", 1.0, extra=[
        "single crease 150 um over a substrate (contact)", "gripper: lumped self-weight, "
        "residual fold 0"]), *heat_loss_lines())
    return fig


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
