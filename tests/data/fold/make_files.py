"""Write the small FOLD files of tests/data/fold (issue 20: crease patterns from other tools).

Run from the repository root: ``python tests/data/fold/make_files.py``. Every file is plain
FOLD 1.1 in millimetres, as an editor writes it; only ``crease_too_wide.fold`` carries
``etorigami:`` fields (it must reach the mesh). The origin of each file is in README.md here.
"""

from __future__ import annotations

import json
import math
import pathlib

import numpy as np

HERE = pathlib.Path(__file__).parent


def _write(name, fold):
    fold = {"file_spec": 1.1, "file_creator": "tests/data/fold/make_files.py", **fold}
    (HERE / name).write_text(json.dumps(fold, indent=1) + "\n")


def strip(lengths, angles_deg, width=1.0, midpoints=False):
    """A strip of panels along x folded along its creases (profile in the x-z plane).

    Crease k folds by angles_deg[k] (> 0 valley: the next panel turns towards the top, +z of
    the first panel). Returns vertices (3-D), faces (counter-clockwise seen from the top),
    edges, assignments, fold angles; with ``midpoints`` every crease line has an extra
    vertex at y = width / 2.
    """
    pts, phi = [np.zeros(2)], 0.0
    for k, length in enumerate(lengths):
        pts.append(pts[-1] + length * np.array([math.cos(phi), math.sin(phi)]))
        if k < len(angles_deg):
            phi += math.radians(angles_deg[k])
    ys = [0.0, width / 2, width] if midpoints else [0.0, width]
    verts = [[p[0], y, p[1]] for p in pts for y in ys]
    ny = len(ys)
    vid = lambda i, j: i * ny + j                                   # noqa: E731
    faces = []
    for i in range(len(lengths)):
        bottom = [vid(i, 0), vid(i + 1, 0)]
        right = [vid(i + 1, j) for j in range(1, ny)]
        left = [vid(i, j) for j in range(ny - 1, 0, -1)]
        faces.append(bottom + right + left)
    edges, assign, angle = [], [], []
    for f in faces:
        for a, b in zip(f, f[1:] + f[:1]):
            e = sorted((a, b))
            if e not in edges:
                edges.append(e)
                i_a, i_b = a // ny, b // ny
                if i_a == i_b and 0 < i_a < len(lengths):
                    x = angles_deg[i_a - 1]
                    assign.append("V" if x > 0 else "M")
                    angle.append(x)
                else:
                    assign.append("B")
                    angle.append(0)
    return np.array(verts), faces, edges, assign, angle


def _fold(verts, faces, edges, assign, angle, **extra):
    out = {"frame_unit": "mm", "vertices_coords": np.round(verts, 12).tolist(),
           "faces_vertices": faces, "edges_vertices": edges, "edges_assignment": assign,
           "edges_foldAngle": angle}
    out.update(extra)
    return out


