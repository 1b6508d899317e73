"""Classic crease patterns drawn as plain FOLD 1.1 dicts, for the study ``pattern_robustness``.

Each function returns a flat crease pattern as an editor writes it: ``frame_unit`` 'mm',
2-D ``vertices_coords``, ``faces_vertices`` counter-clockwise seen from +z, ``edges_vertices``
with ``edges_assignment`` M / V (creases), F (drawn but unfolded: the two faces are one panel)
and B (outline), ``frame_classes: ["creasePattern"]``; no ``etorigami:`` field. The patterns:

* :func:`waterbomb_base` - a square, 8 triangles around its centre: diagonals V, midlines M
  (the 8-crease waterbomb vertex of issue 28, which folds rigidly into 3-D);
* :func:`square_twist` - the classic 4-fold square twist (central square turned 45 deg, its
  sides M, one M and one V pleat crease from each corner);
* :func:`miura_vertex` - one Miura degree-4 vertex, 4 panels (zig-zag rays M, the straight
  line M below / V above the vertex);
* :func:`miura_sheet` - a flat m x n Miura-ori sheet of parallelogram panels;
* :func:`huffman_tessellation` - a triangulated tessellation of the kind Huffman analysed
  (waterbomb / Yoshimura: horizontal lines M, diagonals V, degree-6 vertices);
* :func:`flapping_bird` - the traditional flapping bird: the bird base (22.5 deg geometry)
  with the neck and head reverse folds, whose edge points are placed by Kawasaki's theorem.

``python studies/patterns/make_patterns.py`` writes them to ``studies/patterns/*.fold``.
Lengths in millimetres.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["PATTERNS", "POWERS_MW", "crease_pattern", "kawasaki_defects", "waterbomb_base",
           "square_twist", "miura_vertex", "miura_sheet", "huffman_tessellation",
           "flapping_bird"]

_T22 = math.tan(math.radians(22.5))


def _faces(xy, edges):
    """Bounded faces of a plane straight-line graph, counter-clockwise (vertex id lists).

    ``xy`` (n, 2) vertex positions, ``edges`` (e, 2) vertex ids (no crossings). Walks every
    half-edge once, turning to the next edge clockwise at each vertex; the outer face (negative
    area) is dropped.
    """
    nbrs = {v: [] for v in range(len(xy))}
    for a, b in edges:
        nbrs[a].append(b)
        nbrs[b].append(a)
    for v, ns in nbrs.items():
        ns.sort(key=lambda w: math.atan2(*(xy[w] - xy[v])[::-1]))
    seen, faces = set(), []
    for a, b in [(a, b) for a, b in edges] + [(b, a) for a, b in edges]:
        face = []
        while (a, b) not in seen:
            seen.add((a, b))
            face.append(a)
            ns = nbrs[b]
            a, b = b, ns[(ns.index(a) - 1) % len(ns)]
        if face and _area(xy[face]) > 0:
            faces.append(face)
    return faces


def _area(p):
    return 0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def crease_pattern(title, xy, creases, outline):
    """FOLD dict of a flat crease pattern.

    Parameters
    ----------
    title : str
        ``frame_title``.
    xy : array_like, shape (n, 2)
        Vertex positions [mm].
    creases : list of (int, int, str)
        Crease segments (vertex ids, assignment 'M', 'V' or 'F'), split at every vertex on them.
    outline : list of int
        Vertex ids around the sheet's outline, in order; consecutive ids make the 'B' edges.
    """
    xy = np.asarray(xy, float)
    edges = [(int(a), int(b)) for a, b, _ in creases]
    assign = [s for _, _, s in creases]
    edges += [(a, b) for a, b in zip(outline, outline[1:] + outline[:1])]
    assign += ["B"] * len(outline)
    if len({frozenset(e) for e in edges}) != len(edges):
        raise ValueError(f"{title}: an edge is given twice")
    return {"file_spec": 1.1, "file_creator": "studies/_classic_patterns.py",
            "file_classes": ["singleModel"], "frame_title": title,
            "frame_classes": ["creasePattern"], "frame_unit": "mm",
            "vertices_coords": np.round(xy, 12).tolist(),
            "edges_vertices": [list(e) for e in edges], "edges_assignment": assign,
            "faces_vertices": _faces(xy, edges)}


def _chain(ids, assignment):
    """Crease segments along the vertices ``ids`` of one straight line, all ``assignment``."""
    return [(a, b, assignment) for a, b in zip(ids, ids[1:])]


def waterbomb_base(side=4.0):
    """Square of ``side`` mm, 8 triangles around the centre: diagonals V, midlines M."""
    h = side / 2
    ring = [(h, 0), (h, h), (0, h), (-h, h), (-h, 0), (-h, -h), (0, -h), (h, -h)]
    xy = [(0.0, 0.0)] + ring
    creases = [(0, k, "M" if k % 2 else "V") for k in range(1, 9)]
    return crease_pattern("waterbomb base", xy, creases, list(range(1, 9)))


def square_twist(unit=1.0):
    """Classic square twist on a 6 x 6 ``unit`` [mm] sheet: the central square (corners at
    (3, 2), (4, 3), (3, 4), (2, 3) units) turned 45 deg, its sides M; from each corner a
    crease parallel to an edge (M) and one to the next edge (V), 4 x 4 Kawasaki-flat vertices.
    """
    corners = [(3, 2), (4, 3), (3, 4), (2, 3)]
    # from each corner: (edge point reached by the M crease, by the V crease)
    ends = [((3, 0), (0, 2)), ((6, 3), (4, 0)), ((3, 6), (6, 4)), ((0, 3), (2, 6))]
    outline = [(0, 0), (3, 0), (4, 0), (6, 0), (6, 3), (6, 4), (6, 6), (3, 6), (2, 6), (0, 6),
               (0, 3), (0, 2)]
    xy = corners + outline
    ids = {p: k for k, p in enumerate(xy)}
    creases = [(k, (k + 1) % 4, "M") for k in range(4)]
    for k, (m, v) in enumerate(ends):
        creases += [(k, ids[m], "M"), (k, ids[v], "V")]
    return crease_pattern("square twist", np.array(xy, float) * unit, creases,
                          [ids[p] for p in outline])


def miura_vertex(side=4.0, sector_deg=60.0):
    """One Miura vertex at the centre of a square of ``side`` mm: the straight crease along y
    (V above the vertex, M below), the zig-zag rays at ``sector_deg`` from +y (both M)."""
    h, g = side / 2, math.radians(sector_deg)
    y_edge = h / math.tan(g)                       # where a zig-zag ray meets x = +-h
    if not 0 < y_edge < h:
        raise ValueError(f"miura_vertex: sector_deg = {sector_deg} must be in (45, 90)")
    xy = [(0, 0), (0, h), (0, -h), (h, y_edge), (-h, y_edge), (h, -h), (h, h), (-h, h), (-h, -h)]
    creases = [(0, 1, "V"), (0, 2, "M"), (0, 3, "M"), (0, 4, "M")]
    return crease_pattern("Miura vertex", xy, creases, [8, 2, 5, 3, 6, 1, 7, 4])


def miura_sheet(a=1.0, b=1.0, gamma_deg=60.0, m=3, n=3):
    """Flat Miura-ori sheet of m x n parallelograms (sides ``a`` along y and ``b`` at
    ``gamma_deg`` from y) [mm]: zig-zag lines alternate M / V, straight lines alternate at
    every vertex (the crease between the two acute sectors is the odd one out)."""
    g = math.radians(gamma_deg)
    vid = lambda i, j: i * (n + 1) + j                                    # noqa: E731
    xy = [(i * b * math.sin(g), j * a + (i % 2) * b * math.cos(g))
          for i in range(m + 1) for j in range(n + 1)]
    zig = lambda j: "M" if j % 2 else "V"                                 # noqa: E731
    other = {"M": "V", "V": "M"}
    creases = [(vid(i, j), vid(i + 1, j), zig(j)) for i in range(m) for j in range(1, n)]
    for i in range(1, m):
        for j in range(n):                         # segment (i, j)-(i, j + 1)
            odd_one = other[zig(j + 1)] if i % 2 else other[zig(j)]
            creases.append((vid(i, j), vid(i, j + 1), odd_one))
    outline = ([vid(i, 0) for i in range(m + 1)] + [vid(m, j) for j in range(1, n + 1)]
               + [vid(i, n) for i in range(m - 1, -1, -1)]
               + [vid(0, j) for j in range(n - 1, 0, -1)])
    return crease_pattern(f"Miura-ori {m} x {n}", xy, creases, outline)


def huffman_tessellation(unit=1.0, cols=3, rows=3):
    """Triangulated tessellation (waterbomb / Yoshimura, after Huffman) of ``2 cols x rows``
    ``unit`` [mm]: horizontal lines y = k (M) and diagonals x +- y = even (V); every interior
    vertex has degree 6 with sectors 45, 90, 45, 45, 90, 45 deg."""
    w = 2 * cols
    pts = [(x, y) for y in range(rows + 1) for x in range(w + 1)
           if (x - y) % 2 == 0 or x in (0, w)]
    ids = {p: k for k, p in enumerate(pts)}
    creases = []
    for y in range(1, rows):
        row = sorted(x for x, yy in pts if yy == y)
        creases += _chain([ids[(x, y)] for x in row], "M")
    for (x, y), k in ids.items():
        if y == rows:
            continue
        for dx in (-1, 1):
            if (x + dx, y + 1) in ids and (x - y) % 2 == 0:
                creases.append((k, ids[(x + dx, y + 1)], "V"))
    outline = ([ids[(x, 0)] for x in range(w + 1) if (x, 0) in ids]
               + [ids[(w, y)] for y in range(1, rows + 1)]
               + [ids[(x, rows)] for x in range(w - 1, -1, -1) if (x, rows) in ids]
               + [ids[(0, y)] for y in range(rows - 1, 0, -1)])
    return crease_pattern("Huffman-style triangulated tessellation",
                          np.array(pts, float) * unit, creases, outline)


def _kawasaki_edge_point(xy, v, dirs, edge_x):
    """Point (edge_x, y) such that the rays from vertex ``v`` towards the points ``dirs`` and
    towards it satisfy Kawasaki's theorem (alternate sector angles sum to 180 deg)."""
    def defect(y):
        return _vertex_defect(xy[v], [*dirs, (edge_x, y)])
    lo, hi = xy[v][1] + 1e-9, 1.0
    for _ in range(200):                           # bisection on the monotone defect
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if defect(lo) * defect(mid) > 0 else (lo, mid)
    return (edge_x, 0.5 * (lo + hi))


