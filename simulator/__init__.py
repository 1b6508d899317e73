"""etorigami simulator: electro-thermo-mechanical bar-and-hinge simulation of active origami.

Everything a user needs is importable from here::

    from simulator import make_model, simulate, SelfFold, Gravity, Heat, get_case

Build a :class:`Pattern` (or take one of :mod:`simulator.example_patterns`), make a
:class:`Model` with :func:`make_model`, run an ordered list of steps with :func:`simulate`, and
read the :class:`SimulationResult` (``success``, ``status``, ``message``, ``to_frame()``,
``save()``).
"""

from . import example_patterns
from ._version import __version__
from .bimorph import Actuators, Bimorph
from .cases import Case, describe_cases, get_case, miura_sheet_model, single_fold_model
from .dynamics import DynamicsOptions, DynamicsResult, MotionState, TimeIntegrator, integrate
from .elements.springs import spring_kernel_backend
from .errors import (ConvergenceError, EtorigamiError, FoldFormatError, ParameterError,
                     PatternError)
from .fold import (fold_to_model, fold_to_pattern, model_to_fold, pattern_to_fold, read_fold,
                   read_model, result_to_fold_frames, write_fold, write_fold_frames, write_model)
from .materials import AIR, GOLD, SILICON, SPR, SU8, SUBSTRATE, WATER, Fluid, Material
from .mass import lumped_masses
from .mesh import BarHingeMesh, build_mesh
from .model import (REFERENCE_GRAVITY, STANDARD_GRAVITY, ContactParameters, Model, Supports,
                    make_model)
from .modes import ModesResult, natural_modes
from .newton import NewtonOptions
from .pattern import Pattern
from .power_schedules import PiecewiseLinear, PowerSchedule, Ramp, Sine, SquareWave, StepPower
from .properties import BarHingeParameters
from .results import SimulationResult, StepResult
from .simulation import simulate
from .state import ROOM_TEMPERATURE, SimulationState, initial_state
from .steps import (AmbientTemperature, Coupling, Dynamics, ElectroThermal, Gravity, Heat, Load,
                    SelfFold, Step, StepContext, StepOutcome, StepRecorder, TransientHeat)
from .steps import ArcLengthLoad, DisplacementControl
from .continuation import ContinuationResult, CriticalPoint, LoadPath, displacement_control, mgdcm
from .stability import Stability, tangent_stability
from .thermal import ThermalParameters
from .transient_heat import (REFERENCE_THETA, ThetaStepper, TransientHeatResult, capacity_vector,
                             integrate_heat, theta_step)
from .viewer import load_viewer_data, viewer_html, write_viewer

__all__ = [
    "__version__", "example_patterns",
    # patterns, meshes, models
    "Pattern", "BarHingeMesh", "build_mesh", "Material", "SU8", "SPR", "SUBSTRATE",
    "BarHingeParameters", "ThermalParameters", "Actuators", "Bimorph", "Supports",
    "ContactParameters", "Model", "make_model", "STANDARD_GRAVITY", "ROOM_TEMPERATURE",
    "Fluid", "GOLD", "SILICON", "AIR", "WATER",
    "REFERENCE_GRAVITY",
    # steps and the facade
    "Step", "StepContext", "StepOutcome", "StepRecorder", "SelfFold", "Load", "Gravity", "Heat",
    "AmbientTemperature", "Coupling", "simulate", "NewtonOptions", "SimulationState",
    "initial_state", "spring_kernel_backend",
    # transient heat
    "TransientHeat", "PowerSchedule", "StepPower", "Ramp", "SquareWave", "Sine",
    "PiecewiseLinear", "integrate_heat", "TransientHeatResult", "capacity_vector",
    "ThetaStepper", "theta_step", "REFERENCE_THETA",
    # dynamics and natural modes
    "Dynamics", "DynamicsOptions", "DynamicsResult", "MotionState", "TimeIntegrator", "integrate",
    "lumped_masses", "natural_modes", "ModesResult",
    # path following through limit points
    "ArcLengthLoad", "DisplacementControl", "LoadPath", "mgdcm", "displacement_control",
    "ContinuationResult", "CriticalPoint", "Stability", "tangent_stability",
    # coupled electro-thermal dynamics
    "ElectroThermal",
    # results and cases
    "SimulationResult", "StepResult", "Case", "get_case", "describe_cases",
    # result viewer (self-contained HTML)
    "write_viewer", "viewer_html", "load_viewer_data",
    # FOLD files
    "read_fold", "write_fold", "fold_to_pattern", "pattern_to_fold", "read_model", "write_model",
    "fold_to_model", "model_to_fold", "write_fold_frames", "result_to_fold_frames",
    "miura_sheet_model", "single_fold_model",
    # errors
    "EtorigamiError", "ParameterError", "PatternError", "ConvergenceError", "FoldFormatError",
]
