"""Natural frequencies of the single crease vs heating power and fold state (issue 10, item 6).

Question
--------
How do the natural frequencies of an electro-thermal single crease change as it is heated
and folds? Without power the thin panel sags under gravity onto the substrate's contact
layer; heating lifts it off and folds it up. Which mode sets the mechanical time scale of the
actuator in each state?

Method
------
* Model: ``get_case("single_fold_step_response")`` (gravity, substrate with contact, the chip
  a heat sink, in air), self-fold to the residual fold and gravity, then static heating
  (:class:`~simulator.steps.Heat`, iterated coupling) to each power in turn, every power
  starting from the previous one's state.
* At every power: the ``MODES`` lowest natural modes (:func:`~simulator.natural_modes`)
  linearised about the heated equilibrium (with its stresses and contact), the fold angle
  and the crease temperature.
* Residual folds 0 and -10 deg (two fold histories); ``--quick``: residual 0, three powers.
* Not done here: the gripper (``design.gripper``), left for a later run.

Outputs (``results/natural_modes/``)
------------------------------------
``natural_modes.csv``: one row per state and mode: ``residual_fold [deg]``, ``power [mW]``,
``fold_angle [deg]``, ``temperature [degC]`` (crease), ``mode`` (1 = lowest),
``frequency [Hz]``, ``converged``. Figure ``natural_modes.png``: frequencies vs power and vs
fold angle.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from simulator import Heat, get_case, natural_modes, simulate
from studies._common import TEMP, progress_bar, study_main

NAME = "natural_modes"
CASE = "single_fold_step_response"
MODES = 4
POWERS_MW = tuple(np.round(np.arange(0.0, 6.01, 0.5), 2))
POWERS_QUICK = (0.0, 2.0, 4.0)
RESIDUALS, RESIDUALS_QUICK = (0.0, -10.0), (0.0,)
FREQ, FOLD, POWER = "frequency [Hz]", "fold_angle [deg]", "power [mW]"


def modes_vs_power(residual_deg: float, powers_mW, progress: bool = False) -> pd.DataFrame:
    """Rows per power and mode for one residual fold (see the module docstring)."""
    case = get_case(CASE, residual_fold_deg=residual_deg)
    res = simulate(case.model, case.steps[:-1])
    state, previous, rows = res.state, 0.0, []
    for p in progress_bar(powers_mW, progress, desc=f"residual {residual_deg:g} deg"):
        if p != previous:
            res = simulate(case.model, [Heat({2: (p - previous) * 1e-3}, increments=10,
                                             coupling="iterated")], state=state)
            state, previous = res.state, p
        modes = natural_modes(case.model, state, MODES)
        for k, f in enumerate(modes.frequency, start=1):
            rows.append({"residual_fold [deg]": residual_deg, POWER: p,
                         FOLD: float(np.degrees(res.fold_angle[-1, 0])),
                         TEMP: float(res.crease_temperature[-1, 0]), "mode": k, FREQ: float(f),
                         "converged": bool(res.success and modes.success)})
        if not res.success:
            break
    return pd.DataFrame(rows)


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Modes vs power for every residual fold; see the module docstring."""
    return pd.concat([modes_vs_power(r, POWERS_QUICK if quick else POWERS_MW, progress)
                      for r in (RESIDUALS_QUICK if quick else RESIDUALS)], ignore_index=True)


def plot(df: pd.DataFrame):
    """Frequencies vs power (a) and vs fold angle (b), one line per mode and residual fold."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.2), layout="constrained")
    ax_p, ax_f = fig.subplots(1, 2)
    styles = ("-", "--", ":", "-.")
    for j, (r, d) in enumerate(df.groupby("residual_fold [deg]", sort=False)):
        for k, m in d.groupby("mode"):
            kw = dict(color=f"C{k - 1}", ls=styles[j % len(styles)], marker="o", ms=3,
                      label=f"mode {k}, residual {r:g} deg")
            ax_p.plot(m[POWER], m[FREQ], **kw)
            ax_f.plot(m[FOLD], m[FREQ], **kw)
    ax_p.set(xlabel="crease power [mW]", title="(a) vs heating power")
    ax_f.set(xlabel="fold angle [deg]", title="(b) vs fold state")
    for ax in (ax_p, ax_f):
        ax.set(ylabel="natural frequency [Hz]", yscale="log")
        ax.grid(True, alpha=0.3)
    ax_p.legend(fontsize="x-small", ncol=2)
    return fig


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
