"""The finite-element reference of steady heat transfer: a verification tool of the heat-loss
models (optional extra ``[fe]``: scikit-fem and gmsh, imported only when a solution is
computed). :func:`fe_disk` (a heated disk in a medium), :func:`fe_sphere`, :func:`solve_fe3d`
(a model's sheet in a 3-D medium) and :func:`solve_fe2d` (a strip's cross-section); see
``docs/heat_fe.md`` for the method and the convergence tables."""

from .thermal.fe import (LEVELS, FE2DResult, FE3DResult, FEDiskResult, FEMeshInfo,
                         estimated_error, fe_disk, fe_sphere, solve_fe2d, solve_fe3d)

__all__ = ["solve_fe3d", "solve_fe2d", "fe_disk", "fe_sphere", "FE3DResult", "FE2DResult",
           "FEDiskResult", "FEMeshInfo", "estimated_error", "LEVELS"]
