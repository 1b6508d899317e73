"""Element families: a new element type is one new family, assembled by the generic path.

Two toy families (a two-node axial spring and a three-point spring) are registered with
``EquilibriumSystem(model, extra_families=...)``; their kernels and the whole system's forces
and tangent through the generic assembly are checked against finite differences with the
shared harness (tests/fd_harness.py); the built-in families keep their numbers; the fused
kernel is chosen only when its own families alone are present; a malformed family is refused
with a message naming the attribute.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from fd_harness import check_kernel
from simulator import _jit
from simulator.errors import ParameterError
from simulator.geometry.example_patterns import miura_sheet_pattern
from simulator.mechanics.assembly import assemble_matrix, assemble_vector, element_dofs
from simulator.mechanics.equilibrium import ENERGY_KINDS, EquilibriumSystem
from simulator.mechanics.families import (BarFamily, Configuration, ContactFamily,
                                          ElementFamily, FamilyValues, SpringFamily, SupportFamily,
                                          check_family)
from simulator.model.model import ContactParameters, Supports, make_model
from simulator.solvers.newton import newton
from simulator.steps import initial_state


def axial_spring(x, k, L0):
    """Energy, gradient (n, 6), Hessian (n, 6, 6) of ``k (|x_b - x_a| - L0)^2 / 2``."""
    d = x[:, 1] - x[:, 0]
    L = np.linalg.norm(d, axis=1)
    n = d / L[:, None]
    s = k * (L - L0)
    g = np.concatenate([-n, n], axis=1)
    nn = n[:, :, None] * n[:, None, :]
    H = k[:, None, None] * nn + (s / L)[:, None, None] * (np.eye(3) - nn)
    return 0.5 * s * (L - L0), s[:, None] * g, np.block([[H, -H], [-H, H]])


def three_point_spring(x, k):
    """Energy, gradient (n, 9), Hessian (n, 9, 9) of ``k |x_a - 2 x_b + x_c|^2 / 2``."""
    c = np.array([1.0, -2.0, 1.0])
    w = np.einsum("a,nai->ni", c, x)
    grad = k[:, None] * (c[None, :, None] * w[:, None, :]).reshape(len(x), 9)
    hess = k[:, None, None] * np.kron(np.outer(c, c), np.eye(3))[None]
    return 0.5 * k * np.einsum("ni,ni->n", w, w), grad, hess


@dataclass(frozen=True, eq=False)
class AxialSprings:
    """Toy family: linear springs between node pairs (n, 2), stiffness k (n,) [N/m]."""

    nodes: np.ndarray
    k: np.ndarray
    L0: np.ndarray
    name: ClassVar[str] = "axial springs"
    changing: ClassVar[bool] = False
    energy_kinds: ClassVar[tuple] = ("axial_springs",)
    labels: ClassVar[None] = None

    @property
    def dofs(self):
        return element_dofs(self.nodes)

    def evaluate(self, c, hessian=True):
        e, g, h = axial_spring(c.x[self.nodes], self.k, self.L0)
        return FamilyValues(e, g, h if hessian else None)

    def material_hessian(self, c):
        return axial_spring(c.x[self.nodes], self.k, self.L0)[2]


@dataclass(frozen=True, eq=False)
class ThreePointSprings:
    """Toy family: ``k |x_a - 2 x_b + x_c|^2 / 2`` on node triples (n, 3), split into two
    energy kinds by ``labels``."""

    nodes: np.ndarray
    k: np.ndarray
    labels: np.ndarray
    name: ClassVar[str] = "three-point springs"
    changing: ClassVar[bool] = False
    energy_kinds: ClassVar[tuple] = ("three_point_a", "three_point_b")

    @property
    def dofs(self):
        return element_dofs(self.nodes)

    def evaluate(self, c, hessian=True):
        e, g, h = three_point_spring(c.x[self.nodes], self.k)
        return FamilyValues(e, g, h if hessian else None)

    def material_hessian(self, c):
        return None


def _toys(mesh, rng, scale=1.0):
    """An axial-spring and a three-point-spring family on a few node sets; stiffness ~scale."""
    n = mesh.n_nodes
    pairs = np.array([[0, n - 1], [3, n // 2], [5, 7]])
    X = mesh.nodes
    L0 = np.linalg.norm(X[pairs[:, 1]] - X[pairs[:, 0]], axis=1) * np.array([0.9, 1.1, 1.0])
    axial = AxialSprings(pairs, scale * rng.uniform(1.0, 3.0, 3), L0)
    triples = np.array([[1, 2, 4], [n - 3, n - 2, n - 1], [0, n // 3, 2 * n // 3]])
    three = ThreePointSprings(triples, scale * rng.uniform(0.5, 2.0, 3), np.array([0, 1, 1]))
    return axial, three


def _sheet(supports=None):
    mesh = make_model(miura_sheet_pattern(m=2, n=2)).mesh
    return make_model(mesh, supports(mesh) if supports else None)


def test_toy_kernels_match_finite_differences():
    rng = np.random.default_rng(0)
    stiff = rng.uniform(1.0, 2.0, 5)
    x2, x3 = rng.normal(size=(5, 2, 3)) * 1e-3, rng.normal(size=(5, 3, 3)) * 1e-3
    L0 = 0.8 * np.linalg.norm(x2[:, 1] - x2[:, 0], axis=1)     # stretched springs
    check_kernel(lambda y: axial_spring(y, stiff, L0), x2)
    check_kernel(lambda y: three_point_spring(y, stiff), x3)


def test_the_toy_families_are_element_families():
    model = _sheet()
    for toy in _toys(model.mesh, np.random.default_rng(1)):
        assert isinstance(toy, ElementFamily) and check_family(toy, model.mesh.n_dof) is toy


def test_registered_toy_families_give_fd_exact_forces_and_tangent():
    """The whole system (bars, springs, toys; no supports, so every DOF is free) as one
    element of the harness: energy, f_int and the CSR tangent of the generic path. The toys
    are as stiff as the stiffest built-in entry, so that an error in them shows."""
    model = _sheet()
    mesh = model.mesh
    rng = np.random.default_rng(2)
    rest = initial_state(model).spring_rest + 0.05
    stiffest = abs(EquilibriumSystem(model).evaluate(0 * mesh.nodes, rest).K).max()
    system = EquilibriumSystem(model, extra_families=_toys(mesh, rng, stiffest))
    assert [f.name for f in system.families][-2:] == ["axial springs", "three-point springs"]
    assert not system.uses_fused and system.n_free == mesh.n_dof

    def whole(x):
        ev = system.evaluate(x[0] - mesh.nodes, rest)
        return (np.array([sum(ev.energies.values())]), ev.f_int[None],
                ev.K.toarray()[None])
    x = (mesh.nodes + rng.normal(size=mesh.nodes.shape) * 1e-6)[None]
    errs = check_kernel(whole, x)
    assert errs["gradient"] < 1e-6 and errs["hessian"] < 1e-6
    ev = system.evaluate(x[0] - mesh.nodes, rest)
    assert list(ev.energies)[:len(ENERGY_KINDS)] == list(ENERGY_KINDS)
    assert {"axial_springs", "three_point_a", "three_point_b"} <= set(ev.energies)
    assert ev.energies["axial_springs"] > 0 and ev.energies["three_point_b"] > 0


def test_toy_families_add_their_own_terms_to_the_built_in_ones():
    """With supports (fixed and elastic): f_int, K and the material stiffness of the system
    with toys are those without plus the toys' own assembly; the built-ins are unchanged."""
    model = _sheet(lambda mesh: Supports({0: "xyz", 1: "xyz", 2: "z"},
                                         elastic=((5, "x", 3.0), (9, "y", 2.0))))
    mesh = model.mesh
    rng = np.random.default_rng(4)
    toys = _toys(mesh, rng)
    plain, with_toys = EquilibriumSystem(model), EquilibriumSystem(model, extra_families=toys)
    u = rng.normal(size=mesh.nodes.shape) * 1e-6
    u[[0, 1]] = 0
    rest = initial_state(model).spring_rest + 0.02
    base, ev = plain.evaluate(u, rest), with_toys.evaluate(u, rest)
    c = Configuration(u, mesh.nodes + u, rest)
    f, K, M = base.f_int.copy(), base.K.copy(), plain.material_stiffness(u)
    for toy in toys:
        v = toy.evaluate(c)
        assert v.energy.sum() > 0
        f += assemble_vector(mesh.n_dof, toy.dofs, v.grad)
        K = K + assemble_matrix(toy.dofs, v.hess, model.free_index, plain.n_free)
        if toy.material_hessian(c) is not None:                # the axial springs only
            M = M + assemble_matrix(toy.dofs, v.hess, model.free_index, plain.n_free)
    scale = np.abs(base.f_int).max()
    np.testing.assert_allclose(ev.f_int, f, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(ev.K.toarray(), K.toarray(), rtol=0,
                               atol=1e-12 * abs(K).max())
    np.testing.assert_allclose(with_toys.material_stiffness(u).toarray(), M.toarray(), rtol=0,
                               atol=1e-12 * abs(M).max())
    for kind in ENERGY_KINDS:
        assert ev.energies[kind] == pytest.approx(base.energies[kind], rel=1e-12)
    assert ev.energies["elastic_support"] > 0


def test_newton_solves_with_a_registered_family():
    """A toy spring shortening the distance between two corners: Newton converges through
    the generic path and the toy's force is balanced by the sheet."""
    model = _sheet(lambda mesh: Supports.nodes(mesh.panel_nodes(0)))
    mesh = model.mesh
    n = mesh.n_nodes
    pair = np.array([[int(mesh.panel_nodes(0)[0]), n - 1]])
    X = mesh.nodes
    L = np.linalg.norm(X[n - 1] - X[pair[0, 0]])
    toy = AxialSprings(pair, np.array([1e-3]), np.array([0.98 * L]))
    system = EquilibriumSystem(model, extra_families=[toy])
    rest = initial_state(model).spring_rest
    r0 = np.linalg.norm(system.evaluate(np.zeros_like(X), rest).f_int[system.free])
    assert r0 > 0                                      # the toy pulls at the start
    res = newton(system, np.zeros_like(X), np.zeros(mesh.n_dof), rest)
    assert res.success, res.message
    ev = system.evaluate(res.u.reshape(-1, 3), rest)
    assert np.linalg.norm(ev.f_int[system.free]) < 1e-6 * r0
    assert np.linalg.norm(res.u.reshape(-1, 3)[n - 1]) > 0
    assert ev.energies["axial_springs"] > 0


@pytest.mark.skipif(not _jit.AVAILABLE, reason="numba not installed")
def test_the_fused_kernel_is_chosen_only_for_its_own_families():
    model = make_model(miura_sheet_pattern(m=2, n=2), None,
                       contact=ContactParameters(2e-5, 300e-6, 250e-6))
    system = EquilibriumSystem(model)
    assert [type(f) for f in system.families] == [BarFamily, SpringFamily, SupportFamily,
                                                  ContactFamily]
    assert system.uses_fused
    assert all(check_family(f, model.mesh.n_dof) is f for f in system.families)
    toy = _toys(model.mesh, np.random.default_rng(0))[0]
    assert not EquilibriumSystem(model, extra_families=[toy]).uses_fused
    twice = EquilibriumSystem(model, extra_families=[system.families[2]])   # supports twice
    assert not twice.uses_fused


def test_malformed_families_are_refused_with_the_attribute_named():
    model = _sheet()
    n_dof = model.mesh.n_dof
    axial, three = _toys(model.mesh, np.random.default_rng(0))
    with pytest.raises(ParameterError, match="lacks .*material_hessian"):
        check_family(object(), n_dof)
    bad = AxialSprings(np.array([[0, n_dof]]), np.ones(1), np.ones(1))
    with pytest.raises(ParameterError, match="dofs range over .* DOF ids of this model"):
        EquilibriumSystem(model, extra_families=[bad])
    no_labels = ThreePointSprings(three.nodes, three.k, None)
    with pytest.raises(ParameterError, match="2 energy kinds need labels of shape"):
        check_family(no_labels, n_dof)

    @dataclass(frozen=True, eq=False)
    class Unnamed(AxialSprings):
        energy_kinds: ClassVar[tuple] = ()
    with pytest.raises(ParameterError, match="energy_kinds = \\(\\)"):
        check_family(Unnamed(axial.nodes, axial.k, axial.L0), n_dof)


def test_built_in_families_sum_in_the_order_of_the_fused_kernel():
    """f = (bars + springs) + supports + contact and K over bars, springs, contact, supports,
    written out by hand: the generic path gives these floats bit for bit (elastic supports on
    every free DOF and many active contact pairs, so that the order shows)."""
    contact = ContactParameters(2e-5, 300e-6, 250e-6)
    mesh = make_model(miura_sheet_pattern(m=2, n=2), None, contact=contact).mesh
    panel0 = mesh.panel_nodes(0)
    elastic = [(n, a, 5.0 + n) for n in range(mesh.n_nodes) if n not in panel0 for a in "xyz"]
    model = make_model(mesh, Supports({int(n): "xyz" for n in panel0}, elastic=elastic),
                       contact=contact)
    system = EquilibriumSystem(model)
    X = mesh.nodes
    rng = np.random.default_rng(1)
    u = rng.normal(size=X.shape) * 1e-4
    u[:, 0] -= 0.67 * (X[:, 0] - X[:, 0].min())
    u[panel0] = 0
    rest = initial_state(model).spring_rest + 0.3
    ev = system._evaluate_numpy(u, rest)
    c = Configuration(u, X + u, rest)
    by_type = {type(f): f for f in system.families}
    bars, springs = by_type[BarFamily], by_type[SpringFamily]
    vb, vs, vc = (by_type[t].evaluate(c) for t in (BarFamily, SpringFamily, ContactFamily))
    assert len(vc.energy) >= 3                      # active pairs
    f = assemble_vector(mesh.n_dof, bars.dofs, vb.grad) \
        + assemble_vector(mesh.n_dof, springs.dofs, vs.grad)
    f[system.elastic_dofs] += system.elastic_k * u.ravel()[system.elastic_dofs]
    f += assemble_vector(mesh.n_dof, vc.dofs, vc.grad)
    np.testing.assert_array_equal(ev.f_int, f)
    K = system.pattern.matrix([vb.hess, vs.hess, vc.hess, system.elastic_k], {2: vc.elements})
    np.testing.assert_array_equal(ev.K.data, K.data)
    assert ev.energies["contact"] == vc.energy.sum() and ev.n_contacts == len(vc.energy)


def test_the_compiled_scatter_takes_the_generic_path_values(monkeypatch):
    """Large patterns sum with the compiled loop (numba backend): the values of every family,
    empty ones included (no elastic supports, no active contact), give the numpy sums."""
    from simulator.mechanics import assembly
    model = _sheet(lambda mesh: Supports.nodes(mesh.panel_nodes(0)))
    system = EquilibriumSystem(model, extra_families=_toys(model.mesh, np.random.default_rng(6)))
    u = np.random.default_rng(7).normal(size=model.mesh.nodes.shape) * 1e-6
    rest = initial_state(model).spring_rest
    ref = system.evaluate(u, rest).K
    monkeypatch.setattr(assembly, "JIT_ENTRIES", 0)
    K = system.evaluate(u, rest).K
    np.testing.assert_array_equal(K.data, ref.data)
