"""Heat transfer: the steady thermal model (conduction in the sheet plus the heat loss to the
medium: the paper's chains or the calibration-free integral), transient heat, heater circuits
and the crease temperature measures and limit.

The public names (``from simulator.thermal import ThermalModel``): the steady operator of a
model (:func:`thermal_model`, a :class:`ThermalModel`), each crease's temperature measures
(:func:`crease_temperatures`) and the 1.2 T_g limit on them, steady temperatures of a fixed
shape, the calibration of the chains, transient heat without mechanics
(:func:`integrate_heat`), the heat-loss choice and the sheet's layer stacks.
"""

from .._lazy import attach as _attach

__getattr__, __dir__ = _attach(__name__, {
    ".steady": ("ThermalModel", "thermal_model"),
    "..state": ("ROOM_TEMPERATURE",),
    "..model.thermal_parameters": ("ThermalParameters", "REFERENCE_BETA", "CONDUCTIONS",
                                   "SHEET_EXTRAPOLATIONS"),
    "..model.heat_loss": ("HEAT_LOSS_MODELS", "ChainLoss", "IntegralLoss", "Substrate"),
    ".integral_levels": ("sheet_levels",),
    "..model.layers": ("Layer", "SheetLayers"),
    ".measures": ("CREASE_MEASURES", "crease_temperatures"),
    ".limit": ("TG_FACTOR", "LIMIT_MEASURES", "TemperatureLimit", "TemperatureVerdict",
               "crease_limit_temperatures"),
    ".fixed_shape": ("FixedShapeTemperatures", "fixed_shape_temperatures",
                     "boundary_panel_plane"),
    ".calibration": ("CalibrationResult", "calibrate_environment"),
    ".transient": ("REFERENCE_THETA", "DEFAULT_THETA", "ThetaStepper", "TransientHeatResult",
                   "capacity_vector", "integrate_heat", "theta_step"),
    ".circuits": ("Circuit", "Drive", "Heater"),
})

__all__ = [
    # the steady operator of a model and its parameters
    "thermal_model", "ThermalModel", "ThermalParameters", "ROOM_TEMPERATURE", "REFERENCE_BETA",
    # heat loss to the medium and the sheet's conduction
    "ChainLoss", "IntegralLoss", "Substrate", "HEAT_LOSS_MODELS", "CONDUCTIONS", "Layer",
    "SheetLayers", "sheet_levels", "SHEET_EXTRAPOLATIONS",
    # each crease's temperature measures and the 1.2 T_g limit on them
    "crease_temperatures", "CREASE_MEASURES", "crease_limit_temperatures", "TemperatureLimit",
    "TemperatureVerdict", "TG_FACTOR", "LIMIT_MEASURES",
    # steady temperatures of a fixed shape; calibrating the chains
    "fixed_shape_temperatures", "FixedShapeTemperatures", "boundary_panel_plane",
    "calibrate_environment", "CalibrationResult",
    # transient heat without mechanics
    "integrate_heat", "TransientHeatResult", "theta_step", "ThetaStepper", "capacity_vector",
    "DEFAULT_THETA", "REFERENCE_THETA",
    # electrical drive: heaters in circuits
    "Heater", "Circuit", "Drive",
]
