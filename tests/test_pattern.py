"""Pattern input: edge / crease numbering (theory 2.1), addressing and input validation."""

import dataclasses
import math

import numpy as np
import pytest

from simulator.errors import PatternError
from simulator.geometry.materials import SU8
from simulator.geometry.pattern import Pattern
from simulator.geometry.example_patterns import gripper_pattern, miura_sheet_pattern, single_fold_pattern

SQ = [(0, 0), (1, 0), (1, 1), (0, 1)]
PENTAGON = [(math.cos(2 * math.pi * k / 5), math.sin(2 * math.pi * k / 5)) for k in range(5)]


def make(vertices, panels, **kw):
    data = dict(crease_width=0.1, crease_thickness=0.01, panel_thickness=0.01)
    return Pattern(vertices, panels, **{**data, **kw})


@pytest.fixture(scope="module")
def fold():
    return single_fold_pattern()


def refold(fold, **kw):
    """The single fold rebuilt with some inputs replaced."""
    data = dict(crease_width=200e-6, crease_thickness=0.5e-6, panel_thickness=fold.panel_thickness,
                panel_material=fold.panel_material)
    return Pattern(fold.vertices, fold.panels, **{**data, **kw})


# ---------------------------------------------------------------------- numbering (positive)
def test_single_fold_edges_and_creases(fold):
    # reference crease 3 = our edge 2 (theory 2.1)
    assert fold.edges.tolist() == [[0, 3], [0, 1], [1, 4], [3, 4], [1, 2], [2, 5], [4, 5],
                                   [6, 8], [6, 7], [7, 9], [8, 9]]
    assert fold.creases.tolist() == [2]
    assert fold.edge_panels[2].tolist() == [0, 1]
    assert np.all(fold.edge_panels[fold.is_crease == 0, 1] == -1)
    assert (fold.n_vertices, fold.n_panels, fold.n_edges) == (10, 3, 11)


@pytest.mark.parametrize("factory", [miura_sheet_pattern, gripper_pattern])
def test_interior_creases(factory):
    assert factory().creases.tolist() == [2, 3, 5, 9]


def test_addressing(fold):
    assert fold.crease_between(0, 1) == fold.crease_between(1, 0) == 2
    assert fold.check_crease(np.int64(2)) == 2 and fold.check_panel(np.int32(2)) == 2
    assert fold.crease_nearest((0.6e-3, 0.25e-3)) == 2
    assert fold.crease_nearest((0.0, 0.0, 0.0)) == 2
    assert fold.panel_containing((0.25e-3, 0.25e-3, 0)) == 0
    assert fold.panel_containing((0.95e-3, 0.25e-3)) == 1
    assert fold.panel_containing((0.5e-3, 0.25e-3, -150e-6)) == 2
    assert fold.panel_containing((0.6e-3, 0.25e-3, 0)) == 0  # on the crease: first panel


def test_per_crease_forms_agree():
    base = miura_sheet_pattern()
    creases = base.creases.tolist()
    widths = {2: 1e-4, 3: 2e-4, 5: 3e-4, 9: 4e-4}
    arr = np.full(base.n_edges, np.nan)  # boundary entries are ignored
    arr[creases] = list(widths.values())
    kw = dict(crease_thickness=1e-6, panel_thickness=1e-5)
    by_map = Pattern(base.vertices, base.panels, crease_width=widths, **kw)
    by_arr = Pattern(base.vertices, base.panels, crease_width=arr, **kw)
    np.testing.assert_array_equal(by_map.crease_width, by_arr.crease_width)
    assert by_map.crease_width[creases].tolist() == list(widths.values())
    boundary = ~base.is_crease
    assert np.all(by_map.crease_width[boundary] == 0) and np.all(by_arr.crease_width[boundary] == 0)
    assert np.all(by_map.crease_thickness[boundary] == 0)
    np.testing.assert_array_equal(by_map.crease_thickness[creases], 1e-6)
    np.testing.assert_array_equal(by_map.panel_thickness, np.full(base.n_panels, 1e-5))
    assert by_map.panel_material == (SU8,) * base.n_panels