def _vertex_defect(p, others):
    ang = sorted(math.atan2(q[1] - p[1], q[0] - p[0]) % (2 * math.pi) for q in others)
    sectors = np.diff(ang + [ang[0] + 2 * math.pi])
    return float(np.sum(sectors[::2]) - math.pi)


def flapping_bird(side=8.0, neck=0.75, head=0.91):
    """The traditional flapping bird on a square of ``side`` mm (unit square below).

    The bird base: diagonals, the midline rays towards corner (0, 0) and the 22.5 deg kite and
    petal lines (points at (1 - tan 22.5)/2 ... from the 22.5 deg geometry); the midline rays
    towards (1, 1) are drawn F. The neck reverse fold meets the diagonal at (neck, neck), the
    head reverse fold at (head, head); their edge points follow from Kawasaki's theorem.
    """
    t = _T22 / 2                                   # 0.2071
    r = 1 - 1 / math.sqrt(2)                       # 0.2929
    p = {"A": (0, 0), "B": (1, 0), "C": (1, 1), "D": (0, 1), "O": (0.5, 0.5),
         "P": (0.5, t), "Q": (t, 0.5), "R": (1 - t, 0.5), "S": (0.5, 1 - t),
         "E": (1 - r, r), "F": (r, 1 - r), "Pb": (r, 0), "Qb": (0, r),
         "mB": (0.5, 0), "mD": (0, 0.5), "mR": (1, 0.5), "mS": (0.5, 1),
         "G": (neck, neck), "H": (head, head)}
    cr = np.subtract(p["C"], p["R"])
    p["U"] = tuple(np.add(p["R"], cr * (head - p["R"][0]) / cr[0]))      # on CR at x = head
    p["T"] = _kawasaki_edge_point(p, "R", [p["E"], p["G"], p["C"]], 1.0)
    p["W"] = _kawasaki_edge_point(p, "U", [p["C"], p["R"], p["H"]], 1.0)
    for a, b in (("U", "U'"), ("T", "T'"), ("W", "W'")):
        p[b] = p[a][::-1]                          # mirror in the diagonal AC
    names = list(p)
    xy = np.array([p[k] for k in names], float) * side
    i = {k: n for n, k in enumerate(names)}
    lines = [("A O", "M"), ("O G", "M"), ("G H", "V"), ("H C", "M"), ("B E", "M"),
             ("E O", "M"), ("O F", "M"), ("F D", "M"), ("O P", "V"), ("O Q", "V"),
             ("P mB", "F"), ("Q mD", "F"), ("O R", "F"), ("O S", "F"), ("R mR", "F"),
             ("S mS", "F"), ("B P", "V"), ("D Q", "V"), ("Pb P", "V"), ("Qb Q", "V"),
             ("E P", "M"), ("F Q", "M"), ("R E", "V"), ("S F", "V"), ("R G", "V"),
             ("S G", "V"), ("R T", "M"), ("S T'", "M"), ("C U", "V"), ("U R", "V"),
             ("C U'", "V"), ("U' S", "V"), ("U H", "M"), ("U' H", "M"), ("U W", "V"),
             ("U' W'", "V")]
    creases = [(i[a], i[b], s) for ab, s in lines for a, b in [ab.split()]]
    outline = ["A", "Pb", "mB", "B", "mR", "T", "W", "C", "W'", "T'", "mS", "D", "mD", "Qb"]
    return crease_pattern("flapping bird", xy, creases, [i[k] for k in outline])


