"""The substrate's isothermal plane under the sheet (theory 4.7; issue 29): the one reading of
a :class:`~simulator.model.heat_loss.Substrate` (an explicit plane, or the plane of the
thermal-boundary panels at the current shape), shared by the steady model,
``fixed_shape_temperatures``, ``calibrate_environment`` and the 3-D FE reference."""

from __future__ import annotations

import logging

import numpy as np

from .._deprecation import warn_deprecated
from .._validate import one_of
from ..errors import ParameterError
from ..model.heat_loss import Substrate

__all__ = ["substrate_plane", "resolve_substrate", "panels_plane", "warn_no_plane"]

logger = logging.getLogger(__name__)

#: Boundary panels farther than this fraction of their extent from one plane are not coplanar.
_COPLANAR = 1e-6

#: Whether :func:`warn_no_plane` has spoken in this process (it speaks once).
_NO_PLANE_WARNED = [False]


def warn_no_plane(params) -> None:
    """Warn, once per process, that the integral model has boundary panels but no substrate
    plane: its medium is unbounded under the sheet."""
    if _NO_PLANE_WARNED[0]:
        return
    _NO_PLANE_WARNED[0] = True
    logger.warning(
        "the integral heat loss with boundary_panels %s but substrate=None: the medium is "
        "taken as unbounded below the sheet, without the substrate's isothermal plane (the "
        "loss near the substrate is underestimated: the gripper's assembly power comes out "
        "43 %% low at m = 2); the default substrate, Substrate(), is the boundary panels' "
        "plane, as the 3-D FE takes it (said once per process).",
        tuple(params.boundary_panels))


def substrate_plane(mesh, params, x=None):
    """The substrate plane ``(point (3,), unit normal (3,))`` of ``params``
    (:attr:`~simulator.model.thermal_parameters.ThermalParameters.substrate`) on ``mesh`` at positions
    ``x`` (default: the mesh's): an explicit plane, the plane of the thermal-boundary panels
    (``Substrate()``; None without boundary panels), or None (``substrate=None``)."""
    v = resolve_substrate("model", mesh, params, x)
    if not v:
        return None
    normal = np.array(v[3:])
    return np.array(v[:3]), normal / np.linalg.norm(normal)


def resolve_substrate(substrate, mesh, params, x=None) -> tuple:
    """A substrate as a plane of 6 floats (a point and a normal into the medium [m]), or ()
    for none: ``"model"`` is ``params.substrate`` (None ``params``: none), a
    :class:`~simulator.model.heat_loss.Substrate` its plane or that of the thermal-boundary panels
    of ``params`` on ``mesh`` at positions ``x`` (default: the mesh's), None none; a pair
    (point (3,), normal (3,)) is a deprecated spelling of ``Substrate.plane(point, normal)``.
    The one reading of a substrate: the steady model, ``fixed_shape_temperatures``,
    ``calibrate_environment`` and ``solve_fe3d``."""
    if isinstance(substrate, str):
        one_of("substrate", substrate, ("model",), hint=" (or a Substrate, None, or (point, "
                                                        "normal))")
        substrate = params.substrate if params is not None else None
    if substrate is None:
        return ()
    if isinstance(substrate, Substrate):
        if not substrate.from_panels:
            return substrate.as_tuple()
        return panels_plane(mesh, params.boundary_panels if params is not None else (), x)
    try:
        point, normal = (np.asarray(v, float).reshape(3) for v in substrate)
    except (TypeError, ValueError):
        raise ParameterError(f"substrate = {substrate!r} must be 'model', a Substrate "
                             "(Substrate.plane(point, normal) [m]) or None.") from None
    warn_deprecated("substrate=(point, normal) is deprecated; give "
                    "substrate=Substrate.plane(point, normal).")
    return Substrate.plane(point, normal).as_tuple()


def panels_plane(mesh, panels, x=None) -> tuple:
    """The plane of ``panels`` at positions ``x`` (n, 3) [m] (default: the mesh's) as 6 floats,
    a point and the unit normal towards the rest of the sheet; () for no panels. Raises
    :class:`ParameterError` if they are not coplanar."""
    panels = tuple(panels)
    if not panels:
        return ()
    x = mesh.nodes if x is None else np.asarray(x, float)
    p = x[np.unique(mesh.triangles[np.isin(mesh.triangle_panel, panels)])]
    origin = p.mean(axis=0)
    normal = np.linalg.svd(p - origin)[2][-1]
    if np.abs((p - origin) @ normal).max() > _COPLANAR * np.ptp(p, axis=0).max():
        raise ParameterError(f"the thermal boundary panels {panels} are not coplanar: there is "
                             "no substrate plane to take from them; give the plane explicitly "
                             "(ThermalParameters(substrate=Substrate.plane(point, normal)), or "
                             "substrate=None for none).")
    if np.mean((x - origin) @ normal) < 0:
        normal = -normal
    return tuple(float(v) for v in np.concatenate([origin, normal]))