def test_2d_vertices_get_z_zero():
    pat = make(np.array(SQ, float), [(0, 1, 2, 3)])
    assert pat.vertices.shape == (4, 3)
    np.testing.assert_array_equal(pat.vertices[:, :2], SQ)
    assert np.all(pat.vertices[:, 2] == 0)


def test_pattern_is_immutable(fold):
    with pytest.raises(dataclasses.FrozenInstanceError):
        fold.vertices = np.zeros((10, 3))
    with pytest.raises(dataclasses.FrozenInstanceError):
        fold.crease_width = 1.0
    with pytest.raises(ValueError):
        fold.vertices[0, 0] = 1.0  # the array is read-only too


# ---------------------------------------------------------------------- bad vertices / panels
@pytest.mark.parametrize("vertices, panels, match", [
    (SQ + [(1, 0)], [(0, 1, 2, 3), (4, 2, 3)], r"vertices 1 and 4 coincide .*merge them"),
    (SQ + [(5, 5)], [(0, 1, 2, 3)], r"vertex 4 is not used by any panel; remove it"),
    ([(0, 0), (1, 0), (math.nan, 1), (0, 1)], [(0, 1, 2, 3)],
     r"vertex 2 has a non-finite coordinate .*replace NaN/inf"),
    ([(0, 0), (math.inf, 0), (1, 1), (0, 1)], [(0, 1, 2, 3)], r"vertex 1 has a non-finite"),
    (np.zeros((4, 4)), [(0, 1, 2, 3)], r"vertices must have shape \(n, 3\) or \(n, 2\).*\(4, 4\)"),
    (np.zeros(4), [(0, 1, 2, 3)], r"vertices must have shape .*got \(4,\)"),
    ([(0, 0), (1, 0)], [(0, 1, 0)], r"n >= 3; got \(2, 2\)"),
    ([(0, 0), (1, 0, 0), (0, 1)], [(0, 1, 2)], r"vertices must be an \(n, 3\) array of numbers"),
    ([(0, 0)] * 3, [(0, 1, 2)], r"All vertices coincide"),
], ids=["duplicate", "unused", "nan", "inf", "4-columns", "1-d", "too-few", "ragged", "all-same"])
def test_bad_vertices(vertices, panels, match):
    with pytest.raises(PatternError, match=match):
        make(vertices, panels)


@pytest.mark.parametrize("panels, match", [
    ([(0, 1, 2, 3), (0, 1)], r"panel 1 has 2 corners \[0, 1\]; a panel needs at least 3"),
    ([(0, 1, 2, 7)], r"panel 0 refers to vertex 7, but vertex ids are 0\.\.3"),
    ([(0, 1, 2, -1)], r"panel 0 refers to vertex -1"),
    ([(0, 1, 2, 1)], r"panel 0 = \[0, 1, 2, 1\] repeats a vertex; list each corner once"),
    ([(0, 1.5, 2, 3)], r"panel 0 = .* is not a list of integer vertex indices; give each corner"),
    ([(0, 1, 2, 3), "abc"], r"panel 1 = 'abc' is not a list of integer vertex indices"),
    ([], r"panels must be a non-empty sequence"),
], ids=["2-corners", "index-too-big", "index-negative", "repeated", "float-index", "string",
        "empty"])
def test_bad_panels(panels, match):
    with pytest.raises(PatternError, match=match):
        make(SQ, panels)


