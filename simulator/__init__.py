"""etorigami simulator: electro-thermo-mechanical bar-and-hinge simulation of active origami.

Everything a user needs is importable from here::

    from simulator import make_model, simulate, SelfFold, Gravity, Heat, get_case

Build a :class:`Pattern` (or take one of :mod:`simulator.example_patterns`), make a
:class:`Model` with :func:`make_model`, run an ordered list of steps with :func:`simulate`, and
read the :class:`SimulationResult` (``success``, ``status``, ``message``, ``to_frame()``,
``save()``).

``import simulator`` imports no submodule: each public name is imported from its submodule on
first use (see :mod:`simulator._lazy`), so a script pays only for what it uses.

The package is organised by physics: ``geometry`` (patterns, materials), ``model`` (mesh,
properties, bimorph, masses), ``mechanics`` (element families, contact, equilibrium),
``thermal`` (steady and transient heat, schedules), ``solvers`` (Newton, continuation,
dynamics, stability, modes), ``linalg`` (factorisations), ``steps`` (the loading steps) and
``io`` (FOLD files, viewer). Import public names from ``simulator`` itself.
"""

from ._lazy import attach as _attach
from ._version import __version__

__getattr__, __dir__ = _attach(__name__, {
    ".model.bimorph": ("Actuators", "Bimorph"),
    ".case_notes": ("parameter_note",),
    ".cases": ("Case", "describe_cases", "get_case", "miura_fold_signs", "miura_sheet_model",
               "single_fold_model"),
    ".solvers.dynamics": ("DynamicsResult", "integrate"),
    ".solvers.dynamics_options": ("DynamicsOptions",),
    ".mechanics.elements.springs": ("spring_kernel_backend",),
    "._jit": ("kernel_cache_warm", "warm_kernel_cache"),
    ".mechanics.kinematics": ("fold_angles",),
    ".mechanics.equilibrium": ("EquilibriumSystem",),
    ".mechanics.families": ("Configuration", "ElementFamily", "FamilyValues"),
    ".errors": ("ConvergenceError", "EtorigamiDeprecationWarning", "EtorigamiError",
                "FoldFormatError", "ParameterError", "PatternError", "SolverError"),
    ".io.fold": ("FoldGeometry", "fold_to_model", "fold_to_pattern", "load_fold_json",
                 "model_to_fold", "parse_fold", "pattern_to_fold",
              "read_fold", "read_model", "result_to_fold_frames", "write_fold",
              "write_fold_frames", "write_model"),
    ".solvers.generalized_alpha": ("MotionState", "TimeIntegrator"),
    ".geometry.materials": ("AIR", "GOLD", "GOLD_FILM", "SILICON", "SPR", "SU8", "SUBSTRATE",
                            "WATER", "Fluid", "Material"),
    ".model.mass": ("lumped_masses",),
    ".model.stack": ("LayerStack", "STACKS", "get_stack", "stack_model", "central_panel",
                     "unsupported_panels", "check_supported", "plain_contact"),
    ".geometry.orientation": ("start_fold_angles",),
    ".model.mesh": ("BarHingeMesh", "build_mesh"),
    ".model.sharp": ("SharpHingeParameters", "sharp_model"),
    ".model.sharp_mesh": ("SharpHingeMesh", "build_sharp_mesh"),
    ".schedules": ("PiecewiseLinearSignal", "RampSignal", "Schedule", "SineSignal",
                   "SquareWaveSignal", "StepSignal"),
    ".model.model": ("REFERENCE_GRAVITY", "STANDARD_GRAVITY", "ContactParameters", "Model",
               "Supports", "make_model"),
    ".solvers.modes": ("ModesResult", "natural_modes"),
    ".solvers.newton": ("NewtonOptions",),
    ".geometry.pattern": ("Pattern",),
    ".thermal.schedules": ("PiecewiseLinear", "PowerSchedule", "Ramp", "Sine", "SquareWave",
                         "StepPower"),
    ".model.properties": ("BarHingeParameters",),
    ".results": ("SimulationResult", "StepResult"),
    ".events": ("EVENT_KINDS", "Event", "crossing_event"),
    ".mechanics.crossing": ("crease_crossings", "node_crossings"),
    ".simulation": ("simulate",),
    ".state": ("ROOM_TEMPERATURE", "SimulationState", "initial_state"),
    ".steps": ("AmbientTemperature", "ArcLengthLoad", "DisplacementControl",
               "Dynamics", "ElectroThermal", "Gravity", "Heat", "Load", "SelfFold", "Step",
               "StepContext", "StepOutcome", "StepRecorder", "TransientHeat"),
    ".solvers.continuation": ("ContinuationResult", "CriticalPoint", "displacement_control", "mgdcm"),
    ".solvers.load_path": ("LoadPath",),
    ".solvers.stability": ("Stability", "tangent_stability", "state_stability"),
    ".solvers.equilibrium_check": ("EQUILIBRIUM_RTOL", "EquilibriumCheck", "check_equilibrium"),
    ".thermal.parameters": ("REFERENCE_BETA", "ThermalParameters"),
    ".thermal.layers": ("Layer", "SheetLayers"),
    ".thermal.loss": ("HEAT_LOSS_MODELS", "ChainLoss", "IntegralLoss", "Substrate"),
    ".thermal.monotone": ("CONDUCTIONS",),
    ".thermal.calibration": ("CalibrationResult", "calibrate_environment"),
    ".thermal.measures": ("CREASE_MEASURES", "crease_temperatures"),
    ".thermal.circuits": ("Circuit", "Drive", "Heater"),
    ".thermal.limit": ("TG_FACTOR", "LIMIT_MEASURES", "TemperatureLimit", "TemperatureVerdict",
                       "crease_limit_temperatures"),
    ".thermal.fixed_shape": ("FixedShapeTemperatures", "fixed_shape_temperatures",
                             "boundary_panel_plane"),
    ".thermal.transient": ("REFERENCE_THETA", "DEFAULT_THETA", "ThetaStepper", "TransientHeatResult",
                        "capacity_vector", "integrate_heat", "theta_step"),
    ".io.viewer": ("load_viewer_data", "viewer_html", "write_viewer"),
    ".thermal.fe": ("FE2DResult", "FE3DResult", "FEDiskResult", "fe_disk", "fe_sphere",
                    "solve_fe2d", "solve_fe3d"),
}, modules={"example_patterns": ".geometry.example_patterns"})

