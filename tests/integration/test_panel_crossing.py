"""Panels never pass through each other silently (issue 28 item 3). Driven past 180 deg without
contact, a crease of finite width folds on with its panels apart (a "fold_past_flat" event,
the step goes on) until a panel corner or centre passes through the other panel (a
"panel_crossing" event, the step stops there); both are checked here against the crossing
tests applied to every pair of consecutive records. With the panel contact of plain patterns
(:func:`simulator.model.plain_contact`, the default of ``stack_model`` and the CLI) no crease
passes 180 deg at all."""

import json
import math
import pathlib

import numpy as np
import pytest

from design.cli import main
from simulator import (ArcLengthLoad, DisplacementControl, Dynamics, ElectroThermal, Heat,
                       ParameterError, Pattern, SelfFold, simulate)
from simulator.fold import load_fold_json, parse_fold
from simulator.mechanics import crease_crossings, node_crossings
from simulator.model import get_stack, plain_contact, stack_model

STACK = get_stack("su8-au")
DATA = pathlib.Path(__file__).resolve().parents[1] / "data" / "fold"


def waterbomb(size_mm=1.0) -> dict:
    """The waterbomb base of issue 28 as a FOLD dict: a square of side 2 ``size_mm`` mm, 8
    triangles around the centre, diagonals V and mid-lines M."""
    L = size_mm
    outer = [(L, 0), (L, L), (0, L), (-L, L), (-L, 0), (-L, -L), (0, -L), (L, -L)]
    return {"frame_unit": "mm", "vertices_coords": [[0, 0]] + [list(p) for p in outer],
            "faces_vertices": [[0, 1 + i, 1 + (i + 1) % 8] for i in range(8)],
            "edges_vertices": [[0, 1 + i] for i in range(8)]
            + [[1 + i, 1 + (i + 1) % 8] for i in range(8)],
            "edges_assignment": ["M" if i % 2 == 0 else "V" for i in range(8)] + ["B"] * 8}


def strip() -> Pattern:
    """Two 1 x 1 mm panels and one 200 um crease."""
    v = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, -1], [1, -1]]) * 1e-3
    return Pattern(v, [[0, 1, 2, 3], [0, 4, 5, 1]], crease_width=STACK.crease_width,
                   crease_thickness=STACK.crease_thickness,
                   panel_thickness=STACK.panel_thickness)


def heated(pattern, power, increments, contact, status="converged"):
    """Heated with the paper's chains, the loss the powers were chosen for."""
    model = stack_model(pattern, STACK, pattern.creases.tolist(), contact=contact,
                        loss_model="chain")
    result = simulate(model, [Heat({int(c): power for c in pattern.creases},
                                   increments=increments)])
    assert result.status == status, result.message
    if status == "panel_crossing":
        check_events(result, model.mesh)
    return model.mesh, model.mesh.nodes + result.history["u"], result.fold_angle


def crossings(mesh, x):
    """(record, crease row) of every crease crossing between consecutive records, and the
    records where a node passed through a panel."""
    creases = [(k, int(c)) for k in range(len(x) - 1)
               for c in crease_crossings(mesh, x[k], x[k + 1])]
    nodes = [k for k in range(len(x) - 1) if len(node_crossings(mesh, x[k], x[k + 1]))]
    return creases, nodes


def check_events(result, mesh, past_flat=True):
    """The crossing events of ``result`` (a run that ends on a panel crossing in its last
    step) against the crossing tests between consecutive records: a "fold_past_flat" event
    at every record where a crease passed 180 deg before the panels met (naming those
    creases), and one "panel_crossing", the last record, at the first record where a panel
    corner or centre passed through a panel."""
    x = mesh.nodes + result.history["u"]
    creases, nodes = crossings(mesh, x)
    offsets = np.cumsum([0] + [s.increments for s in result.steps])
    at = [(e.kind, int(offsets[e.step_index] + e.increment), e.creases) for e in result.events
          if e.kind in ("fold_past_flat", "panel_crossing")]
    *passed, (kind, k_cross, named) = at
    assert kind == "panel_crossing" and k_cross == len(x) - 2, at        # the last record
    assert nodes and nodes[0] == k_cross, (nodes, at)          # the first node crossing
    wrapped = sorted({k for k, _ in creases if k <= k_cross})
    assert [k for _, k, _ in passed] == wrapped[:len(passed)], (passed, creases)
    assert all(kind == "fold_past_flat" for kind, _, _ in passed)
    assert bool(passed) is past_flat
    for _, k, ids in passed:
        assert set(ids) == {int(mesh.crease_ids[c]) for j, c in creases if j == k}
    if passed:                            # the creases past flat are named at the crossing
        assert set(passed[0][2]) <= set(named)
    return passed, k_cross