@pytest.mark.parametrize("vertices, panels, match", [
    (SQ + [(2, 0), (3, 0)], [(0, 1, 2, 3), (1, 4, 5)],
     r"panel 1 = \[1, 4, 5\] is degenerate \(zero area.*fix its vertices"),
    ([(0, 0), (1, 0), (0.5, 1e-9)], [(0, 1, 2)], r"panel 0 = \[0, 1, 2\] is degenerate"),
    ([(0, 0, 0), (1, 0, 0), (1, 1, 0.1), (0, 1, 0)], [(0, 1, 2, 3)],
     r"panel 0 is not planar .*split it into planar panels"),
    (SQ, [(0, 2, 1, 3)], r"panel 0 = \[0, 2, 1, 3\] is self-intersecting .*reorder its corners"),
    ([(0, 0), (2, 0), (0, 1), (3, 1)], [(0, 1, 2, 3)], r"panel 0 = \[0, 1, 2, 3\] is self-inter"),
    (PENTAGON, [(0, 2, 4, 1, 3)], r"panel 0 = \[0, 2, 4, 1, 3\] is .*not star-shaped about its "
                                  r"centroid; reorder its corners"),
    ([(0, 0), (2, 0), (2, 2), (1, 0.5), (0, 2)], [(0, 1, 2, 3, 4)], r"not star-shaped"),
    ([(0, 0, 0), (1, 0, 0), (0.5, 1, 0), (0.5, -1, 0), (0.5, 0, 1)], [(0, 1, 2), (0, 1, 3), (0, 1, 4)],
     r"Edge between vertices 0 and 1 is shared by panels \[0, 1, 2\].*Split the pattern"),
], ids=["collinear", "sliver", "non-planar", "bow-tie", "bow-tie-skew", "pentagram",
        "non-star", "3-panel-edge"])
def test_bad_geometry(vertices, panels, match):
    with pytest.raises(PatternError, match=match):
        make(vertices, panels)


def test_good_polygons_accepted():
    assert make(PENTAGON, [(4, 3, 2, 1, 0)]).n_edges == 5  # clockwise is fine
    assert make([(0, 0), (2, 0), (2, 2), (1, 1.5), (0, 2)], [(0, 1, 2, 3, 4)]).n_panels == 1


# ---------------------------------------------------------------------- bad crease / panel data
@pytest.mark.parametrize("name", ["crease_width", "crease_thickness"])
@pytest.mark.parametrize("bad", [0.0, -1e-6, math.nan, math.inf])
@pytest.mark.parametrize("form", ["scalar", "mapping", "array"])
def test_nonpositive_crease_data(fold, name, bad, form):
    value = {"scalar": bad, "mapping": {2: bad},
             "array": np.where(np.arange(fold.n_edges) == 2, bad, 1e-6)}[form]
    with pytest.raises(PatternError, match=rf"{name} of crease 2 \(between panels 0 and 1\) is "
                                           r".*; every interior crease needs a positive finite"):
        refold(fold, **{name: value})


@pytest.mark.parametrize("value, match", [
    ({2: 1e-4, 99: 1e-4}, r"Unknown crease_width crease id 99: edge ids are 0\.\.10, interior "
                          r"creases are \[2\]"),
    ({2: 1e-4, 0: 1e-4}, r"Edge 0 \(vertices 0-3\) is a boundary edge, not a crease; interior "
                         r"creases are \[2\]"),
    ({}, r"crease_width has no value for crease\(s\) \[2\]; give every interior crease a value"),
    (np.ones(5), r"crease_width array must have one entry per edge \(11, .*got shape \(5,\)"),
    (np.ones((11, 1)), r"got shape \(11, 1\)\. Use a mapping"),
    ("abc", r"crease_width = 'abc' is not a number"),
    ({2: "x"}, r"crease_width of crease 2 = 'x' is not a number"),
    ({2: [1e-4, 2e-4]}, r"crease_width of crease 2 is \[.*\]; give one number per crease"),
], ids=["unknown-id", "boundary-id", "missing", "short-array", "2d-array", "string",
        "string-in-map", "list-in-map"])
def test_bad_crease_width(fold, value, match):
    with pytest.raises(PatternError, match=match):
        refold(fold, crease_width=value)