__all__ = [
    "__version__", "example_patterns",
    # patterns, meshes, models
    "Pattern", "BarHingeMesh", "build_mesh", "Material", "SU8", "SPR", "SUBSTRATE",
    # concentrated hinges (sharp creases)
    "sharp_model", "SharpHingeParameters", "SharpHingeMesh", "build_sharp_mesh",
    "BarHingeParameters", "ThermalParameters", "Actuators", "Bimorph", "Supports",
    "ContactParameters", "Model", "make_model", "STANDARD_GRAVITY", "ROOM_TEMPERATURE",
    "Fluid", "GOLD", "GOLD_FILM", "SILICON", "AIR", "WATER",
    # the sheet's layer stacks for the heat balance (crease_conduction="layers", theory 4.10)
    "Layer", "SheetLayers",
    # heat loss to the medium: the paper's chains or the calibration-free integral, a substrate
    "ChainLoss", "IntegralLoss", "Substrate", "HEAT_LOSS_MODELS",
    # the sheet's conduction: the reference's T3 or the monotone one (theory 4.9)
    "CONDUCTIONS",
    "REFERENCE_GRAVITY", "REFERENCE_BETA", "fold_angles",
    # plain crease patterns: layer stacks and fold signs of a start shape
    "LayerStack", "STACKS", "get_stack", "stack_model", "central_panel", "unsupported_panels",
    "check_supported", "start_fold_angles", "plain_contact",
    # steps and the facade
    "Step", "StepContext", "StepOutcome", "StepRecorder", "SelfFold", "Load", "Gravity", "Heat",
    "AmbientTemperature", "simulate", "NewtonOptions", "SimulationState",
    "initial_state", "spring_kernel_backend", "kernel_cache_warm", "warm_kernel_cache",
    # element families (a new element type) and the system that assembles them
    "EquilibriumSystem", "ElementFamily", "FamilyValues", "Configuration",
    # transient heat
    "TransientHeat", "PowerSchedule", "StepPower", "Ramp", "SquareWave", "Sine",
    "PiecewiseLinear", "integrate_heat", "TransientHeatResult", "capacity_vector",
    "ThetaStepper", "theta_step", "REFERENCE_THETA", "DEFAULT_THETA",
    # time schedules of mechanical drives (Dynamics, ElectroThermal)
    "Schedule", "StepSignal", "RampSignal", "SquareWaveSignal", "SineSignal",
    "PiecewiseLinearSignal",
    # the crease temperature limit (1.2 T_g, judged on the crease centre-line mean)
    "TemperatureLimit", "TemperatureVerdict", "crease_limit_temperatures", "TG_FACTOR",
    "LIMIT_MEASURES",
    # each crease's temperature measures (actuation, centre line, centre, hottest node)
    "crease_temperatures", "CREASE_MEASURES",
    # heat loss: calibrating the chain model to the boundary-integral model or the FE
    "calibrate_environment", "CalibrationResult",
    # steady temperatures of a fixed shape under the chain, integral or FE loss model
    "fixed_shape_temperatures", "FixedShapeTemperatures", "boundary_panel_plane",
    # the FE reference of steady heat transfer (optional extra [fe])
    "fe_disk", "fe_sphere", "solve_fe3d", "solve_fe2d", "FEDiskResult", "FE3DResult",
    "FE2DResult",
    # dynamics and natural modes
    "Dynamics", "DynamicsOptions", "DynamicsResult", "MotionState", "TimeIntegrator", "integrate",
    "lumped_masses", "natural_modes", "ModesResult",
    # path following through limit points
    "ArcLengthLoad", "DisplacementControl", "LoadPath", "mgdcm", "displacement_control",
    "ContinuationResult", "CriticalPoint", "Stability", "tangent_stability", "Event",
    "EVENT_KINDS",
    # analyses about a given state check that it is an equilibrium
    "state_stability", "check_equilibrium", "EquilibriumCheck", "EQUILIBRIUM_RTOL",
    # panels passing through each other between two states
    "crossing_event", "crease_crossings", "node_crossings",
    # coupled electro-thermal dynamics
    "ElectroThermal",
    # electrical drive: heaters with a temperature coefficient in circuits (theory 8.8)
    "Heater", "Circuit", "Drive",
    # results and cases
    "SimulationResult", "StepResult", "Case", "get_case", "describe_cases", "parameter_note",
    # result viewer (self-contained HTML)
    "write_viewer", "viewer_html", "load_viewer_data",
    # FOLD files
    "read_fold", "write_fold", "fold_to_pattern", "pattern_to_fold", "read_model", "write_model",
    "fold_to_model", "model_to_fold", "write_fold_frames", "result_to_fold_frames",
    "parse_fold", "load_fold_json", "FoldGeometry",
    "miura_sheet_model", "miura_fold_signs", "single_fold_model",
    # errors
    "EtorigamiError", "ParameterError", "PatternError", "ConvergenceError", "FoldFormatError",
    "SolverError", "EtorigamiDeprecationWarning",
]
