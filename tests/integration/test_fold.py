"""FOLD reader and writer: pattern round trips, hand-written files, malformed files."""

import copy
import json
import math
import pathlib
import re

import numpy as np
import pytest

from simulator import FoldFormatError, ParameterError, Pattern
from simulator.fold import fold_to_pattern, pattern_to_fold, read_fold, write_fold
from simulator.geometry.example_patterns import (crane_pattern, gripper_pattern, miura_sheet_pattern,
                                        single_fold_pattern)
from simulator.geometry.materials import Material

NULL4 = [None] * 4


def two_panels() -> dict:
    """Two unit squares sharing the edge 1-4 (a valley crease), in mm, written by hand."""
    return {
        "file_spec": 1.2, "frame_unit": "mm",
        "vertices_coords": [[0, 0], [1, 0], [2, 0], [0, 1], [1, 1], [2, 1]],
        "faces_vertices": [[0, 1, 4, 3], [1, 2, 5, 4]],
        "edges_vertices": [[0, 1], [1, 2], [2, 5], [5, 4], [4, 3], [3, 0], [1, 4]],
        "edges_assignment": ["B", "B", "B", "B", "B", "B", "V"],
        "edges_etorigami:width": [None] * 6 + [100e-6],
        "edges_etorigami:thickness": [None] * 6 + [1e-6],
        "faces_etorigami:thickness": [10e-6, 10e-6],
    }


def assert_same_pattern(p: Pattern, q: Pattern):
    assert np.array_equal(p.vertices, q.vertices)
    assert p.panels == q.panels
    assert np.array_equal(p.edges, q.edges)
    assert p.edge_assignment.tolist() == q.edge_assignment.tolist()
    assert np.array_equal(p.edge_fold_angle, q.edge_fold_angle)
    for name in ("crease_width", "crease_thickness", "panel_thickness"):
        assert np.array_equal(getattr(p, name), getattr(q, name)), name
    assert p.panel_material == q.panel_material
    assert p.crease_material == q.crease_material


# ---------------------------------------------------------------------- round trips
@pytest.mark.parametrize("factory", [single_fold_pattern, crane_pattern, miura_sheet_pattern,
                                     gripper_pattern])
def test_pattern_round_trip_is_exact(factory, tmp_path):
    p = factory()
    path = write_fold(p, tmp_path / "p.fold")
    assert_same_pattern(p, read_fold(path))


def test_round_trip_keeps_assignments_angles_and_other_namespaces(tmp_path):
    base = miura_sheet_pattern()
    letters = base.edge_assignment.copy()
    angles = np.zeros(base.n_edges)
    for k, e in enumerate(base.creases):
        letters[e] = "MV"[k % 2]
        angles[e] = (-1) ** (k + 1) * 0.1 * (k + 1) / 3
    mat = Material("gold-ish", youngs_modulus=7e10, poisson_ratio=0.4, density=19300.0,
                   thermal_conductivity=310.0)
    meta = {"file_author": "tests", "frame_title": "miura", "faces_other:color":
            [f"c{i}" for i in range(base.n_panels)], "edges_other:tag": list(range(base.n_edges)),
            "other:anything": {"x": [1, 2]}}
    p = Pattern(base.vertices, base.panels, crease_width=base.crease_width,
                crease_thickness=base.crease_thickness, panel_thickness=2e-6,
                panel_material=[mat] + [base.panel_material[0]] * (base.n_panels - 1),
                edge_assignment=letters, edge_fold_angle=angles, metadata=meta)
    q = read_fold(write_fold(p, tmp_path / "m.fold"))
    assert_same_pattern(p, q)
    assert q.metadata == meta
    assert q.edge_assignment[base.creases].tolist() == ["M", "V", "M", "V"]


def test_other_namespace_fields_follow_the_edges_on_file_round_trip():
    data = two_panels()
    data["edges_other:label"] = [f"e{i}" for i in range(7)]
    data["vertices_other:w"] = list(range(6))
    data["file_author"] = "me"
    p = fold_to_pattern(data)
    out = pattern_to_fold(p)
    label = dict(zip(map(tuple, map(sorted, data["edges_vertices"])), data["edges_other:label"]))
    assert [label[tuple(e)] for e in out["edges_vertices"]] == out["edges_other:label"]
    assert out["vertices_other:w"] == list(range(6)) and out["file_author"] == "me"
    clash = Pattern(p.vertices, p.panels, crease_width=1e-4, crease_thickness=1e-6,
                    panel_thickness=1e-5, metadata={"edges_vertices": [], "etorigami:x": 1})
    written = pattern_to_fold(clash)
    assert written["edges_vertices"] == clash.edges.tolist() and "etorigami:x" not in written
    assert_same_pattern(p, fold_to_pattern(out))


# ---------------------------------------------------------------------- hand-written files
def test_hand_written_file_scale_assignment_and_default_fold_angle():
    p = fold_to_pattern(two_panels())
    assert p.size == pytest.approx(2e-3)
    assert p.creases.tolist() == [2]
    assert p.edge_assignment[2] == "V" and p.edge_fold_angle[2] == math.pi
    assert p.crease_width[2] == 100e-6 and p.panel_thickness.tolist() == [10e-6, 10e-6]


