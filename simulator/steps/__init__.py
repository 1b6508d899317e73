"""Loading steps: the step protocol and the steps that implement it.

For step authors (``from simulator.steps import Step, StepRecorder``): a step subclasses
:class:`Step` and implements ``run(context, state)``, which takes a :class:`StepContext` and the
:class:`SimulationState` left by the previous step and returns a :class:`StepOutcome` built with
a :class:`StepRecorder` (see :mod:`simulator.steps.base`); :func:`~simulator.simulate` turns the
outcomes into :class:`StepResult` records and :class:`Event` records (snaps, limit points,
panels crossing: :func:`crossing_event`). The steps themselves are also at ``simulator``'s door.
"""

from .._lazy import attach as _attach
from .base import Step, StepContext, StepOutcome, StepRecorder
from .dynamics import Dynamics
from .continuation import ArcLengthLoad, DisplacementControl
from .electrothermal import ElectroThermal
from .heating import AmbientTemperature, Heat, coupled_increments
from .mechanical import Gravity, Load, SelfFold
from .transient import TransientHeat

__getattr__, __dir__ = _attach(__name__, {
    "..state": ("SimulationState", "initial_state"),
    "..results": ("StepResult",),
    "..events": ("EVENT_KINDS", "Event", "crossing_event"),
})

__all__ = [
    # the steps (also at simulator's door)
    "SelfFold", "Load", "Gravity", "Heat", "AmbientTemperature", "TransientHeat", "Dynamics",
    "ElectroThermal", "ArcLengthLoad", "DisplacementControl",
    # the step protocol: what a step takes, returns and records
    "Step", "StepContext", "StepOutcome", "StepRecorder", "SimulationState", "initial_state",
    "StepResult", "Event", "EVENT_KINDS", "crossing_event", "coupled_increments",
]
