"""Element families: the terms of the total potential, each behind one interface.

The equilibrium system (:class:`~simulator.mechanics.equilibrium.EquilibriumSystem`) loops over
a list of element families; one generic assembly
(:class:`~simulator.mechanics.assembly.FamilyAssembly`) turns what they return into the global
internal force (``np.bincount``) and the free-DOF CSR tangent (scattered into a pattern cached
from the families' DOFs). See docs/theory.md#310-element-families-and-assembly.

The protocol (:class:`ElementFamily`) is structural: any object with these attributes is a
family.

``name`` : str
    Short label for messages (``"bars"``).
``dofs`` : (n_el, m) int array or None
    Global DOF ids of every element (node-major ``3 * node + axis`` for node elements, see
    :func:`~simulator.mechanics.assembly.element_dofs`; ``m = 1``: one DOF per element, such
    as a spring to ground, assembled on the diagonal). They fix the cached stiffness pattern.
    A family whose elements change (contact) gives here the superset it may use, or None when
    its pairs are assembled apart from the pattern at every evaluation.
``changing`` : bool
    Whether the active elements change between evaluations (contact). Their count is the
    evaluation's ``n_contacts``.
``energy_kinds`` : tuple of str
    Names of the energy components it contributes (keys of ``SystemValues.energies``).
``labels`` : (n_el,) int array or None
    With more than one kind: the kind of every element (index into ``energy_kinds``).
``evaluate(c, hessian) -> FamilyValues``
    Energy per element [J], gradient (n, m) [N] and Hessian (n, m, m) [N/m] (None without
    ``hessian``) at the :class:`Configuration` ``c``, vectorised over the elements.
``material_hessian(c) -> (n_el, m, m) array or None``
    The Hessian without stress (geometric) terms, for stiffness-proportional damping
    (theory section 8.3); None: the family adds nothing to it (contact).

A new element type is a new family class plus one entry in :data:`FAMILY_BUILDERS` (a
function ``(model, system) -> family or None``), or, for a family not described by the model,
``EquilibriumSystem(model, extra_families=[...])``. The fused compiled kernel of
:mod:`.elements._fused_jit` is an accelerator for the four families below: the system uses it
on small models whose families are exactly of these types (:data:`FUSED_FAMILIES`).
Gravity and other dead loads are not families: they are external forces, constant in the
displacements (zero Hessian), which the solvers scale by the load factor (theory 3.8, 6.5).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar, NamedTuple, Protocol, runtime_checkable

import numpy as np

from ..errors import ParameterError
from ..model.mesh import BarType, SpringKind
from ..model.model import AXES
from .assembly import element_dofs
from .elements import _bars_jit
from .elements.bars import bar_kernel
from .elements.contact import contact_kernel
from .elements.springs import fold_angle_derivatives, spring_kernel

__all__ = ["Configuration", "FamilyValues", "ElementFamily", "BarFamily", "SpringFamily",
           "ContactFamily", "SupportFamily", "FAMILY_BUILDERS", "FUSED_FAMILIES",
           "model_families", "check_family"]


class Configuration(NamedTuple):
    """What a family may read at one evaluation (a named tuple: cheap to make at every
    evaluation).

    Attributes
    ----------
    u : (n_nodes, 3) displacements from the mesh nodes [m]
    x : (n_nodes, 3) current node positions ``mesh.nodes + u`` [m]
    spring_rest : (n_springs,) rest angles of the rotational springs [rad], or None
        (material stiffness)
    """

    u: np.ndarray
    x: np.ndarray
    spring_rest: np.ndarray | None = None


class FamilyValues(NamedTuple):
    """What a family's ``evaluate`` returns for the elements it evaluated (a named tuple).

    Attributes
    ----------
    energy : (n,) energy per element [J]
    grad : (n, m) gradient per element [N]
    hess : (n, m, m) Hessian per element [N/m], or None
    elements : (n,) int array or None
        Which elements of the family's ``dofs`` these are (None: all, in order).
    dofs : (n, m) int array or None
        Their global DOFs when they are not rows of the family's ``dofs`` (contact pairs
        assembled apart from the pattern); None: taken from ``dofs``.
    """

    energy: np.ndarray
    grad: np.ndarray
    hess: np.ndarray | None
    elements: np.ndarray | None = None
    dofs: np.ndarray | None = None


def _nothing(m: int, elements: bool = False, dofs: bool = False) -> FamilyValues:
    """Values of no element of an m-DOF family (empty arrays, shared: nothing to write)."""
    return FamilyValues(np.zeros(0), np.zeros((0, m)), np.zeros((0, m, m)),
                        np.zeros(0, dtype=int) if elements else None,
                        np.zeros((0, m), dtype=int) if dofs else None)


_NO_PAIR, _NO_PAIR_IN_PATTERN, _NO_SUPPORT = _nothing(12, False, True), _nothing(12, True, True), \
    _nothing(1)


@runtime_checkable
class ElementFamily(Protocol):
    """A family of elements of the total potential (see the module docstring)."""

    name: str
    dofs: np.ndarray | None
    changing: bool
    energy_kinds: tuple
    labels: np.ndarray | None

    def evaluate(self, c: Configuration, hessian: bool = True) -> FamilyValues:
        ...

    def material_hessian(self, c: Configuration) -> np.ndarray | None:
        ...


@dataclass(frozen=True, eq=False)
class BarFamily:
    """Bars (theory section 3.2): nodes (n, 2), reference end vectors dX (n, 3) [m], stored
    lengths L0 (n,) [m], axial stiffnesses EA (n,) [N]; labels 0 crease, 1 panel."""

    nodes: np.ndarray
    dofs: np.ndarray
    dX: np.ndarray
    L0: np.ndarray
    EA: np.ndarray
    labels: np.ndarray
    name: ClassVar[str] = "bars"
    changing: ClassVar[bool] = False
    energy_kinds: ClassVar[tuple] = ("crease_stretching", "panel_stretching")

    def evaluate(self, c: Configuration, hessian: bool = True) -> FamilyValues:
        du = c.u[self.nodes[:, 1]] - c.u[self.nodes[:, 0]]
        kernel = _bars_jit.bar_kernel_jit if _bars_jit.use_compiled() else bar_kernel
        return FamilyValues(*kernel(self.dX, du, self.L0, self.EA, hessian))

    def material_hessian(self, c: Configuration) -> np.ndarray:
        """``EA L0 g g^T`` with ``g = d strain / d x``."""
        dx = self.dX + c.u[self.nodes[:, 1]] - c.u[self.nodes[:, 0]]
        g = np.concatenate([-dx, dx], axis=1) / (self.L0**2)[:, None]
        return (self.EA * self.L0)[:, None, None] * (g[:, :, None] * g[:, None, :])


@dataclass(frozen=True, eq=False)
class SpringFamily:
    """Four-node rotational springs (theory section 3.3): nodes (n, 4), stiffnesses k (n,)
    [N m/rad], rest angles from the configuration; labels 0 crease, 1 panel."""

    nodes: np.ndarray
    dofs: np.ndarray
    k: np.ndarray
    labels: np.ndarray
    name: ClassVar[str] = "springs"
    changing: ClassVar[bool] = False
    energy_kinds: ClassVar[tuple] = ("crease_bending", "panel_bending")

    def evaluate(self, c: Configuration, hessian: bool = True) -> FamilyValues:
        return FamilyValues(*spring_kernel(c.x[self.nodes], self.k, c.spring_rest, hessian))

    def material_hessian(self, c: Configuration) -> np.ndarray:
        """``k grad(theta) grad(theta)^T``."""
        _, g, _ = fold_angle_derivatives(c.x[self.nodes], hessian=False)
        return self.k[:, None, None] * (g[:, :, None] * g[:, None, :])


@dataclass(frozen=True, eq=False)
class ContactFamily:
    """Node-to-triangle penalty contact (theory sections 3.5-3.7): the candidates of ``search``
    (a :class:`~simulator.mechanics.contact_search.ContactSearch`) at every evaluation, of which
    the pairs with positive energy are active. ``in_pattern``: all admissible pairs join the
    cached pattern, zero when inactive (small meshes), else they are assembled apart."""

    search: object
    stiffness: float
    in_pattern: bool
    name: ClassVar[str] = "contact"
    changing: ClassVar[bool] = True
    energy_kinds: ClassVar[tuple] = ("contact",)
    labels: ClassVar[None] = None

    @cached_property
    def dofs(self) -> np.ndarray | None:
        """DOFs (m, 12) of all admissible pairs if they join the pattern, else None (made on
        first use: the fused kernel never asks)."""
        return element_dofs(self.search.static_conn) if self.in_pattern else None

    def evaluate(self, c: Configuration, hessian: bool = True) -> FamilyValues:
        conn, d0, index = self.search.candidates(c.x)
        if len(conn):
            ec, gc, hc = contact_kernel(c.x[conn], d0, self.stiffness)
            active = np.flatnonzero(ec > 0)
            if len(active):
                return FamilyValues(ec[active], gc[active], hc[active],
                                    index[active] if self.in_pattern else None,
                                    element_dofs(conn[active]))
        return _NO_PAIR_IN_PATTERN if self.in_pattern else _NO_PAIR

    def material_hessian(self, c: Configuration) -> None:
        return None


@dataclass(frozen=True, eq=False)
class SupportFamily:
    """Elastic supports (theory section 3.9): a spring to ground ``k u_d^2 / 2`` on each DOF
    of ``dofs`` (n, 1), stiffnesses k (n,) [N/m]."""

    dofs: np.ndarray
    k: np.ndarray
    name: ClassVar[str] = "supports"
    changing: ClassVar[bool] = False
    energy_kinds: ClassVar[tuple] = ("elastic_support",)
    labels: ClassVar[None] = None

    def evaluate(self, c: Configuration, hessian: bool = True) -> FamilyValues:
        if not len(self.k):
            return _NO_SUPPORT
        u = c.u.ravel()[self.dofs[:, 0]]
        return FamilyValues(0.5 * self.k * u**2, (self.k * u)[:, None],
                            self.k[:, None, None] if hessian else None)

    def material_hessian(self, c: Configuration) -> np.ndarray:
        return self.k[:, None, None]


def _bars(model, system) -> BarFamily:
    mesh = model.mesh
    X, bars = mesh.nodes, mesh.bars
    panel = np.isin(mesh.bar_type, (BarType.PANEL_EDGE, BarType.SPOKE))
    return BarFamily(bars, element_dofs(bars), X[bars[:, 1]] - X[bars[:, 0]], mesh.bar_length,
                     model.properties.bar_axial_stiffness, panel.astype(int))


def _springs(model, system) -> SpringFamily:
    mesh = model.mesh
    return SpringFamily(mesh.springs, element_dofs(mesh.springs),
                        model.properties.spring_stiffness,
                        (mesh.spring_kind == SpringKind.PANEL).astype(int))


def _contact(model, system) -> ContactFamily | None:
    if system.contact is None:
        return None
    return ContactFamily(system.contact, model.contact.stiffness, system.contact_in_pattern)


def _supports(model, system) -> SupportFamily:
    el = model.supports.elastic
    dofs = np.array([3 * n + AXES[d] for n, d, _ in el], dtype=int)
    return SupportFamily(dofs[:, None], np.array([k for _, _, k in el], dtype=float))


#: The families a model describes, in assembly order: ``(model, system) -> family or None``
#: (``system``: the EquilibriumSystem being built, for its contact search). The order fixes
#: the summation order: forces bars, springs, supports, contact; the tangent the same with
#: the one-DOF families (supports) last, as the fused kernel sums.
FAMILY_BUILDERS = (_bars, _springs, _supports, _contact)

#: The family types the fused compiled kernel evaluates in one call.
FUSED_FAMILIES = (BarFamily, SpringFamily, ContactFamily, SupportFamily)


def model_families(model, system) -> list:
    """The element families of a model (:data:`FAMILY_BUILDERS`, those that exist)."""
    found = (build(model, system) for build in FAMILY_BUILDERS)
    return [f for f in found if f is not None]


_MEMBERS = ("name", "dofs", "changing", "energy_kinds", "labels", "evaluate", "material_hessian")


def check_family(family, n_dof: int):
    """``family`` if it follows :class:`ElementFamily` on a model of ``n_dof`` DOFs, else a
    :class:`~simulator.errors.ParameterError` naming the attribute and the fix."""
    what = f"element family {getattr(family, 'name', type(family).__name__)!r}"
    missing = [a for a in _MEMBERS if not hasattr(family, a)]
    if missing:
        raise ParameterError(f"{what} lacks {', '.join(missing)}: an element family needs "
                             "the attributes of simulator.mechanics.families.ElementFamily.")
    kinds = family.energy_kinds
    if not (isinstance(kinds, tuple) and kinds and all(isinstance(k, str) for k in kinds)):
        raise ParameterError(f"{what}: energy_kinds = {kinds!r}; give a non-empty tuple of "
                             "names, e.g. ('my_energy',).")
    d = family.dofs
    if d is None:
        if not family.changing:
            raise ParameterError(f"{what}: dofs = None is only for changing families; give "
                                 "the (n_el, m) DOF ids of its elements.")
        return family
    if not (isinstance(d, np.ndarray) and d.ndim == 2 and d.dtype.kind in "iu"):
        raise ParameterError(f"{what}: dofs must be an (n_el, m) integer array, got "
                             f"{type(d).__name__} {getattr(d, 'shape', '')}.")
    if d.size and (d.min() < 0 or d.max() >= n_dof):
        raise ParameterError(f"{what}: dofs range over {d.min()}..{d.max()}; DOF ids of this "
                             f"model are 0..{n_dof - 1} (3 * node + axis).")
    if d.shape[1] == 1 and family.changing:
        raise ParameterError(f"{what}: one-DOF elements go on the diagonal of the cached "
                             "pattern and cannot change; make the family static.")
    if len(kinds) > 1 and (family.labels is None or np.shape(family.labels) != (len(d),)):
        raise ParameterError(f"{what}: {len(kinds)} energy kinds need labels of shape "
                             f"({len(d)},), got {np.shape(family.labels)}.")
    return family
