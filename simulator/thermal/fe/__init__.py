"""Finite-element reference of steady heat transfer (a verification tool, optional extra
``[fe]``: scikit-fem, gmsh): :func:`fe_disk`, :func:`solve_fe3d`, :func:`solve_fe2d`.

Nothing of the simulator imports this package; it imports scikit-fem and gmsh only
when a solution is computed. See docs/heat_fe.md for the method and the convergence tables.
"""

from ._gmsh import LEVELS
from .results import FE2DResult, FE3DResult, FEDiskResult, FEMeshInfo
from .solve2d import solve_fe2d
from .accuracy import estimated_error
from .solve3d import fe_disk, fe_sphere, solve_fe3d

__all__ = ["LEVELS", "fe_disk", "fe_sphere", "solve_fe3d", "solve_fe2d", "estimated_error", "FEDiskResult",
           "FE3DResult", "FE2DResult", "FEMeshInfo"]
