"""gmsh meshes of the FE reference: a ball (or half ball over an isothermal plane) with
embedded conducting surfaces (sheet triangles, a disk), or a 2-D disk with an embedded line.

All geometry is handed to gmsh in units of a length scale ``scale`` (so OpenCASCADE's absolute
tolerances fit any model size) and returned in metres. gmsh is imported here only.
"""

from __future__ import annotations

import contextlib
import logging

import numpy as np

logger = logging.getLogger(__name__)

#: Mesh levels: (edge size / a, face size / a, growth of the size with distance, sheet size
#: / triangle altitude). Level 0 is coarse (CI), 2 converged to about 0.5 % (docs, FE section).
LEVELS = {0: (0.05, 0.35, 0.55, 0.6), 1: (0.025, 0.22, 0.42, 0.42),
          2: (0.0125, 0.14, 0.32, 0.3), 3: (0.00625, 0.09, 0.25, 0.21)}


def level_sizes(level: int) -> tuple:
    """(edge, face, growth, sheet) size factors of a mesh level (see :data:`LEVELS`)."""
    if level in LEVELS:
        return LEVELS[level]
    raise ValueError(level)


@contextlib.contextmanager
def _session():
    import gmsh

    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        for k in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
            gmsh.option.setNumber("Mesh." + k, 0)
        gmsh.model.add("fe")
        yield gmsh
    finally:
        gmsh.finalize()


def _domain(gmsh, radius, plane_z, dim=3):
    """Ball (disk in 2-D) of ``radius`` about the origin, cut below ``plane_z`` if given."""
    occ = gmsh.model.occ
    if dim == 3:
        ball = occ.addSphere(0, 0, 0, radius)
        if plane_z is not None:
            cut = occ.addBox(-2 * radius, -2 * radius, -2 * radius, 4 * radius, 4 * radius,
                             2 * radius + plane_z)
            ball = occ.cut([(3, ball)], [(3, cut)])[0][0][1]
        return ball
    disk = occ.addDisk(0, 0, 0, radius, radius)
    if plane_z is not None:
        cut = occ.addRectangle(-2 * radius, -2 * radius, 0, 4 * radius, 2 * radius + plane_z)
        disk = occ.cut([(2, disk)], [(2, cut)])[0][0][1]
    return disk


def _size_field(gmsh, groups, grow, h_max, dim_entities):
    """Background size ``min_g (h_g + grow * distance_g)`` capped at ``h_max``.

    ``groups``: list of (h, [(dim, tag), ...]) entities the distance is measured to.
    """
    f = gmsh.model.mesh.field
    terms = []
    for h, ents in groups:
        if not ents:
            continue
        d = f.add("Distance")
        for dim, key in dim_entities:
            tags = [t for e, t in ents if e == dim]
            if tags:
                f.setNumbers(d, key, tags)
        f.setNumber(d, "Sampling", 40)
        terms.append(f"{h:.9g} + {grow:.9g} * F{d}")
    expr = f"{h_max:.9g}"
    for t in terms:
        expr = f"Min({t}, {expr})"
    m = f.add("MathEval")
    f.setString(m, "F", expr)
    f.setAsBackgroundMesh(m)


def _nodes_and_cells(gmsh, dim):
    """All mesh nodes (N, 3) and the cells of dimension ``dim`` (0-based node ids)."""
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    types, _, nodes = gmsh.model.mesh.getElements(dim)
    n_vertex = dim + 1
    cells = np.concatenate([index[np.asarray(nd, np.int64)].reshape(-1, n_vertex)
                            for t, nd in zip(types, nodes)
                            if gmsh.model.mesh.getElementProperties(t)[3] == n_vertex])
    return xyz.reshape(-1, 3), index, cells


def _entity_triangles(gmsh, index, tag, dim=2):
    """Vertex ids (k, dim + 1) of the linear mesh cells on entity ``(dim, tag)``: triangles on
    a surface, segments (``dim=1``) on a curve."""
    types, _, nodes = gmsh.model.mesh.getElements(dim, tag)
    linear = {2: 2, 1: 1}[dim]                 # gmsh element types: 3-node triangle, 2-node line
    return np.concatenate([index[np.asarray(nd, np.int64)].reshape(-1, dim + 1)
                           for t, nd in zip(types, nodes) if t == linear])


def _embedded_cells(gmsh, index, maps, dim):
    """Mesh cells on the embedded entities (every input but the first of ``fragment``'s maps)
    and the input each lies in: ((k, dim + 1), (k,))."""
    cells, parent = [], []
    for i, m in enumerate(maps[1:]):
        for _, t in m:
            cells.append(_entity_triangles(gmsh, index, t, dim))
            parent.append(np.full(len(cells[-1]), i))
    return np.concatenate(cells), np.concatenate(parent)


