"""Total potential of a model: the sum of its element families.

:class:`EquilibriumSystem` caches everything that depends only on the model (the element
families of :mod:`simulator.mechanics.families`: bars, rotational springs, contact, elastic
supports, plus any ``extra_families``; the CSR pattern of the free-DOF stiffness; contact
candidates) and evaluates energies, internal forces and the tangent stiffness at a given
displacement and set of spring rest angles.

Two paths compute the same numbers (to rounding):

* the generic path: every family's vectorised kernel, assembled by
  :class:`simulator.mechanics.assembly.FamilyAssembly` (the reference, the path of models with
  more than :data:`DENSE_LIMIT` free DOFs and of models with families the fused kernel does
  not know);
* an accelerator on small models whose families are exactly those of
  :data:`~simulator.mechanics.families.FUSED_FAMILIES`, when the compiled backend is in force
  (numba installed, ``ETORIGAMI_JIT`` not off: :func:`simulator._jit.numba_selected`): one
  call of the fused kernel of :mod:`simulator.mechanics.elements._fused_jit`, which writes the
  tangent straight into a dense matrix. :attr:`SystemValues.tangent` is then that dense
  matrix (Newton solves with it) and :attr:`SystemValues.K` the same values in the cached CSR
  pattern, built on first access, so every consumer of ``K`` sees a CSR matrix whichever path ran.

See docs/theory.md#310-element-families-and-assembly.
"""

from __future__ import annotations

import logging
import weakref
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .assembly import FamilyAssembly, StiffnessPattern, element_dofs
from ..linalg import thresholds
from ..linalg.ladder import solve
from ..linalg.small_solve import SparseCholesky, pattern_of
from ..linalg.thresholds import DENSE_LIMIT
from .contact_search import ContactSearch
from .elements import _fused_jit, _springs_jit
from .families import (FUSED_FAMILIES, BarFamily, Configuration, FamilyValues, SpringFamily,
                       SupportFamily, check_family, model_families)
from ..model.model import Model

__all__ = ["SystemValues", "EquilibriumSystem", "ENERGY_KINDS", "assembled_tangent",
           "equilibrium_system"]

logger = logging.getLogger(__name__)
_all = np.logical_and.reduce            # with axis=None: ndarray.all() without its wrapper

#: Merge contact pairs into the cached stiffness pattern up to this many Hessian entries.
MERGE_LIMIT = 200_000

#: Energy components reported by every evaluation [J] (those of the built-in families; extra
#: families add their own kinds after these).
ENERGY_KINDS = ("crease_bending", "panel_bending", "panel_stretching", "crease_stretching",
                "contact", "elastic_support")


@dataclass(frozen=True, eq=False, init=False)
class SystemValues:
    """Internal energy, force and stiffness at one configuration.

    ``SystemValues(f_int, K, energies, n_contacts=0, to_csr=None, contact_pairs=None)``: ``K``
    is the tangent as assembled, CSR, a dense ndarray (then ``to_csr(K)`` gives its CSR form,
    e.g. :meth:`EquilibriumSystem.to_csr`) or None.

    Attributes
    ----------
    f_int : (n_dof,) internal force = gradient of the internal energy [N]
    K : (n_free, n_free) CSR tangent stiffness on the free DOFs [N/m], or None (property:
        converted from a dense :attr:`tangent` on first access)
    tangent : the tangent as assembled: the CSR ``K`` or a dense (n_free, n_free) ndarray
        (fused kernel, small models), or None
    energies : dict of the components in :data:`ENERGY_KINDS` [J]
    n_contacts : number of active contact pairs (d <= d0)
    contact_pairs : (n_contacts,) int array or None
        The active pairs as indices into ``ContactSearch.static`` (fused kernel only).
    """

    f_int: np.ndarray
    tangent: np.ndarray | sp.csr_matrix | None
    energies: dict
    n_contacts: int
    to_csr: object
    contact_pairs: np.ndarray | None

    def __init__(self, f_int, K, energies, n_contacts=0, to_csr=None, contact_pairs=None):
        if isinstance(K, np.ndarray) and to_csr is None:
            raise ValueError("SystemValues: a dense tangent needs to_csr (e.g. "
                             "EquilibriumSystem.to_csr) to give K as CSR.")
        # frozen: set once, here (one dict update: this runs at every Newton iteration)
        self.__dict__.update(f_int=f_int, tangent=K, energies=energies, n_contacts=n_contacts,
                             to_csr=to_csr, contact_pairs=contact_pairs)

    @cached_property
    def K(self) -> sp.csr_matrix | None:
        if isinstance(self.tangent, np.ndarray):
            return self.to_csr(self.tangent)
        return self.tangent


