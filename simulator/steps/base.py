"""The step protocol: what every loading step implements and returns.

A simulation is an ordered list of steps. Each step receives a :class:`StepContext` (the
model, its cached equilibrium system, the Newton options and an optional progress callback)
and the :class:`~simulator.state.SimulationState` left by the previous step, and returns a
:class:`StepOutcome`: success flag, status and message, the state it ends in, and one record
per accepted increment (path parameter, displacements, temperatures, powers, iterations, plus
any step-specific columns). :func:`~simulator.simulation.simulate` only ever calls
``step.run(context, state)``, so a new physics is a new :class:`Step` subclass, never a new
branch in the facade.

To write a step, subclass :class:`Step` (a frozen dataclass is the house style), validate the
parameters in ``__post_init__``, implement :meth:`Step.run` with a :class:`StepRecorder`, and
describe the parameters for ``meta.json`` in :meth:`Step.describe`.
"""

from __future__ import annotations

import contextlib
import contextvars
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .._validate import integer
from ..mechanics.equilibrium import equilibrium_system
from ..state import SimulationState
from ..thermal.steady import thermal_model

__all__ = ["Step", "StepContext", "StepOutcome", "StepRecorder", "check_increments",
           "SUCCESS_STATUSES"]

#: Statuses that count as success.
SUCCESS_STATUSES = ("converged",)


@dataclass(frozen=True, eq=False)
class StepContext:
    """What a step needs besides the state: the model and the settings of the run.

    Attributes
    ----------
    model : Model
    options : NewtonOptions
        Newton settings of the run.
    progress : callable or None
        ``progress(done, total)`` after every accepted increment of a step.
    """

    model: object
    options: object
    progress: Callable[[int, int], None] | None = None

    @cached_property
    def system(self):
        """The model's cached :class:`~simulator.mechanics.equilibrium.EquilibriumSystem`."""
        return equilibrium_system(self.model)

    @cached_property
    def thermal(self):
        """The model's cached :class:`~simulator.thermal.steady.ThermalModel` (error if it has none)."""
        return thermal_model(self.model)

    def report(self, done: int, total: int) -> None:
        """Call the progress callback, if any."""
        if self.progress is not None:
            self.progress(done, total)


@dataclass(frozen=True, eq=False)
class StepOutcome:
    """What :meth:`Step.run` returns (``m`` accepted increments).

    Attributes
    ----------
    success : bool
    status : str
        "converged" on success; otherwise "failed", "stopped", "limit_point", ...
    message : str
    state : SimulationState
        State at the end of the step (the last accepted one if it failed).
    f_ext : (n_dof,) external load at the end [N] (for the support reactions)
    iterations, cuts : int
        Total Newton iterations and increment halvings.
    load_factor : (m,) path parameter of every accepted increment
    u : (m, n_nodes, 3) displacements [m]
    temperature : (m, n_nodes) node temperatures [deg C]
    power : (m, C) crease powers [W]
    increment_iterations : (m,) Newton iterations per increment
    residual_norms : tuple of (k,) arrays, Newton residual norms per increment [N]
    velocity : (m, n_nodes, 3) node velocities [m/s] of time-integration steps, else None
        (quasi-static records are at rest)
    columns : dict of (m,) arrays
        Step-specific per-increment quantities with unit-bearing names (``"stable"``,
        ``"time [s]"``, ...).
    evaluation : SystemValues or None
        Equilibrium evaluation at the end state, if the step has it.
    events : tuple of Event
        Limit points, bifurcations and snaps on the step's path (:mod:`simulator.events`),
        in path order (a snap after the limit point it starts at).
    stable : bool or None
        Whether the end state is a stable equilibrium (positive definite tangent), where the
        step checked it (``NewtonOptions.stability``); None if it did not (time integration,
        ``stability="off"``).
    first_increment : int
        Number of the first record: 1 (the first accepted increment), or 0 when the first
        record is the step's start state (time-domain steps,
        :meth:`StepRecorder.record_start`).
    """

    success: bool
    status: str
    message: str
    state: SimulationState
    f_ext: np.ndarray
    iterations: int
    cuts: int
    load_factor: np.ndarray
    u: np.ndarray
    temperature: np.ndarray
    power: np.ndarray
    increment_iterations: np.ndarray
    residual_norms: tuple = ()
    columns: dict = field(default_factory=dict)
    evaluation: object = None
    velocity: np.ndarray | None = None
    events: tuple = ()
    stable: bool | None = None
    first_increment: int = 1


