"""The gripper's electrical drive at full function: what its two circuits draw (theory 8.8).

The paper drove its grippers by voltage and measured electrical power. The power search of
:func:`~design.devices.gripper.evaluate_gripper` gives the heat each heater must dissipate
(assembly power on the base creases, then grip power on the arm creases with the base kept
on). At full function (the grip state) both circuits are on; each is two heaters in series
(:class:`~simulator.Circuit`: the base hinges, the arm hinges), gold films along their creases
(:class:`~simulator.Heater`: R0 = sheet resistance x crease length / W at 21 deg C, resistance
R0 (1 + tcr (T - 21 deg C)) at the crease's actuation temperature T), with leads of
``GripperDesign.lead_fraction`` times the heaters' R0 in series. :func:`gripper_drive` turns
the heater powers into the circuit quantities at that operating point:

* current I from I^2 sum R(T) = the heater powers (the search heats the two creases of a
  circuit equally; the symmetric gripper runs them at the same temperature, so a series
  circuit splits its power the same way);
* the electrical power V I = I^2 (sum R(T) + R_lead): heaters plus leads, what a source meter
  reads;
* the power quoted from the voltage and the room-temperature resistance, V^2 / R0_total
  (R0_total = sum R0 + R_lead): larger than V I by R_total(T) / R0_total, 1.4-1.5 for gold at
  the assembly temperature; shown because a measured "power" may have been computed so.

This is the steady operating point of the heater powers found by the power search, not a search
driven by voltage: at constant voltage the base circuit's power would drift slightly as the arms
heat it during the grip stage (its resistance rises with its temperature).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simulator import Circuit, Heater

from .gripper import ARM_CREASES, BASE_CREASES, GripperResult, gripper_design_pattern

__all__ = ["GripperDrive", "gripper_drive", "gripper_circuits", "DRIVE_STATUSES"]

#: The drive's statuses: computed, or no full function to drive (a stage not met).
DRIVE_STATUSES = ("computed", "not_met")


def gripper_circuits(design) -> tuple:
    """The gripper's two series circuits ``(base, arm)`` (:class:`~simulator.Circuit`) of the
    design's gold heaters (``heater_tcr``) with leads of ``lead_fraction`` x their R0."""
    tcr = {} if design.heater_tcr is None else {"tcr": design.heater_tcr}
    pattern = gripper_design_pattern(design)
    out = []
    for name, creases in (("base", BASE_CREASES), ("arm", ARM_CREASES)):
        heaters = tuple(Heater(c, **tcr) for c in creases)
        r0 = sum(h.base_resistance(pattern) for h in heaters)
        out.append(Circuit(heaters, "series", design.lead_fraction * r0, name))
    return tuple(out)


@dataclass(frozen=True)
class GripperDrive:
    """The two circuits at full function (the grip state); SI units.

    Attributes
    ----------
    success, status, message : the drive was computed (``"computed"``), or not (``"not_met"``:
        a stage of the power search was not met, there is no full function)
    heater_power : float or None
        Heat the four heaters dissipate [W]: 2 x (assembly + grip power per crease).
    electrical_power : float or None
        V I of both circuits [W]: heaters plus leads.
    quoted_power : float or None
        V^2 / R0_total of both circuits [W] (resistance at 21 deg C, leads included).
    lead_loss : float or None
        I^2 R_lead of both circuits [W].
    voltage, current : tuple of float
        (base, arm) circuit voltage [V] and current [A]; empty if not computed.
    resistance_ratio : tuple of float
        (base, arm) R_total(T) / R0_total [-]; empty if not computed.
    heater_temperature : tuple of float
        (base, arm) mean actuation temperature of the circuit's heaters [deg C]; empty if not
        computed.
    """

    success: bool
    status: str
    message: str
    heater_power: float | None = None
    electrical_power: float | None = None
    quoted_power: float | None = None
    lead_loss: float | None = None
    voltage: tuple = ()
    current: tuple = ()
    resistance_ratio: tuple = ()
    heater_temperature: tuple = ()


def gripper_drive(result: GripperResult) -> GripperDrive:
    """The circuits' voltage, current and power at the full function of ``result`` (its grip
    state: the assembly power on the base creases, the grip power on the arm creases, the
    crease temperatures of :attr:`StageResult.crease_temperatures`); see the module
    docstring."""
    if not result.success:
        return GripperDrive(False, "not_met", f"no full function to drive: {result.message}")
    design, grip = result.design, result.grip
    pattern = gripper_design_pattern(design)
    rows = {int(c): k for k, c in enumerate(pattern.creases)}     # crease rows of the mesh
    temps = np.asarray(grip.crease_temperatures, float)
    power = {"base": result.assembly.power_per_crease, "arm": grip.power_per_crease}
    totals = np.zeros(4)                      # heater, V I, V^2 / R0, leads
    volts, amps, ratios, temps_out = [], [], [], []
    for circuit in gripper_circuits(design):
        r0 = np.array([h.base_resistance(pattern) for h in circuit.heaters])
        T = temps[[rows[h.crease] for h in circuit.heaters]]
        R = r0 * (1.0 + np.array([h.tcr * (t - h.reference_temperature)
                                  for h, t in zip(circuit.heaters, T)]))
        p = power[circuit.name] * len(circuit.heaters)
        i2 = p / R.sum()
        r_tot, r0_tot = R.sum() + circuit.lead_resistance, r0.sum() + circuit.lead_resistance
        v = np.sqrt(i2) * r_tot
        totals += (p, i2 * r_tot, v * v / r0_tot, i2 * circuit.lead_resistance)
        volts.append(float(v))
        amps.append(float(np.sqrt(i2)))
        ratios.append(float(r_tot / r0_tot))
        temps_out.append(float(T.mean()))
    heat, vi, quoted, leads = (float(x) for x in totals)
    return GripperDrive(True, "computed", "both circuits at full function", heat, vi, quoted,
                        leads, tuple(volts), tuple(amps), tuple(ratios),
                        tuple(temps_out))
