"""Lumped nodal masses and areas of a bar-and-hinge mesh (theory 7.1).

Every triangle of the mesh carries the mass ``rho t A`` of the sheet it covers, with ``A`` its
area in the reference (undeformed) configuration:

* a panel fan triangle (centre, corner_j, corner_j+1) of a panel of density ``rho_p`` and
  thickness ``t_p`` gives 2/3 of its mass to the panel centre and 1/6 to each corner, so a
  quadrilateral panel of mass m_P puts 2/3 m_P on its centre node and m_P / 12 on every corner;
* a crease triangle of a crease of thickness ``t_c`` (crease material density ``rho_c``) gives
  1/3 of its mass to each of its vertices.

Panel and crease masses are conserved exactly. There is no rotational inertia: the mass matrix
is ``diag(m_1, m_1, m_1, m_2, ...)``. (The reference sends the 2/3 share of one fan triangle to a
corner by an index slip, theory 7.1; this port does not.)
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .mesh import BarHingeMesh

__all__ = ["lumped_masses", "lumped_areas", "check_masses"]

#: Share of a fan triangle's mass given to the panel centre (the rest goes half to each corner).
CENTRE_SHARE = 2.0 / 3.0


def _triangle_areas(mesh: BarHingeMesh) -> np.ndarray:
    """Reference areas of all triangles [m^2], shape (nt,)."""
    x = mesh.nodes[mesh.triangles]
    return 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)


def _lump(mesh: BarHingeMesh, panel_weight: np.ndarray, crease_weight: np.ndarray) -> np.ndarray:
    """Lump ``weight * area`` of every triangle onto its nodes by the rule of theory 7.1.

    ``panel_weight`` (P,) and ``crease_weight`` (C,) are per-area weights of the panels and
    creases (e.g. rho t in kg/m^2); returns (n_nodes,).
    """
    area = _triangle_areas(mesh)
    tri = mesh.triangles
    is_fan = mesh.triangle_panel >= 0
    w = np.where(is_fan, panel_weight[np.maximum(mesh.triangle_panel, 0)],
                 crease_weight[np.maximum(mesh.triangle_crease, 0)]) * area
    # fan triangles are (centre, corner_j, corner_j+1) as built by make_mesh; a
    # concentrated-hinge mesh (theory 2.6) gives the share of every triangle's nodes itself
    share = mesh.mass_shares if getattr(mesh, "sharp", False) else \
        np.where(is_fan[:, None], [CENTRE_SHARE, (1 - CENTRE_SHARE) / 2,
                                   (1 - CENTRE_SHARE) / 2], 1.0 / 3.0)
    return np.bincount(tri.ravel(), (w[:, None] * share).ravel(), minlength=mesh.n_nodes)


def lumped_masses(mesh: BarHingeMesh) -> np.ndarray:
    """Nodal masses [kg], shape (n_nodes,), from panel and crease volumes and densities.

    Panel mass density is ``panel_material[p].density * panel_thickness[p]`` per unit area; crease
    mass density ``crease_material.density * crease_thickness[c]``. Materials with zero density
    contribute nothing (see :func:`check_masses`).
    """
    pat = mesh.pattern
    rho_p = np.array([m.density for m in pat.panel_material], float)
    panel = rho_p * pat.panel_thickness
    crease = pat.crease_material.density * pat.crease_thickness[mesh.crease_ids]
    return _lump(mesh, panel, crease)


def lumped_areas(mesh: BarHingeMesh) -> np.ndarray:
    """Sheet area attributed to every node [m^2], shape (n_nodes,), lumped like the masses.

    Used for area-proportional (air) damping; the areas sum to the total area of panels and
    creases.
    """
    return _lump(mesh, np.ones(mesh.pattern.n_panels), np.ones(mesh.n_creases))


def check_masses(model, masses: np.ndarray) -> None:
    """Raise :class:`ParameterError` if a node with a free DOF has no mass.

    A massless free node makes the mass matrix singular; the message names the materials whose
    density is zero (``Material.density`` defaults to 0) and how to fix it.
    """
    free_node = ~model.fixed_mask.all(axis=1)
    bad = np.flatnonzero(free_node & ~(masses > 0))
    if not len(bad):
        return
    pat = model.mesh.pattern
    massless = sorted({m.name for m in (*pat.panel_material, pat.crease_material)
                       if not m.density > 0})
    what = (f"material(s) {', '.join(repr(n) for n in massless)} have density 0"
            if massless else "its panels and creases have no mass")
    raise ParameterError(
        f"Dynamics needs a mass at every free node, but node {int(bad[0])} (and {len(bad) - 1} "
        f"more) has none: {what}. Give every panel and crease material a positive density in "
        "kg/m^3, e.g. Material('SU-8', youngs_modulus=2e9, density=1200.0), or fix those nodes.")
