"""Panels never pass through each other silently (issue 28 item 3): driven past 180 deg without
contact, a crease's fold angle wraps and the crossing tests find it; with the panel contact of
plain patterns (:func:`simulator.plain_contact`, the default of ``stack_model`` and the CLI) no
crease passes 180 deg at all."""

import json
import math
import pathlib

import numpy as np
import pytest

from design.cli import main
from simulator import (Dynamics, ElectroThermal, Heat, ParameterError, Pattern,
                       crease_crossings, get_stack, load_fold_json, node_crossings, parse_fold,
                       plain_contact, simulate, stack_model)

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
    model = stack_model(pattern, STACK, pattern.creases.tolist(), contact=contact)
    result = simulate(model, [Heat({int(c): power for c in pattern.creases},
                                   increments=increments)])
    assert result.status == status, result.message
    if status == "panel_crossing":                 # the step stops at the crossing, with it
        (event,) = result.events
        assert event.kind == "panel_crossing" and event.increment == len(result.fold_angle) - 2
    return model.mesh, model.mesh.nodes + result.history["u"], result.fold_angle


def crossings(mesh, x):
    """(record, crease row) of every crease crossing between consecutive records, and the
    records where a node passed through a panel."""
    creases = [(k, int(c)) for k in range(len(x) - 1)
               for c in crease_crossings(mesh, x[k], x[k + 1])]
    nodes = [k for k in range(len(x) - 1) if len(node_crossings(mesh, x[k], x[k + 1]))]
    return creases, nodes


@pytest.mark.parametrize("power", [25e-3, 40e-3])
def test_a_crease_driven_past_180_deg_without_contact_is_a_crossing(power):
    mesh, x, fold = heated(strip(), power, 50, contact=False, status="panel_crossing")
    creases, nodes = crossings(mesh, x)
    # the heating step stops at the increment where the crease crossed: its last record
    assert creases == [(len(x) - 2, 0)]
    assert all(k >= creases[0][0] for k in nodes)   # the panels touch after turning parallel
    k = creases[0][0]
    assert abs(fold[k, 0]) > math.radians(170) and np.sign(fold[k, 0]) != np.sign(fold[k + 1, 0])


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
    assert crossings(mesh, x)[0]
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
def test_time_domain_steps_stop_where_a_crease_passes_180_deg(make):
    """The strip without contact heated hard in time (ElectroThermal), or its crease driven
    to 179 deg suddenly (Dynamics: it overshoots): the step stops at the first time step in
    which the crease passes +-180 deg, with the event on its last record."""
    model = stack_model(strip(), STACK, [1], contact=False)
    res = simulate(model, [make()])
    assert not res.success and res.status == "panel_crossing", res.message
    (event,) = res.events
    assert event.kind == "panel_crossing" and event.creases == (1,)
    assert event.increment == res.steps[0].increments - 1
    assert "folded past +-180 deg" in res.message and " s: panels passed" in res.message
    mesh, x = model.mesh, model.mesh.nodes + res.history["u"]
    assert crossings(mesh, x)[0] == [(len(x) - 2, 0)]


def test_heated_in_time_with_contact_the_crease_stops_short_of_180_deg():
    model = stack_model(strip(), STACK, [1])
    res = simulate(model, [ElectroThermal(power={1: 40e-3}, duration=0.05, dt=1e-3,
                                          mechanics="quasi_static")])
    assert res.success and res.events == ()
    assert np.all(np.abs(res.fold_angle) < math.pi) and np.degrees(res.fold_angle[-1, 0]) > 170
