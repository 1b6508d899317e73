"""Panels passing through each other between two states (issue 28 item 3): a strip of two panels
folded rigidly about its crease through 180 deg."""

import numpy as np
import pytest

from simulator import Pattern, make_mesh
from simulator.mechanics import crease_crossings, fold_angles, node_crossings
from simulator.model import build_sharp_mesh
from simulator.steps import EVENT_KINDS, Event, crossing_event
from simulator.errors import ParameterError


@pytest.fixture(scope="module")
def strip():
    """Panel 0: 1 x 2 mm (y in [0, 2] mm); panel 1: 1 x 1 mm (y in [-1, 0] mm); crease 1 on
    y = 0, 200 um wide. Folded, panel 1's centre lands inside panel 0 (off its fan spokes)."""
    v = np.array([[0, 0], [1, 0], [1, 2], [0, 2], [0, -1], [1, -1]]) * 1e-3
    pattern = Pattern(v, [[0, 1, 2, 3], [0, 4, 5, 1]], crease_width=200e-6,
                      crease_thickness=1e-6, panel_thickness=10e-6)
    return make_mesh(pattern)


def folded(mesh, deg):
    """Node positions with every node on panel 1's side (y < 0) turned by ``deg`` about the
    crease's centre line (the x axis)."""
    return _turn(mesh.nodes, deg)


def test_fold_angle_wraps_at_180_deg(strip):
    """The premise: fold_angles lies in (-pi, pi], so 181 deg reads as -179 deg."""
    a = np.degrees([fold_angles(strip, folded(strip, d))[0] for d in (-179, 179, 181)])
    assert abs(abs(a[1]) - 179) < 1e-9 and a[1] == pytest.approx(-a[2])
    assert a[0] == pytest.approx(-a[1])


@pytest.mark.parametrize("before, after, crossed", [
    (179, 181, True), (181, 179, True),        # through 180 deg, and back
    (-179, -181, True), (170, 179, False), (-60, 60, False), (0, 1, False),
    (100, 260, True)])                         # fold angle 100 -> -100 deg, the short way
def test_crease_crossing_is_a_fold_angle_passing_180_deg(strip, before, after, crossed):
    rows = crease_crossings(strip, folded(strip, before), folded(strip, after))
    assert rows.tolist() == ([0] if crossed else [])


def test_a_panel_centre_passing_through_the_other_panel_is_found(strip):
    pairs = node_crossings(strip, folded(strip, 179), folded(strip, 181))
    assert pairs.tolist() == [[strip.panel_center[1], 0]]
    assert node_crossings(strip, folded(strip, 181), folded(strip, 179)).tolist() == \
        pairs.tolist()


@pytest.mark.parametrize("before, after", [(0, 1), (170, 179), (90, 170), (-30, 30)])
def test_no_node_crossing_while_the_panels_stay_apart(strip, before, after):
    assert node_crossings(strip, folded(strip, before), folded(strip, after)).shape == (0, 2)


def test_no_crossing_from_the_flat_sheet_whatever_the_noise(strip):
    """A flat sheet: every point lies in every panel's plane, so signed distances change sign
    at random; none is inside another panel."""
    x = strip.nodes + 1e-12 * np.random.default_rng(0).standard_normal(strip.nodes.shape)
    assert node_crossings(strip, strip.nodes, x).shape == (0, 2)
    assert crease_crossings(strip, strip.nodes, x).size == 0


def test_crossing_event_names_the_crease_and_the_panels(strip):
    u0, u1 = folded(strip, 179) - strip.nodes, folded(strip, 181) - strip.nodes
    event = crossing_event(strip, u0, u1, increment=4, load_factor=0.25,
                           power=[3e-3], temperature=np.full(strip.n_nodes, 80.0))
    assert isinstance(event, Event) and event.kind == "panel_crossing" in EVENT_KINDS
    assert event.creases == (1,) and event.panels == (0, 1)      # crease id, not the row
    assert event.increment == 4 and event.load_factor == 0.25
    assert event.power_per_crease == (3e-3,) and event.temperature_max == 80.0
    assert "crease 1 folded past +-180 deg" in event.message
    assert "increment 5" in event.message and "contact" in event.message
    d = event.to_dict([1])
    assert d["creases"] == [1] and d["panels"] == [0, 1] and d["kind"] == "panel_crossing"


