"""Simulation results: per-step outcomes, per-increment history, tables and files.

Every accepted increment of every loading step is a record: displacements,
node temperatures and crease powers. Crease fold angles (panel to panel), crease
rotations (sum over the crease's fold lines, see :mod:`simulator.mechanics.kinematics`) and crease
temperatures are derived from them on demand. :meth:`SimulationResult.to_frame` gives a long
table (one row per record and crease, unit-bearing column names) and
:meth:`SimulationResult.save` writes ``creases.csv``, ``nodes.npz`` and ``meta.json``;
:meth:`SimulationResult.to_columns` is the same table as numpy columns, without pandas (what
``save`` writes ``creases.csv`` from, byte for byte as pandas would: :mod:`simulator._table`).
"""

from __future__ import annotations

import json
import pathlib
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ._result import ResultFiles, git_hash, jsonable
from ._table import step_array, write_csv
from ._version import __version__
from .mechanics.kinematics import crease_rotations, fold_angles
from .thermal.measures import crease_temperatures

__all__ = ["StepResult", "SimulationResult"]


@dataclass(frozen=True, eq=False)
class StepResult(ResultFiles):
    """Result of one loading step.

    Attributes
    ----------
    name : str
    success : bool
    status : str
        "converged" on success; otherwise "failed", "stopped", "limit_point", ...
    message : str
    state : SimulationState
        State at the end of the step (the last converged one if it failed).
    iterations, cuts : int
        Total Newton iterations and increment halvings.
    load_factor : (m,) path parameter of every accepted increment, in (0, 1]
    u_history : (m, n_nodes, 3) displacements after every accepted increment [m]
    temperature_history : (m, n_nodes) node temperatures [deg C]
    power_history : (m, C) crease powers [W]
    increment_iterations : (m,) Newton iterations of each accepted increment
    residual_norms : list of (k,) arrays, Newton residual norms of each accepted increment [N]
    reactions : (n_nodes, 3) support reactions on the structure at the end [N]
    energies : dict of energy components at the end [J]
    wall_time : float [s]
    settings : dict
        The step's parameters (:meth:`~simulator.steps.Step.describe`).
    columns : dict of (m,) arrays
        Step-specific per-increment quantities (e.g. ``stable``, ``time [s]``).
    velocity_history : (m, n_nodes, 3) node velocities [m/s], or None (quasi-static step)
    events : tuple of Event
        Limit points, bifurcations, snaps and branch switches on the step's path
        (:mod:`simulator.events`).
    stable : bool or None
        Whether the step's end state is a stable equilibrium, where the step checked it
        (quasi-static steps, ``NewtonOptions.stability`` not "off"); else None.
    first_increment : int
        Number of the first record: 1, or 0 for a time-domain step, whose first record is its
        start state (the state the previous step left, at the step's start time).
    """

    name: str
    success: bool
    status: str
    message: str
    state: object
    iterations: int
    cuts: int
    load_factor: np.ndarray
    u_history: np.ndarray
    temperature_history: np.ndarray
    power_history: np.ndarray
    increment_iterations: np.ndarray
    residual_norms: list
    reactions: np.ndarray
    energies: dict
    wall_time: float
    settings: dict = field(default_factory=dict)
    columns: dict = field(default_factory=dict)
    velocity_history: np.ndarray | None = None
    events: tuple = ()
    stable: bool | None = None
    first_increment: int = 1

    @property
    def increments(self) -> int:
        """Number of records (accepted increments, plus the start record of a time-domain
        step)."""
        return len(self.load_factor)

    @property
    def increment_numbers(self) -> np.ndarray:
        """(m,) ``increment`` of every record: 1, 2, ... (0, 1, ... for a time-domain step,
        record 0 being its start)."""
        return np.arange(self.first_increment, self.first_increment + self.increments)

    _csv_name = "step.csv"

    def to_frame(self):
        """One row per record: ``increment`` (0 = the start of a time-domain step),
        ``load_factor``, ``iterations``, ``power [mW]`` (largest crease power),
        ``max_temperature [degC]`` (hottest node), then the step-specific columns (e.g.
        ``time [s]``, ``stable``)."""
        import pandas as pd

        return pd.DataFrame({
            "increment": self.increment_numbers, "load_factor": self.load_factor,
            "iterations": self.increment_iterations,
            "power [mW]": 1e3 * np.max(self.power_history, axis=1, initial=0.0),
            "max_temperature [degC]": np.max(self.temperature_history, axis=1, initial=-np.inf),
            **{name: list(values) for name, values in self.columns.items()}})

    def _meta(self) -> dict:
        return {"name": self.name, "increments": self.increments, "iterations": self.iterations,
                "cuts": self.cuts, "wall_time [s]": self.wall_time, "settings": self.settings}


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Results of all steps of :func:`~simulator.simulation.simulate` and the final state.

    ``initial_state`` is the state before the first step (record 0 of the history).

    Time: a time-domain step (:class:`~simulator.steps.Dynamics`,
    :class:`~simulator.steps.TransientHeat`, :class:`~simulator.steps.ElectroThermal`) records
    its start state first, at its start time (``time [s]`` = 0 unless an earlier time-domain
    step advanced the clock), so its time series begins where its time begins; the records of
    quasi-static steps have no time (None, empty in CSV), nor has the initial record unless
    the first step is a time-domain one (then it is that step's start, at its time).
    """

    steps: list
    state: object
    model: object = field(repr=False, default=None)
    initial_state: object = field(repr=False, default=None)
    options: dict = field(default_factory=dict)
    wall_time: float = 0.0

    @property
    def success(self) -> bool:
        """True if every step succeeded."""
        return all(s.success for s in self.steps)

    @property
    def status(self) -> str:
        """"converged", or the status of the first step that did not succeed."""
        bad = [s for s in self.steps if not s.success]
        return "converged" if not bad else bad[0].status

    @property
    def message(self) -> str:
        bad = [s for s in self.steps if not s.success]
        return "all steps converged" if not bad else f"step {bad[0].name!r}: {bad[0].message}"

    @property
    def stable(self) -> bool | None:
        """Whether the final state is a stable equilibrium: the last step's check (None if
        it made none)."""
        return self.steps[-1].stable if self.steps else None

    @property
    def events(self) -> tuple:
        """Events of all steps in order (:class:`~simulator.events.Event`; ``step_index``
        says whose)."""
        return tuple(e for s in self.steps for e in s.events)

    # ------------------------------------------------------------------ history
    @cached_property
    def history(self) -> dict:
        """Per-record arrays (record 0 = initial state, then every accepted increment).

        Keys: ``stage`` (step index, -1 for the initial record), ``stage_name``, ``increment``
        (0 for the initial record and for the start record of a time-domain step),
        ``u`` (m, n, 3) [m], ``velocity`` (m, n, 3) [m/s] (zero on quasi-static records),
        ``temperature`` (m, n) [deg C], ``power`` (m, C) [W],
        ``iterations`` (m,), ``columns`` (dict of the steps' step-specific columns, each a list
        of m values with None for records of steps without that column: ``time [s]`` is None
        on quasi-static records and on the initial record, unless the first step is a
        time-domain one, which starts on it).
        """
        s0 = self.initial_state
        stage, names, inc = [-1], ["initial"], [0]
        u, temp, power, its = [s0.u], [s0.temperature], [s0.crease_power], [0]
        vel = [s0.node_velocity]
        for k, step in enumerate(self.steps):
            m = step.increments
            vel += list(np.zeros_like(step.u_history) if step.velocity_history is None
                        else step.velocity_history)
            stage += [k] * m
            names += [step.name] * m
            inc += list(step.increment_numbers)
            u += list(step.u_history)
            temp += list(step.temperature_history)
            power += list(step.power_history)
            its += list(step.increment_iterations)
        columns: dict = {}
        for k, step in enumerate(self.steps):
            for name, values in step.columns.items():
                col = columns.setdefault(name, [None] * len(stage))
                col[stage.index(k):stage.index(k) + step.increments] = list(values)
        if "time [s]" in columns and "time [s]" in self.steps[0].columns:
            columns["time [s]"][0] = float(s0.time)   # the start of a first time-domain step
        return {"stage": np.array(stage), "stage_name": np.array(names), "increment": np.array(inc),
                "u": np.array(u), "velocity": np.array(vel), "temperature": np.array(temp),
                "power": np.array(power),
                "iterations": np.array(its), "columns": columns}

    @cached_property
    def fold_angle(self) -> np.ndarray:
        """(m, C) crease fold angles [rad] of every record (0 flat, > 0 towards +z)."""
        return _per_record(fold_angles, self.model.mesh, self.history["u"])

    @cached_property
    def crease_rotation(self) -> np.ndarray:
        """(m, C) crease rotations [rad] of every record: the sum of the rotations of each
        crease's fold lines (what the bimorph drives); equals :attr:`fold_angle` (panel to
        panel) while the panels stay flat (:func:`~simulator.mechanics.kinematics.crease_rotations`)."""
        return _per_record(crease_rotations, self.model.mesh, self.history["u"])

    @cached_property
    def crease_temperature(self) -> np.ndarray:
        """(m, C) crease temperature used for actuation [deg C] (7-node weighted mean)."""
        return crease_temperatures(self.history["temperature"].T, self.model.mesh).T

    @cached_property
    def crease_temperature_centre_line(self) -> np.ndarray:
        """(m, C) mean of the 3 centre-line nodes (A, B, Ctr) of each crease [deg C]: the
        measure the 1.2 T_g design limit is judged on (theory 5.4;
        :class:`~simulator.thermal.limit.TemperatureLimit`)."""
        return crease_temperatures(self.history["temperature"].T, self.model.mesh,
                                   "centre_line").T

    @cached_property
    def crease_temperature_max(self) -> np.ndarray:
        """(m, C) hottest of the 7 crease nodes (2 hinge nodes of a sharp crease) [deg C]."""
        return crease_temperatures(self.history["temperature"].T, self.model.mesh,
                                   "crease_max").T

    def to_frame(self):
        """Long table: one row per record and crease.

        Columns: ``step`` (record index, 0 = initial state), ``stage``, ``increment``,
        ``crease`` (edge id), ``power [mW]``, ``fold_angle [deg]`` (panel-to-panel rotation),
        ``crease_rotation [deg]`` (sum of the crease's fold-line rotations, what the bimorph
        drives; differs from the fold angle when panels bend), ``temperature [degC]``,
        ``temperature_max [degC]``, ``iterations``, then the steps' step-specific columns (e.g.
        ``time [s]``; empty for records of steps without them; a column whose values are (C,)
        arrays is per crease).

        ``power [mW]`` is each crease's power AT the record (at its time, for time-domain
        steps); :class:`~simulator.steps.TransientHeat` adds ``mean_power [mW]``, the power
        averaged over the time step ending at the record (what the heat equation integrated:
        a square wave switched off at t = 5 ms has ``power [mW]`` 0 there, while its
        ``mean_power [mW]`` over 4-5 ms is the on-power; empty on the step's start record, where
        no time step ends). ``time [s]`` is empty on quasi-static records and on the initial
        record unless the first step is a time-domain one; a time-domain step's first record
        (``increment`` 0) is its start state at its start time.
        """
        import pandas as pd

        C = len(self.model.mesh.crease_ids)
        return pd.DataFrame({**self._record_columns(), **{
            name: _step_column(values, C) for name, values in self.history["columns"].items()}})

    def to_columns(self) -> dict:
        """The columns of :meth:`to_frame` without pandas: {name: (records x creases,) numpy
        array}, the same values and order; a step column is typed as pandas types it (float
        with NaN where a record lacks it, int, bool, or an object array of booleans or
        strings with None; :func:`simulator._table.step_array`)."""
        C = len(self.model.mesh.crease_ids)
        return {**self._record_columns(), **{
            name: step_array(values, C) for name, values in self.history["columns"].items()}}

    def _record_columns(self) -> dict:
        """The columns of :meth:`to_frame` every result has (all but the step columns)."""
        h = self.history
        creases = self.model.mesh.crease_ids
        m, C = len(h["stage"]), len(creases)
        rep = lambda a: np.repeat(a, C)  # noqa: E731
        return {
            "step": rep(np.arange(m)), "stage": rep(h["stage_name"]),
            "increment": rep(h["increment"]), "crease": np.tile(creases, m),
            "power [mW]": h["power"].ravel() * 1e3,
            "fold_angle [deg]": np.degrees(self.fold_angle).ravel(),
            "crease_rotation [deg]": np.degrees(self.crease_rotation).ravel(),
            "temperature [degC]": self.crease_temperature.ravel(),
            "temperature_max [degC]": self.crease_temperature_max.ravel(),
            "iterations": rep(h["iterations"]),
        }

    def path_frame(self):
        """Equilibrium path of the steps with path-following columns (one row per increment),
        or None if no step has them.

        Columns: ``step`` (record index), ``stage``, ``increment``, ``load_factor``,
        ``power [mW]`` (largest crease power), ``event`` (the kinds of the events just
        before the row, e.g. ``"limit_point; snap"``, see :meth:`events_frame`), then the step
        columns with metres shown in um (``displacement [um]``), e.g. ``stable``,
        ``negative_eigenvalues``, ``lowest_eigenvalue [N/m]``, ``reaction [N]``; values a row
        lacks are empty.
        """
        import pandas as pd

        frames, record = [], 1
        for step in self.steps:
            m = step.increments
            if step.columns:
                event = [None] * m
                for e in step.events:
                    if e.increment is not None:
                        k = e.increment
                        event[k] = e.kind if event[k] is None else f"{event[k]}; {e.kind}"
                data = {"step": np.arange(record, record + m), "stage": [step.name] * m,
                        "increment": step.increment_numbers, "load_factor": step.load_factor,
                        "power [mW]": 1e3 * step.power_history.max(axis=1, initial=0.0),
                        "event": event}
                for name, values in step.columns.items():
                    if any(np.ndim(v) == 1 for v in values):
                        continue                          # per crease: in to_frame only
                    if name.endswith(" [m]"):
                        name = name[:-4] + " [um]"
                        values = [None if v is None else 1e6 * v for v in values]
                    data[name] = list(values)
                frames.append(pd.DataFrame(data))
            record += m
        return pd.concat(frames, ignore_index=True) if frames else None

    def events_frame(self):
        """Events of all steps (:attr:`events`), one row each (no rows if there are none).

        Columns: ``step`` (record index of the first record past the event, as in
        :meth:`to_frame` and :meth:`path_frame`; empty if none was recorded past it),
        ``stage`` (step name), ``increment`` (of the step, as in :meth:`to_frame`), ``kind``,
        ``load_factor``, ``power [mW]`` (largest crease power), ``total_power [mW]``,
        ``displacement [um]`` (of the monitored ``node``), ``node``, ``jump [um]`` (snaps),
        ``temperature_max [degC]``, ``message``.
        """
        import pandas as pd

        first = np.cumsum([1] + [s.increments for s in self.steps])   # record of increment 0
        um = lambda v: None if v is None else 1e6 * v  # noqa: E731
        rows = [{"step": None if e.increment is None else int(first[k] + e.increment),
                 "stage": s.name, "increment": None if e.increment is None
                 else e.increment + s.first_increment,
                 "kind": e.kind, "load_factor": e.load_factor,
                 "power [mW]": 1e3 * max(e.power_per_crease, default=0.0),
                 "total_power [mW]": 1e3 * e.total_power,
                 "displacement [um]": um(e.displacement), "node": e.node,
                 "jump [um]": um(e.jump), "temperature_max [degC]": e.temperature_max,
                 "message": e.message} for k, s in enumerate(self.steps) for e in s.events]
        return pd.DataFrame(rows, columns=list(_EVENT_COLUMNS)).astype(
            {"step": "Int64", "increment": "Int64", "node": "Int64", "load_factor": float,
             "displacement [um]": float, "jump [um]": float, "temperature_max [degC]": float})

    def save(self, directory, metadata: dict | None = None) -> pathlib.Path:
        """Write ``creases.csv``, ``nodes.npz``, ``meta.json`` (with the :attr:`events`, crease
        powers keyed by crease id) and, when a step followed a path (:meth:`path_frame`),
        ``path.csv`` into ``directory``.

        ``metadata`` (e.g. the case name and its parameters) is added to ``meta.json``.
        """
        out = pathlib.Path(directory)
        out.mkdir(parents=True, exist_ok=True)
        if not write_csv(out / "creases.csv", self.to_columns()):   # pandas only if needed
            self.to_frame().to_csv(out / "creases.csv", index=False)
        if any(step.columns for step in self.steps):                 # else no path.csv
            path = self.path_frame()
            if path is not None:
                path.to_csv(out / "path.csv", index=False)
        h = self.history
        mesh = self.model.mesh
        np.savez_compressed(out / "nodes.npz", reference_positions=mesh.nodes,
                            displacements=h["u"], positions=mesh.nodes + h["u"],
                            velocity=h["velocity"],
                            temperature=h["temperature"], power=h["power"],
                            crease_ids=mesh.crease_ids, triangles=mesh.triangles,
                            triangle_kind=triangle_kinds(self.model))
        meta = {"etorigami_version": __version__, "git": git_hash(),
                "status": self.status, "message": self.message, "stable": self.stable,
                "wall_time [s]": self.wall_time, "model": self.model.to_dict(),
                "options": self.options,
                "steps": [{"name": s.name, "status": s.status, "message": s.message,
                           "stable": s.stable, "increments": s.increments, "iterations": s.iterations,
                           "cuts": s.cuts, "wall_time [s]": s.wall_time, **s.settings}
                          for s in self.steps],
                "events": [e.to_dict(mesh.crease_ids) for e in self.events],
                **(metadata or {})}
        (out / "meta.json").write_text(json.dumps(meta, indent=2, default=jsonable))
        return out


#: Codes of ``triangle_kind`` in ``nodes.npz``: crease, panel, substrate (a thermal boundary
#: panel, held at room temperature).
TRIANGLE_CREASE, TRIANGLE_PANEL, TRIANGLE_SUBSTRATE = 0, 1, 2


def triangle_kinds(model) -> np.ndarray:
    """(nt,) uint8 kind of every mesh triangle: ``TRIANGLE_CREASE`` (0),
    ``TRIANGLE_PANEL`` (1) or ``TRIANGLE_SUBSTRATE`` (2) (the panels the thermal model holds at
    room temperature, ``ThermalParameters.boundary_panels``: the substrate or heat sink)."""
    mesh = model.mesh
    kind = np.where(mesh.triangle_crease >= 0, TRIANGLE_CREASE, TRIANGLE_PANEL).astype(np.uint8)
    boundary = getattr(model.thermal, "boundary_panels", ()) or ()
    kind[np.isin(mesh.triangle_panel, list(boundary)) & (mesh.triangle_panel >= 0)] = \
        TRIANGLE_SUBSTRATE
    return kind


#: Records measured at once by :func:`_per_record` (bounds the temporary arrays).
_RECORD_BLOCK = 256


def _per_record(measure, mesh, u: np.ndarray) -> np.ndarray:
    """(m, C) ``measure(mesh, positions)`` of every record of the displacements u (m, n, 3),
    computed for blocks of records at once (the same numbers as one call per record)."""
    if len(u) == 0:
        return np.zeros((0, len(mesh.crease_ids)))
    return np.concatenate([measure(mesh, mesh.nodes + u[i:i + _RECORD_BLOCK])
                           for i in range(0, len(u), _RECORD_BLOCK)])


def _step_column(values, C: int):
    """A step column (one value per record) as (m C,) rows: (C,) arrays laid out per crease,
    other values repeated for every crease; records without the column are empty."""
    import pandas as pd

    if any(np.ndim(v) == 1 for v in values):
        return np.concatenate([np.full(C, np.nan) if v is None else
                               np.broadcast_to(np.asarray(v, float), (C,)) for v in values])
    return pd.Series(values).repeat(C).reset_index(drop=True)


_EVENT_COLUMNS = ("step", "stage", "increment", "kind", "load_factor", "power [mW]",
                  "total_power [mW]", "displacement [um]", "node", "jump [um]",
                  "temperature_max [degC]", "message")
