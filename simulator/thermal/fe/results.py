"""Result types of the FE reference: every one has ``success``, ``status``, ``message``."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..._result import ResultFiles
from ..fixed_shape import CreaseTemperatureTable

__all__ = ["FEMeshInfo", "FEDiskResult", "FE3DResult", "FE2DResult"]


@dataclass(frozen=True)
class FEMeshInfo:
    """Size of one FE solution.

    Attributes
    ----------
    level : int, mesh level (:data:`simulator.thermal.fe.LEVELS`).
    n_vertices, n_cells, n_dofs : int, mesh vertices, tetrahedra (triangles in 2-D), P2 dofs.
    h_min : float, smallest target element size [m].
    box_radius : float, radius R of the outer sphere (circle) [m].
    box_factor : float, R over the structure's size (its radius about the box centre) [-].
    far_field : str, ``"robin"`` or ``"dirichlet"`` on the outer sphere.
    estimated_error : float, a-priori relative error of mesh plus box (calibrated by the
        convergence tables in docs/heat_fe.md) [-].
    wall_time : float, mesh plus solve [s].
    """

    level: int
    n_vertices: int
    n_cells: int
    n_dofs: int
    h_min: float
    box_radius: float
    box_factor: float
    far_field: str
    estimated_error: float
    wall_time: float

    def to_dict(self) -> dict:
        return {"level [-]": self.level, "vertices [-]": self.n_vertices,
                "cells [-]": self.n_cells, "dofs [-]": self.n_dofs, "h_min [m]": self.h_min,
                "box_radius [m]": self.box_radius, "box_factor [-]": self.box_factor,
                "far_field": self.far_field, "estimated_error [-]": self.estimated_error,
                "wall_time [s]": self.wall_time}


@dataclass(frozen=True)
class FEDiskResult(ResultFiles):
    """Conductance of an isothermal disk (:func:`~simulator.thermal.fe.fe_disk`).

    Attributes
    ----------
    success, status, message : outcome (status ``"converged"``, ``"accuracy_warning"`` (solved; a
        check of its accuracy failed: ``warnings``) or ``"failed"``).
    conductance : float or None, Q / dT [W/K] (None if failed).
    radius, k_medium : float, disk radius [m], medium conductivity [W/(m K)].
    height : float or None, distance to the isothermal plane [m].
    mesh : FEMeshInfo or None.
    warnings : tuple of str, accuracy warnings (also logged at WARNING).
    levels : tuple of float, conductances of the levels solved [W/K] (two with
        ``extrapolate=True``: level - 1, level).
    """

    success: bool
    status: str
    message: str
    conductance: float | None
    radius: float
    k_medium: float
    height: float | None = None
    mesh: FEMeshInfo | None = None
    warnings: tuple = ()
    levels: tuple = ()

    @property
    def free_space_ratio(self):
        """conductance / (8 k a) [-] (None if failed)."""
        return None if self.conductance is None else self.conductance / (8 * self.k_medium
                                                                         * self.radius)

    def to_dict(self) -> dict:
        d = {"success": self.success, "status": self.status, "message": self.message,
             "conductance [W/K]": self.conductance, "radius [m]": self.radius,
             "k_medium [W/(m K)]": self.k_medium, "height [m]": self.height,
             "Q/(8 k a) [-]": self.free_space_ratio}
        return d | (self.mesh.to_dict() if self.mesh else {})


@dataclass(frozen=True)
class FE3DResult(CreaseTemperatureTable, ResultFiles):
    """Steady temperatures of a model's sheet in a 3-D medium (:func:`solve_fe3d`).

    Attributes
    ----------
    success, status, message : outcome (status ``"converged"``, ``"accuracy_warning"`` (solved; a
        check of its accuracy failed: ``warnings``) or ``"failed"``).
    temperature : (n,) array or None, bar-and-hinge node temperatures [deg C].
    crease_temperature : (C,) array, 7-node weighted mean (the actuation temperature, as
        :attr:`simulator.SimulationResult.crease_temperature`) [deg C].
    crease_temperature_max : (C,) array, hottest of the 7 crease nodes [deg C].
    crease_t_ctr : (C,) array, T at the crease centre node Ctr (Fig. 6's T_max) [deg C].
    crease_t_ave : (C,) array, mean of the centre line A, B, Ctr (Fig. 6's T_ave) [deg C].
    heat_input : float, total heat [W].
    room_temperature : float [deg C].
    mesh : FEMeshInfo or None.
    warnings : tuple of str.
    """

    success: bool
    status: str
    message: str
    temperature: np.ndarray | None = None
    crease_temperature: np.ndarray | None = None
    crease_temperature_max: np.ndarray | None = None
    crease_t_ctr: np.ndarray | None = None
    crease_t_ave: np.ndarray | None = None
    heat_input: float = 0.0
    room_temperature: float = 21.0
    mesh: FEMeshInfo | None = None
    warnings: tuple = field(default=())

    _csv_name = "fe3d_creases.csv"

    def _meta(self) -> dict:
        return {"heat_input [W]": self.heat_input, "warnings": list(self.warnings)} | (
            self.mesh.to_dict() if self.mesh else {})


@dataclass(frozen=True)
class FE2DResult(ResultFiles):
    """Steady temperatures of a strip cross-section (:func:`solve_fe2d`).

    Attributes
    ----------
    success, status, message : outcome.
    x : (m + 1,) array, segment end positions along the section [m].
    temperature : (m + 1,) array, temperature at the segment ends [deg C].
    segment_temperature : (m,) array, temperature at every segment's midpoint [deg C].
    mesh : FEMeshInfo or None; warnings : tuple of str.
    """

    success: bool
    status: str
    message: str
    x: np.ndarray | None = None
    temperature: np.ndarray | None = None
    segment_temperature: np.ndarray | None = None
    mesh: FEMeshInfo | None = None
    warnings: tuple = ()

    _csv_name = "fe2d_section.csv"

    def to_frame(self):
        """One row per segment end: ``x [m]`` and ``temperature [degC]``."""
        import pandas as pd

        if self.x is None:
            return pd.DataFrame()
        return pd.DataFrame({"x [m]": self.x, "temperature [degC]": self.temperature})