#: The recorders made while :func:`watch_recorders` is active (the step's records so far,
#: for a partial result when the run is interrupted), else None.
_WATCHED: contextvars.ContextVar = contextvars.ContextVar("etorigami_recorders", default=None)


@contextlib.contextmanager
def watch_recorders():
    """Collect the :class:`StepRecorder` objects made inside the block (in order) into the list
    it yields; a nested block (a step running ``simulate`` itself) collects its own."""
    found: list = []
    token = _WATCHED.set(found)
    try:
        yield found
    finally:
        _WATCHED.reset(token)


class StepRecorder:
    """Collects the records of a running step and builds its :class:`StepOutcome`.

    ``events`` is the list of :class:`~simulator.events.Event` records found so far (their
    ``increment`` indexes the records of this recorder). ``first_increment`` is the number of
    the first record (1; 0 after :meth:`record_start`).
    """

    def __init__(self, state: SimulationState):
        watched = _WATCHED.get()
        if watched is not None:
            watched.append(self)
        self.start = state
        self.iterations = 0
        self.cuts = 0
        self._rows: dict[str, list] = {k: [] for k in (
            "load_factor", "u", "temperature", "power", "increment_iterations")}
        self._residuals: list = []
        self._velocity: list = []
        self._columns: dict[str, list] = {}
        self.events: list = []
        self.stable: bool | None = None
        self.first_increment = 1

    def __len__(self) -> int:
        return len(self._rows["load_factor"])

    @property
    def last_u(self) -> np.ndarray:
        """(n_nodes, 3) displacements [m] of the last record (the start state's if none)."""
        return self._rows["u"][-1] if len(self) else self.start.u

    def record(self, load_factor: float, u, temperature, power, iterations: int = 0,
               residual_norms=(), *, velocity=None, **columns) -> None:
        """Add one accepted increment; ``velocity`` (n_nodes, 3) [m/s] for time-integration
        steps (None: at rest); ``columns`` are step-specific named values."""
        for key, value in (("load_factor", load_factor), ("u", u), ("temperature", temperature),
                           ("power", power), ("increment_iterations", iterations)):
            self._rows[key].append(value)
        self._residuals.append(np.asarray(residual_norms, float))
        self._velocity.append(velocity)
        for name, value in columns.items():
            self._columns.setdefault(name, [None] * (len(self) - 1)).append(value)
        for name, values in self._columns.items():
            if len(values) < len(self):
                values.append(None)

    def record_start(self, temperature=None, power=None, *, velocity=None, **columns) -> None:
        """Record the step's start state as its first record, increment 0 (path parameter 0,
        no iterations): what a time-domain step records at its start time, so that its time
        series begins on the state the previous steps left, not on their first record.
        ``temperature`` and ``power`` default to the start state's; ``columns`` carry
        ``time [s]`` (the start time) and the step's other columns at the start."""
        if len(self):
            raise RuntimeError("StepRecorder.record_start: the start must be the first record.")
        s0 = self.start
        self.first_increment = 0
        self.record(0.0, s0.u, s0.temperature if temperature is None else temperature,
                    s0.crease_power if power is None else power, 0, velocity=velocity,
                    **columns)

    def add_path(self, path, temperature, power, load_factor=None) -> None:
        """Record every accepted increment of a :class:`~simulator.solvers.newton.PathResult`,
        with its stability and its unstable states as events (:meth:`note_stability`);
        ``load_factor(t)`` maps the path's parameter to the step's (default: the same)."""
        self.iterations += path.iterations
        self.cuts += path.cuts
        scale = (lambda t: t) if load_factor is None else load_factor
        self.note_stability(path, temperature, power, scale, before=len(self))
        for (t, u, its), res in zip(path.history, path.residual_norms):
            self.record(scale(t), u, temperature, power, its, res)

    def note_stability(self, path, temperature, power, load_factor, before=None,
                       one_record: bool = False) -> None:
        """Take the stability of a :class:`~simulator.solvers.newton.PathResult`'s last
        accepted state (:attr:`stable`) and its branch switches as events
        (:func:`~simulator.events.branch_event`), before its increments are recorded:
        ``load_factor(t)`` maps its path parameter to the step's; the path's first increment
        is record ``before`` (default: the next one). ``one_record``: the path is recorded as
        one record, its end state (a heating increment, whose sub-increments after step cuts
        are not recorded): its events are at that record."""
        if path.switches:
            self._note_switches(path, temperature, power, load_factor, before, one_record)
        if path.stable is not None:
            self.stable = path.stable

    def _note_switches(self, path, temperature, power, load_factor, before,
                       one_record=False) -> None:
        from ..events import branch_event

        first = len(self) if before is None else before
        times = [t for t, _, _ in path.history]
        for sw in path.switches:
            if not sw.switched and self.stable is False:
                continue                       # still unstable: lost once, one event
            k = first if one_record else \
                first + (times.index(sw.t) if sw.t in times else len(times) - 1)
            self.events.append(branch_event(sw, load_factor(sw.t), k, power, temperature))
            self.stable = sw.switched

    def last_state(self) -> SimulationState:
        """The start state with the displacements, temperatures and powers of the last accepted
        increment (the start state if none); rest angles and clock stay the start's."""
        from dataclasses import replace

        if not len(self):
            return self.start
        rows = self._rows
        return replace(self.start, u=np.asarray(rows["u"][-1], float),
                       temperature=np.asarray(rows["temperature"][-1], float),
                       crease_power=np.asarray(rows["power"][-1], float))

    def finish(self, success: bool, status: str, message: str, state: SimulationState,
               f_ext: np.ndarray, evaluation=None) -> StepOutcome:
        """The frozen outcome of the step. A step that would succeed on an end state known
        to be unstable (:attr:`stable` False) ends with status "unstable" instead: no step calls
        an unstable equilibrium converged."""
        if success and self.stable is False:
            lost = [e.message for e in self.events if e.kind == "stability_lost"]
            success, status = False, "unstable"
            message = ("ends on an unstable equilibrium (its tangent stiffness has a negative "
                       "eigenvalue)" + (f"; {lost[-1]}" if lost else ""))
        s0 = self.start
        n, C = s0.u.shape, s0.crease_power.shape
        rows = self._rows
        return StepOutcome(
            success=bool(success), status=status, message=message, state=state,
            f_ext=np.asarray(f_ext, float), iterations=self.iterations, cuts=self.cuts,
            load_factor=np.array(rows["load_factor"], float),
            u=np.array(rows["u"], float).reshape(-1, *n),
            temperature=np.array(rows["temperature"], float).reshape(-1, n[0]),
            power=np.array(rows["power"], float).reshape(-1, *C),
            increment_iterations=np.array(rows["increment_iterations"], int),
            residual_norms=tuple(self._residuals),
            columns={k: _column(v) for k, v in self._columns.items()}, evaluation=evaluation,
            velocity=self._velocities(n), events=tuple(sorted(  # along the path (stable)
                self.events, key=lambda e: (e.increment is None, e.increment or 0))),
            stable=self.stable, first_increment=self.first_increment)

    def _velocities(self, shape) -> np.ndarray | None:
        if all(v is None for v in self._velocity):
            return None
        return np.array([np.zeros(shape) if v is None else np.asarray(v, float).reshape(shape)
                         for v in self._velocity])


class Step(ABC):
    """A loading step: the one interface :func:`~simulator.simulation.simulate` knows.

    Subclasses have a ``name`` attribute (used in tables) and implement :meth:`run`; they
    should be immutable and validate their parameters on construction.
    """

    name: str = "step"

    @abstractmethod
    def run(self, context: StepContext, state: SimulationState) -> StepOutcome:
        """Apply the step to ``state`` and return its outcome; never raise on non-convergence
        (report it in the outcome), raise :class:`~simulator.errors.ParameterError` on bad
        input."""

    def describe(self) -> dict:
        """The step's parameters, JSON-able, with units in the keys (for ``meta.json``)."""
        return {}


def _column(values: list) -> np.ndarray:
    """A step column as an array: numeric, or an object array when some records lack a
    per-crease value (None beside (C,) arrays)."""
    if any(v is None for v in values) and any(np.ndim(v) == 1 for v in values):
        out = np.empty(len(values), dtype=object)
        out[:] = values
        return out
    return np.array(values)


def check_increments(step, name: str = "increments") -> None:
    """Raise :class:`ParameterError` unless ``step.<name>`` is a positive integer."""
    integer(f"{type(step).__name__}.{name}", getattr(step, name))
