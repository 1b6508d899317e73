"""Merging of faces joined by flat (F) and join (J) edges into one planar panel."""

from __future__ import annotations

import math

import numpy as np

from ._common import fail as _fail


def merge_flat_faces(coords, faces, edges, letters):
    """Merge faces joined by F / J edges into panels; returns (groups, panel polygons)."""
    parent = list(range(len(faces)))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    owners = {}
    for f, poly in enumerate(faces):
        for a, b in zip(poly, poly[1:] + poly[:1]):
            owners.setdefault((min(a, b), max(a, b)), []).append(f)
    flat = set()
    for i, ((a, b), letter) in enumerate(zip(edges.tolist(), letters)):
        if letter in "FJ":
            f, g = owners[(min(a, b), max(a, b))]
            _check_coplanar(coords, faces, f, g, i, letter)
            parent[root(f)] = root(g)
            flat.add((min(a, b), max(a, b)))
    roots = [root(f) for f in range(len(faces))]
    order = list(dict.fromkeys(roots))
    groups = [[f for f in range(len(faces)) if roots[f] == r] for r in order]
    panels = [faces[g[0]] if len(g) == 1 else _boundary(faces, g, flat) for g in groups]
    return groups, panels


def _check_coplanar(coords, faces, f, g, i, letter):
    n = [_normal(coords[faces[k]]) for k in (f, g)]
    angle = math.degrees(math.atan2(np.linalg.norm(np.cross(n[0], n[1])), n[0] @ n[1]))
    if abs(angle) > 1e-4:
        _fail(f"edges_assignment[{i}]", f"{letter!r} (flat) but faces {f} and {g} meet at a fold "
              f"angle of {angle:.4g} deg; assign M, V or U, or make the faces coplanar.")


def _normal(x) -> np.ndarray:
    c = x.mean(axis=0)
    n = np.cross(x - c, np.roll(x, -1, axis=0) - c).sum(axis=0)
    return n / max(np.linalg.norm(n), 1e-300)


def _boundary(faces, group, flat) -> list:
    """Outer polygon of faces merged along flat edges (directed sides chained into one cycle)."""
    nxt = {}
    for f in group:
        poly = faces[f]
        for a, b in zip(poly, poly[1:] + poly[:1]):
            if (min(a, b), max(a, b)) in flat:
                continue
            if a in nxt:
                _fail(f"faces_vertices[{f}]", f"merging faces {group} along their F/J edges "
                      f"does not give a simple polygon (vertex {a} is pinched or the faces are "
                      "not consistently oriented).")
            nxt[a] = b
    start = next(iter(nxt))
    cycle, v = [start], nxt[start]
    while v != start and len(cycle) <= len(nxt):
        cycle.append(v)
        v = nxt.get(v, start)
    if len(cycle) != len(nxt) or nxt.get(cycle[-1]) != start:
        _fail(f"faces_vertices[{group[0]}]", f"merging faces {group} along their F/J edges "
              "gives a panel with a hole or several outlines; mark some edges U instead.")
    return cycle