def kawasaki_defects(fold):
    """Kawasaki defect [deg] (alternate sector sum - 180) of every interior vertex of a FOLD
    dict, over its M / V creases (F edges are no creases); {vertex id: defect}."""
    xy = np.asarray(fold["vertices_coords"], float)
    rays, on_outline = {}, set()
    for (a, b), s in zip(fold["edges_vertices"], fold["edges_assignment"]):
        if s == "B":
            on_outline |= {a, b}
        elif s in "MV":
            rays.setdefault(a, []).append(xy[b])
            rays.setdefault(b, []).append(xy[a])
    return {v: math.degrees(_vertex_defect(xy[v], q)) for v, q in rays.items()
            if v not in on_outline}


#: The study's patterns: file name -> generator (defaults as written to studies/patterns/).
PATTERNS = {"waterbomb_base": waterbomb_base, "square_twist": square_twist,
            "miura_vertex": miura_vertex, "miura_3x3": miura_sheet,
            "huffman_tessellation": huffman_tessellation, "flapping_bird": flapping_bird}

#: Powers per heated crease [mW] that fold each pattern meaningfully, heated with ``--heat all``
#: (SU-8/Au stack, 200 um creases). Largest |fold angle| at the three powers on main 4e62691
#: (stable branch; the same at 25 and 200 increments): waterbomb 28 / 56 / 114 deg, square twist
#: 11 / 22 / 46, Miura vertex 17 / 35 / 70, Miura 3 x 3 17 / 44 / 89, Huffman 18 / 46 / 93,
#: flapping bird 19 / 38 / ~77. On a57a509 the waterbomb and the square twist stay near flat
#: (2 - 6 deg, unstable at the top power) or jump branch with the increment count. The top power
#: is the one for ``--quick``. The hottest crease node passes the 1.2 T_g = 252 degC limit at the
#: top power of the square twist (285 degC) and the flapping bird (453 degC).
POWERS_MW = {"waterbomb_base": (5.0, 10.0, 20.0), "square_twist": (5.0, 10.0, 20.0),
             "miura_vertex": (5.0, 10.0, 20.0), "miura_3x3": (2.0, 5.0, 10.0),
             "huffman_tessellation": (2.0, 5.0, 10.0), "flapping_bird": (5.0, 10.0, 20.0)}
