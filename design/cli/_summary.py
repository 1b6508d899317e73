"""What a finished simulation printed by the CLI says besides its status: the events of its steps
(snaps, limit points: typed records, :class:`simulator.Event`), the hottest crease and any
crossing of the design limit 1.2 T_g of the crease material.

Creases are named by their crease id (the pattern's edge id), as in ``creases.csv``, the FOLD
files and the viewer. The temperature is the hottest of a crease's 7 nodes
(``temperature_max [degC]`` of ``creases.csv``): the conservative measure, the one the limit is
checked on here.
"""

from __future__ import annotations

from simulator._validate import listed

from .precheck import TG_FACTOR

__all__ = ["summary_lines"]


def _event_line(event, crease_ids) -> str:
    """``snap in step heat at 9.215 mW in all (crease 2: 9.215 mW), jump 51.0 um (node 7)``."""
    where = f" in step {event.step}" if event.step else ""
    powers = [(int(c), p) for c, p in zip(crease_ids, event.power_per_crease) if p > 0]
    per = ", ".join(f"crease {c}: {1e3 * p:.4g} mW" for c, p in powers[:4])
    per += ", ..." if len(powers) > 4 else ""
    text = f"{event.kind.replace('_', ' ')}{where} at {1e3 * event.total_power:.4g} mW in all"
    text += f" ({per})" if per else ""
    if event.jump is not None:
        text += f", jump {1e6 * event.jump:.3g} um"
    elif event.displacement is not None:
        text += f", displacement {1e6 * event.displacement:.3g} um"
    if event.node is not None:
        text += f" (node {event.node})"
    if event.temperature_max is not None:
        text += f", hottest node {event.temperature_max:.0f} degC"
    if event.creases:
        text += f"; creases {listed(event.creases)} folded past +-180 deg"
    if event.panels:
        text += f"; panels {listed(event.panels)} passed through each other"
    return text



def _temperature_lines(result) -> list:
    """The hottest crease over all records and the first record above 1.2 T_g, if any."""
    import numpy as np

    tmax = result.crease_temperature_max                         # (records, C) [degC]
    if tmax.size == 0 or not np.isfinite(tmax).any():
        return []
    h, ids = result.history, result.model.mesh.crease_ids
    rec, row = np.unravel_index(int(np.nanargmax(tmax)), tmax.shape)
    hottest = float(tmax[rec, row])
    lines = [f"hottest crease: crease {int(ids[row])} at {hottest:.1f} degC (hottest of its 7 "
             f"nodes; record {rec}, step {h['stage_name'][rec]})"]
    material = result.model.mesh.pattern.crease_material
    tg = getattr(material, "glass_transition", None)
    if tg is None:
        return lines
    limit = TG_FACTOR * tg
    above = np.flatnonzero((tmax > limit).any(axis=1))
    if len(above):
        first = int(above[0])
        crease = int(ids[int(np.argmax(tmax[first]))])
        total = 1e3 * float(np.sum(h["power"][first]))
        lines.append(f"above {TG_FACTOR:g} T_g = {limit:.0f} degC of the crease material from "
                     f"record {first} (step {h['stage_name'][first]}, {total:.4g} mW in all, "
                     f"crease {crease} first): the design limit is exceeded")
    else:
        lines.append(f"below {TG_FACTOR:g} T_g = {limit:.0f} degC of the crease material "
                     "throughout")
    return lines


def summary_lines(result) -> list:
    """Lines for the CLI summary of a :class:`simulator.SimulationResult`: one per event
    (``event: ...``), then the hottest crease and the 1.2 T_g check (a model without a
    thermal part, e.g. concentrated hinges, or without thermal records: none)."""
    ids = result.model.mesh.crease_ids
    lines = [f"event: {_event_line(e, ids)}" for e in result.events]
    if result.history["temperature"].size and result.model.thermal is not None:
        lines += _temperature_lines(result)
    return lines
