"""Loading steps: the step protocol and the steps that implement it."""

from .base import Step, StepContext, StepOutcome, StepRecorder
from .dynamics import Dynamics
from .continuation import ArcLengthLoad, DisplacementControl
from .electrothermal import ElectroThermal
from .heating import AmbientTemperature, Heat, coupled_increments
from .mechanical import Gravity, Load, SelfFold
from .transient import TransientHeat

__all__ = ["Step", "StepContext", "StepOutcome", "StepRecorder", "SelfFold", "Load", "Gravity",
           "Heat", "AmbientTemperature", "coupled_increments", "TransientHeat",
           "Dynamics", "ArcLengthLoad", "DisplacementControl",
           "ElectroThermal"]
