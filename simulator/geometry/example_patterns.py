"""Pattern generators for the paper's examples (geometry only, SI units).

Each function returns a :class:`~simulator.geometry.pattern.Pattern` whose vertex and
panel order is that of the reference scripts (theory 10), so that
crease and node numbers match the reference (0-based = reference id - 1).
"""

from __future__ import annotations

import cmath
import math

import numpy as np

from ..errors import ParameterError
from .materials import SU8, SUBSTRATE, Material
from .pattern import Pattern
from .polygons import centroids, unit_normals

__all__ = ["single_fold_pattern", "strip_pattern", "double_fold_pattern", "miura_sheet_pattern",
           "gripper_pattern", "crane_pattern", "roof_pattern"]


def _positive(**kwargs):
    for name, value in kwargs.items():
        if not (isinstance(value, (int, float, np.floating)) and math.isfinite(value) and value > 0):
            raise ParameterError(f"{name} = {value!r} is invalid; it must be a positive finite number "
                                 "(SI units).")


def single_fold_pattern(L: float = 0.5e-3, W: float = 200e-6, undercut: float = 150e-6,
                        panel_thickness: float = 21e-6, anchor_thickness: float = 500e-6,
                        crease_thickness: float = 0.5e-6, substrate: bool = True,
                        panel_material: Material = SU8, substrate_material: Material = SUBSTRATE,
                        ) -> Pattern:
    """Single crease between a thick anchor panel and a thin folding panel (theory 10.1).

    Panels: 0 anchor (thickness ``anchor_thickness``), 1 folding panel, 2 substrate
    ``undercut`` below (when ``substrate``). The crease is edge 2 (reference crease 3).
    All lengths in metres.
    """
    _positive(L=L, W=W, undercut=undercut, panel_thickness=panel_thickness,
              anchor_thickness=anchor_thickness, crease_thickness=crease_thickness)
    v = [(0, 0, 0), (L + W / 2, 0, 0), (2 * L + W, 0, 0), (0, L, 0), (L + W / 2, L, 0),
         (2 * L + W, L, 0)]
    panels = [(0, 1, 4, 3), (1, 2, 5, 4)]
    thick = [anchor_thickness, panel_thickness]
    mats = [substrate_material, panel_material]
    if substrate:
        v += [(0, -0.7 * L, -undercut), (0, 1.8 * L, -undercut), (2.5 * L, -0.6 * L, -undercut),
              (2.5 * L, 1.6 * L, -undercut)]
        panels.append((6, 7, 9, 8))
        thick.append(anchor_thickness)
        mats.append(substrate_material)
    return Pattern(np.array(v, float), panels, crease_width=W, crease_thickness=crease_thickness,
                   panel_thickness=thick, panel_material=mats, crease_material=panel_material)


def strip_pattern(W: float = 0.4, L: float = 1.0, L1: float = 1.0, L2: float = 1.0,
                  crease_thickness: float = 0.001, panel_thickness: float = 0.01,
                  material: Material = SU8) -> Pattern:
    """Two panels joined by one crease, no substrate: the verification strip (theory 10.7).

    Non-dimensional by default (the reference verification uses unit lengths).
    """
    _positive(W=W, L=L, L1=L1, L2=L2, crease_thickness=crease_thickness,
              panel_thickness=panel_thickness)
    v = [(0, 0, 0), (L1 + W / 2, 0, 0), (L1 + L2 + W, 0, 0), (0, L, 0), (L1 + W / 2, L, 0),
         (L1 + L2 + W, L, 0)]
    return Pattern(np.array(v, float), [(0, 1, 4, 3), (1, 2, 5, 4)], crease_width=W,
                   crease_thickness=crease_thickness, panel_thickness=panel_thickness,
                   panel_material=material, crease_material=material)


