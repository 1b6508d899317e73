"""How fast does an electro-thermal crease fold and release?

Question
--------
A single gold / SU-8 crease (gravity, 150 um over a substrate, the chip a heat sink at room
temperature, in air) and the micro-gripper (``design.devices.gripper``) are driven by power steps.
How long do folding (rise) and release take, how do they scale with the power, what sets
them - the thermal time constant or the mechanical period - and how much electrical energy
does one actuation cost? Up to which drive frequency does a square wave still give a full
fold of the single crease (the -3 dB bandwidth)?

Method
------
* Step response: one :class:`~simulator.steps.ElectroThermal` run (the settings of the case
  ``single_fold_step_response``: dynamic mechanics, generalized-alpha, air damping, adaptive
  steps up to :data:`DT_MAX`) with the power on for a phase and off for a phase, from: the
  single crease after self-fold and gravity (powers :data:`POWERS_MW` [mW]); the gripper
  after its self-weight, base circuit (assembly, :data:`ASSEMBLY_MW` per crease); the
  gripper assembled statically at 28 mW per base crease (held on), arm circuit (grip,
  :data:`GRIP_MW`). Measures: fold angle (single crease), base fold (assembly), arm tip
  distance (grip).
* Rise time = 10 % to 90 % of the change reached at the end of the on-phase; release time =
  90 % to 10 % after switching off; thermal time constant = time for the mean heated-crease
  temperature to reach 63.2 % of its rise at the end of the on-phase; mechanical periods =
  1 / first natural frequency (:func:`~simulator.natural_modes`) about the start state and
  about the static heated one (the unheated single crease rests on the substrate's contact
  layer: a stiff, fast mode; lifted off, it swings on its crease). Energy = total power x
  on-phase; energy to 90 % = total power x time to 90 %.
* Square wave (single crease): ``SquareWave(3 mW, period=1/f, duty=0.5)`` for
  :data:`PERIODS` periods and at least :data:`SETTLE` s plus one period; fold amplitude
  (peak to peak over the last period) vs f,
  normalised by the lowest frequency's; the -3 dB bandwidth is where it falls to 1/sqrt(2)
  (log interpolation).
* ``--quick``: two single-crease powers and one per gripper stage, 0.15 s phases, square
  waves at 10 and 100 Hz.

Outputs (``results/actuation_speed/``)
--------------------------------------
``actuation_speed.csv`` with a ``table`` column: ``response`` (time series per run, at most
:data:`MAX_RECORDS` records spread over the run plus its extremes: ``device``, ``power [mW]``
per heated crease, ``time [s]``, ``fold_angle [deg]`` or ``tip_distance [um]``,
``temperature [degC]``), ``summary`` (per run: ``rise_time [s]``, ``release_time [s]``,
``time_to_90 [s]``, ``thermal_time_constant [s]``, ``change [deg or um]``,
``mechanical_period_unheated [s]``, ``mechanical_period_heated [s]``, ``energy [mJ]``,
``energy_to_90 [mJ]``), ``square_wave`` (per frequency: ``frequency [Hz]``, ``amplitude
[deg]``, ``relative_amplitude [-]``, ``bandwidth [Hz]``). Figure ``actuation_speed.png``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from design.devices.gripper import (ARM_CREASES, BASE_CREASES, GripperDesign, GripperHeatModel,
                                    _base_fold, _tip_distance, make_gripper_model)
from simulator import Heat, get_case, natural_modes, simulate
from simulator.schedules import SquareWave, StepPower
from simulator.mechanics import fold_angles
from studies._common import TEMP, progress_bar, study_main

NAME = "actuation_speed"
CASE = "single_fold_step_response"
#: The gripper in the paper setting (its chain heat loss).
PAPER_HEAT = GripperHeatModel(loss_model="chain")
POWERS_MW, POWERS_QUICK = (1.0, 2.0, 3.0, 4.0, 5.0), (2.0, 4.0)
PHASE, PHASE_QUICK = 1.0, 0.15                     # s, on and off
FREQS, FREQS_QUICK = (1.0, 3.0, 10.0, 20.0, 30.0, 50.0, 100.0), (10.0, 100.0)
WAVE_POWER_MW, PERIODS = 3.0, 4
#: Time [s] the square wave runs before its last period is measured, at least: the ringing of
#: the lifted-off fold mode (~35 Hz, damping ratio ~0.08) decays by e in ~60 ms.
SETTLE, SETTLE_QUICK = 0.4, 0.1
DT_MAX = 5e-4                                  # s, resolves the ~4 ms release
MAX_RECORDS = 800                              # response rows kept per run in the table
#: Gripper powers per heated crease [mW]: assembly needs 26.4 (base fold 90 deg), grip 5.9
#: (tips 100 um apart) with the base held at the assembly power (``evaluate_gripper``); above
#: about 6.2 mW the arm tips touch and the static solution fails.
ASSEMBLY_MW, GRIP_MW = (28.0, 32.0), (6.0, 5.5)
T, FOLD, TIP = "time [s]", "fold_angle [deg]", "tip_distance [um]"


def crossing(t, y, level) -> float:
    """First time [s] at which ``y`` passes ``level`` (linear interpolation; NaN if never)."""
    y = np.asarray(y, float) - level
    k = np.flatnonzero(np.sign(y[1:]) != np.sign(y[:-1]))
    if not len(k):
        return float("nan")
    i = int(k[0])
    return float(t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i]))


@dataclass(frozen=True, eq=False)
class Device:
    """What one actuation heats and measures: ``creases`` (a heater circuit) of ``model``
    heated from ``state``; ``measure(x)`` of the node positions (n, 3) [m] in ``column``."""

    label: str
    model: object
    state: object
    creases: tuple
    measure: Callable
    column: str


def single_crease(residual_fold_deg: float = 0.0) -> Device:
    """The single crease of ``single_fold_step_response`` after self-fold and gravity."""
    case = get_case(CASE, residual_fold_deg=residual_fold_deg)
    pre = simulate(case.model, case.steps[:-1])
    mesh = case.model.mesh
    return Device("single crease", case.model, pre.state, (2,),
                  lambda x: float(np.degrees(fold_angles(mesh, x)[0])), FOLD)


def gripper(stage: str, base_power: float = 0.0) -> Device:
    """The gripper (``design.devices.gripper``) before assembly, or assembled by ``base_power`` [W]
    per base crease (static, held on) before the grip."""
    model, pre = make_gripper_model(GripperDesign(), heat=PAPER_HEAT)        # the paper setting
    state = simulate(model, pre).state
    if stage == "assembly":
        return Device("gripper assembly", model, state, BASE_CREASES,
                      lambda x: float(np.degrees(_base_fold(x))), FOLD)
    state = _static(model, state, BASE_CREASES, base_power).state
    return Device("gripper grip", model, state, ARM_CREASES, lambda x: 1e6 * _tip_distance(x),
                  TIP)


def _static(model, state, creases, power):
    res = simulate(model, [Heat({creases: power}, increments=10, coupling="iterated")],
                   state=state)
    if not res.success:
        raise RuntimeError(f"static heating to {1e3 * power:g} mW: {res.message}")
    return res


def pulse(device: Device, schedule, duration: float, dt_max: float = DT_MAX):
    """Times [s] from the start, measure and mean heated-crease temperature [deg C] of the
    records of one :class:`~simulator.steps.ElectroThermal` run of ``duration`` [s] driven by
    ``schedule`` on the device's circuit (the step settings of the case); record 0 is the
    step's start (the device's state)."""
    step = dataclasses.replace(get_case(CASE).steps[-1], power={device.creases: schedule},
                               duration=duration, dt=dt_max, dt_min=1e-6, dt_max=dt_max)
    res = simulate(device.model, [step], state=device.state)
    if not res.success:
        raise RuntimeError(f"{device.label}: {res.message}")
    records = res.history["stage"] == 0                    # the step's, from its start
    t = res.steps[0].columns[T] - device.state.time
    x = device.model.mesh.nodes[None] + res.history["u"][records]
    rows = [device.model.mesh.crease_row_of(c) for c in device.creases]
    return t, np.array([device.measure(xk) for xk in x]), \
        res.crease_temperature[records][:, rows].mean(axis=1)


def step_metrics(t, y, temp, t_on) -> dict:
    """Rise and release times (10-90 % of the change reached at ``t_on``), the time to 90 %,
    thermal time constant (63.2 % of the temperature rise) [s] and the change."""
    on = int(np.searchsorted(t, t_on - 1e-12))
    y0, dy = y[0], y[on] - y[0]
    t10, t90 = (crossing(t[:on + 1], y[:on + 1], y0 + f * dy) for f in (0.1, 0.9))
    release = crossing(t[on:], y[on:], y0 + 0.1 * dy) - crossing(t[on:], y[on:], y0 + 0.9 * dy)
    tau = crossing(t[:on + 1], temp[:on + 1], temp[0] + 0.632 * (temp[on] - temp[0]))
    return {"rise_time [s]": t90 - t10, "release_time [s]": release, "time_to_90 [s]": t90,
            "thermal_time_constant [s]": tau, "change [deg or um]": dy}


def mechanical_periods(device: Device, power) -> dict:
    """First natural period [s] about the start state and about the static heated one."""
    heated = _static(device.model, device.state, device.creases, power).state
    return {f"mechanical_period_{k} [s]": 1.0 / float(natural_modes(device.model, s,
                                                                   1).frequency[0])
            for k, s in (("unheated", device.state), ("heated", heated))}


def _step_response(runs, phase, progress):
    """``runs``: [(device, power per heated crease [mW])]."""
    rows, series = [], []
    for device, p in progress_bar(runs, progress, desc="step response"):
        t, y, temp = pulse(device, StepPower(p * 1e-3, 0.0, phase), 2 * phase)
        keep = np.unique(np.r_[np.linspace(0, len(t) - 1, MAX_RECORDS).astype(int),
                               np.argmax(y), np.argmin(y)])              # keep the extremes
        series.append(pd.DataFrame({"table": "response", "device": device.label,
                                    "power [mW]": p, T: t[keep], device.column: y[keep],
                                    TEMP: temp[keep]}))
        metrics = step_metrics(t, y, temp, phase)
        total = p * len(device.creases)
        rows.append({"table": "summary", "device": device.label, "power [mW]": p, **metrics,
                     **mechanical_periods(device, p * 1e-3), "energy [mJ]": total * phase,
                     "energy_to_90 [mJ]": total * metrics["time_to_90 [s]"]})
    return pd.concat([*series, pd.DataFrame(rows)], ignore_index=True)


def _square_wave(freqs, settle, progress):
    device = single_crease()
    rows = []
    for f in progress_bar(freqs, progress, desc="square wave"):
        n = max(PERIODS, math.ceil(settle * f) + 1)       # transients decay for >= settle s
        t, fold, _ = pulse(device, SquareWave(WAVE_POWER_MW * 1e-3, 1 / f, 0.5), n / f,
                           min(5e-3, 0.02 / f))
        last = t >= (n - 1) / f - 1e-12
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
    crease = single_crease()
    runs = [(crease, p) for p in (POWERS_QUICK if quick else POWERS_MW)]
    assembly, grip = gripper("assembly"), gripper("grip", ASSEMBLY_MW[0] * 1e-3)
    runs += [(assembly, p) for p in ASSEMBLY_MW[:1 if quick else None]]
    runs += [(grip, p) for p in GRIP_MW[:1 if quick else None]]
    steps = _step_response(runs, PHASE_QUICK if quick else PHASE, progress)
    return pd.concat([steps, _square_wave(FREQS_QUICK if quick else FREQS,
                                                  SETTLE_QUICK if quick else SETTLE, progress)],
                     ignore_index=True)


METRICS = (("rise_time [s]", "o"), ("release_time [s]", "s"),
           ("thermal_time_constant [s]", "^"), ("mechanical_period_heated [s]", "x"),
           ("mechanical_period_unheated [s]", "+"))


def plot(df: pd.DataFrame):
    """(a) single-crease fold vs time per power, (b) normalised gripper responses, (c) time
    scales of every run, (d) square-wave amplitude vs frequency."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 8.5), layout="constrained")
    (ax_t, ax_g), (ax_s, ax_f) = fig.subplots(2, 2)
    resp = df[df["table"] == "response"]
    for (device, p), d in resp.groupby(["device", "power [mW]"], sort=False):
        if device == "single crease":
            ax_t.plot(d[T], d[FOLD], label=f"{p:g} mW")
        else:
            y = d[FOLD if device == "gripper assembly" else TIP].to_numpy()
            on = int(np.argmin(np.abs(d[T].to_numpy() - d[T].max() / 2)))
            ax_g.plot(d[T], (y - y[0]) / (y[on] - y[0]), label=f"{device}, {p:g} mW")
    ax_t.set(xlabel="time [s]", ylabel="fold angle [deg]",
             title="(a) single crease: power on, then off")
    ax_g.set(xlabel="time [s]", ylabel="change / change at power off [-]",
             title="(b) gripper: base fold (assembly), tip distance (grip)")
    s = df[df["table"] == "summary"].reset_index(drop=True)
    labels = [f"{d.replace('gripper ', '').replace('single ', '')}\n{p:g} mW"
              for d, p in zip(s["device"], s["power [mW]"])]
    for col, marker in METRICS:
        ax_s.plot(range(len(s)), s[col], marker, ls="none", ms=7,
                  label=col.split(" [")[0].replace("_", " "))
    ax_s.set_xticks(range(len(s)), labels, fontsize="x-small")
    ax_s.set(ylabel="time [s]", yscale="log", title="(c) time scales per run")
    w = df[df["table"] == "square_wave"]
    ax_f.loglog(w["frequency [Hz]"], w["relative_amplitude [-]"], "o-")
    ax_f.axhline(1 / np.sqrt(2), color="grey", ls=":", label="-3 dB")
    bw = w["bandwidth [Hz]"].iloc[0] if len(w) else np.nan
    ax_f.set(xlabel="square-wave frequency [Hz]", ylabel="fold amplitude / low-frequency one",
             title=(f"(d) single crease, {WAVE_POWER_MW:g} mW square wave: bandwidth "
                    f"{bw:.3g} Hz" if np.isfinite(bw) else "(d) square wave"))
    for ax in (ax_t, ax_g, ax_s, ax_f):
        ax.grid(True, alpha=0.3)
    ax_t.legend(fontsize="x-small", loc="upper right")
    ax_g.legend(fontsize="x-small", loc="center right")
    ax_s.legend(fontsize="x-small", loc="upper left", ncols=2)
    ax_f.legend(fontsize="x-small", loc="lower left")
    from studies.plotting import environment_note, note_assumptions

    note_assumptions(fig, environment_note("air", 0.026, 0, 1.0, extra=[
        "single crease 150 um over a substrate (contact), chip a heat sink at room "
        "temperature", "gripper: lumped self-weight, residual fold 0", "air damping "
        "2 N s/m^3"]), *heat_loss_lines())
    return fig


def heat_loss_lines() -> list:
    """The footer lines naming each device's heat-loss model (the models this study runs)."""
    from studies.plotting import heat_loss_note

    return [f"single crease: {heat_loss_note(get_case(CASE).model)}",
            f"gripper: {heat_loss_note(make_gripper_model(GripperDesign(), heat=PAPER_HEAT)[0])}"]


def main(argv=None):
    return study_main(NAME, __doc__, run, plot, argv)


if __name__ == "__main__":
    main()
