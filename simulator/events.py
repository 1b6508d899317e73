"""Events of a loading step as data: limit points, bifurcations and snaps.

A path-following step (:class:`~simulator.steps.ArcLengthLoad`,
:class:`~simulator.steps.DisplacementControl`) and a load-controlled step continued past a limit
point (``on_limit_point="continue"`` of :class:`~simulator.steps.Heat`,
:class:`~simulator.steps.Load`, :class:`~simulator.steps.SelfFold`) record what happened on
their path as :class:`Event` records, next to the human-readable message: the
:class:`~simulator.solvers.path_trace.CriticalPoint` located by the continuation (limit point,
bifurcation, stability change) with what the step knows there (crease powers, the monitored
node, its hottest temperature), for a snap the jump load control makes, and for a panel
crossing (:func:`crossing_event`) the creases that folded past +-180 deg and the panels a node
passed through. A step stopped at a
limit point (``on_limit_point="stop"``) records the limit point its probe found. The events are
on :attr:`StepResult.events <simulator.results.StepResult.events>` and
:attr:`SimulationResult.events <simulator.results.SimulationResult.events>`, in
``meta.json`` and in :meth:`~simulator.results.SimulationResult.events_frame`; code reads them,
never the messages.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

from ._validate import capped
from .errors import ParameterError
from ._angles_jit import fold_angles_kernel, quiet_kernel
from .solvers.path_trace import CRITICAL_KINDS, CriticalPoint

__all__ = ["Event", "EVENT_KINDS", "event_at", "monitored_node", "branch_event",
           "crossing_event", "CrossingWatch", "crossing_stop", "stops", "renumbered"]

#: Kinds of :class:`Event`: those of a critical point, ``"snap"``, the two of an accepted
#: load-controlled state found unstable (:func:`branch_event`): ``"branch_switch"`` (left for
#: a stable branch along its critical mode) and ``"stability_lost"`` (not left),
#: ``"panel_crossing"`` (:func:`crossing_event`) and ``"fold_past_flat"`` (a crease of finite
#: width folded past 180 deg, its panels still apart: :class:`CrossingWatch`).
EVENT_KINDS = CRITICAL_KINDS + ("snap", "branch_switch", "stability_lost", "panel_crossing",
                                "fold_past_flat")


@dataclass(frozen=True)
class Event(CriticalPoint):
    """A critical point of a step's path, located on the step's records (SI units).

    Attributes
    ----------
    kind : {"limit_point", "bifurcation", "stability_change", "snap", "branch_switch",
            "stability_lost", "panel_crossing"}
        A ``"snap"`` starts at a load-factor maximum (a ``"limit_point"`` event of the same
        step at the same load factor) and ends where the path crosses that load factor again
        moving forward: the jump load control would make there. A ``"panel_crossing"``
        (:func:`crossing_event`): between the increment before ``increment`` and ``increment``
        panels passed through each other (``creases``, ``panels``). A ``"fold_past_flat"``:
        between them the creases ``creases`` of finite width folded on past 180 deg with no
        panel through another (the step goes on; fold angles are reported in (-180, 180] deg,
        so such a crease's angle wraps to near -180 deg).
    load_factor : float
        The step's path parameter there (0 at its start, 1 at its end; the load factor of an
        :class:`~simulator.steps.ArcLengthLoad` or :class:`~simulator.steps.DisplacementControl`).
    increment : int or None
        Index (0-based) into the step's records (``StepResult.load_factor``, ``u_history``) of
        the first accepted increment past the event; None if none was recorded past it (the
        probe of a step stopped at a limit point).
    displacement : float or None
        Displacement of the monitored node ``node`` there [m], from the mesh position, along a
        direction: the controlled or monitored one of a path-following step; for a
        load-controlled step continued past a limit point, the node that moved most in the
        step, along its motion (up to where load control failed; for a heating step whose
        continuation restarted at a located loss of stability, up to that point, which
        does not depend on the increments) (interpolated at a limit point).
    maximum : bool
        True at a load-factor maximum (and for a snap).
    power_per_crease : tuple of float
        Crease powers there [W], in crease-row order (as ``state.crease_power`` and the columns
        of ``StepResult.power_history``; ``mesh.crease_ids`` gives the crease of each).
    jump : float or None
        Snap only: change of ``displacement`` from the limit point to where the path crosses its
        load factor again [m].
    temperature_max : float or None
        Hottest node at the accepted point just past the event (at the last converged state for
        an unrecorded event) [deg C].
    node : int or None
        Node whose displacement ``displacement`` is.
    step : str or None
        Name of the step (set by :func:`~simulator.simulation.simulate`).
    step_index : int or None
        Position of the step in the simulation (0-based, set by
        :func:`~simulator.simulation.simulate`).
    message : str
        The event in words, as it appears in the step's message.
    creases : tuple of int
        Panel crossing, fold past flat: crease ids (``mesh.crease_ids``) whose fold angle
        passed +-180 deg (a panel crossing of a mesh with creases of finite width: those
        folded past 180 deg when the panels met).
    panels : tuple of int
        Panel crossing: the panels of which a corner or centre node passed through another
        panel, and those it passed through (ascending).
    """

    increment: int | None = None
    power_per_crease: tuple = ()
    jump: float | None = None
    temperature_max: float | None = None
    node: int | None = None
    step: str | None = None
    step_index: int | None = None
    message: str = ""
    creases: tuple = ()
    panels: tuple = ()

    def __post_init__(self):
        if self.kind not in EVENT_KINDS:
            raise ParameterError(f"Event.kind = {self.kind!r}; use one of {EVENT_KINDS}.")
        if not (isinstance(self.load_factor, (int, float, np.number))
                and math.isfinite(self.load_factor)):
            raise ParameterError(f"Event.load_factor = {self.load_factor!r} must be a finite "
                                 "number.")
        object.__setattr__(self, "power_per_crease",
                           tuple(float(p) for p in np.ravel(self.power_per_crease)))
        for name in ("creases", "panels"):
            object.__setattr__(self, name, tuple(int(i) for i in np.ravel(getattr(self, name))))

    @property
    def total_power(self) -> float:
        """Sum of the crease powers there [W]."""
        return float(sum(self.power_per_crease))

    def to_dict(self, crease_ids=None) -> dict:
        """JSON-able record, units in the keys; crease powers keyed by crease id if
        ``crease_ids`` (C,) is given (``mesh.crease_ids``), else a list in crease-row order."""
        p = self.power_per_crease
        return {"kind": self.kind, "step": self.step, "step_index": self.step_index,
                "increment": self.increment, "load_factor": self.load_factor,
                "maximum": self.maximum,
                "power_per_crease [W]": list(p) if crease_ids is None else
                {str(int(c)): v for c, v in zip(crease_ids, p)},
                "total_power [W]": self.total_power, "displacement [m]": self.displacement,
                "node": self.node, "jump [m]": self.jump,
                "temperature_max [degC]": self.temperature_max, "creases": list(self.creases),
                "panels": list(self.panels), "message": self.message}


def event_at(point: CriticalPoint, path, power, temperature, offset: int | None = 0,
             node: int | None = None, **fields) -> Event:
    """The :class:`Event` of a critical point of a continuation run.

    Parameters
    ----------
    point : CriticalPoint of ``path``
    path : ContinuationResult (its ``temperatures`` give ``temperature_max``)
    power : (C,) crease powers there [W]
    temperature : (n_nodes,) node temperatures [deg C] where ``path`` has none
    offset : int or None
        Records of the step before the first point of ``path`` (None: ``path`` is not
        recorded, the event has no increment).
    node : int, optional (see :attr:`Event.node`)
    **fields : more :class:`Event` fields (``kind``, ``jump``, ``message``, ...)
    """
    k = point.increment
    temps = getattr(path, "temperatures", None) or []
    t = temps[k] if 0 <= k < len(temps) and temps[k] is not None else temperature
    values = {"kind": point.kind, "load_factor": point.load_factor,
              "increment": None if offset is None else offset + k,
              "displacement": point.displacement, "maximum": point.maximum,
              "power_per_crease": power, "temperature_max": float(np.max(t)), "node": node,
              "message": point.describe(), **fields}
    return Event(**values)


def monitored_node(c) -> int | None:
    """Node of a displacement measure ``c`` (n_dof,) weighing one node's DOFs, else None."""
    if c is None:
        return None
    nodes = np.unique(np.flatnonzero(np.asarray(c).ravel()) // 3)
    return int(nodes[0]) if len(nodes) == 1 else None


def branch_event(switch, load_factor: float, increment: int, power, temperature) -> Event:
    """The :class:`Event` of a :class:`~simulator.solvers.branches.BranchSwitch` of a step's
    load control: kind ``"branch_switch"`` when a stable state was reached (``jump`` and
    ``node``: the largest node displacement from the unstable state to it, and whose) or
    ``"stability_lost"``; ``load_factor`` and ``increment`` as the step counts them (the
    record the state is, or would be, recorded as), ``power`` (C,) [W] and ``temperature``
    (n_nodes,) [deg C] there."""
    jump = node = None
    if switch.switched:
        d = np.linalg.norm(np.asarray(switch.choice.u, float).reshape(-1, 3)
                           - np.asarray(switch.u_from, float).reshape(-1, 3), axis=1)
        node = int(np.argmax(d))
        jump = float(d[node])
    return Event(kind="branch_switch" if switch.switched else "stability_lost",
                 load_factor=float(load_factor), increment=int(increment), maximum=False,
                 power_per_crease=power, temperature_max=float(np.max(temperature)), node=node,
                 jump=jump, message=switch.describe().replace(
                     f"path parameter {switch.t:.6g}", f"load factor {load_factor:.6g}"))


def crossing_event(mesh, u_prev, u, *, increment: int, load_factor: float, power=(),
                   temperature=None, nodes: bool = True, creases: bool = True,
                   past_flat=()) -> Event | None:
    """The ``"panel_crossing"`` :class:`Event` of an accepted increment, or None if no panels
    passed through each other since the previous one.

    Intended call site: a quasi-static step loop, right after it records an accepted
    increment (``rec.record(...)``), with the displacements before and after it; on an event
    the step appends it to ``rec.events`` and stops (it does not continue through panels)::

        event = crossing_event(mesh, u_prev, u, increment=len(rec) - 1, load_factor=lam,
                               power=power, temperature=temp)

    The steps' loops use :class:`CrossingWatch`, which applies the test that fits the mesh.

    Tests (:mod:`simulator.mechanics.crossing`): a crease's fold angle passing +-180 deg
    (:func:`~simulator.mechanics.crossing.crease_crossings`) and a panel corner or centre node
    passing through another panel (:func:`~simulator.mechanics.crossing.node_crossings`).
    Panel contact (:class:`~simulator.ContactParameters`) is what prevents both; this is the
    check for models run without it.

    Parameters
    ----------
    mesh : BarHingeMesh
    u_prev, u : (n_nodes, 3) displacements [m] at the previous accepted increment (the step's
        start state for its first) and at this one
    increment : int
        Index (0-based) of this increment in the step's records (:attr:`Event.increment`).
    load_factor : float
        The step's path parameter at this increment.
    power : (C,) crease powers there [W], optional
    temperature : (n_nodes,) node temperatures there [deg C], optional
    nodes : bool
        Test panel corners and centres passing through panels (about 1-2 ms a call).
    creases : bool
        Count a fold angle passing +-180 deg as a crossing (tens of microseconds): on a mesh
        of sharp creases the panels pass through each other there; a crease of finite width
        folds on past 180 deg with its panels apart (:class:`CrossingWatch` then tests nodes).
    past_flat : crease ids (``mesh.crease_ids``) known to be folded past 180 deg, named with
        a node crossing (optional)
    """
    from .mechanics.crossing import crease_crossings, node_crossings

    x0, x1 = mesh.nodes + np.asarray(u_prev, float), mesh.nodes + np.asarray(u, float)
    crossed = mesh.crease_ids[crease_crossings(mesh, x0, x1)] if creases else \
        np.zeros(0, int)
    pairs = node_crossings(mesh, x0, x1) if nodes else np.zeros((0, 2), int)
    if not len(crossed) and not len(pairs):
        return None
    parts = []
    if len(crossed):
        ids = capped(crossed.tolist(), brackets=False)
        parts.append(f"crease{'s' * (len(crossed) > 1)} {ids} folded past +-180 deg")
    if len(pairs):
        own = mesh.node_panel[pairs[:, 0]]
        parts.append("panel corner or centre nodes passed through panels: " + capped(
            [f"node {n} (panel {o}) through panel {q}" for (n, q), o in zip(pairs, own)],
            brackets=False))
        past = [int(c) for c in past_flat]
        if past and not len(crossed):
            crossed = np.asarray(past, int)
            parts.append(f"crease{'s' * (len(past) > 1)} {capped(past, brackets=False)} "
                         "folded past 180 deg")
    message = (f"panels passed through each other in increment {increment + 1} (load factor "
               f"{load_factor:.6g}): {'; '.join(parts)}. Panel contact keeps them apart: "
               "leave out --no-contact (etorigami run), or give the model contact "
               "(stack_model(..., contact=True), simulator.model.plain_contact(pattern))")
    panels = np.unique(np.r_[mesh.node_panel[pairs[:, 0]], pairs[:, 1]]) if len(pairs) else ()
    return Event("panel_crossing", float(load_factor), increment, power_per_crease=power,
                 temperature_max=None if temperature is None else float(np.max(temperature)),
                 message=message, creases=crossed, panels=panels)


#: :class:`CrossingWatch` tests panel corners and centres against panels (a finite-width
#: crease's panels can meet) while a crease is folded past 180 deg or its fold angle is
#: within this much of it [rad] (the start state of a step may be past flat already) ...
NEAR_FLAT = math.radians(30)
#: ... and after an increment that turned a crease by more than this [rad] (a motion the
#: increment does not resolve: a panel may have swung through another).
LARGE_TURN = math.radians(90)


class CrossingWatch:
    """Panels passing through each other in a step loop, checked after each accepted
    increment; cheaply while every crease is far from flat.

    It keeps the fold angles of the last accepted state (the numbers of
    :func:`~simulator.mechanics.kinematics.fold_angles` up to round-off, from the normals of
    the creases' panels only, with the cross products written out on gathered coordinates:
    :class:`_CreaseAngles`), and how many times each has wrapped past +-180 deg (at the start
    from :func:`~simulator.mechanics.kinematics.crease_rotations`, which does not wrap, where
    a fold angle is within :data:`NEAR_FLAT` of +-180 deg).

    * Sharp creases (concentrated hinges): a fold angle passing +-180 deg is a
      ``"panel_crossing"`` (:func:`crossing_event`, creases only): the panels meet there.
    * Creases of finite width ``W``: the panels are still about ``0.71 W`` apart when they
      turn parallel and a crease can fold on past 180 deg (theory 3.5). Its first passing is a
      ``"fold_past_flat"`` event (the step goes on), and while any crease is past flat or
      within :data:`NEAR_FLAT` of it (and after an increment that turned a crease by more
      than :data:`LARGE_TURN`), each increment is tested for panel corner and centre nodes
      passing through panels (:func:`crossing_event`, nodes only, 1-2 ms): a
      ``"panel_crossing"``, which names the creases past flat.

    * With the model's ``supports``: a node below a substrate (a fixed panel with the whole
      structure on one side, :mod:`simulator.mechanics.substrate`) after any increment is a
      ``"panel_crossing"`` too, which names the nodes, how deep and which panel (crease nodes
      are not contact points; a long step can pass a contact point through).

    ``CrossingWatch(mesh, u0, supports=None)``; ``check(u, increment, load_factor, power, temperature)``
    after each accepted increment: the :class:`Event` or None; a step stops on a
    ``"panel_crossing"`` (:func:`stops`) and records a ``"fold_past_flat"``. The angles of the
    last few states checked on a mesh are kept (by their displacements' bytes), so a step that
    starts where an earlier one ended (the trials of a power search restart from saved states)
    does not compute its start angles again.
    """

    def __init__(self, mesh, u0, supports=None):
        from .mechanics.substrate import substrate_of

        self.mesh, self.u = mesh, np.asarray(u0, float)
        self.substrate = None if supports is None else substrate_of(mesh, supports)
        self._angles = _crease_angles(mesh)
        # the compiled kernels where numba is selected (None: numpy), chosen once per watch
        self._kernel, self._quiet = fold_angles_kernel(), quiet_kernel()
        self.a = self._angles.known(self.u, self._kernel)
        self.sharp = bool(getattr(mesh, "sharp", False))
        self.turns = np.zeros(len(self.a), int)
        if len(self.a) and not self.sharp and _fmax(_abs(self.a)) > np.pi - NEAR_FLAT:
            # whether a crease starts past flat: its rotation, summed over its fold lines,
            # does not wrap (crease_rotations), where the panel-to-panel angle does (asked
            # only where a fold angle is near +-180 deg: a start folded more than NEAR_FLAT
            # past flat is not recognised)
            self.turns = self._angles.turns(self.u, self._kernel).copy()
        #: whether a crease is folded past flat (then nodes are tested every increment)
        self._past = bool(self.turns.any())

    def check(self, u, increment: int, load_factor: float, power=(), temperature=None):
        u = np.asarray(u, float)
        a = self._angles.known(u, self._kernel)
        event = None
        if len(a) and not self.sharp and not self._past and _quiet(a, self.a, self._quiet):
            pass                 # the common case: every crease far from flat, no large turn
        elif len(a):
            d = a - self.a
            with np.errstate(invalid="ignore"):
                wrapped = np.abs(d) > np.pi                       # (NaN: not wrapped)
            kw = dict(increment=increment, load_factor=load_factor, power=power,
                      temperature=temperature)
            if self.sharp:
                if wrapped.any():
                    event = crossing_event(self.mesh, self.u, u, nodes=False, **kw)
            else:
                self.turns[wrapped] -= np.sign(d[wrapped]).astype(int)
                past = self.turns != 0
                self._past = bool(past.any())
                turn = np.fmax.reduce(np.abs(np.where(wrapped, 2 * np.pi - np.abs(d), d)))
                if past.any() or np.fmax.reduce(np.abs(a)) > np.pi - NEAR_FLAT or \
                        turn > LARGE_TURN:
                    event = crossing_event(self.mesh, self.u, u, creases=False,
                                           past_flat=self.mesh.crease_ids[past], **kw)
                newly = wrapped & past
                if event is None and newly.any():
                    event = _past_flat(self.mesh, np.flatnonzero(newly), a, **kw)
        if self.substrate is not None and not stops(event):
            event = _through_substrate(self.mesh, self.substrate, u, increment=increment,
                                       load_factor=load_factor, power=power,
                                       temperature=temperature) or event
        self.u, self.a = u, a
        return event


def _through_substrate(mesh, substrate, u, *, increment, load_factor, power, temperature):
    """The ``"panel_crossing"`` :class:`Event` of nodes below a substrate at displacements
    ``u`` (:func:`~simulator.mechanics.substrate.substrate_breaches`), else None."""
    from .mechanics.substrate import breach_message, substrate_breaches

    rows = substrate_breaches(substrate, mesh.nodes + u)
    if not len(rows):
        return None
    nodes = rows[:, 0].astype(int)
    own = mesh.node_panel[nodes]
    panels = np.unique(np.r_[own[own >= 0], rows[:, 1].astype(int)])
    message = (f"nodes passed through the substrate in increment {increment + 1} (load "
               f"factor {load_factor:.6g}): {breach_message(mesh, rows)}; the state is not "
               "physical (panel contact holds panel corners and centres above it, not crease "
               "nodes, and a step longer than the contact distance passes it)")
    return Event("panel_crossing", float(load_factor), increment, power_per_crease=power,
                 temperature_max=None if temperature is None else float(np.max(temperature)),
                 message=message, panels=panels)


def stops(event) -> bool:
    """Whether a step stops on an event of :class:`CrossingWatch` (a ``"panel_crossing"``;
    a ``"fold_past_flat"`` is recorded and the step goes on)."""
    return event is not None and event.kind == "panel_crossing"


def _past_flat(mesh, rows, a, *, increment, load_factor, power, temperature) -> Event:
    """The ``"fold_past_flat"`` event of crease rows ``rows`` (fold angles ``a`` [rad])."""
    ids = mesh.crease_ids[rows]
    angles = ", ".join(f"{np.degrees(x):.1f} deg" for x in a[rows[:3]])
    message = (f"crease{'s' * (len(ids) > 1)} {capped(ids.tolist(), brackets=False)} folded "
               f"past 180 deg in increment {increment + 1} (load factor {load_factor:.6g}); "
               "no panel passed through another (the crease's width holds its panels apart): "
               "the step goes on. Fold angles are reported in (-180, 180] deg: "
               f"{angles} here (360 deg more). Panel contact from the crease's gap "
               "(simulator.model.plain_contact) stops creases short of 180 deg")
    return Event("fold_past_flat", float(load_factor), increment, power_per_crease=power,
                 temperature_max=None if temperature is None else float(np.max(temperature)),
                 message=message, creases=ids)


def renumbered(event: Event, increment: int) -> Event:
    """``event`` of :class:`CrossingWatch` at record ``increment`` (its field and its message's
    "in increment N"), for a loop that learns the record index after the check."""
    from dataclasses import replace

    old = f"in increment {event.increment + 1} (" if event.increment is not None else None
    message = event.message.replace(old, f"in increment {increment + 1} (", 1) if old else \
        event.message
    return replace(event, increment=int(increment), message=message)


def crossing_stop(mesh, u0, then=None, supports=None):
    """A ``callback(lam, u)`` for the path followers (:func:`~simulator.solvers.continuation.mgdcm`,
    :func:`~simulator.solvers.displacement_control.displacement_control`) that stops them
    (returns True) at the first accepted point where panels passed through each other since
    the previous one (:class:`CrossingWatch`, from displacements ``u0``), else returns
    ``then(lam, u)`` (False without ``then``). The events themselves are made where the points
    are recorded (:func:`~simulator.steps.limit.record_continuation`), which knows their
    record indices."""
    watch = CrossingWatch(mesh, u0, supports)

    def callback(lam, u):
        if stops(watch.check(u, 0, lam)):
            return True
        return bool(then(lam, u)) if then is not None else False
    return callback


_fmax, _abs = np.fmax.reduce, np.abs        # (NaN-safe maximum: a NaN is not a large turn)
#: Largest fold angle [rad] of a crease far from flat (:data:`NEAR_FLAT`).
_FAR = np.pi - NEAR_FLAT


def _quiet(a, b, kernel=None) -> bool:
    """Whether the fold angles ``a`` (C,) [rad] of a state are all far from flat and none
    turned by more than :data:`LARGE_TURN` from those ``b`` (C,) of the state before (C >= 1):
    by the compiled test ``kernel`` (:func:`~simulator._angles_jit.quiet_kernel`)
    if given, else numpy."""
    if kernel is not None:
        return kernel(a, b, LARGE_TURN, _FAR)
    return _fmax(_abs(a - b)) <= LARGE_TURN and _fmax(_abs(a)) <= _FAR


# numpy >= 2: vecdot is a ufunc, with less overhead than einsum on small arrays
_dot = getattr(np, "vecdot", None) or (lambda u, v: np.einsum("...i,...i->...", u, v))

#: Fold angles kept per mesh by :class:`_CreaseAngles` (states; fewer on meshes where this many
#: copies of the displacements would exceed :data:`_KEPT_BYTES`).
_KEPT_STATES = 8
_KEPT_BYTES = 4 << 20


class _CreaseAngles:
    """Fold angles [rad] (C,) of a mesh's creases at displacements u (n_nodes, 3) [m]: the
    numbers of :func:`~simulator.mechanics.kinematics.fold_angles` (up to round-off) from
    index arrays built once per mesh (:func:`_crease_angles`) for a few whole-array
    operations, and the angles of the last states asked for (:meth:`known`).

    The fold angle is ``atan2((n1 x n2) . t1 A, (n1 . n2) |A|)`` with n1, n2 the top-side
    normals of the crease's panels, A its axis (corner ``prev`` minus corner ``q1`` of panel
    1) and t1 the top side of panel 1. Here: only the panels next to a crease; their normals
    are fan sums (Newell's method about the centre node) left unnormalised (a positive
    factor of both arguments does not change atan2), turned to the top side by running the
    fan backwards (a panel whose top side is its back); t1 A by taking the axis's corners
    the other way round; every cross product ``a x b = a' b'' - a'' b'`` (', '': the
    components cycled once, twice) from one gather of the cycled coordinates. Where numba is
    selected the same formulas run compiled, in one call
    (:mod:`simulator._angles_jit`, the same angles to round-off):
    :class:`CrossingWatch` passes its kernel.
    """

    def __init__(self, mesh):
        from .geometry.polygons import rings

        self.mesh, self.nodes = mesh, mesh.nodes
        self.kept, self.kept_turns = {}, {}
        self.room = max(1, min(_KEPT_STATES, _KEPT_BYTES // max(1, 24 * mesh.n_nodes)))
        # concentrated hinges, or no crease: fold_angles itself
        self.plain = bool(getattr(mesh, "sharp", False)) or not mesh.n_creases
        if self.plain:
            return
        s = mesh.panel_corner_start
        p1, p2 = mesh.crease_panels.T
        top = mesh.pattern.panel_orientation
        panels, local = np.unique(np.r_[p1, p2], return_inverse=True)
        sizes = np.diff(s)[panels]
        corners = np.concatenate([np.arange(s[p], s[p + 1]) for p in panels])
        r = rings(sizes)
        centre = mesh.panel_center[panels][r.owner]
        nxt = corners[np.where(top[panels][r.owner] > 0, r.nxt, r.prev)]
        q1 = mesh.crease_edge_bars[:, 0]               # edge bar q ends at corner node q
        prev = rings(np.diff(s)).prev[q1]
        head, tail = np.where(top[p1] > 0, prev, q1), np.where(top[p1] > 0, q1, prev)
        cyc = (np.array([1, 2, 0]), np.array([2, 0, 1]))

        def flat(nodes, k):
            return 3 * nodes[:, None] + cyc[k]
        n_fan = len(corners)
        # rows: corner', corner'', next', next'' (fan vectors from the centre), then the axis
        self._at = np.concatenate([flat(corners, 0), flat(corners, 1), flat(nxt, 0),
                                   flat(nxt, 1), 3 * head[:, None] + np.arange(3)])
        self._from = np.concatenate([flat(centre, 0), flat(centre, 1)] * 2
                                    + [3 * tail[:, None] + np.arange(3)])
        self._fan = (slice(0, 4 * n_fan), (4, n_fan, 3))
        self._axis = slice(4 * n_fan, None)
        self._start = np.cumsum(sizes) - sizes
        k1, k2 = local[:len(p1)], local[len(p1):]
        self._normals = np.stack([flat(k1, 0), flat(k1, 1), flat(k2, 0), flat(k2, 1)])
        # the same in node numbers, for the compiled kernel (simulator._angles_jit)
        self._fan_nodes = np.ascontiguousarray(np.stack([corners, centre, nxt]), np.int64)
        self._fan_start = np.r_[self._start, n_fan].astype(np.int64)
        self._crease_rows = np.ascontiguousarray(np.stack([k1, k2, head, tail]), np.int64)

    def __call__(self, u, kernel=None) -> np.ndarray:
        """The angles at ``u``: by the compiled ``kernel``
        (:func:`~simulator._angles_jit.fold_angles_kernel`) if given, else numpy
        (:meth:`reference`)."""
        x = self.nodes + u
        if self.plain:
            from .mechanics.kinematics import fold_angles
            return fold_angles(self.mesh, x)
        if kernel is None:
            return self.reference(x)
        a = np.empty(self._crease_rows.shape[1])
        kernel(x, self._fan_nodes, self._fan_start, self._crease_rows,
               np.empty((len(self._fan_start) - 1, 3)), a)
        return a

    def reference(self, x) -> np.ndarray:
        """The fold angles [rad] (C,) at node positions ``x`` (n_nodes, 3) [m] by numpy (the
        reference of the compiled kernel, and the path without numba); a mesh with creases
        that are not sharp."""
        xf = x.ravel()
        g = xf[self._at] - xf[self._from]
        fan, shape = self._fan
        a1, a2, b1, b2 = g[fan].reshape(shape)
        n = np.add.reduceat(a1 * b2 - a2 * b1, self._start, axis=0).ravel()
        n1, n1_, n2, n2_ = n[self._normals]       # n1', n1'', n2', n2'' of every crease
        axis = g[self._axis]
        y = _dot(n1 * n2_ - n1_ * n2, axis)
        return np.arctan2(y, _dot(n1, n2) * np.sqrt(_dot(axis, axis)))

    def known(self, u, kernel=None) -> np.ndarray:
        """The angles at ``u``, from those kept when the same displacements were asked for
        (else computed as :meth:`__call__` does, with ``kernel``)."""
        key = u.tobytes()
        a = self.kept.get(key)
        if a is None:
            a = self(u, kernel)
            if len(self.kept) >= self.room:
                del self.kept[next(iter(self.kept))]
            self.kept[key] = a
        return a

    def turns(self, u, kernel=None) -> np.ndarray:
        """(C,) int: how many times each crease's fold angle has wrapped past +-180 deg at
        ``u`` (from :func:`~simulator.mechanics.kinematics.crease_rotations`, which does not
        wrap), kept per state as :meth:`known` (``kernel`` as there)."""
        key = u.tobytes()
        t = self.kept_turns.get(key)
        if t is None:
            from .mechanics.kinematics import crease_rotations

            rot = crease_rotations(self.mesh, self.mesh.nodes + u)
            with np.errstate(invalid="ignore"):
                t = np.nan_to_num(np.rint((rot - self.known(u, kernel)) / (2 * np.pi))
                                  ).astype(int)
            if len(self.kept_turns) >= self.room:
                del self.kept_turns[next(iter(self.kept_turns))]
            self.kept_turns[key] = t
        return t


_ANGLES: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _crease_angles(mesh) -> _CreaseAngles:
    """The :class:`_CreaseAngles` of a mesh (built on first use)."""
    angles = _ANGLES.get(mesh)
    if angles is None:
        angles = _ANGLES[mesh] = _CreaseAngles(mesh)
    return angles