def assembled_tangent(ev):
    """The tangent as assembled (dense on small models) of a :class:`SystemValues`, else
    ``ev.K`` (systems with the EquilibriumSystem interface may return other objects)."""
    return ev.tangent if isinstance(ev, SystemValues) else ev.K


class EquilibriumSystem:
    """Cached assembly data for one :class:`Model`.

    Parameters
    ----------
    model : Model
    extra_families : sequence of element families, optional
        Families beyond those the model describes (:data:`~.families.FAMILY_BUILDERS`),
        assembled after them (see :mod:`simulator.mechanics.families`). With any, the generic
        path runs (the fused kernel knows only its own families).

    Attributes
    ----------
    families : tuple of the element families, in summation order
    assembly : the :class:`~simulator.mechanics.assembly.FamilyAssembly` of them
    """

    def __init__(self, model: Model, extra_families=()):
        mesh = model.mesh
        self.model = model
        self.n_dof = mesh.n_dof
        self.free_index = model.free_index
        self.free = np.flatnonzero(self.free_index >= 0)
        X = mesh.nodes
        self.size = float(np.max(np.ptp(X, axis=0))) if len(X) else 0.0   # model size [m]
        self.contact = None if model.contact is None else ContactSearch(mesh, model.contact)
        self.max_step = None if model.contact is None else model.contact.max_step
        # Small meshes: all admissible contact pairs join the cached pattern (zero when inactive),
        # which is cheaper than assembling and adding a second sparse matrix per iteration.
        static = None if self.contact is None else self.contact.static_conn
        # Small models: all of them, so that the pattern holds every entry of a dense tangent.
        small = len(self.free) <= DENSE_LIMIT
        self.contact_in_pattern = static is not None and (small or 144 * len(static) <= MERGE_LIMIT)
        extra = [check_family(f, self.n_dof) for f in extra_families]
        self.families = (*model_families(model, self), *extra)
        self.assembly = FamilyAssembly(self.families, self.free_index)
        self._changing = [i for i, f in enumerate(self.families) if f.changing]
        self._alias_builtin_families()
        types = [type(f) for f in self.families]      # the fused kernel's own, once each
        fusable = all(t in FUSED_FAMILIES for t in types) and len(set(types)) == len(types)
        self._fused = self._fused_data() if small and fusable and (
            self.contact is None or self.contact_in_pattern) else None
        n_pairs = 0 if static is None else len(static)
        self._chol = None, np.zeros(n_pairs, bool)     # sparse Cholesky structure, pairs in it

    def _alias_builtin_families(self):
        """The arrays of the built-in families under the names the fused kernel and the
        sparse Cholesky structure read (the first family of each built-in type)."""
        first = {}
        for f in self.families:
            first.setdefault(type(f), f)
        bars, springs, supports = first[BarFamily], first[SpringFamily], first[SupportFamily]
        self.bar_dofs, self.spr_dofs = bars.dofs, springs.dofs
        self.bar_dX, self.bar_L0, self.bar_EA = bars.dX, bars.L0, bars.EA
        self.spr_k = springs.k
        self.bar_kind, self.spr_kind = bars.labels, springs.labels   # 0 crease, 1 panel
        self.bar_is_panel, self.spr_is_panel = bars.labels == 1, springs.labels == 1
        self.elastic_dofs, self.elastic_k = supports.dofs[:, 0], supports.k

    @property
    def n_free(self) -> int:
        """Number of free DOFs."""
        return len(self.free)

    @property
    def pattern(self) -> StiffnessPattern:
        """CSR pattern of the free-DOF tangent (built on first use: the fused path needs it
        only when a SystemValues' ``K`` is asked for)."""
        return self.assembly.pattern

    @property
    def uses_fused(self) -> bool:
        """Whether :meth:`evaluate` runs the fused compiled kernel (small model, compiled
        backend in force, compilation not failed); it then gives a dense ``tangent``."""
        return (self._fused is not None and _springs_jit.compiled_backend()
                and not _fused_jit.broken)

    def to_csr(self, D: np.ndarray) -> sp.csr_matrix:
        """The dense free-DOF tangent ``D`` of the fused kernel as CSR in :attr:`pattern`."""
        return self.pattern.from_dense(D)

    def _fused_data(self) -> tuple:
        """Arguments of the fused kernel that depend only on the model (writeable copies, int64 /
        float64, C-contiguous: its one compiled signature), in its order; the per-call ones are
        filled in by :meth:`_evaluate_fused`."""
        mesh, i8 = self.model.mesh, np.int64

        def c(a, dtype=float):
            return np.array(a, dtype=dtype, order="C")
        if self.contact is None:
            pairs = (np.zeros(0, i8), np.zeros(0, i8), np.zeros(0), np.zeros((0, 3), i8), 0.0)
        else:
            p, t = self.contact.static
            pairs = (c(self.contact.points[p], i8), c(t, i8), c(self.contact.point_d0[p]),
                     c(self.contact.tri, i8), float(self.model.contact.stiffness))
        return (mesh.nodes, (c(mesh.bars, i8), c(self.bar_dX), c(self.bar_L0), c(self.bar_EA),
                 c(self.bar_kind, i8), c(mesh.springs, i8), c(self.spr_k)),
                (c(self.spr_kind, i8), c(self.free_index, i8), c(self.elastic_dofs, i8),
                 c(self.elastic_k)) + pairs)

    def _evaluate_fused(self, u, spring_rest, hessian):
        return self._fused_evaluator(spring_rest)(u, hessian)

    def _fused_evaluator(self, spring_rest):
        """u -> SystemValues by the fused kernel for fixed rest angles (arguments prepared once);
        the numpy path if compilation failed (logged)."""
        kernel = _fused_jit.fused_kernel()
        if kernel is None:
            return lambda u, hessian=True: self._evaluate_numpy(u, spring_rest, hessian)
        nodes, first, rest = self._fused
        spring_rest = np.ascontiguousarray(spring_rest, dtype=float)
        n_dof, n_free, n_pairs, to_csr = self.n_dof, self.n_free, len(rest[4]), self.to_csr
        model_args = (*first, spring_rest, *rest)        # the arguments fixed for this loop
        empty, i8 = np.empty, np.int64

        def evaluate(u, hessian=True):
            u = np.ascontiguousarray(u, dtype=float)
            f, e = empty(n_dof), empty(6)
            K = empty((n_free, n_free) if hessian else (0, 0))
            active = empty(n_pairs, i8)
            n_contacts = kernel(nodes + u, u, *model_args, hessian, f, K, e, active)
            return SystemValues(f, K if hessian else None, dict(zip(ENERGY_KINDS, e.tolist())),
                              n_contacts, to_csr, active[:n_contacts])
        return evaluate

    def evaluator(self, spring_rest: np.ndarray):
        """``evaluate(u, hessian=True)`` with the rest angles fixed: :meth:`evaluate` with less
        overhead per call on the fused path (for Newton's loop)."""
        if self.uses_fused:
            return self._fused_evaluator(spring_rest)
        return lambda u, hessian=True: self._evaluate_numpy(u, spring_rest, hessian)

    def solve_dense_tangent(self, ev: SystemValues, r: np.ndarray):
        """Newton correction for an evaluation with a dense tangent (fused kernel): du
        (n_free,) with ``ev.tangent du = r`` [m], or None if the tangent is singular (see
        :mod:`simulator.linalg.small_solve`).

        From :data:`~simulator.linalg.thresholds.SPARSE_MIN` rows the tangent is factored
        sparsely: the structure of its Cholesky factor is that of the bars, springs, supports
        and the contact pairs active so far (recomputed, rarely, when a pair becomes active
        for the first time); if that factor needs more than a twentieth of dense Cholesky's
        ~n^3/3 multiply-adds, LAPACK's dense routines are faster and solve instead, as they do
        below SPARSE_MIN (the choice is the dense rung of the ladder,
        :func:`~simulator.linalg.ladder.solve`)."""
        if ev.contact_pairs is None or len(self.free) < thresholds.SPARSE_MIN:
            return solve(ev.tangent, r)
        return solve(ev.tangent, r, cholesky=self._cholesky(ev.contact_pairs))

    def _cholesky(self, pairs: np.ndarray) -> SparseCholesky:
        chol, covered = self._chol
        if chol is None or (len(pairs) and not _all(covered[pairs], axis=None)):
            covered = covered.copy()
            covered[pairs] = True
            families = [self.bar_dofs, self.spr_dofs]
            if covered.any():
                families.append(element_dofs(self.contact.static_conn[covered]))
            rows, cols = pattern_of(families, self.free_index, self.elastic_dofs)
            chol = SparseCholesky(rows, cols, self.n_free)
            self._chol = chol, covered
            logger.debug("sparse Cholesky structure for %d contact pairs: %d entries in L, "
                         "%d multiply-adds", covered.sum(), chol.nnz, chol.flops)
        return chol

    def evaluate(self, u: np.ndarray, spring_rest: np.ndarray, hessian: bool = True) -> SystemValues:
        """Energies, internal force and (optionally) free-DOF stiffness.

        Parameters
        ----------
        u : (n_nodes, 3) displacements from the mesh nodes [m]
        spring_rest : (n_springs,) spring rest angles [rad]

        Notes
        -----
        With the fused kernel (:attr:`uses_fused`) ``tangent`` is dense; ``K`` is CSR either way.
        """
        if self.uses_fused:
            return self._evaluate_fused(u, spring_rest, hessian)
        return self._evaluate_numpy(u, spring_rest, hessian)

    def _evaluate_numpy(self, u, spring_rest, hessian=True) -> SystemValues:
        """:meth:`evaluate` by the generic path: every family's kernel, then
        :class:`~simulator.mechanics.assembly.FamilyAssembly` (element Hessians scattered into
        the cached pattern; the path of models outside the fused kernel; bars and springs
        compiled with the "numba" backend, else numpy)."""
        c = Configuration(u, self.model.mesh.nodes + u, spring_rest)
        values = [f.evaluate(c, hessian) for f in self.families]
        a = self.assembly
        n_changing = sum(len(values[i].energy) for i in self._changing)
        return SystemValues(f_int=a.vector(values), K=a.matrix(values) if hessian else None,
                          energies=a.energies(values, ENERGY_KINDS), n_contacts=n_changing)

    def material_stiffness(self, u: np.ndarray) -> sp.csr_matrix:
        """Free-DOF stiffness without stress (geometric) terms and contact [N/m].

        ``sum EA L0 g g^T`` over bars (g = d strain / d x) and ``sum k grad(theta) grad(theta)^T``
        over springs, plus elastic supports, at displacements ``u`` (n_nodes, 3) [m] (each
        family's ``material_hessian``). It is positive semi-definite and annihilates the
        rigid-body velocities of the current configuration, which makes it the matrix of
        stiffness-proportional damping.
        """
        c = Configuration(u, self.model.mesh.nodes + u)
        hess = [f.material_hessian(c) for f in self.families]
        return self.assembly.matrix([None if h is None else FamilyValues(None, None, h)
                                     for h in hess])


_SYSTEMS: "weakref.WeakKeyDictionary[Model, EquilibriumSystem]" = weakref.WeakKeyDictionary()


def equilibrium_system(model: Model) -> EquilibriumSystem:
    """The cached :class:`EquilibriumSystem` of a model (built on first use)."""
    sys = _SYSTEMS.get(model)
    if sys is None:
        sys = _SYSTEMS[model] = EquilibriumSystem(model)
    return sys
