"""3-D FE reference of steady heat conduction into a medium: an isothermal disk
(:func:`fe_disk`) and a bar-and-hinge model's sheet (:func:`solve_fe3d`).

Method (docs/heat_fe.md): P2 tetrahedra (scikit-fem) on a gmsh mesh of a ball of radius
``R = box_factor x size`` about the structure (a half ball over an isothermal substrate plane),
with the structure embedded as a surface of the mesh. The far field is a Robin condition
``k du/dn + (c k / R) u = 0`` that is exact for the leading term of the far field (c = 1, a
monopole ``1/r`` in free space; c = 2, a dipole over the plane) or, with
``far_field="dirichlet"``, room temperature on the sphere. The sheet's own conduction is the
bar-and-hinge model's (its T3 or monotone conduction, as its parameters say:
:meth:`~simulator.thermal.steady.ThermalModel.sheet_conduction`), and the
medium's dofs on the sheet follow the sheet's piecewise-linear temperature, so the FE and the
chain model differ only in the heat lost to the medium.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time

import numpy as np
import scipy.sparse as sp

from ..._validate import array, finite, positive
from ...errors import ParameterError
from . import _assembly, _gmsh
from .accuracy import MESH_ERROR, accuracy_warnings, check_settings, failed_result
from .results import FE3DResult, FEDiskResult, FEMeshInfo

__all__ = ["fe_disk", "fe_sphere", "solve_fe3d"]

logger = logging.getLogger(__name__)

def fe_disk(radius: float, k_medium: float, height: float | None = None, *,
            box_factor: float = 4.0, level: int = 1, far_field: str = "robin",
            accuracy: float = 0.02, extrapolate: bool = False) -> FEDiskResult:
    """Conductance Q / dT [W/K] of an isothermal disk in a medium, by 3-D FE.

    Parameters
    ----------
    radius : float
        Disk radius a [m].
    k_medium : float
        Medium conductivity k [W/(m K)].
    height : float, optional
        Distance h [m] of the disk (parallel) over an isothermal plane; None: free space,
        where the exact value is ``8 k a``.
    box_factor : float
        Outer sphere radius over the disk's size ``sqrt(a^2 + h^2)`` [-].
    level : int
        Mesh level 0-3 (:data:`simulator.thermal.fe.LEVELS`).
    far_field : {"robin", "dirichlet"}
        Condition on the outer sphere (module notes).
    accuracy : float
        Stated relative accuracy [-]; a coarser level or smaller box is warned about
        (logging WARNING and ``result.warnings``, status ``"accuracy_warning"``).
    extrapolate : bool
        Richardson extrapolation ``2 Q_level - Q_(level-1)`` (the error is first order in the
        mesh size, halved per level; level >= 1): about 0.02 % at level 2 in free space.

    Returns
    -------
    FEDiskResult
        ``levels`` holds the un-extrapolated conductances of the levels solved [W/K].
    """
    if extrapolate and level == 0:
        raise ParameterError("extrapolate=True needs level >= 1 (it also solves level - 1).")
    if extrapolate:
        lo = fe_disk(radius, k_medium, height, box_factor=box_factor, level=level - 1,
                     far_field=far_field, accuracy=1.0)
        hi = fe_disk(radius, k_medium, height, box_factor=box_factor, level=level,
                     far_field=far_field, accuracy=accuracy)
        if not (lo.success and hi.success):
            return lo if not lo.success else hi
        return dataclasses.replace(hi, conductance=2 * hi.conductance - lo.conductance,
                                   levels=(lo.conductance, hi.conductance),
                                   message=hi.message + " (Richardson-extrapolated)")
    positive("radius", radius, "m")
    positive("height", height, "m", allow_none=True)
    check_settings(k_medium, box_factor, level, far_field, accuracy)
    t0 = time.perf_counter()
    size = math.hypot(radius, height or 0.0)
    R = box_factor * size
    err, warns = accuracy_warnings(level, box_factor, far_field, accuracy, "fe_disk")
    base = dict(conductance=None, radius=radius, k_medium=k_medium, height=height)
    try:
        pts, tets, disk_tris = _gmsh.disk_mesh(radius, R, height, level)
        order = (2.0 if height is not None else 1.0) if far_field == "robin" else None
        A, _, fixed, basis = _assembly.medium_system(pts, tets, k_medium, R, order,
                                                     None if height is None else 0.0)
        Q = _conductance(A, fixed, _assembly.facet_dofs(basis,
                                                        _assembly.facet_ids(basis, disk_tris)))
    except Exception as exc:                                      # noqa: BLE001 - as data
        return failed_result(FEDiskResult, exc, **base)
    h_min = _gmsh.level_sizes(level)[0] * radius * min(1.0, 4 * (height or radius) / radius)
    mesh = FEMeshInfo(level, len(pts), len(tets), A.shape[0], h_min, R, box_factor, far_field,
                      err, time.perf_counter() - t0)
    return FEDiskResult(True, "accuracy_warning" if warns else "converged",
                        warns[0] if warns else "converged",
                        conductance=Q, radius=radius, k_medium=k_medium, height=height,
                        mesh=mesh, warnings=warns, levels=(Q,))


def _conductance(A, fixed, held):
    """Dirichlet-principle conductance ``u^T A u`` [W/K] with ``u = 1`` on dofs ``held``."""
    u = np.zeros(A.shape[0])
    u[held] = 1.0
    free = np.flatnonzero(~fixed & (u == 0))
    u[free], _ = _assembly.solve_spd(A[free][:, free], -(A[free] @ u))
    return float(u @ (A @ u))


def fe_sphere(radius: float, k_medium: float, *, box_factor: float = 4.0, level: int = 1,
              far_field: str = "robin") -> FEDiskResult:
    """Conductance [W/K] of an isothermal sphere in a medium by 3-D FE: the 1-D check.

    Exact: ``4 pi k a`` in free space; the Robin far field (c = 1) is exact for this monopole,
    and with ``far_field="dirichlet"`` the exact value in the ball of radius R is
    ``4 pi k / (1/a - 1/R)``. Parameters as in :func:`fe_disk` (``radius`` = sphere radius).
    """
    positive("radius", radius, "m")
    check_settings(k_medium, box_factor, level, far_field, 1.0)
    t0 = time.perf_counter()
    base = dict(conductance=None, radius=radius, k_medium=k_medium)
    try:
        pts, tets, tris = _gmsh.sphere_mesh(box_factor, level)
        A, _, fixed, basis = _assembly.medium_system(pts * radius, tets, k_medium,
                                                     box_factor * radius,
                                                     1.0 if far_field == "robin" else None)
        Q = _conductance(A, fixed, _assembly.facet_dofs(basis,
                                                        _assembly.facet_ids(basis, tris)))
    except Exception as exc:                                      # noqa: BLE001 - as data
        return failed_result(FEDiskResult, exc, **base)
    mesh = FEMeshInfo(level, len(pts), len(tets), A.shape[0], _gmsh.level_sizes(level)[1]
                      * radius, box_factor * radius, box_factor, far_field,
                      MESH_ERROR[level], time.perf_counter() - t0)
    return FEDiskResult(True, "converged", "converged", conductance=Q, radius=radius,
                        k_medium=k_medium, mesh=mesh)


# ---------------------------------------------------------------------------- sheets
def _plane_frame(x, mesh, params, substrate):
    """(origin (3,), rotation (3, 3) whose last row is the plane normal, has_plane) of the
    substrate: ``"model"`` (the model's own, ``ThermalParameters.substrate``: its plane, that
    of its boundary panels at ``x``, or none), a :class:`~simulator.model.heat_loss.Substrate`,
    None, or (point, normal)."""
    from ..substrate import resolve_substrate

    plane = resolve_substrate(substrate, mesh, params, x)
    if not plane:
        return x.mean(axis=0), np.eye(3), False
    origin, normal = np.array(plane[:3]), np.array(plane[3:])
    normal = normal / np.linalg.norm(normal)
    if np.mean((x - origin) @ normal) < 0:
        normal = -normal
    e1 = np.cross(normal, [1.0, 0, 0] if abs(normal[0]) < 0.9 else [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    return origin, np.array([e1, np.cross(normal, e1), normal]), True


def _barycentric(p, tri):
    """Barycentric coordinates (k, 3) of points p (k, 3) in the plane of triangle tri (3, 3)."""
    u, v, w = tri[1] - tri[0], tri[2] - tri[0], p - tri[0]
    uu, uv, vv, wu, wv = u @ u, u @ v, v @ v, w @ u, w @ v      # 2 x 2 normal equations
    det = uu * vv - uv * uv
    s, t = (vv * wu - uv * wv) / det, (uu * wv - uv * wu) / det
    lam = np.clip(np.stack([1 - s - t, s, t], axis=1), 0.0, 1.0)
    return lam / lam.sum(axis=1, keepdims=True)


def _sheet_prolongation(basis, doflocs, sheet_tris, parent, bh_tris, xs, n_nodes):
    """Sparse (n_dof, n_nodes) interpolation of the bar-and-hinge node temperatures onto the
    medium dofs on the sheet, and the mask of those dofs."""
    facets = _assembly.facet_ids(basis, sheet_tris)
    rows, cols, vals = [], [], []
    for t in np.unique(parent):
        dofs = _assembly.facet_dofs(basis, facets[parent == t])
        lam = _barycentric(doflocs[dofs], xs[bh_tris[t]])
        rows.append(np.repeat(dofs, 3))
        cols.append(np.tile(bh_tris[t], len(dofs)))
        vals.append(lam.ravel())
    rows, cols, vals = (np.concatenate(a) for a in (rows, cols, vals))
    on, first = np.unique(rows, return_index=True)
    # a dof on an edge shared by two triangles gets one row (either triangle: continuous)
    keep = np.isin(np.arange(len(rows)), np.concatenate([first + i for i in range(3)]))
    P = sp.csr_matrix((vals[keep], (rows[keep], cols[keep])), shape=(basis.N, n_nodes))
    mask = np.zeros(basis.N, bool)
    mask[on] = True
    return P, mask


def _model_inputs(model, positions, state, crease_power, heat):
    """(positions (n, 3) [m], nodal heat (n,) [W], thermal parameters, thermal model)."""
    from ...model.heat_loss import ChainLoss
    from ...model.thermal_parameters import ThermalParameters
    from ..steady import ThermalModel

    mesh = getattr(model, "mesh", None)
    if mesh is None:
        raise ParameterError(f"model must be a simulator Model, got {type(model).__name__}.")
    n = mesh.n_nodes
    if positions is None:
        positions = mesh.nodes if state is None else mesh.nodes + np.asarray(state.u, float)
    x = array("positions", positions, (n, 3), "m")
    params = model.thermal or ThermalParameters()
    # the nodal heat and the sheet's conduction only: no loss model (the FE is the loss;
    # the chains, whose t_env plays no part here, keep the integral operator unbuilt), the
    # model's own sheet conduction (T3 or monotone), on the mesh triangles (the FE's sheet is
    # the mesh's P1 sheet, whatever the model's sheet_refinement: theory 4.11)
    tm = ThermalModel(mesh, dataclasses.replace(params, loss=ChainLoss(thickness=1.0),
                                                conduction=params.conduction_method,
                                                sheet_refinement=1),
                      actuators=model.actuators)
    if heat is not None:
        if crease_power is not None:
            raise ParameterError("give crease_power or heat, not both.")
        q = array("heat", heat, (n,), "W", hint="one nodal heat input per mesh node")
    else:
        if crease_power is None:
            crease_power = None if state is None else state.crease_power
        if crease_power is None:
            raise ParameterError("crease_power (C,) [W] is required (or heat (n,) [W], or a "
                                 "state with crease_power).")
        q = tm.heat_vector(np.broadcast_to(np.asarray(crease_power, float), (mesh.n_creases,)))
    return x, q, params, tm


def _embedded(mesh, xl, has_plane, tol):
    """Triangles to embed (not lying in the plane) and the nodes on the plane."""
    tri = mesh.triangles
    on_plane = np.zeros(len(xl), bool)
    if has_plane:
        if xl[:, 2].min() < -tol:
            raise ParameterError(f"node {int(np.argmin(xl[:, 2]))} lies {-xl[:, 2].min():.3g} m "
                                 "below the substrate plane: the FE needs the structure above it.")
        on_plane = xl[:, 2] < tol
    return np.flatnonzero(~on_plane[tri].all(axis=1)), on_plane


def _sheet_sizes(mesh, xl, emb, level, plane, scale):
    """Target sheet sizes (crease, panel) in mesher units from the triangle altitudes."""
    f = _gmsh.level_sizes(level)[3]
    tri = xl[mesh.triangles[emb]]
    e = np.linalg.norm(tri[:, [1, 2, 0]] - tri, axis=2)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    alt = 2 * area / e.max(axis=1) / scale
    is_crease = mesh.triangle_crease[emb] >= 0
    h_c = f * alt[is_crease].min() if is_crease.any() else f * alt.min()
    h_p = f * alt[~is_crease].min() if (~is_crease).any() else h_c
    if plane:
        gap = xl[mesh.triangles[emb]][:, :, 2].ravel() / scale
        gap = gap[gap > 1e-6]
        if len(gap):
            h_c, h_p = min(h_c, f * gap.min()), min(h_p, f * gap.min())
    return h_c, min(h_p, 0.5), is_crease


def solve_fe3d(model, crease_power=None, k_medium: float | None = None, *, heat=None,
               state=None, positions=None, substrate="model", room_temperature=None,
               box_factor: float = 4.0, level: int = 1, far_field: str = "robin",
               accuracy: float = 0.02) -> FE3DResult:
    """Steady sheet temperatures of ``model`` in its current shape, by 3-D FE of the medium.

    Parameters
    ----------
    model : Model
        Any bar-and-hinge model; its sheet conduction (k t on its triangles) and
        ``thermal.room_temperature_nodes`` are used, its chain parameters are not.
    crease_power : (C,) array or float, optional
        Power on each crease row [W], shared on the crease nodes as in the chain model
        (:meth:`~simulator.thermal.steady.ThermalModel.heat_vector`); default
        ``state.crease_power``.
    k_medium : float, optional
        Medium conductivity [W/(m K)]; default ``model.thermal.medium.thermal_conductivity``.
    heat : (n,) array, optional
        Nodal heat input [W] instead of ``crease_power``.
    state : SimulationState, optional
        Shape (``mesh.nodes + state.u``) and default power; ``positions`` (n, 3) [m] overrides
        the shape. Default: the flat mesh.
    substrate : "model", Substrate or None
        Isothermal plane at room temperature: the model's own substrate (``"model"``,
        ``ThermalParameters.substrate``: by default the plane of its thermal boundary panels,
        none if it has none), a :class:`~simulator.model.heat_loss.Substrate`, none, or a given
        plane [m].
    room_temperature : float, optional
        [deg C], default ``model.thermal.room_temperature``.
    box_factor, level, far_field, accuracy
        As in :func:`fe_disk`; the size is the structure's radius about the box centre.

    Returns
    -------
    FE3DResult
    """
    check_settings(1.0 if k_medium is None else k_medium, box_factor, level, far_field, accuracy)
    t0 = time.perf_counter()
    x, q, params, tm = _model_inputs(model, positions, state, crease_power, heat)
    k = float(params.medium.thermal_conductivity if k_medium is None else k_medium)
    positive("k_medium", k, "W/(m K)")
    rt = float(params.room_temperature if room_temperature is None else room_temperature)
    finite("room_temperature", rt, "deg C")
    mesh = model.mesh
    origin, rot, plane = _plane_frame(x, mesh, params, substrate)
    xl = (x - origin) @ rot.T
    tol = 1e-9 * np.ptp(xl, axis=0).max()
    emb, on_plane = _embedded(mesh, xl, plane, tol)
    centre = xl[np.unique(mesh.triangles[emb])].mean(axis=0)
    if plane:
        centre[2] = 0.0
    scale = float(np.linalg.norm(xl[np.unique(mesh.triangles[emb])] - centre, axis=1).max())
    xs = (xl - centre) / scale                                  # mesher units
    err, warns = accuracy_warnings(level, box_factor, far_field, accuracy, "solve_fe3d")
    try:
        h_c, h_p, is_crease = _sheet_sizes(mesh, xl, emb, level, plane, scale)
        pts, tets, sheet_tris, parent = _gmsh.sheet_mesh(
            xs[mesh.triangles[emb]], box_factor, 0.0 if plane else None, h_c, h_p, is_crease,
            level)
        order = (2.0 if plane else 1.0) if far_field == "robin" else None
        # the medium in mesher units: conductances scale with length, k -> k * scale
        A, doflocs, fixed, basis = _assembly.medium_system(pts, tets, k * scale, box_factor,
                                                           order, 0.0 if plane else None)
        P, on_sheet = _sheet_prolongation(basis, doflocs, sheet_tris, parent,
                                          mesh.triangles[emb], xs, mesh.n_nodes)
        T = _solve_reduced(A, P, on_sheet, fixed, tm, x, q, params, on_plane)
    except ParameterError:
        raise
    except Exception as exc:                                      # noqa: BLE001 - as data
        return failed_result(FE3DResult, exc, room_temperature=rt)
    T = T + rt
    from ..fixed_shape import crease_measures

    info = FEMeshInfo(level, len(pts), len(tets), A.shape[0], min(h_c, h_p) * scale,
                      box_factor * scale, box_factor, far_field, err, time.perf_counter() - t0)
    return FE3DResult(True, "accuracy_warning" if warns else "converged",
                      warns[0] if warns else "converged",
                      temperature=T, **crease_measures(T, mesh), heat_input=float(q.sum()),
                      room_temperature=rt, mesh=info, warnings=warns)


def _solve_reduced(A, P, on_sheet, fixed, tm, x, q, params, on_plane):
    """Temperature rise of the bar-and-hinge nodes [K] from the reduced system.

    Unknowns: the n sheet nodes, then the medium dofs off the sheet and not held; the medium
    dofs on the sheet are ``P T_nodes``.
    """
    n = P.shape[1]
    rest = np.flatnonzero(~on_sheet & ~fixed)
    E = sp.csr_matrix((np.ones(len(rest)), (rest, n + np.arange(len(rest)))),
                      shape=(A.shape[0], n + len(rest)))
    Z = (sp.hstack([P, sp.csr_matrix((A.shape[0], len(rest)))]) + E).tocsr()
    Kn = tm.sheet_conduction(x).tocoo()
    Ks = sp.csr_matrix((Kn.data, (Kn.row, Kn.col)), shape=(n + len(rest),) * 2)
    Ar = (Z.T @ A @ Z + Ks).tocsr()
    held = np.zeros(n + len(rest), bool)
    held[list(params.room_temperature_nodes)] = True
    held[:n] |= on_plane
    diag = Ar.diagonal()
    lonely = np.flatnonzero(~held[:n] & (diag[:n] <= 0))
    if len(lonely):
        logger.warning("nodes %s have no heat path in the FE; held at room temperature",
                       lonely[:10].tolist())
        held[lonely] = True
    b = np.concatenate([q, np.zeros(len(rest))])
    free = np.flatnonzero(~held)
    u = np.zeros(n + len(rest))
    u[free], res = _assembly.solve_spd(Ar[free][:, free], b[free])
    if not res < 1e-6:
        raise RuntimeError(f"the linear solve did not converge (relative residual {res:.2e})")
    return u[:n]
