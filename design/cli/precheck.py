"""A cheap look at the crease temperatures a heating run asks for, before it runs.

One linear steady thermal solve on the unfolded shape at the power the run's ``Heat`` steps
end at (milliseconds): an absurd request is refused in one line, one above the design limit
1.2 T_g of the crease material is run with a warning. The shape changes as the sheet folds,
so this is an estimate; the run reports the real temperatures.
"""

from __future__ import annotations

from ._common import CLIError

__all__ = ["estimate_crease_temperature", "check_heating", "ABSURD_TEMPERATURE_C"]

#: Estimated crease temperature [degC] above which a run is refused: beyond any material of
#: these devices (SU-8 decomposes near 380 degC, gold melts at 1064 degC).
ABSURD_TEMPERATURE_C = 1000.0


def _steady_temperature(model, steps):
    """(n,) nodal temperatures [degC] at the power the ``Heat`` steps of ``steps`` end at,
    from one steady solve on the unfolded shape; None if the run heats nothing by ``Heat``
    steps or the model has no thermal parameters."""
    from simulator import Heat
    # behind the doors, as the heater LP: the steady thermal operator
    # (tests/unit/test_architecture.py)
    from simulator.thermal import thermal_model

    heats = [s for s in steps if isinstance(s, Heat)]
    if not heats or model.thermal is None:
        return None
    mesh = model.mesh
    power = sum(s.power_array(mesh) for s in heats)
    thermal = thermal_model(model)
    return thermal.solve(mesh.nodes, thermal.heat_vector(power))


def estimate_crease_temperature(model, steps):
    """(C,) crease temperatures [degC] on the measure of the design limit, the centre-line
    mean (:func:`simulator.thermal.crease_limit_temperatures`), at the power the ``Heat`` steps of
    ``steps`` end at, from one steady solve on the unfolded shape; None if the run heats
    nothing by ``Heat`` steps or the model has no thermal parameters (numpy is imported here,
    so that ``etorigami --version`` stays light)."""
    from simulator.thermal import crease_limit_temperatures

    temperature = _steady_temperature(model, steps)
    return None if temperature is None else crease_limit_temperatures(temperature, model.mesh)


def check_heating(model, steps, what: str) -> str | None:
    """Refuse (``CLIError``) a run whose estimated hottest crease (centre-line mean, the
    measure of the design limit) exceeds :data:`ABSURD_TEMPERATURE_C`; return a warning line
    naming the crease, its estimate and the limit if it exceeds 1.2 T_g of the crease material
    (:class:`simulator.thermal.TemperatureLimit`), else None."""
    import numpy as np

    from simulator.thermal import TemperatureLimit, crease_limit_temperatures

    mesh = model.mesh
    temperature = _steady_temperature(model, steps)
    if temperature is None or not len(mesh.crease_ids):
        return None
    temps = crease_limit_temperatures(temperature, mesh)
    row = int(np.argmax(temps))                              # a NaN is refused below
    hottest, crease = float(temps[row]), int(mesh.crease_ids[row])
    how = "(one linear thermal solve on the unfolded shape)"
    if not np.isfinite(hottest) or hottest > ABSURD_TEMPERATURE_C:
        raise CLIError(f"{what}: crease {crease} would reach a centre-line mean of about "
                       f"{hottest:.0f} degC {how}, above {ABSURD_TEMPERATURE_C:g} degC where no "
                       "material of these devices survives; lower the power")
    limit = TemperatureLimit.of_material(mesh.pattern.crease_material)
    v = None if limit is None else limit.judge(temperature, mesh)
    if v is None or v.success:
        return None
    return (f"warning: {what}: crease {v.crease} would reach a {limit.measure_words} of about "
            f"{v.temperature:.0f} degC {how}, above {limit.text} of the crease material; "
            "running anyway")
