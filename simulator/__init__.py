"""etorigami simulator: electro-thermo-mechanical bar-and-hinge simulation of active origami.

The front door has what a simulation needs::

    from simulator import make_model, simulate, SelfFold, Gravity, Heat, get_case

Build a :class:`Pattern` (or take one of :mod:`simulator.example_patterns`), make a
:class:`Model` with :func:`make_model`, run an ordered list of steps with :func:`simulate`, and
read the :class:`SimulationResult` (``success``, ``status``, ``message``, ``to_frame()``,
``save()``).

Families live in namespaces, imported on first use: :mod:`simulator.materials`,
:mod:`simulator.model` (concentrated hinges, layer stacks, masses), :mod:`simulator.thermal`
(the steady thermal operator, crease temperature measures and limit, transient heat),
:mod:`simulator.schedules` (power schedules and signals), :mod:`simulator.steps` (the step
protocol, for step authors), :mod:`simulator.solvers` (Newton, path following, dynamics,
stability, modes), :mod:`simulator.mechanics` (the equilibrium system, element families),
:mod:`simulator.cases`, :mod:`simulator.fold` (FOLD files), :mod:`simulator.viewer`,
:mod:`simulator.fe` (the FE reference, optional extra ``[fe]``), :mod:`simulator.kernels`
(compiled kernels) and :mod:`simulator.sensitivity` (exact gradients of a steady heated state). Older spellings at the door (``simulator.read_fold``) still work for one
release with a deprecation warning naming the new place (the table is in ``_moved.py``).

``import simulator`` imports no submodule: each public name is imported from its submodule on
first use (see :mod:`simulator._lazy`), so a script pays only for what it uses.
"""

from ._lazy import attach as _attach
from ._version import __version__

__getattr__, __dir__ = _attach(__name__, {
    ".geometry.pattern": ("Pattern",),
    ".geometry.materials": ("AIR", "WATER", "Material"),
    ".model.mesh": ("BarHingeMesh", "make_mesh"),
    ".model.model": ("ContactParameters", "Model", "Supports", "make_model"),
    ".model.properties": ("BarHingeParameters",),
    ".model.bimorph": ("Actuators", "Bimorph"),
    ".model.thermal_parameters": ("ThermalParameters",),
    ".model.heat_loss": ("ChainLoss", "IntegralLoss", "Substrate"),
    ".thermal.circuits": ("Circuit", "Drive", "Heater"),
    ".steps.mechanical": ("Gravity", "Load", "SelfFold"),
    ".steps.heating": ("AmbientTemperature", "Heat"),
    ".steps.transient": ("TransientHeat",),
    ".steps.dynamics": ("Dynamics",),
    ".steps.electrothermal": ("ElectroThermal",),
    ".steps.continuation": ("ArcLengthLoad", "DisplacementControl"),
    ".simulation": ("simulate",),
    ".solvers.newton": ("NewtonOptions",),
    ".solvers.dynamics_options": ("DynamicsOptions",),
    ".results": ("SimulationResult",),
    ".cases": ("Case", "get_case"),
    ".solvers.modes": ("ModesResult", "natural_modes"),
    ".errors": ("ConvergenceError", "EtorigamiDeprecationWarning", "EtorigamiError",
                "FoldFormatError", "ParameterError", "PatternError", "SolverError"),
}, modules={"example_patterns": ".example_patterns", "materials": ".materials",
            "model": ".model", "thermal": ".thermal", "schedules": ".schedules",
            "steps": ".steps", "solvers": ".solvers", "mechanics": ".mechanics",
            "cases": ".cases", "fold": ".fold", "viewer": ".viewer", "fe": ".fe",
            "kernels": ".kernels", "sensitivity": ".sensitivity"}, moved="._moved",
            renamed="._moved")

__all__ = [
    "__version__",
    # pattern, mesh, model and their parameters
    "Pattern", "BarHingeMesh", "make_mesh", "Model", "make_model", "Supports",
    "ContactParameters", "BarHingeParameters", "ThermalParameters", "Actuators", "Bimorph",
    "Material",
    # heat loss to the medium: the paper's chains or the calibration-free integral, a substrate
    "ChainLoss", "IntegralLoss", "Substrate", "AIR", "WATER",
    # electrical drive: heaters in circuits
    "Heater", "Circuit", "Drive",
    # the steps and the facade
    "SelfFold", "Load", "Gravity", "Heat", "AmbientTemperature", "TransientHeat", "Dynamics",
    "ElectroThermal", "ArcLengthLoad", "DisplacementControl", "simulate", "NewtonOptions",
    "DynamicsOptions",
    # results, cases, natural modes
    "SimulationResult", "Case", "get_case", "natural_modes", "ModesResult",
    # errors
    "EtorigamiError", "ParameterError", "PatternError", "FoldFormatError", "ConvergenceError",
    "SolverError", "EtorigamiDeprecationWarning",
    # the namespaces
    "example_patterns", "materials", "model", "thermal", "schedules", "steps", "solvers",
    "mechanics", "cases", "fold", "viewer", "fe", "kernels", "sensitivity",
]
