"""A cheap look at the crease temperatures a heating run asks for, before it runs.

One linear steady thermal solve on the unfolded shape at the power the run's ``Heat`` steps
end at (milliseconds): an absurd request is refused in one line, one above the design limit
1.2 T_g of the crease material is run with a warning. The shape changes as the sheet folds,
so this is an estimate; the run reports the real temperatures.
"""

from __future__ import annotations

from ._common import CLIError

__all__ = ["estimate_crease_temperature", "check_heating", "ABSURD_TEMPERATURE_C",
           "TG_FACTOR"]

#: Estimated crease temperature [degC] above which a run is refused: beyond any material of
#: these devices (SU-8 decomposes near 380 degC, gold melts at 1064 degC).
ABSURD_TEMPERATURE_C = 1000.0
#: The design limit on crease temperatures, as a multiple of T_g (paper section 6.3).
TG_FACTOR = 1.2


def estimate_crease_temperature(model, steps):
    """(C,) crease temperatures [degC] (7-node weighted mean) at the power the ``Heat`` steps
    of ``steps`` end at, from one steady solve on the unfolded shape; None if the run heats
    nothing by ``Heat`` steps or the model has no thermal parameters (numpy is imported here,
    so that ``etorigami --version`` stays light)."""
    from simulator import Heat
    # behind the doors, as the heater LP: the steady thermal operator and the crease
    # temperature weights (tests/unit/test_architecture.py)
    from simulator.model.bimorph import crease_temperature_weights
    from simulator.state import thermal_model

    heats = [s for s in steps if isinstance(s, Heat)]
    if not heats or model.thermal is None:
        return None
    mesh = model.mesh
    power = sum(s.power_array(mesh) for s in heats)
    thermal = thermal_model(model)
    temperature = thermal.solve(mesh.nodes, thermal.heat_vector(power))
    return temperature[mesh.crease_nodes] @ crease_temperature_weights()


def check_heating(model, steps, what: str) -> str | None:
    """Refuse (``CLIError``) a run whose estimated hottest crease exceeds
    :data:`ABSURD_TEMPERATURE_C`; return a warning line if it exceeds 1.2 T_g, else None."""
    import numpy as np

    temps = estimate_crease_temperature(model, steps)
    if temps is None or not len(temps):
        return None
    row = int(np.argmax(temps))
    hottest, crease = float(temps[row]), int(model.mesh.crease_ids[row])
    estimate = (f"{what}: crease {crease} would reach about {hottest:.0f} degC (one linear "
                "thermal solve on the unfolded shape)")
    if not np.isfinite(hottest) or hottest > ABSURD_TEMPERATURE_C:
        raise CLIError(f"{estimate}, above {ABSURD_TEMPERATURE_C:g} degC where no material of "
                       "these devices survives; lower the power")
    tg = model.mesh.pattern.crease_material.glass_transition
    if tg is not None and hottest > TG_FACTOR * tg:
        return (f"warning: {estimate}, above {TG_FACTOR:g} T_g = {TG_FACTOR * tg:.0f} degC of "
                "the crease material; running anyway")
    return None
