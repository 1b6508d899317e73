"""etorigami simulator: electro-thermo-mechanical bar-and-hinge simulation of active origami.

Everything a user needs is importable from here::

    from simulator import make_model, simulate, SelfFold, Gravity, Heat, get_case

Build a :class:`Pattern` (or take one of :mod:`simulator.example_patterns`), make a
:class:`Model` with :func:`make_model`, run an ordered list of steps with :func:`simulate`, and
read the :class:`SimulationResult` (``success``, ``status``, ``message``, ``to_frame()``,
``save()``).
"""

from ._version import __version__
from .bimorph import Actuators, Bimorph
from .cases import Case, describe_cases, get_case
from .errors import ConvergenceError, EtorigamiError, ParameterError, PatternError
from .materials import SPR, SU8, SUBSTRATE, Material
from .mesh import BarHingeMesh, build_mesh
from .model import STANDARD_GRAVITY, ContactParameters, Model, Supports, make_model
from .newton import NewtonOptions
from .pattern import Pattern
from .properties import BarHingeParameters
from .results import SimulationResult, StepResult
from .simulation import simulate
from .state import ROOM_TEMPERATURE, SimulationState, initial_state
from .steps import (AmbientTemperature, Coupling, Gravity, Heat, Load, SelfFold, Step,
                    StepContext, StepOutcome, StepRecorder)
from .steps import ArcLengthLoad, DisplacementControl
from .continuation import ContinuationResult, CriticalPoint, LoadPath, displacement_control, mgdcm
from .stability import Stability, tangent_stability
from .thermal import ThermalParameters

__all__ = [
    "__version__",
    # patterns, meshes, models
    "Pattern", "BarHingeMesh", "build_mesh", "Material", "SU8", "SPR", "SUBSTRATE",
    "BarHingeParameters", "ThermalParameters", "Actuators", "Bimorph", "Supports",
    "ContactParameters", "Model", "make_model", "STANDARD_GRAVITY", "ROOM_TEMPERATURE",
    # steps and the facade
    "Step", "StepContext", "StepOutcome", "StepRecorder", "SelfFold", "Load", "Gravity", "Heat",
    "AmbientTemperature", "Coupling", "simulate", "NewtonOptions", "SimulationState",
    "initial_state",
    # path following through limit points
    "ArcLengthLoad", "DisplacementControl", "LoadPath", "mgdcm", "displacement_control",
    "ContinuationResult", "CriticalPoint", "Stability", "tangent_stability",
    # results and cases
    "SimulationResult", "StepResult", "Case", "get_case", "describe_cases",
    # errors
    "EtorigamiError", "ParameterError", "PatternError", "ConvergenceError",
]