def test_no_event_without_a_crossing(strip):
    u0, u1 = folded(strip, 90) - strip.nodes, folded(strip, 100) - strip.nodes
    assert crossing_event(strip, u0, u1, increment=0, load_factor=0.1) is None


def test_event_kind_is_still_checked():
    with pytest.raises(ParameterError, match="Event.kind = 'crossing'"):
        Event("crossing", 0.5, 1)


def test_the_cli_summary_line_names_the_creases_and_panels(strip):
    from design.cli._summary import _event_line

    u0, u1 = folded(strip, 179) - strip.nodes, folded(strip, 181) - strip.nodes
    event = crossing_event(strip, u0, u1, increment=4, load_factor=0.25, power=[3e-3])
    line = _event_line(event, strip.crease_ids)
    assert line.startswith("panel crossing at 3 mW in all (crease 1: 3 mW)")
    assert line.endswith("; creases 1 folded past +-180 deg; panels 0, 1 passed through each "
                         "other")


@pytest.mark.parametrize("before, after, kind", [
    (179, 181, "panel_crossing"), (181, 179, "panel_crossing"),
    (-179, -181, "panel_crossing"), (170, 179, None), (-60, 60, None), (0, 1, None),
    (100, 260, "fold_past_flat")])
def test_the_step_loops_watch_finds_what_crease_crossings_finds(strip, before, after, kind):
    """Panel 1 turned rigidly about the crease's centre line: its centre passes through
    panel 0 where the fold passes 180 deg (as with a sharp crease), a panel crossing. In one
    increment from 100 to 260 deg (turning down through -z and up past 180 deg) its nodes
    move on straight lines that pass through the crease, not through panel 0: the crease
    folded past 180 deg."""
    from simulator.events import CrossingWatch

    watch = CrossingWatch(strip, folded(strip, before) - strip.nodes)
    event = watch.check(folded(strip, after) - strip.nodes, 3, 0.5)
    assert (None if event is None else event.kind) == kind
    if kind:
        assert event.creases == (1,) and event.increment == 3
    if kind == "panel_crossing":
        assert event.panels == (0, 1)


def lifted(mesh, deg, h):
    """Node positions with panel 1's side turned by ``deg`` about the line y = 0, z = ``h``
    [m] (positive ``deg`` turns it down, towards -z: ``h`` < 0 puts the axis on that side):
    the crease's arc of a crease of finite width, whose panels are 2 |h| apart when
    parallel."""
    return _turn(mesh.nodes - [0, 0, h], deg) + [0, 0, h]


def _turn(X, deg):
    t, x = np.radians(deg), X.copy()
    side = X[:, 1] < -1e-12
    y, z = X[side, 1], X[side, 2]
    x[side, 1], x[side, 2] = y * np.cos(t) - z * np.sin(t), y * np.sin(t) + z * np.cos(t)
    return x