def disk_mesh(radius, box_radius, height, level):
    """Tetrahedra around an isothermal disk (unit-free: lengths in units of ``radius``).

    Returns (points (N, 3) [m], tets (M, 4), disk triangles (k, 3)): the disk lies at
    ``z = height`` over a plane ``z = 0`` when ``height`` is given, else at ``z = 0`` in a ball.
    """
    h_edge, h_face, grow, _ = level_sizes(level)
    a, R = 1.0, box_radius / radius
    z = 0.0 if height is None else height / radius
    if height is not None and z < 0.25:          # resolve the gap: every size scales with it
        h_edge, h_face = h_edge * z / 0.25, h_face * z / 0.25
    with _session() as gmsh:
        occ = gmsh.model.occ
        ball = _domain(gmsh, R, None if height is None else 0.0)
        disk = occ.addDisk(0, 0, z, a, a)
        _, maps = occ.fragment([(3, ball)], [(2, disk)])
        occ.synchronize()
        faces = maps[1]
        edges = gmsh.model.getBoundary(faces, oriented=False)
        _size_field(gmsh, [(h_edge, edges), (h_face, faces)], grow, R / 4,
                    [(1, "CurvesList"), (2, "SurfacesList")])
        gmsh.model.mesh.generate(3)
        xyz, index, tets = _nodes_and_cells(gmsh, 3)
        disk_tris = np.concatenate([_entity_triangles(gmsh, index, t) for _, t in faces])
    return xyz * radius, tets, disk_tris


def sphere_mesh(box_radius, level):
    """Tetrahedra between a unit sphere and a ball of ``box_radius`` (unit-free).

    Returns (points (N, 3), tets (M, 4), inner sphere triangles (k, 3)).
    """
    _, h_face, grow, _ = level_sizes(level)
    with _session() as gmsh:
        occ = gmsh.model.occ
        vol = occ.cut([(3, occ.addSphere(0, 0, 0, box_radius))],
                      [(3, occ.addSphere(0, 0, 0, 1.0))])[0]
        occ.synchronize()
        inner = [e for e in gmsh.model.getBoundary(vol, oriented=False)
                 if max(np.abs(gmsh.model.getBoundingBox(*e))) < 1.5]
        _size_field(gmsh, [(h_face, inner)], grow, box_radius / 4, [(2, "SurfacesList")])
        gmsh.model.mesh.generate(3)
        xyz, index, tets = _nodes_and_cells(gmsh, 3)
        tris = np.concatenate([_entity_triangles(gmsh, index, t) for _, t in inner])
    return xyz, tets, tris


def sheet_mesh(triangles, box_radius, plane_z, h_crease, h_panel, is_crease, level):
    """Tetrahedra of a ball (half ball over ``z = plane_z``) with the sheet triangles embedded.

    ``triangles``: (m, 3, 3) vertices in mesher units (the structure scaled to size ~1 and
    centred at the origin); ``h_crease`` / ``h_panel``: sheet mesh sizes of crease and panel
    triangles. Returns (points (N, 3), tets (M, 4), sheet triangles (k, 3), parent (k,)): the
    mesh triangles on the sheet and the index of the input triangle each lies in.
    """
    _, _, grow, _ = level_sizes(level)
    with _session() as gmsh:
        occ = gmsh.model.occ
        vol = _domain(gmsh, box_radius, plane_z)
        pts, lines, surfs = {}, {}, []

        def point(p):
            key = tuple(np.round(p, 9))
            if key not in pts:
                pts[key] = occ.addPoint(*p)
            return pts[key]

        def line(a, b):
            if (b, a) in lines:
                return -lines[(b, a)]
            if (a, b) not in lines:
                lines[(a, b)] = occ.addLine(a, b)
            return lines[(a, b)]

        for tri in triangles:
            p = [point(v) for v in tri]
            loop = occ.addCurveLoop([line(p[0], p[1]), line(p[1], p[2]), line(p[2], p[0])])
            surfs.append(occ.addPlaneSurface([loop]))
        _, maps = occ.fragment([(3, vol)], [(2, s) for s in surfs])
        occ.synchronize()
        crease = [e for i, m in enumerate(maps[1:]) if is_crease[i] for e in m]
        panel = [e for i, m in enumerate(maps[1:]) if not is_crease[i] for e in m]
        _size_field(gmsh, [(h_crease, crease), (h_panel, panel)], grow, box_radius / 3,
                    [(2, "SurfacesList")])
        gmsh.model.mesh.generate(3)
        xyz, index, tets = _nodes_and_cells(gmsh, 3)
        tris, parent = _embedded_cells(gmsh, index, maps, 2)
    return xyz, tets, tris, parent


def section_mesh(x_nodes, box_radius, plane_z, h_sheet, level):
    """Triangles of a disk (half disk over ``y = plane_z``) with the sheet line from
    ``x_nodes[0]`` to ``x_nodes[-1]`` on ``y = 0`` embedded, split at every ``x_nodes``.

    Returns (points (N, 3), triangles (M, 3), sheet segments (k, 2), parent segment (k,)).
    """
    _, _, grow, _ = level_sizes(level)
    with _session() as gmsh:
        occ = gmsh.model.occ
        dom = _domain(gmsh, box_radius, plane_z, dim=2)
        p = [occ.addPoint(x, 0, 0) for x in x_nodes]
        segs = [occ.addLine(a, b) for a, b in zip(p[:-1], p[1:])]
        _, maps = occ.fragment([(2, dom)], [(1, s) for s in segs])
        occ.synchronize()
        lines = [e for m in maps[1:] for e in m]
        _size_field(gmsh, [(h_sheet, lines)], grow, box_radius / 4, [(1, "CurvesList")])
        gmsh.model.mesh.generate(2)
        xyz, index, tris = _nodes_and_cells(gmsh, 2)
        segs, parent = _embedded_cells(gmsh, index, maps, 1)
    return xyz, tris, segs, parent
