"""2-D cross-section FE of a strip (the paper's 2-D reference, an upper bound of the 3-D one).

The section is a line of segments along x (lengths, in-plane conductance k t per unit depth,
heat per unit depth) embedded in a disk of radius ``R = box_factor x half length`` of medium
(P2 triangles, scikit-fem on a gmsh mesh), optionally over an isothermal plane. The outer
circle is at room temperature: a 2-D medium has no steady far field (the temperature grows
like ``ln R``), so the 2-D result depends on the box and bounds the 3-D one from above for the
same box; the sheet's own conduction is resolved on the medium's mesh (P2 on the line).
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from ..._validate import array, finite, positive
from ...errors import ParameterError
from . import _assembly, _gmsh
from .accuracy import accuracy_warnings, check_settings, failed_result
from .results import FE2DResult, FEMeshInfo

__all__ = ["solve_fe2d"]


def _line_stiffness(basis, segs, parent, kt, scale):
    """P2 line conduction ``kt int T' v'`` on the sheet segments, (n_dof, n_dof) [W/K per m],
    the segments' dofs (k, 3) (ends, midpoint) and physical lengths (k,) [m] (mesh in units of
    ``scale`` [m]).

    A P2 line element with end dofs (a, b) and midpoint dof m, length l:
    ``(kt / (3 l)) [[7, 1, -8], [1, 7, -8], [-8, -8, 16]]``.
    """
    facets = _assembly.facet_ids(basis, segs)
    ends = basis.dofs.nodal_dofs[0][basis.mesh.facets[:, facets].T]     # (k, 2)
    midd = basis.dofs.facet_dofs[0, facets]                              # (k,)
    pts = basis.mesh.p.T
    length = np.linalg.norm(pts[segs[:, 1]] - pts[segs[:, 0]], axis=1) * scale
    ke = np.array([[7, 1, -8], [1, 7, -8], [-8, -8, 16]]) / 3.0
    local = (kt[parent] / length)[:, None, None] * ke
    dof = np.column_stack([ends, midd])
    rows = np.repeat(dof, 3, axis=1).ravel()
    cols = np.tile(dof, (1, 3)).ravel()
    K = sp.csr_matrix((local.ravel(), (rows, cols)), shape=(basis.N, basis.N))
    return K, dof, length


def solve_fe2d(lengths, kt, heat, k_medium: float, *, fixed_ends: bool = True,
               plane_distance: float | None = None, room_temperature: float = 21.0,
               box_factor: float = 4.0, level: int = 1, accuracy: float = 0.02) -> FE2DResult:
    """Steady temperatures of a strip's cross-section in a 2-D medium, by FE.

    Parameters
    ----------
    lengths : (m,) array
        Segment lengths along the section [m] (e.g. panel, crease, panel).
    kt : (m,) array
        In-plane conductance k t of every segment [W/K] (per unit depth: W/(m K) x m).
    heat : (m,) array
        Heat of every segment per unit depth [W/m], spread uniformly over the segment.
    k_medium : float
        Medium conductivity [W/(m K)].
    fixed_ends : bool
        Hold both ends of the section at room temperature (the strip's held ends).
    plane_distance : float, optional
        Distance [m] of an isothermal plane below the section.
    room_temperature : float
        [deg C].
    box_factor, level, accuracy
        Outer circle radius over the half length, mesh level, stated accuracy (as in
        :func:`~simulator.thermal.fe.fe_disk`; the box error here is the ``ln R`` growth).

    Returns
    -------
    FE2DResult
    """
    L = array("lengths", lengths, (None,), "m")
    m = len(L)
    kt = array("kt", kt, (m,), "W/K", hint="one entry per segment")
    heat = array("heat", heat, (m,), "W/m", hint="one entry per segment")
    if not (np.all(L > 0) and np.all(kt >= 0)):
        raise ParameterError("lengths must be > 0 and kt >= 0 for every segment.")
    positive("plane_distance", plane_distance, "m", allow_none=True)
    finite("room_temperature", room_temperature, "deg C")
    check_settings(k_medium, box_factor, level, "dirichlet", accuracy)
    t0 = time.perf_counter()
    xe = np.concatenate([[0.0], np.cumsum(L)])
    half = xe[-1] / 2
    scale = half
    xs = (xe - half) / scale
    R = box_factor
    err, warns = accuracy_warnings(level, box_factor, "dirichlet", accuracy, "solve_fe2d")
    f = _gmsh.level_sizes(level)[3]
    h = f * min(L.min() / scale, 1.0, *(() if plane_distance is None
                                         else (plane_distance / scale,)))
    plane = None if plane_distance is None else -plane_distance / scale
    try:
        pts, tris, segs, parent = _gmsh.section_mesh(xs, R, plane, h, level)
        A, doflocs, fixed, basis = _assembly.medium_system(pts[:, :2], tris, k_medium, R,
                                                           None, plane)
        K, dof, seg_len = _line_stiffness(basis, segs, parent, kt, scale)
        b = np.zeros(basis.N)
        load = heat[parent] * seg_len / L[parent]
        np.add.at(b, dof, load[:, None] * np.array([1 / 6, 1 / 6, 2 / 3]))
        if fixed_ends:
            ends = np.flatnonzero(np.isclose(np.abs(doflocs[:, 0]), 1.0) &
                                  np.isclose(doflocs[:, 1], 0.0))
            fixed[ends] = True
        free = np.flatnonzero(~fixed)
        u = np.zeros(basis.N)
        Ar = (A + K).tocsr()
        u[free], _ = _assembly.solve_spd(Ar[free][:, free], b[free])
    except Exception as exc:                                      # noqa: BLE001 - as data
        return failed_result(FE2DResult, exc)
    node_x = doflocs[:, 0] * scale + half
    on = np.unique(dof)
    order = np.argsort(node_x[on])
    xline, tline = node_x[on][order], u[on][order] + room_temperature
    t_ends = np.interp(xe, xline, tline)
    t_mid = np.interp(0.5 * (xe[:-1] + xe[1:]), xline, tline)
    info = FEMeshInfo(level, len(pts), len(tris), basis.N, h * scale, R * scale, box_factor,
                      "dirichlet", err, time.perf_counter() - t0)
    return FE2DResult(True, "accuracy_warning" if warns else "converged",
                      warns[0] if warns else "converged", x=xe, temperature=t_ends,
                      segment_temperature=t_mid, mesh=info, warnings=warns)
