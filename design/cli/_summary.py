"""What a finished simulation printed by the CLI says besides its status: the events of its steps
(snaps, limit points: typed records, :class:`simulator.steps.Event`) and the verdict on the design
limit 1.2 T_g of the crease material.

Creases are named by their crease id (the pattern's edge id), as in ``creases.csv``, the FOLD
files and the viewer. The limit is judged, as everywhere, on the crease centre-line mean (the
mean of its nodes A, B, Ctr; theory 5.4, :class:`simulator.thermal.TemperatureLimit`), the hottest
crease over all records counting; the hottest of its nodes (``temperature_max [degC]`` of
``creases.csv``) follows as information.
"""

from __future__ import annotations

from simulator._validate import capped

__all__ = ["summary_lines"]

#: What the CLI adds to the line of an unstable state met by load control.
_BRANCH_NOTES = {
    "branch_switch": "; left the unstable state for the stable branch of lower energy along its "
                     "critical mode (--branch other takes the other)",
    "stability_lost": "; the state stays unstable (not left: --stability switch leaves it)"}


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
    text += _BRANCH_NOTES.get(event.kind, "")
    if event.creases:
        text += f"; creases {capped(event.creases, brackets=False)} folded past +-180 deg"
    if event.kind == "fold_past_flat":
        text += " (their panels still apart: the run goes on)"
    if event.panels:
        text += f"; panels {capped(event.panels, brackets=False)} passed through each other"
    return text



def _temperature_lines(result) -> list:
    """The verdict on the 1.2 T_g limit over all records (the crease centre-line mean, theory
    5.4), then the hottest node as information; none if the crease material has no T_g."""
    import numpy as np

    from simulator.thermal import TemperatureLimit

    mesh, h = result.model.mesh, result.history
    limit = TemperatureLimit.of_material(mesh.pattern.crease_material)
    if limit is None or not len(mesh.crease_ids) or not np.isfinite(h["temperature"]).any():
        return []
    v = limit.judge(h["temperature"], mesh)
    where = lambda rec: f"record {rec}, step {h['stage_name'][rec]}"  # noqa: E731
    lines = [f"temperature limit {'met' if v.success else 'exceeded'}: {v.message} "
             f"(hottest crease on that measure, {where(v.record)})"]
    if v.first_record is not None:
        first = v.first_record
        lines.append(f"the centre-line mean first exceeds {limit.text} at {where(first)} "
                     f"({1e3 * np.sum(h['power'][first]):.4g} mW in all), on crease "
                     f"{v.first_crease}")
    lines.append(v.information(where(v.hottest_node_record)))
    return lines


def summary_lines(result) -> list:
    """Lines for the CLI summary of a :class:`simulator.SimulationResult`: one per event
    (``event: ...``), then the verdict on the 1.2 T_g limit and the hottest node (a model without a
    thermal part, e.g. concentrated hinges, or without thermal records: none)."""
    ids = result.model.mesh.crease_ids
    lines = [f"event: {_event_line(e, ids)}" for e in result.events]
    if result.history["temperature"].size and result.model.thermal is not None:
        lines += _temperature_lines(result)
    return lines
