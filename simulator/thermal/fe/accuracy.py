"""The FE reference's accuracy and settings, shared by the 3-D (:mod:`.solve3d`) and 2-D
(:mod:`.solve2d`) solvers: the a-priori error of a mesh level and box, the check of the common
settings and the result of a failed solution."""

from __future__ import annotations

import logging

from ..._validate import integer, positive
from ...errors import ParameterError
from . import _gmsh

__all__ = ["MESH_ERROR", "estimated_error", "check_settings", "accuracy_warnings",
           "failed_result"]

logger = logging.getLogger(__name__)

#: Measured relative error of the conductance per mesh level (the disk in free space, 1.2, 0.53
#: and 0.26 % at levels 0-2: first order in the mesh size, from the edge singularity; see the
#: convergence table of docs/heat_fe.md) [-].
MESH_ERROR = {0: 0.012, 1: 0.006, 2: 0.003, 3: 0.0015}


def estimated_error(level: int, box_factor: float, far_field: str = "robin") -> float:
    """A-priori relative error [-] of an FE conductance or temperature rise: the mesh level's
    measured error (:data:`MESH_ERROR`) plus the box error: Robin ``(0.5 / box_factor)^3``
    (measured below 0.2 % from box_factor 2.5); Dirichlet ``x / (1 - x)``,
    ``x = 0.64 / box_factor``, the disk's monopole ``Q / (4 pi k R)``."""
    x = 0.64 / box_factor
    box = (0.5 / box_factor) ** 3 if far_field == "robin" else x / (1 - x)
    return MESH_ERROR[level] + box


def check_settings(k_medium, box_factor, level, far_field, accuracy):
    """Refuse a bad setting shared by the FE solvers (the medium's conductivity, the box, the
    mesh level, the far field, the stated accuracy), naming it."""
    positive("k_medium", k_medium, "W/(m K)")
    positive("box_factor", box_factor, "-")
    if box_factor <= 1.5:
        raise ParameterError(f"box_factor = {box_factor!r} must exceed 1.5 (the outer sphere's "
                             "radius over the structure's size); use 3 to 8.")
    integer("level", level, 0, max(_gmsh.LEVELS), hint=" (the mesh level: 0 coarse, 2 "
            "converged)")
    if far_field not in ("robin", "dirichlet"):
        raise ParameterError(f"far_field = {far_field!r}; use 'robin' or 'dirichlet'.")
    positive("accuracy", accuracy, "-")


def accuracy_warnings(level, box_factor, far_field, accuracy, what):
    """``(estimated error, warnings)``: the a-priori error of :func:`estimated_error` and, when it
    exceeds ``accuracy``, one warning (logged too) saying how to refine; ``what`` names the
    solver."""
    err = estimated_error(level, box_factor, far_field)
    if err <= accuracy:
        return err, ()
    msg = (f"{what}: estimated error {err:.2%} exceeds the stated accuracy {accuracy:.2%} "
           f"(level {level}, box_factor {box_factor:g}, far_field {far_field!r}); refine the "
           "mesh (level + 1) or enlarge the box (box_factor x 2).")
    logger.warning(msg)
    return err, (msg,)


def failed_result(cls, exc, **kw):
    """A result of type ``cls`` that reports the FE solution's failure ``exc`` (logged)."""
    logger.warning("FE solution failed: %s", exc)
    return cls(success=False, status="failed", message=f"FE solution failed: {exc}", **kw)