def test_a_wide_crease_folds_past_flat_with_an_event_until_its_panels_meet(strip):
    """A crease of finite width: past 180 deg the panels are still apart ("fold_past_flat",
    once, naming the crease; the step goes on); turning further, panel 1's far corners reach
    panel 0 ("panel_crossing", naming the crease past flat and both panels). A watch started
    past flat tests the nodes too; a sharp mesh's crease passing 180 deg is a crossing."""
    from simulator.events import CrossingWatch, stops

    h = -50e-6                                     # panels 100 um apart when parallel
    watch = CrossingWatch(strip, lifted(strip, 170, h) - strip.nodes)
    kinds = []
    for deg in (175, 179, 181, 183, 185, 190, 200):
        e = watch.check(lifted(strip, deg, h) - strip.nodes, deg, deg / 200)
        kinds.append(None if e is None else e.kind)
        if e is not None:
            assert e.creases == (1,)
        if stops(e):
            assert e.panels == (0, 1) and "crease 1 folded past 180 deg" in e.message
            break
    # panel 1's centre (0.55 mm from the axis) reaches panel 0 at 180 + asin(2 |h| / 0.55 mm)
    # = 190.5 deg (its corners, on the edges of panel 0, are not counted: grazing)
    assert kinds == [None, None, "fold_past_flat", None, None, None, "panel_crossing"]
    e = CrossingWatch(strip, lifted(strip, 183, h) - strip.nodes).check(
        lifted(strip, 200, h) - strip.nodes, 1, 0.1)
    assert stops(e)
    v = np.array([[0, 0], [1, 0], [1, 2], [0, 2], [0, -1], [1, -1]]) * 1e-3
    sharp = build_sharp_mesh(Pattern(v, [[0, 1, 2, 3], [0, 4, 5, 1]], crease_width=200e-6,
                                     crease_thickness=1e-6, panel_thickness=10e-6))
    e = CrossingWatch(sharp, folded(sharp, 179) - sharp.nodes).check(
        folded(sharp, 181) - sharp.nodes, 1, 0.1)
    assert stops(e) and e.creases == (1,)


@pytest.mark.parametrize("flip", [False, True])
def test_the_watchs_fold_angles_are_fold_angles(flip):
    """On panels of either top side (the second panel drawn the other way round): the
    watch's angles are those of fold_angles to round-off, and kept per state."""
    from simulator.events import _crease_angles

    v = np.array([[0, 0], [1, 0], [1, 2], [0, 2], [0, -1], [1, -1]]) * 1e-3
    second = [1, 5, 4, 0] if flip else [0, 4, 5, 1]
    mesh = make_mesh(Pattern(v, [[0, 1, 2, 3], second], crease_width=200e-6,
                              crease_thickness=1e-6, panel_thickness=10e-6))
    angles = _crease_angles(mesh)
    rng = np.random.default_rng(5)
    for deg in (-170, -30, 0, 45, 179):
        u = folded(mesh, deg) - mesh.nodes + rng.normal(size=mesh.nodes.shape) * 1e-6
        assert angles(u) == pytest.approx(fold_angles(mesh, mesh.nodes + u), abs=1e-12)
        assert angles.known(u) is angles.known(u.copy())


def _spring_angles(mesh, x):
    from simulator.mechanics.elements.springs import fold_angle
    return fold_angle(x[np.asarray(mesh.springs)])


@pytest.mark.parametrize("before, after, wraps", [
    (170, 190, True), (190, 170, True), (100, 170, False), (-170, -190, True), (0, 60, False)])
def test_a_spring_passing_half_a_turn_from_its_rest_angle_wraps(strip, before, after, wraps):
    """Rest angles those of the flat strip: a spring turned by the whole fold passes the
    law's wrap point where the fold passes 180 deg (the law's moment reverses there)."""
    from simulator.mechanics.crossing import spring_wraps

    rest = _spring_angles(strip, strip.nodes)
    rows = spring_wraps(strip, folded(strip, before), rest, folded(strip, after), rest)
    assert bool(len(rows)) == wraps
    # the same fold with the rest angles turned along (a crease that follows its rest angle)
    turned = _spring_angles(strip, folded(strip, after))
    assert not len(spring_wraps(strip, folded(strip, before), _spring_angles(
        strip, folded(strip, before)), folded(strip, after), turned))


def test_wrap_refusal_names_the_springs_and_their_crease(strip):
    from types import SimpleNamespace

    from simulator.mechanics.crossing import wrap_refusal

    rest = _spring_angles(strip, strip.nodes)
    system = SimpleNamespace(model=SimpleNamespace(mesh=strip))
    why = wrap_refusal(system, folded(strip, 170) - strip.nodes, rest,
                       folded(strip, 190) - strip.nodes, rest)
    assert "(crease 1)" in why and "wrap point" in why and "not physical" in why
    assert wrap_refusal(system, folded(strip, 100) - strip.nodes, rest,
                        folded(strip, 170) - strip.nodes, rest) == ""
    assert wrap_refusal(object(), strip.nodes, rest, strip.nodes, rest) == ""