@pytest.mark.parametrize("unit, scale", [("cm", 1e-2), ("in", 0.0254), ("pt", 0.0254 / 72),
                                         ("um", 1e-6), ("nm", 1e-9), ("m", 1.0)])
def test_frame_units(unit, scale):
    data = two_panels()
    data["frame_unit"] = unit
    assert fold_to_pattern(data).size == pytest.approx(2 * scale, rel=1e-12)


def test_unit_needs_an_explicit_scale():
    data = two_panels()
    del data["frame_unit"]
    with pytest.raises(FoldFormatError, match="frame_unit: is 'unit'.*unit_scale"):
        fold_to_pattern(data)
    assert fold_to_pattern(data, unit_scale=0.5e-3).size == pytest.approx(1e-3)


def test_legacy_fold_angles_and_defaults_from_keywords():
    data = two_panels()
    data["edges_foldAngles"] = [0] * 6 + [45]
    for key in ("edges_etorigami:width", "edges_etorigami:thickness", "faces_etorigami:thickness"):
        del data[key]
    p = fold_to_pattern(data, crease_width=50e-6, crease_thickness=2e-6, panel_thickness=5e-6)
    assert p.edge_fold_angle[2] == pytest.approx(math.pi / 4)
    assert (p.crease_width[2], p.crease_thickness[2], p.panel_thickness[0]) == (50e-6, 2e-6, 5e-6)


def test_flat_edges_merge_triangulated_panels():
    """A quad panel split into 4 triangles around a centre vertex (F edges) becomes one panel."""
    data = two_panels()
    data["vertices_coords"].append([0.5, 0.5])                        # vertex 6, inside face 0
    data["faces_vertices"] = [[0, 1, 6], [1, 4, 6], [4, 3, 6], [3, 0, 6], [1, 2, 5, 4]]
    data["edges_vertices"] += [[0, 6], [1, 6], [4, 6], [3, 6]]
    data["edges_assignment"] += ["F", "F", "F", "J"]
    data["edges_etorigami:width"] += NULL4
    data["edges_etorigami:thickness"] += NULL4
    data["faces_etorigami:thickness"] = [10e-6] * 5
    p = fold_to_pattern(data)
    assert p.n_panels == 2 and p.n_vertices == 6
    assert sorted(p.panels[0]) == [0, 1, 3, 4]
    assert p.creases.tolist() == [p.crease_between(0, 1)]
    assert p.edge_assignment[p.creases[0]] == "V"


def test_vertices_in_no_face_are_dropped_with_a_warning(caplog):
    data = two_panels()
    data["vertices_coords"].append([5, 5])
    data["vertices_other:n"] = list(range(7))
    p = fold_to_pattern(data)
    assert p.n_vertices == 6 and p.metadata["vertices_other:n"] == list(range(6))
    assert "vertices [6] belong to no face" in caplog.text


def test_written_files_are_fold_json(tmp_path):
    path = write_fold(single_fold_pattern(), tmp_path / "s.fold")
    data = json.loads(path.read_text())
    assert data["file_spec"] == 1.2 and data["frame_unit"] == "m"
    assert set(data["edges_assignment"]) <= set("BMVU")
    assert len(data["edges_foldAngle"]) == len(data["edges_vertices"])


def test_writer_rejects_two_materials_with_one_name():
    p = fold_to_pattern(two_panels(), material=Material("SU-8", youngs_modulus=1e9))
    p = Pattern(p.vertices, p.panels, crease_width=1e-4, crease_thickness=1e-6,
                panel_thickness=1e-5, panel_material=p.panel_material)   # crease: built-in SU-8
    with pytest.raises(ParameterError, match="both named 'SU-8'"):
        pattern_to_fold(p)


# ---------------------------------------------------------------------- malformed files
def _set(path, value):
    def edit(d):
        *head, last = path
        for k in head:
            d = d[k]
        d[last] = value
    return edit


def _delete(key):
    return lambda d: d.pop(key)