def double_fold_pattern(L: float = 450e-6, W: float = 200e-6, undercut: float = 60e-6,
                        panel_thickness: float = 21e-6, anchor_thickness: float = 500e-6,
                        crease_thickness: float = 1.1e-6, panel_material: Material = SU8,
                        substrate_material: Material = SUBSTRATE) -> Pattern:
    """Anchor + two folding panels over a substrate (theory 10.2); creases are edges 2 and 5."""
    _positive(L=L, W=W, undercut=undercut, panel_thickness=panel_thickness,
              anchor_thickness=anchor_thickness, crease_thickness=crease_thickness)
    uc = undercut
    v = [(0, 0, 0), (L, 0, 0), (2 * L + W, 0, 0), (3 * L + 1.5 * W, 0, 0), (0, L, 0), (L, L, 0),
         (2 * L + W, L, 0), (3 * L + 1.5 * W, L, 0), (0, -0.6 * L, -uc), (0, 1.6 * L, -uc),
         (4 * L, -0.6 * L, -uc), (4 * L, 1.6 * L, -uc)]
    panels = [(0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (8, 10, 11, 9)]
    return Pattern(np.array(v, float), panels, crease_width=W, crease_thickness=crease_thickness,
                   panel_thickness=[anchor_thickness, panel_thickness, panel_thickness,
                                    anchor_thickness],
                   panel_material=[substrate_material, panel_material, panel_material,
                                   substrate_material], crease_material=panel_material)


def miura_vertices(a: float, b: float, gamma: float, m: int, n: int, ext: float = 1.0):
    """Vertices and panels of the reference ``GenerateMiuraSheet(a, b, gamma, m, n, Ext)``.

    ``ext`` in (0, 1] is the extension (1 = flat). Reproduces the reference's complex-arccos
    round-off (a ~1e-11 m out-of-plane wiggle of every other row at ext = 1) so that meshes
    match it to the last digit.
    """
    if not (isinstance(m, (int, np.integer)) and isinstance(n, (int, np.integer)) and m >= 1
            and n >= 1):
        raise ParameterError(f"Miura cells m = {m!r}, n = {n!r} must be positive integers.")
    _positive(a=a, b=b, gamma=gamma, ext=ext)
    if not (ext <= 1 and gamma < math.pi / 2):
        raise ParameterError(f"Miura: need 0 < ext <= 1 and 0 < gamma < pi/2; got ext = {ext}, "
                             f"gamma = {gamma}.")
    theta = math.asin(ext * math.sin(gamma))
    ell2 = (a + b * math.cos(gamma)) ** 2 + (b * math.sin(gamma)) ** 2
    h = b * math.sin(gamma) * ext
    temp = (ell2 - h**2 - a**2 - (b * math.cos(theta)) ** 2) / (2 * a * b * math.cos(theta))
    beta = abs(cmath.acos(temp))
    dz, dx, dy0, dy1 = a * math.sin(beta), b * math.sin(theta), b * math.cos(theta), a * math.cos(beta)
    i, j = np.meshgrid(np.arange(1, m + 2), np.arange(1, n + 2), indexing="ij")
    x = (i - 1) * dx
    y = (j - 1) * dy1 + np.where(i % 2 == 0, dy0, 0.0)
    z = np.where(j % 2 == 0, dz, 0.0)
    verts = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    pi, pj = np.meshgrid(np.arange(1, m + 1), np.arange(1, n + 1), indexing="ij")
    pi, pj = pi.ravel(), pj.ravel()
    panels = np.column_stack([(pi - 1) * (n + 1) + pj, pi * (n + 1) + pj, pi * (n + 1) + pj + 1,
                              (pi - 1) * (n + 1) + pj + 1]) - 1
    return verts, panels


def miura_sheet_pattern(a: float = 1e-3, b: float = 1e-3, gamma: float = math.radians(60),
                        m: int = 2, n: int = 2, W: float = 200e-6, crease_thickness: float = 1e-6,
                        panel_thickness: float = 10e-6, material: Material = SU8) -> Pattern:
    """Flat Miura-ori sheet of m x n cells (theory 10.3; 2 x 2 cells of Example03 by default).

    ``a`` is the panel side along y, ``b`` the zig-zag side at sector angle ``gamma`` [rad].
    """
    verts, panels = miura_vertices(a, b, gamma, m, n)
    return Pattern(verts, panels, crease_width=W, crease_thickness=crease_thickness,
                   panel_thickness=panel_thickness, panel_material=material, crease_material=material)


def gripper_pattern(w: float = 200e-6, la: float = 700e-6, l1: float = 1000e-6, l2: float = 1000e-6,
                    crease_thickness: float = 1e-6, grip_range: float = 1000e-6,
                    undercut: float = 150e-6, panel_thickness: float = 5e-6,
                    substrate_thickness: float = 500e-6, panel_material: Material = SU8,
                    substrate_material: Material = SUBSTRATE) -> Pattern:
    """Origami micro-gripper of the paper's section 6.3 (theory 10.6), before node edits.

    Panels: 0 left base, 1 central panel, 2 right base, 3 left arm, 4 right arm, 5 substrate.
    Creases: 2 left base hinge, 3 left arm hinge, 5 right base hinge, 9 right arm hinge.
    """
    _positive(w=w, la=la, l1=l1, l2=l2, crease_thickness=crease_thickness, grip_range=grip_range,
              undercut=undercut, panel_thickness=panel_thickness,
              substrate_thickness=substrate_thickness)
    r, uc = grip_range, undercut
    v = [(0, 0, 0), (l1, 0, 0), (l1 + r, 0, 0), (2 * l1 + r, 0, 0), (0, l2, 0), (l1, l2, 0),
         (l1 + r, l2, 0), (2 * l1 + r, l2, 0), (0.5 * l1, la + l2, 0), (l1, la + l2, 0),
         (l1 + r, la + l2, 0), (1.5 * l1 + r, la + l2, 0),
         (-l1, -l1, -uc), (3 * l1 + r, -0.5 * l1, -uc), (-0.5 * l1, la + l2 + l1, -uc),
         (3 * l1 + r, la + l2 + l1, -uc)]
    panels = [(0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (4, 5, 9, 8), (6, 7, 11, 10),
              (12, 13, 15, 14)]
    return Pattern(np.array(v, float), panels, crease_width=w, crease_thickness=crease_thickness,
                   panel_thickness=[panel_thickness] * 5 + [substrate_thickness],
                   panel_material=[panel_material] * 5 + [substrate_material],
                   crease_material=panel_material)


def crane_pattern(a: float = 1e-3, W: float = 100e-6, crease_thickness: float = 1e-6,
                  panel_thickness: float = 10e-6, material: Material = SU8) -> Pattern:
    """Origami crane pattern of the paper's section 6.1 (theory 10.4): 14 panels, 17 creases."""
    _positive(a=a, W=W, crease_thickness=crease_thickness, panel_thickness=panel_thickness)
    v = a * np.array([(-3.2, 0), (-0.7, 0), (0, 0), (0.8, 0), (2.3, 0), (3.4, 0), (-1.1, 1),
                      (1.1, 1), (2.6, 0.5), (0, 4), (-1.1, -1), (1.1, -1), (2.6, -0.5), (0, -4)])
    panels = np.array([[1, 11, 2], [1, 2, 7], [2, 3, 7], [2, 11, 3], [11, 12, 3], [7, 3, 8],
                       [3, 4, 8], [3, 12, 4], [12, 13, 5, 4], [4, 5, 9, 8], [5, 13, 6], [5, 6, 9],
                       [7, 8, 10], [11, 14, 12]], dtype=object)
    panels = [tuple(int(i) - 1 for i in p) for p in panels]
    return Pattern(v, panels, crease_width=W, crease_thickness=crease_thickness,
                   panel_thickness=panel_thickness, panel_material=material, crease_material=material)


def roof_pattern(span: float = 1e-3, rise: float = 40e-6, depth: float = 500e-6,
                 crease_width: float = 20e-6, crease_thickness: float = 5e-6,
                 panel_thickness: float = 20e-6, material: Material = SU8) -> Pattern:
    """Shallow two-panel roof: eaves at x = 0 and x = ``span`` (z = 0), ridge crease (edge 2)
    at x = span / 2, z = ``rise``, all ``depth`` long in y. Pinned along the eaves and pushed
    at the ridge it is a von Mises truss in every section (a snap-through). Lengths in metres.
    """
    _positive(span=span, rise=rise, depth=depth, crease_width=crease_width,
              crease_thickness=crease_thickness, panel_thickness=panel_thickness)
    h = span / 2
    v = [(0, 0, 0), (h, 0, rise), (span, 0, 0), (0, depth, 0), (h, depth, rise),
         (span, depth, 0)]
    return Pattern(np.array(v, float), [(0, 1, 4, 3), (1, 2, 5, 4)], crease_width=crease_width,
                   crease_thickness=crease_thickness, panel_thickness=panel_thickness,
                   panel_material=material, crease_material=material)


def with_substrate(pattern: Pattern, undercut: float, margin: float,
                   thickness: float = 500e-6, material: Material = SUBSTRATE) -> Pattern:
    """Add a rectangular substrate panel ``undercut`` below the pattern's lowest vertex.

    The substrate extends ``margin`` beyond the pattern's x-y bounding box. It becomes the
    last panel; its edges get the last edge ids, so existing crease ids are unchanged.
    """
    _positive(undercut=undercut, margin=margin, thickness=thickness)
    v = pattern.vertices
    lo, hi = v[:, :2].min(axis=0) - margin, v[:, :2].max(axis=0) + margin
    z = v[:, 2].min() - undercut
    n = len(v)
    corners = np.array([[lo[0], lo[1], z], [hi[0], lo[1], z], [hi[0], hi[1], z], [lo[0], hi[1], z]])
    creases = pattern.creases
    return Pattern(np.vstack([v, corners]), pattern.panels + ((n, n + 1, n + 2, n + 3),),
                   crease_width={int(c): pattern.crease_width[c] for c in creases},
                   crease_thickness={int(c): pattern.crease_thickness[c] for c in creases},
                   panel_thickness=np.r_[pattern.panel_thickness, thickness],
                   panel_material=pattern.panel_material + (material,),
                   crease_material=pattern.crease_material)


def fold_directions(vertices, panels) -> dict:
    """Sign (+1 towards +z, -1 towards -z) of every interior crease of a folded pattern.

    Computed from the signed dihedral angle of the two panels with normals oriented to +z:
    used to give actuators the fold directions of a target shape (e.g. a partly folded Miura).
    """
    verts = np.asarray(vertices, float)
    geo = Pattern(verts, panels, crease_width=1.0, crease_thickness=1.0, panel_thickness=1.0)
    corners, sizes = verts[geo.corner_vertices], geo.corner_sizes
    normal = unit_normals(corners, sizes, upward=True)
    centroid = centroids(corners, sizes)
    p1, p2 = geo.edge_panels[geo.creases].T
    axis = np.cross(centroid[p2] - centroid[p1], normal[p1])
    s = np.einsum("ij,ij->i", np.cross(normal[p1], normal[p2]), axis)
    return {int(k): (1 if v > 0 else -1) for k, v in zip(geo.creases, s)}