@pytest.mark.parametrize("power", [25e-3, 40e-3])
def test_a_crease_driven_past_180_deg_without_contact_folds_on_until_the_panels_meet(power):
    """The strip's 200 um crease passes 180 deg with its 1 mm panels apart (an event, the
    step goes on) and stops where a corner of the free panel passes through the held one,
    some degrees further."""
    mesh, x, fold = heated(strip(), power, 50, contact=False, status="panel_crossing")
    creases, nodes = crossings(mesh, x)
    (k,) = {k for k, _ in creases}                 # passes 180 deg once, before they meet
    assert k < nodes[0] == len(x) - 2
    assert fold[k, 0] > math.radians(170) and fold[k + 1, 0] < -math.radians(170)
    unwrapped = np.degrees(2 * np.pi + fold[-1, 0])
    assert 185 < unwrapped < 215                   # the panels meet some degrees past flat


def test_with_contact_the_same_crease_stops_short_of_180_deg():
    mesh, x, fold = heated(strip(), 40e-3, 50, contact=True)
    assert crossings(mesh, x) == ([], [])
    assert np.all(np.abs(fold) < math.pi)
    assert np.degrees(fold[-1, 0]) > 170                        # folded flat, against contact


def test_waterbomb_of_the_issue_crosses_without_contact_and_not_with_it():
    """Issue 28: at 20 mW a valley crease goes 179.6, then -179.0 deg. With plain-pattern
    contact every crease stays within (-180, 180) deg at every record."""
    pattern = parse_fold(waterbomb(), crease_width=STACK.crease_width,
                         crease_thickness=STACK.crease_thickness,
                         panel_thickness=STACK.panel_thickness).pattern
    mesh, x, _ = heated(pattern, 20e-3, 200, contact=False, status="panel_crossing")
    assert crossings(mesh, x)[0] and crossings(mesh, x)[1]
    mesh, x, fold = heated(pattern, 20e-3, 200, contact=True)
    assert crossings(mesh, x) == ([], [])
    assert np.all(np.abs(fold) < math.pi)
    assert np.degrees(np.abs(fold[-1])).max() > 150                # driven hard


def test_plain_contact_starts_beyond_the_gap_of_a_crease_folded_flat():
    """A crease of width W folded to 180 deg holds its panels W cos(pi f / 2) apart."""
    c = plain_contact(strip())
    gap = STACK.crease_width * math.cos(math.pi / 4)
    assert c.d0_corner == c.d0_centre == pytest.approx(1.15 * gap)


def test_a_start_shape_with_touching_paper_runs_without_contact_and_says_why(tmp_path, capsys):
    """The triangular tube's free edges touch: contact would push from the start."""
    path = DATA / "touching_points.fold"
    pattern = parse_fold(load_fold_json(path), crease_width=STACK.crease_width,
                         crease_thickness=STACK.crease_thickness,
                         panel_thickness=STACK.panel_thickness).pattern
    assert plain_contact(pattern) is None
    assert stack_model(pattern, STACK, pattern.creases.tolist()).contact is None
    with pytest.raises(ParameterError, match=r"node \d+ \(panel \d\) starts 0 um from panel "
                                             r"\d, within the 163 um at which panel contact"):
        plain_contact(pattern, required=True)
    assert main(["run", str(path), "--heat", "all", "--power", "1", "--set", "thermal_steps=2",
                 "--out", str(tmp_path / "r"), "-q"]) == 0
    assert "panel contact: off: node" in capsys.readouterr().out


def test_the_cli_heats_plain_patterns_with_contact_unless_told_not_to(tmp_path):
    path = tmp_path / "waterbomb.fold"
    path.write_text(json.dumps(waterbomb()))
    for flags, on in (([], True), (["--no-contact"], False)):
        out = tmp_path / f"run{len(flags)}"
        assert main(["run", str(path), "--heat", "all", "--power", "1", *flags, "--set",
                     "thermal_steps=2", "--out", str(out), "-q"]) == 0
        meta = json.loads((out / "meta.json").read_text())
        assert (meta["model"]["contact"] is not None) is on
        assert meta["overrides"]["contact"] is on


