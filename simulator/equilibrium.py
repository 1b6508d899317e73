"""Total potential of a model: bars + rotational springs + contact + elastic supports.

:class:`EquilibriumSystem` caches everything that depends only on the model
(element DOFs, the CSR pattern of the free-DOF stiffness, contact candidates)
and evaluates energies, internal forces and the tangent stiffness at a given
displacement and set of spring rest angles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .assembly import StiffnessPattern, assemble_matrix, assemble_vector, element_dofs
from .contact_search import ContactSearch
from .elements.bars import bar_kernel
from .elements.contact import contact_kernel
from .elements.springs import fold_angle_derivatives, spring_kernel
from .mesh import BarType, SpringKind
from .model import Model, _AXES

__all__ = ["Evaluation", "EquilibriumSystem", "ENERGY_KINDS"]

#: Energy components reported by every evaluation [J].
#: Merge contact pairs into the cached stiffness pattern up to this many Hessian entries.
MERGE_LIMIT = 200_000

ENERGY_KINDS = ("crease_bending", "panel_bending", "panel_stretching", "crease_stretching",
                "contact", "elastic_support")


@dataclass(frozen=True, eq=False)
class Evaluation:
    """Internal energy, force and stiffness at one configuration.

    Attributes
    ----------
    f_int : (n_dof,) internal force = gradient of the internal energy [N]
    K : (n_free, n_free) CSR tangent stiffness on the free DOFs [N/m], or None
    energies : dict of the components in :data:`ENERGY_KINDS` [J]
    n_contacts : number of active contact pairs (d <= d0)
    """

    f_int: np.ndarray
    K: sp.csr_matrix | None
    energies: dict
    n_contacts: int = 0


class EquilibriumSystem:
    """Cached assembly data for one :class:`Model`."""

    def __init__(self, model: Model):
        mesh = model.mesh
        self.model = model
        self.n_dof = mesh.n_dof
        self.free_index = model.free_index
        self.free = np.flatnonzero(self.free_index >= 0)
        X = mesh.nodes
        self.bar_dofs = element_dofs(mesh.bars)
        self.spr_dofs = element_dofs(mesh.springs)
        self.bar_dX = X[mesh.bars[:, 1]] - X[mesh.bars[:, 0]]
        self.bar_L0 = mesh.bar_length
        self.bar_EA = model.properties.bar_axial_stiffness
        self.spr_k = model.properties.spring_stiffness
        self.bar_is_panel = np.isin(mesh.bar_type, (BarType.PANEL_EDGE, BarType.SPOKE))
        self.spr_is_panel = mesh.spring_kind == SpringKind.PANEL
        el = model.supports.elastic
        self.elastic_dofs = np.array([3 * n + _AXES[d] for n, d, _ in el], dtype=int)
        self.elastic_k = np.array([k for _, _, k in el], dtype=float)
        self.contact = None if model.contact is None else ContactSearch(mesh, model.contact)
        self.max_step = None if model.contact is None else model.contact.max_step
        # Small meshes: all admissible contact pairs join the cached pattern (zero when inactive),
        # which is cheaper than assembling and adding a second sparse matrix per iteration.
        static = None if self.contact is None else self.contact.static_conn
        self.contact_in_pattern = static is not None and 144 * len(static) <= MERGE_LIMIT
        families = [self.bar_dofs, self.spr_dofs]
        if self.contact_in_pattern:
            families.append(element_dofs(static))
        self.pattern = StiffnessPattern(families, self.free_index, diagonal=self.elastic_dofs)
        self.bar_kind = self.bar_is_panel.astype(int)        # 0 crease, 1 panel
        self.spr_kind = self.spr_is_panel.astype(int)

    @property
    def n_free(self) -> int:
        return self.pattern.n_free

    def evaluate(self, u: np.ndarray, spring_rest: np.ndarray, hessian: bool = True) -> Evaluation:
        """Energies, internal force and (optionally) free-DOF stiffness.

        Parameters
        ----------
        u : (n_nodes, 3) displacements from the mesh nodes [m]
        spring_rest : (n_springs,) spring rest angles [rad]
        """
        mesh = self.model.mesh
        x = mesh.nodes + u
        du = u[mesh.bars[:, 1]] - u[mesh.bars[:, 0]]
        eb, gb, hb = bar_kernel(self.bar_dX, du, self.bar_L0, self.bar_EA, hessian)
        es, gs, hs = spring_kernel(x[mesh.springs], self.spr_k, spring_rest, hessian)
        f = assemble_vector(self.n_dof, self.bar_dofs, gb) \
            + assemble_vector(self.n_dof, self.spr_dofs, gs)
        u_el = u.ravel()[self.elastic_dofs]
        f[self.elastic_dofs] += self.elastic_k * u_el
        e_bar = np.bincount(self.bar_kind, eb, minlength=2)
        e_spr = np.bincount(self.spr_kind, es, minlength=2)
        energies = {"crease_bending": float(e_spr[0]), "panel_bending": float(e_spr[1]),
                    "panel_stretching": float(e_bar[1]), "crease_stretching": float(e_bar[0]),
                    "contact": 0.0,
                    "elastic_support": float(0.5 * np.sum(self.elastic_k * u_el**2))}
        families = [hb, hs]
        subsets = None
        extra = None
        n_contacts = 0
        if self.contact is not None:
            if self.contact_in_pattern:        # only the active pairs' entries are scattered
                families.append(np.zeros((0, 12, 12)))
                subsets = {2: np.zeros(0, dtype=int)}
            conn, d0, index = self.contact.candidates(x)
            if len(conn):
                ec, gc, hc = contact_kernel(x[conn], d0, self.model.contact.stiffness)
                active = np.flatnonzero(ec > 0)
                n_contacts = len(active)
                if n_contacts:
                    f += assemble_vector(self.n_dof, element_dofs(conn[active]), gc[active])
                    energies["contact"] = float(ec[active].sum())
                    if subsets is not None:
                        families[2], subsets[2] = hc[active], index[active]
                    elif hessian:
                        extra = assemble_matrix(element_dofs(conn[active]), hc[active],
                                                self.free_index, self.n_free)
        K = None
        if hessian:
            K = self.pattern.matrix(families + [self.elastic_k], subsets)
            if extra is not None:
                K = K + extra
        return Evaluation(f_int=f, K=K, energies=energies, n_contacts=n_contacts)

    def material_stiffness(self, u: np.ndarray) -> sp.csr_matrix:
        """Free-DOF stiffness without stress (geometric) terms and contact [N/m].

        ``sum EA L0 g g^T`` over bars (g = d strain / d x) and ``sum k grad(theta) grad(theta)^T``
        over springs, plus elastic supports, at displacements ``u`` (n_nodes, 3) [m]. It is
        positive semi-definite and annihilates the rigid-body velocities of the current
        configuration, which makes it the matrix of stiffness-proportional damping.
        """
        mesh = self.model.mesh
        dx = self.bar_dX + u[mesh.bars[:, 1]] - u[mesh.bars[:, 0]]
        g = np.concatenate([-dx, dx], axis=1) / (self.bar_L0**2)[:, None]
        hb = (self.bar_EA * self.bar_L0)[:, None, None] * (g[:, :, None] * g[:, None, :])
        _, gs, _ = fold_angle_derivatives((mesh.nodes + u)[mesh.springs], hessian=False)
        hs = self.spr_k[:, None, None] * (gs[:, :, None] * gs[:, None, :])
        families, subsets = [hb, hs], None
        if self.contact_in_pattern:
            families.append(np.zeros((0, 12, 12)))
            subsets = {2: np.zeros(0, dtype=int)}
        return self.pattern.matrix(families + [self.elastic_k], subsets)