MALFORMED = [   # (id, edit of the valid two-panel file, expected message)
    ("missing coords", _delete("vertices_coords"), r"vertices_coords: missing required"),
    # faces are derived from the edges of a flat file (issue 20); without edges they are missing
    ("missing faces", lambda d: (d.pop("faces_vertices"), d.pop("edges_vertices"),
                                 d.pop("edges_assignment"), d.pop("edges_foldAngle", None)),
     r"faces_vertices: missing required"),
    ("coordinate text", _set(("vertices_coords", 2), [2, "a"]),
     r"vertices_coords\[2\].*non-numeric"),
    ("coordinate nan", _set(("vertices_coords", 1), [1, math.nan]),
     r"vertices_coords\[1\].*non-finite"),
    ("coordinate length", _set(("vertices_coords", 0), [0]),
     r"vertices_coords\[0\]: \[0\] must be"),
    ("face index", _set(("faces_vertices", 1), [1, 2, 9, 4]),
     r"faces_vertices\[1\]: index 9 is out of range"),
    ("face size", _set(("faces_vertices", 0), [0, 1]), r"faces_vertices\[0\].*at least 3"),
    ("edge index", _set(("edges_vertices", 3), [5, 7]), r"edges_vertices\[3\]: index 7"),
    ("assignment length", _set(("edges_assignment",), ["B"] * 6),
     r"edges_assignment: has 6 entries.*\(7\)"),
    ("assignment letter", _set(("edges_assignment", 6), "X"),
     r"edges_assignment\[6\]: 'X' is not"),
    ("crease on boundary", _set(("edges_assignment", 0), "M"),
     r"edges_assignment\[0\]: 'M' is a crease on the boundary"),
    ("B between faces", _set(("edges_assignment", 6), "B"),
     r"edges_assignment\[6\]: 'B' but edge 1-4 borders two"),
    ("edge not a side", _set(("edges_vertices", 6), [1, 5]),
     r"edges_vertices\[6\].*not a side of any face"),
    ("side not an edge", _set(("edges_vertices",), [[0, 1], [1, 2], [2, 5], [5, 4], [4, 3],
                                                     [3, 0]]),
     r"faces_vertices\[0\]: side 1-4 is not in edges_vertices"),
    ("non-planar", _set(("vertices_coords", 5), [2, 1, 0.2]),
     r"faces_vertices\[1\]: panel 1 is not planar"),
    ("duplicate vertex", _set(("vertices_coords", 5), [1, 1]),
     r"vertices_coords\[5\]: vertices 4 and 5 coincide"),
    ("unknown unit", _set(("frame_unit",), "furlong"),
     r"frame_unit: 'furlong' is not a FOLD unit"),
    ("fold sign", _set(("edges_foldAngle",), [0] * 6 + [-30]),
     r"edges_foldAngle\[6\]: -30 deg does not match assignment 'V'"),
    ("fold range", _set(("edges_foldAngle",), [0] * 6 + [270]),
     r"edges_foldAngle\[6\]: 270 must be"),
    ("missing width", _delete("edges_etorigami:width"), r"edges_etorigami:width: missing"),
    ("negative width", _set(("edges_etorigami:width", 6), -1e-4),
     r"edges_etorigami:width\[6\]: -0.0001"),
    ("bad thickness", _set(("faces_etorigami:thickness", 1), 0),
     r"faces_etorigami:thickness\[1\]: 0 must be"),
    ("unknown material", _set(("faces_etorigami:material",), ["SU-8", "unobtainium"]),
     r"faces_etorigami:material\[1\]: 'unobtainium' is not defined"),
    ("flat but folded", lambda d: (_set(("edges_assignment", 6), "F")(d),
                                   _set(("vertices_coords", 2), [1.5, 0, 0.5])(d),
                                   _set(("vertices_coords", 5), [1.5, 1, 0.5])(d)),
     r"edges_assignment\[6\]: 'F' \(flat\) but faces 0 and 1 meet at a fold angle of 45"),
    ("faces not a list", _set(("faces_vertices",), {"0": [0, 1, 2]}),
     r"faces_vertices: must be a non-empty list"),
    ("slit", _set(("faces_vertices", 0), [0, 1, 4, 1, 3]),
     r"faces_vertices\[0\].*repeats a vertex"),
]


@pytest.mark.parametrize("edit, match", [m[1:] for m in MALFORMED], ids=[m[0] for m in MALFORMED])
def test_malformed_files_give_one_error_naming_field_and_index(edit, match):
    data = copy.deepcopy(two_panels())
    edit(data)
    with pytest.raises(FoldFormatError, match=match) as info:
        fold_to_pattern(data)
    assert "\n" not in str(info.value)
    assert isinstance(info.value, ParameterError)


def test_invalid_json_names_the_line(tmp_path):
    path = tmp_path / "bad.fold"
    path.write_text('{\n  "file_spec": 1.2,\n  "vertices_coords": [[0, 0], [1, 0]]]\n}\n')
    with pytest.raises(FoldFormatError, match="bad.fold: invalid JSON at line 3"):
        read_fold(path)
    path.write_text("[1, 2]")
    with pytest.raises(FoldFormatError, match="top level must be a JSON object"):
        read_fold(path)
    with pytest.raises(FoldFormatError, match="cannot read FOLD file"):
        read_fold(tmp_path / "missing.fold")


# ---------------------------------------------------------------------- documentation
def test_docs_example_file_and_code_blocks_run(tmp_path, monkeypatch):
    root = pathlib.Path(__file__).resolve().parents[2]
    text = (root / "docs" / "fold-format.md").read_text()
    example = json.loads((root / "docs" / "examples" / "two_panels.fold").read_text())
    blocks = re.findall(r"```(\w*)\n(.*?)```", text, flags=re.S)
    assert json.loads([b for lang, b in blocks if lang == "json" and "vertices_coords" in b][0]) \
        == example
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for lang, code in blocks:
        if lang == "python":
            exec(compile(code, "fold-format.md", "exec"), namespace)
    assert namespace["result"].success
