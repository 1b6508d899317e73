"""How fast does an electro-thermal crease fold and release? (issue 10, item 6)

Question
--------
A single gold / SU-8 crease (gravity, 150 um over a substrate, the chip a heat sink at room
temperature, in air) is driven by a power step. How long do folding (rise) and release take,
how do they scale with the power, what sets them - the thermal time constant or the
mechanical period of the fold mode - and how much electrical energy does one actuation cost?
Up to which drive frequency does a square wave still give a full fold (the -3 dB bandwidth)?

Method
------
* Step response: ``get_case("single_fold_step_response", power_mW=P, t_on, t_off)`` (self-fold,
  gravity, then one :class:`~simulator.steps.ElectroThermal` step, dynamic mechanics with
  adaptive time steps). Rise time = 10 % to 90 % of the fold change reached at the end of the
  on-phase; release time = 90 % to 10 % after the power is switched off. Thermal time
  constant = time for the crease temperature to reach 63.2 % of its rise at the end of the
  on-phase; mechanical periods = 1 / first natural frequency (:func:`~simulator.natural_modes`)
  about the unheated state (the sagging panel rests on the substrate's contact layer: a stiff,
  fast mode) and about the static heated state (lifted off: the fold mode on the crease).
  Energy per actuation = P t_on.
* Square wave: the same model driven by ``SquareWave(P, period=1/f, duty=0.5)`` for a few
  periods; the fold amplitude (peak to peak over the last period) against f, normalised by the
  lowest frequency's; the -3 dB bandwidth is where it falls to 1/sqrt(2) (log interpolation).
* ``--quick``: two powers, 0.15 s phases, square waves at 10 and 100 Hz.
* Not done here: the gripper's assembly and grip (the same functions work on ``design.gripper``
  models, but one coupled run of the gripper takes minutes).

Outputs (``results/actuation_speed/``)
--------------------------------------
``actuation_speed.csv`` with a ``table`` column: ``response`` (time series per power: ``time
[s]``, ``fold_angle [deg]``, ``temperature [degC]`` crease), ``summary`` (per power: ``rise_time
[s]``, ``release_time [s]``, ``thermal_time_constant [s]``,
``energy [mJ]``, ``fold_change [deg]``, ``mechanical_period_unheated [s]``,
``mechanical_period_heated [s]``), ``square_wave`` (per frequency: ``frequency [Hz]``,
``amplitude [deg]``, ``relative_amplitude [-]``, ``bandwidth [Hz]``). Figure
``actuation_speed.png``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from simulator import Heat, SquareWave, get_case, natural_modes, simulate
from studies._common import TEMP, progress_bar, study_main

NAME = "actuation_speed"
CASE = "single_fold_step_response"
POWERS_MW, POWERS_QUICK = (1.0, 2.0, 3.0, 4.0, 5.0), (2.0, 4.0)
PHASE, PHASE_QUICK = 1.0, 0.15                     # s, on and off
FREQS, FREQS_QUICK = (1.0, 3.0, 10.0, 30.0, 100.0), (10.0, 100.0)
WAVE_POWER_MW, PERIODS = 3.0, 4
DT_MAX = 5e-4                                  # s, resolves the ~4 ms release
T, FOLD = "time [s]", "fold_angle [deg]"


def crossing(t, y, level) -> float:
    """First time [s] at which ``y`` passes ``level`` (linear interpolation; NaN if never)."""
    y = np.asarray(y, float) - level
    k = np.flatnonzero(np.sign(y[1:]) != np.sign(y[:-1]))
    if not len(k):
        return float("nan")
    i = int(k[0])
    return float(t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i]))


def _trace(case, pre):
    res = simulate(case.model, case.steps[-1:], state=pre.state)
    if not res.success:
        raise RuntimeError(f"{case.name}: {res.message}")
    t = np.r_[pre.state.time, res.steps[0].columns[T]] - pre.state.time
    return t, np.degrees(res.fold_angle[:, 0]), res.crease_temperature[:, 0]   # record 0: start


def step_metrics(t, fold, temp, t_on) -> dict:
    """Rise and release times (10-90 %), thermal time constant (63.2 %) [s], fold change."""
    on = int(np.searchsorted(t, t_on - 1e-12))
    f0, df = fold[0], fold[on] - fold[0]
    rise = crossing(t[:on + 1], fold[:on + 1], f0 + 0.9 * df) - \
        crossing(t[:on + 1], fold[:on + 1], f0 + 0.1 * df)
    off_t, off_f = t[on:], fold[on:]
    release = crossing(off_t, off_f, f0 + 0.1 * df) - crossing(off_t, off_f, f0 + 0.9 * df)
    tau = crossing(t[:on + 1], temp[:on + 1], temp[0] + 0.632 * (temp[on] - temp[0]))
    return {"rise_time [s]": rise, "release_time [s]": release,
            "thermal_time_constant [s]": tau, "fold_change [deg]": df}


def mechanical_periods(model, state, power) -> dict:
    """First natural period [s] about the unheated state and about the static heated one."""
    heated = simulate(model, [Heat({2: power}, increments=10, coupling="iterated")], state=state)
    return {f"mechanical_period_{k} [s]": 1.0 / float(natural_modes(model, s, 1).frequency[0])
            for k, s in (("unheated", state), ("heated", heated.state))}


def _step_response(powers, phase, progress):
    rows, series = [], []
    for p in progress_bar(powers, progress, desc="step response"):
        case = get_case(CASE, power_mW=p, t_on=phase, t_off=phase, dt=DT_MAX,
                        dt_max=DT_MAX)
        pre = simulate(case.model, case.steps[:-1])
        t, fold, temp = _trace(case, pre)
        series.append(pd.DataFrame({"table": "response", "power [mW]": p, T: t, FOLD: fold,
                                    TEMP: temp}))
        rows.append({"table": "summary", "power [mW]": p, **step_metrics(t, fold, temp, phase),
                     **mechanical_periods(case.model, pre.state, p * 1e-3),
                     "energy [mJ]": p * phase})
    return pd.concat([*series, pd.DataFrame(rows)], ignore_index=True)


def _square_wave(freqs, progress):
    case = get_case(CASE, power_mW=WAVE_POWER_MW)
    pre = simulate(case.model, case.steps[:-1])
    rows = []
    for f in progress_bar(freqs, progress, desc="square wave"):
        step = dataclasses.replace(
            case.steps[-1], power={2: SquareWave(WAVE_POWER_MW * 1e-3, 1 / f, 0.5)},
            duration=PERIODS / f, dt=min(1e-3, 0.02 / f), dt_min=1e-6,
            dt_max=min(5e-3, 0.02 / f))
        t, fold, _ = _trace(dataclasses.replace(case, steps=(*case.steps[:-1], step)), pre)
        last = t >= (PERIODS - 1) / f - 1e-12
        rows.append({"table": "square_wave", "frequency [Hz]": f,
                     "amplitude [deg]": float(np.ptp(fold[last]))})
    df = pd.DataFrame(rows)
    df["relative_amplitude [-]"] = df["amplitude [deg]"] / df["amplitude [deg]"].iloc[0]
    df["bandwidth [Hz]"] = bandwidth(df["frequency [Hz]"], df["relative_amplitude [-]"])
    return df


def bandwidth(freqs, relative) -> float:
    """Frequency [Hz] where ``relative`` first drops below 1/sqrt(2) (log-log interpolation;
    NaN if it never does)."""
    f, a = np.log(np.asarray(freqs, float)), np.log(np.asarray(relative, float))
    x = crossing(f, a, np.log(1 / np.sqrt(2)))
    return float(np.exp(x)) if np.isfinite(x) else float("nan")


def run(quick: bool = False, progress: bool = True) -> pd.DataFrame:
    """Step responses vs power and the square-wave sweep; see the module docstring."""
    steps = _step_response(POWERS_QUICK if quick else POWERS_MW,
                           PHASE_QUICK if quick else PHASE, progress)
    return pd.concat([steps, _square_wave(FREQS_QUICK if quick else FREQS, progress)],
                     ignore_index=True)


def plot(df: pd.DataFrame):
    """Fold vs time per power, times vs power, square-wave amplitude vs frequency."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(13, 4.2), layout="constrained")
    ax_t, ax_s, ax_f = fig.subplots(1, 3)
    resp = df[df["table"] == "response"]
    for p, d in resp.groupby("power [mW]"):
        ax_t.plot(d[T], d[FOLD], label=f"{p:g} mW")
    ax_t.set(xlabel="time [s]", ylabel="fold angle [deg]", title="(a) power step on, then off")
    ax_t.legend(fontsize="small")
    s = df[df["table"] == "summary"]
    for col, style in (("rise_time [s]", "o-"), ("release_time [s]", "s-"),
                       ("thermal_time_constant [s]", "^--"),
                       ("mechanical_period_heated [s]", "x:"),
                       ("mechanical_period_unheated [s]", "+:")):
        ax_s.plot(s["power [mW]"], s[col], style, label=col.split(" [")[0].replace("_", " "))
    ax_s.set(xlabel="power [mW]", ylabel="time [s]", yscale="log", title="(b) time scales")
    ax_s.legend(fontsize="x-small", loc="center right")
    w = df[df["table"] == "square_wave"]
    ax_f.loglog(w["frequency [Hz]"], w["relative_amplitude [-]"], "o-")
    ax_f.axhline(1 / np.sqrt(2), color="grey", ls=":", label="-3 dB")
    bw = w["bandwidth [Hz]"].iloc[0] if len(w) else np.nan
    ax_f.set(xlabel="square-wave frequency [Hz]", ylabel="fold amplitude / low-frequency one",
             title=f"(c) bandwidth {bw:.3g} Hz" if np.isfinite(bw) else "(c) square wave")
    ax_f.legend(fontsize="small")
    for ax in (ax_t, ax_s, ax_f):
        ax.grid(True, alpha=0.3)
    return fig


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