@pytest.mark.parametrize("make", [
    lambda: ElectroThermal(power={1: 40e-3}, duration=0.5, dt=1e-3, mechanics="quasi_static"),
    lambda: Dynamics(duration=2e-3, dt=2e-5, folds={1: math.radians(179)}),
], ids=["electro_thermal", "dynamics"])
def test_time_domain_steps_stop_where_panels_pass_through_each_other(make):
    """The strip without contact heated hard in time (ElectroThermal: past 180 deg, then
    its panels meet), or its crease driven to 179 deg suddenly (Dynamics: unresolved swings
    of up to 165 deg a time step, a panel swinging through the other): the step stops at the
    first time step in which a panel passes through the other, its last record."""
    model = stack_model(strip(), STACK, [1], contact=False)
    step = make()
    res = simulate(model, [step])
    assert not res.success and res.status == "panel_crossing", res.message
    check_events(res, model.mesh, past_flat=isinstance(step, ElectroThermal))
    assert res.events[-1].panels == (0, 1)
    assert "through panel 0" in res.message and " s: panels passed" in res.message


def test_heated_in_time_with_contact_the_crease_stops_short_of_180_deg():
    model = stack_model(strip(), STACK, [1])
    res = simulate(model, [ElectroThermal(power={1: 40e-3}, duration=0.05, dt=1e-3,
                                          mechanics="quasi_static")])
    assert res.success and res.events == ()
    assert np.all(np.abs(res.fold_angle) < math.pi) and np.degrees(res.fold_angle[-1, 0]) > 170


def _folded_strip(angle_deg=160):
    """The strip without contact, its crease self-folded to ``angle_deg``: the free panel
    leans back over the held one (its free edge is nodes 5 and 6)."""
    model = stack_model(strip(), STACK, [1], contact=False)
    return model, SelfFold({1: math.radians(angle_deg)}, increments=20)


@pytest.mark.parametrize("make", [
    lambda: ArcLengthLoad(forces={5: (0, 0, -1e-6), 6: (0, 0, -1e-6)}, arc_length=0.02,
                          max_increments=200),
    lambda: DisplacementControl(node=5, direction="-z", target=0.7e-3, increments=40,
                                forces={5: (0, 0, -1), 6: (0, 0, -1)}),
], ids=["arc_length_load", "displacement_control"])
def test_path_following_steps_stop_where_panels_pass_through_each_other(make):
    """The folded strip's free edge pushed down through the held panel: the path-following
    step records the crease passing 180 deg and stops at the first point where a panel
    corner passed through the held panel (not at its end), with the events there."""
    model, fold = _folded_strip()
    step = make()
    res = simulate(model, [fold, step])
    assert not res.success and res.status == "panel_crossing", res.message
    check_events(res, model.mesh)
    last = res.steps[1]
    assert last.increments < getattr(step, "max_increments", getattr(step, "increments", 0))
    # the final state is the crossing one
    assert np.array_equal(res.state.u, res.history["u"][-1])
    assert "folded past 180 deg" in res.message and "through panel 0" in res.message


def test_recorded_continuation_ends_at_the_first_crossing():
    """:func:`record_continuation` (shared by arc length, displacement control and the
    continuation of load-controlled steps past a limit point) records an arc-length run that
    went on past 180 deg only up to the first crossing, with its event, and leaves out the
    critical points after it."""
    from simulator.solvers import mgdcm
    from simulator.solvers.load_path import LoadPath
    from simulator.steps.base import StepContext, StepRecorder
    from simulator.steps.limit import record_continuation
    from simulator import NewtonOptions

    model, fold = _folded_strip()
    start = simulate(model, [fold]).state
    P = np.zeros((model.mesh.n_nodes, 3))
    P[[5, 6], 2] = -1e-6
    system = StepContext(model, NewtonOptions()).system
    path = LoadPath(system, start.applied_load.ravel(), P.ravel(), start.spring_rest)
    run = mgdcm(path, start.u, 0.0, arc_length=0.02, max_increments=40)      # no callback
    rec = StepRecorder(start)
    event = record_continuation(rec, run, start.temperature, start.crease_power, None,
                                mesh=model.mesh)
    assert event is not None and event.kind == "panel_crossing" and event.creases == (1,)
    assert 1 <= len(rec) < len(run.history)                   # the run went on past it
    assert event.increment == len(rec) - 1 and rec.events[-1] is event
    assert all(e.increment <= event.increment for e in rec.events)
    x = model.mesh.nodes + np.array([start.u] + [u for _, u, _ in run.history])
    creases, nodes = crossings(model.mesh, x)
    assert len(rec) == nodes[0] + 1 and np.array_equal(rec.last_u, run.history[nodes[0]][1])
    (past,) = [e for e in rec.events if e.kind == "fold_past_flat"]
    assert past.increment == creases[0][0] < event.increment and past.creases == (1,)