def rot_x(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def grid_pattern(n=4):
    """A box-pleat-like n x n grid drawn as F-triangulated squares; creases: x = 2 (V), y = 2
    (M) and x = 1 for y <= 2 (V, a T-junction on y = 2); every other grid line F."""
    vid = lambda i, j: j * (n + 1) + i                              # noqa: E731
    verts = [[i * 0.5, j * 0.5] for j in range(n + 1) for i in range(n + 1)]
    faces, edges, assign, angle = [], [], [], []

    def letter(a, b):
        (xa, ya), (xb, yb) = verts[a], verts[b]
        if xa == xb == 1.0 or (xa == xb == 0.5 and max(ya, yb) <= 1.0):
            return ("V", 90) if 0 < xa < n * 0.5 else ("B", 0)
        if ya == yb == 1.0 and 0 < ya < n * 0.5:
            return "M", -90
        on_border = (xa == xb and xa in (0, n * 0.5)) or (ya == yb and ya in (0, n * 0.5))
        return ("B", 0) if on_border else ("F", 0)

    for j in range(n):
        for i in range(n):
            a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
            faces += [[a, b, c], [a, c, d]]
    for f in faces:
        for a, b in zip(f, f[1:] + f[:1]):
            e = sorted((a, b))
            if e not in edges:
                edges.append(e)
                let, ang = letter(a, b)
                assign.append(let)
                angle.append(0 if let == "F" else ang)
    return _fold(np.column_stack([verts, np.zeros(len(verts))]), faces, edges, assign,
                 [0] * len(edges), frame_title="box-pleat-like grid (F-triangulated)")


def miura_plain():
    """The 3 x 3 Miura sheet of simulator.geometry.example_patterns, drawn flat in mm, M/V."""
    from simulator.cases import miura_fold_signs
    from simulator.geometry.example_patterns import miura_sheet_pattern

    a = b = 1e-3
    gamma = math.radians(60)
    p = miura_sheet_pattern(a, b, gamma, 3, 3, W=200e-6, crease_thickness=1e-6,
                            panel_thickness=10e-6)
    signs = miura_fold_signs(a, b, gamma, 3, 3)
    assign = ["V" if signs.get(e, 0) > 0 else "M" if e in signs else
              ("U" if p.is_crease[e] else "B") for e in range(p.n_edges)]
    return {"frame_unit": "mm", "frame_title": "Miura-ori 3 x 3, drawn flat",
            "vertices_coords": np.round(p.vertices[:, :2] * 1e3, 12).tolist(),
            "faces_vertices": [list(f) for f in p.panels], "edges_vertices": p.edges.tolist(),
            "edges_assignment": assign}


def main():
    two = dict(lengths=[1.0, 1.0, 1.0], angles_deg=[60.0, -40.0])
    _write("strip_folded.fold", _fold(*strip(**two), frame_classes=["foldedForm"]))
    _write("strip_folded_midpoints.fold", _fold(*strip(**two, midpoints=True),
                                                frame_classes=["foldedForm"]))
    zig = strip([1.0] * 5, [120.0, -120.0, 120.0, -120.0])
    _write("zigzag_folded.fold", _fold(*zig, frame_title="pleat folded past 90 deg: panels "
                                       "face up and down (mixed orientations)"))
    single = strip([1.0, 1.0], [60.0])
    _write("single_crease_60.fold", _fold(*single))
    v, *rest = single
    _write("single_crease_60_upside_down.fold", _fold(v @ rot_x(180).T, *rest))
    _write("fully_folded.fold", _fold(*strip([1.0, 1.0], [180.0])))
    _write("touching_points.fold", _fold(*strip([1.0, 1.0, 1.0], [120.0, 120.0]),
                                         frame_title="triangular tube: the two free edges "
                                         "touch but are distinct paper"))
    flat = strip([1.0, 0.1, 1.0], [0.0, 0.0])
    v, f, e, a, ang = flat
    a = ["V" if x == "M" else x for x in a]
    wide = _fold(v, f, e, a, ang)
    crease = [x == "V" for x in a]
    wide.update({"edges_etorigami:width": [3e-4 if c else None for c in crease],
                 "edges_etorigami:thickness": [1e-6 if c else None for c in crease],
                 "faces_etorigami:thickness": [1e-5] * len(f)})
    _write("crease_too_wide.fold", wide)
    v, f, e, a, ang = strip([1.0, 1.0, 1.0], [0.0, 0.0])
    a = ["V" if x in "MV" else x for x in a]
    _write("origami_simulator_xz.fold",
           _fold(v[:, [0, 2, 1]] * [1, 1, 1], f, e, a, [0] * len(e),
                 frame_title="flat strip exported in the x-z plane (y up), as Origami "
                 "Simulator writes it"))
    cp = strip([1.0, 1.0, 1.0], [0.0, 0.0])
    folded = strip(**two)
    _write("frames.fold", {
        "frame_unit": "mm", "frame_classes": ["creasePattern"],
        "vertices_coords": np.round(cp[0], 12).tolist(), "faces_vertices": cp[1],
        "edges_vertices": cp[2], "edges_assignment": folded[3],
        "file_frames": [{"frame_classes": ["foldedForm"], "frame_inherit": True,
                         "frame_parent": 0, "vertices_coords": np.round(folded[0], 12).tolist(),
                         "edges_foldAngle": folded[4]}]})
    m = miura_plain()
    _write("miura_3x3_plain.fold", m)
    _write("miura_3x3_no_faces.fold", {k: v for k, v in m.items() if k != "faces_vertices"})
    _write("box_pleat_grid.fold", grid_pattern())
    tj = {"frame_unit": "mm", "frame_title": "T-junction: a crease ends on a straight crease",
          "vertices_coords": [[0, 0], [2, 0], [2, 1], [1, 1], [0, 1], [2, 2], [1, 2], [0, 2]],
          "faces_vertices": [[0, 1, 2, 3, 4], [4, 3, 6, 7], [3, 2, 5, 6]],
          "edges_vertices": [[0, 1], [1, 2], [2, 3], [3, 4], [0, 4], [3, 6], [6, 7], [4, 7],
                             [2, 5], [5, 6]],
          "edges_assignment": ["B", "B", "V", "V", "B", "M", "B", "B", "B", "B"]}
    _write("t_junction.fold", tj)
    _write("sheets_touching_at_a_vertex.fold", {
        "frame_unit": "mm", "frame_title": "two creased squares that share one vertex only",
        "vertices_coords": [[0, 0], [1, 0], [1, 1], [0, 1], [2, 1], [2, 2], [1, 2]],
        "faces_vertices": [[0, 1, 2], [0, 2, 3], [2, 4, 5], [2, 5, 6]],
        "edges_vertices": [[0, 1], [1, 2], [2, 0], [2, 3], [3, 0], [2, 4], [4, 5], [5, 2],
                           [5, 6], [6, 2]],
        "edges_assignment": ["B", "B", "V", "B", "B", "B", "B", "M", "B", "B"]})
    _write("no_creases.fold", {
        "frame_unit": "mm", "frame_title": "a square sheet without creases (boundary edges and "
        "one flat F diagonal)",
        "vertices_coords": [[0, 0], [1, 0], [1, 1], [0, 1]],
        "faces_vertices": [[0, 1, 2], [0, 2, 3]],
        "edges_vertices": [[0, 1], [1, 2], [2, 3], [3, 0], [0, 2]],
        "edges_assignment": ["B", "B", "B", "B", "F"]})

    _write("box_pleat_off_line_vertex.fold", off_line_vertex())
    pleats = [180.0 if k % 2 == 0 else -180.0 for k in range(39)]
    _write("accordion_folded_flat.fold", _fold(*strip([1.0] * 40, pleats), frame_title=(
        "a 40-panel accordion folded flat: 39 creases at +-180 deg (a long list to name)")))


def off_line_vertex(off=1.5e-8):
    """Two F-triangulated squares joined by a valley crease at x = 0.5 whose line has an extra
    vertex 10 um from its end, ``off`` mm (15 pm) beside the line: the rounding of an editor
    that keeps coordinates in single precision (an Origami Simulator box-pleat export)."""
    verts = [[0, 0], [0.5, 0], [1, 0], [1, 1], [0.5, 1], [0, 1], [0.5 + off, 0.01]]
    faces = [[0, 1, 6], [0, 6, 5], [5, 6, 4], [1, 2, 6], [2, 3, 6], [6, 3, 4]]
    edges = [[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [0, 5], [1, 6], [4, 6], [0, 6], [5, 6],
             [2, 6], [3, 6]]
    assign = ["B"] * 6 + ["V", "V"] + ["F"] * 4
    return {"frame_unit": "mm", "frame_title": "crease line with a vertex 15 pm off it "
            "(single-precision rounding of an editor export)", "vertices_coords": verts,
            "faces_vertices": faces, "edges_vertices": edges, "edges_assignment": assign}


if __name__ == "__main__":
    main()