@pytest.mark.parametrize("kw, match", [
    (dict(panel_thickness=0.0), r"panel_thickness of panel 0 is 0\.0; it must be a positive"),
    (dict(panel_thickness=[1e-5, math.nan, 1e-5]), r"panel_thickness of panel 1 is nan"),
    (dict(panel_thickness=[1e-5, 1e-5]), r"panel_thickness must be a scalar or have one entry "
                                         r"per panel \(3\); got shape \(2,\)"),
    (dict(panel_thickness="x"), r"panel_thickness = 'x' is not a number"),
    (dict(panel_material="SU8"), r"panel_material is 'SU8'; give a Material or a sequence of 3"),
    (dict(panel_material=5), r"panel_material is 5; give a Material"),
    (dict(panel_material=[SU8] * 2), r"panel_material has 2 entries for 3 panels"),
    (dict(panel_material=[SU8, "x", SU8]), r"panel_material of panel 1 is 'x', not a Material"),
    (dict(crease_material="SU8"), r"crease_material must be a Material, got 'SU8'"),
], ids=["thickness-zero", "thickness-nan", "thickness-length", "thickness-string",
        "material-string", "material-int", "material-length", "material-entry", "crease-material"])
def test_bad_panel_data(fold, kw, match):
    with pytest.raises(PatternError, match=match):
        refold(fold, **kw)


# ---------------------------------------------------------------------- bad ids / points
@pytest.mark.parametrize("crease, match", [
    (99, r"Unknown crease id 99: edge ids are 0\.\.10, interior creases are \[2\]"),
    (-1, r"Unknown crease id -1"), (2.0, r"Unknown crease id 2\.0"), (True, r"Unknown crease id True"),
    (0, r"Edge 0 \(vertices 0-3\) is a boundary edge, not a crease; interior creases are \[2\]"),
])
def test_check_crease_rejects(fold, crease, match):
    with pytest.raises(PatternError, match=match):
        fold.check_crease(crease)


@pytest.mark.parametrize("panel", [3, -1, "0", 1.0])
def test_check_panel_rejects(fold, panel):
    with pytest.raises(PatternError, match=rf"Unknown panel id {panel!r}: panel ids are 0\.\.2"):
        fold.check_panel(panel)


def test_crease_between_rejects(fold):
    with pytest.raises(PatternError, match=r"Unknown panel id 5: panel ids are 0\.\.2"):
        fold.crease_between(0, 5)
    with pytest.raises(PatternError, match=r"Panels 0 and 2 do not share a crease; panel 0 borders "
                                           r"panels \[1\]"):
        fold.crease_between(0, 2)


def test_point_queries_reject(fold):
    with pytest.raises(PatternError, match=r"No panel contains the point \[0\.01, 0\.01, 0\.0\] "
                                           r".*give a point on a panel"):
        fold.panel_containing((10e-3, 10e-3, 0))
    with pytest.raises(PatternError, match=r"No panel contains"):  # above the anchor
        fold.panel_containing((0.25e-3, 0.25e-3, 50e-6))
    with pytest.raises(PatternError, match=r"A point must be 2 or 3 finite coordinates"):
        fold.panel_containing((math.nan, 0, 0))
    with pytest.raises(PatternError, match=r"A point must be 2 or 3 finite coordinates"):
        fold.crease_nearest((1, 2, 3, 4))
    with pytest.raises(PatternError, match=r"no interior crease"):
        make(SQ, [(0, 1, 2, 3)]).crease_nearest((0.5, 0.5))


@pytest.mark.parametrize("limit", [10_000, 10], ids=["pairwise", "kd_tree"])
def test_coincident_vertices_found_alike_by_pairwise_distances_and_the_kd_tree(monkeypatch,
                                                                                limit):
    """Small patterns check duplicates by all pairwise distances, large ones by a k-d tree."""
    from simulator.geometry import pattern_checks as pattern_module
    monkeypatch.setattr(pattern_module, "_PAIRWISE_VERTICES", limit)
    v = np.random.default_rng(3).uniform(size=(800, 3))
    assert pattern_module._coincident_pair(v, 1e-9) is None
    v[700] = v[12] + 1e-10
    assert pattern_module._coincident_pair(v, 1e-9) == (12, 700)
