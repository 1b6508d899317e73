"""Loading steps: the step protocol and the steps that implement it."""

from .base import Step, StepContext, StepOutcome, StepRecorder
from .continuation import ArcLengthLoad, DisplacementControl
from .heating import AmbientTemperature, Coupling, Heat, coupled_increments
from .mechanical import Gravity, Load, SelfFold

__all__ = ["Step", "StepContext", "StepOutcome", "StepRecorder", "SelfFold", "Load", "Gravity",
           "Heat", "AmbientTemperature", "Coupling", "coupled_increments",
           "ArcLengthLoad", "DisplacementControl"]
