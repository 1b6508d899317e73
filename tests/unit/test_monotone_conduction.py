"""Monotone sheet conduction (simulator.thermal.monotone, theory 4.2): the flip routine, the
M-matrix property on the devices' meshes, linear precision and the conduction setting."""

import dataclasses

import numpy as np
import pytest
from scipy.spatial import Delaunay

from simulator import ChainLoss
from simulator.errors import ParameterError
from simulator.geometry.example_patterns import crane_pattern, strip_pattern
from simulator.geometry.materials import Material
from simulator.model.mesh import make_mesh
from simulator.thermal.monotone import (corner_cotangents, delaunay_flips, monotone_conduction,
                                        t3_matrices)
from simulator.thermal import ThermalModel, ThermalParameters


def _edge_weights(x, tri, kt):
    """``{edge: sum k t cot / 2}`` of a triangulation (minus the assembled coupling)."""
    cot = corner_cotangents(np.asarray(x)[tri])
    out = {}
    for t, corners in enumerate(tri):
        for c in range(3):
            i, j = sorted((corners[(c + 1) % 3], corners[(c + 2) % 3]))
            out[(i, j)] = out.get((i, j), 0.0) + kt[t] * cot[t, c] / 2
    return out


def _assembled(families, values, n):
    A = np.zeros((n, n))
    for nodes, v in zip(families, values):
        k = nodes.shape[1]
        np.add.at(A, (np.repeat(nodes, k, axis=1).ravel(), np.tile(nodes, (1, k)).ravel()),
                  np.ravel(v))
    return A


#: the chains (no operator to build) with the monotone conduction
_CHAIN_MONOTONE = ThermalParameters(loss=ChainLoss(thickness=1e-3), conduction="monotone")


def _region(mesh):
    return np.where(mesh.triangle_panel >= 0, mesh.triangle_panel, -1 - mesh.triangle_crease)


# ---------------------------------------------------------------- the flip routine
def _obtuse_pair(height=0.3):
    """Two planar triangles on the edge (0, 1) with obtuse angles opposite it (146 deg each
    at height 0.3): the pair is not Delaunay."""
    x = np.array([[0, 0, 0], [2, 0, 0], [1, height, 0], [1, -height, 0]], float)
    return x, np.array([[0, 1, 2], [1, 0, 3]])


def test_a_planar_obtuse_pair_is_flipped_to_non_negative_weights():
    x, tri = _obtuse_pair()
    before = _edge_weights(x, tri, np.ones(2))
    assert before[(0, 1)] < 0                                   # a positive coupling
    out = delaunay_flips(x, tri, np.zeros(2))
    edges = {tuple(sorted((t[i], t[(i + 1) % 3]))) for t in out for i in range(3)}
    assert (2, 3) in edges and (0, 1) not in edges
    after = _edge_weights(x, out, np.ones(2))
    assert after[(2, 3)] > 0 and min(after.values()) >= 0
    area = 0.5 * np.linalg.norm(np.cross(x[out[:, 1]] - x[out[:, 0]], x[out[:, 2]] - x[out[:, 0]]),
                                axis=1)
    assert area.sum() == pytest.approx(2 * 0.5 * 2 * 0.3)       # the same quad


def test_a_pair_of_two_regions_is_not_flipped():
    x, tri = _obtuse_pair()
    np.testing.assert_array_equal(delaunay_flips(x, tri, np.array([0, 1])), tri)


def test_flips_give_the_delaunay_triangulation_of_a_region():
    rng = np.random.default_rng(3)
    pts = np.vstack([[0, 0], [1, 0], [1, 1], [0, 1], rng.random((20, 2))])
    fan = Delaunay(pts).simplices                         # any triangulation: spoil it by flips
    x = np.c_[pts, np.zeros(len(pts))]
    spoiled = _spoil(x, fan)
    assert min(_edge_weights(x, spoiled, np.ones(len(spoiled))).values()) < 0
    out = delaunay_flips(x, spoiled, np.zeros(len(spoiled)))
    w = _edge_weights(x, out, np.ones(len(out)))
    inner = {e for e, v in w.items() if sum(e in _edges(t) for t in out) == 2}
    assert min(w[e] for e in inner) >= -1e-12
    assert {e for t in out for e in _edges(t)} == {e for t in fan for e in _edges(t)}


def _edges(t):
    return {tuple(sorted((t[i], t[(i + 1) % 3]))) for i in range(3)}


def _spoil(x, tri):
    """Flip every inner edge whose flip is valid once (a non-Delaunay triangulation)."""
    tri = [list(t) for t in tri]
    for _ in range(3 * len(tri)):
        owner = {}
        for t, c in enumerate(tri):
            for i in range(3):
                owner.setdefault(tuple(sorted((c[(i + 1) % 3], c[(i + 2) % 3]))), []).append((t, i))
        for (a, b), sides in owner.items():
            if len(sides) != 2:
                continue
            (t1, c1), (t2, c2) = sides
            k, m = tri[t1][c1], tri[t2][c2]
            p, q = tri[t1][(c1 + 1) % 3], tri[t1][(c1 + 2) % 3]
            new = [[k, p, m], [k, m, q]]
            cross = [np.cross(x[n[1]] - x[n[0]], x[n[2]] - x[n[0]])[2] for n in new]
            w = _edge_weights(x, np.array([tri[t1], tri[t2]]), np.ones(2))[(a, b)]
            if min(cross) > 1e-9 and w > 0:          # a Delaunay edge: flip it away
                tri[t1], tri[t2] = new
                break
        else:
            break
    return np.array(tri)


# ---------------------------------------------------------------- M-matrix on the devices
def _device_meshes():
    from design.devices.gripper import GripperDesign, GripperHeatModel, make_gripper_model
    from simulator.cases import get_case

    crane = get_case("crane").model
    gripper, _ = make_gripper_model(GripperDesign(),                 # the chains: T3
                                    heat=GripperHeatModel(loss_model="chain"))
    double = get_case("double_fold").model
    return {"crane": crane, "gripper": gripper, "double_fold": double}


@pytest.fixture(scope="module")
def devices():
    return _device_meshes()


@pytest.mark.parametrize("name, t3_positive", [("crane", 42), ("gripper", 14),
                                               ("double_fold", 7)])
def test_monotone_conduction_is_an_m_matrix_where_t3_is_not(devices, name, t3_positive):
    model = devices[name]
    mesh, x = model.mesh, model.mesh.nodes
    t3 = ThermalModel(mesh, dataclasses.replace(model.thermal, conduction="t3"))
    mono = ThermalModel(mesh, dataclasses.replace(model.thermal, conduction="monotone"))
    A0 = t3.sheet_conduction(x).toarray()
    A = mono.sheet_conduction(x).toarray()
    scale = np.abs(A0).max()
    off0, off = A0 - np.diag(np.diag(A0)), A - np.diag(np.diag(A))
    assert int((np.triu(off0) > 1e-12 * scale).sum()) == t3_positive     # the T3's couplings
    assert off.max() <= 1e-12 * scale                                     # none left
    np.testing.assert_allclose(A, A.T, atol=1e-14 * scale)
    np.testing.assert_allclose(A.sum(axis=1), 0.0, atol=1e-12 * scale)
    assert np.all(np.diag(A) > 0)
    # the region boundaries are where they were: every Steiner point is on a mesh edge
    mc = mono.monotone
    assert mc.n_steiner > 0 and np.all((mc.steiner[:, 2] > 0) & (mc.steiner[:, 2] < 1))


def test_monotone_conduction_follows_the_shape(devices):
    """At a shape other than the mesh's (a rigid rotation and a small stretch) the same
    triangulation is built from the current positions: a rotation changes nothing."""
    mesh = devices["gripper"].mesh
    mc = monotone_conduction(mesh.nodes, mesh.triangles, _region(mesh),
                             ThermalModel(mesh, _CHAIN_MONOTONE).conduction.kt)
    c, s = np.cos(0.7), np.sin(0.7)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    a = _assembled(mc.families, mc.element_values(mesh.nodes), mesh.n_nodes)
    b = _assembled(mc.families, mc.element_values(mesh.nodes @ R.T + 1e-3), mesh.n_nodes)
    np.testing.assert_allclose(b, a, atol=1e-12 * np.abs(a).max())


@pytest.mark.parametrize("name", ["crane", "gripper", "double_fold"])
def test_compiled_triangle_matrices_are_numpys(devices, name):
    """The compiled T3 matrices of the monotone triangulation (Steiner points included) are
    numpy's (:func:`t3_matrices`) to round-off, at a shape other than the mesh's."""
    from simulator.mechanics.elements import _springs_jit

    if not _springs_jit.compiled_backend():
        pytest.skip("numba backend not selected")
    mesh = devices[name].mesh
    mc = monotone_conduction(mesh.nodes, mesh.triangles, _region(mesh),
                             ThermalModel(mesh, _CHAIN_MONOTONE).conduction.kt)
    x = mesh.nodes + np.random.default_rng(2).normal(0, 1e-5, mesh.nodes.shape)
    a = mc.triangle_matrices(x, compiled=False)
    b = mc.triangle_matrices(x, compiled=True)
    assert mc.n_steiner > 0 and a.shape == b.shape
    np.testing.assert_allclose(b, a, rtol=0, atol=1e-14 * np.abs(a).max())


# ---------------------------------------------------------------- linear precision
def _uniform_strip():
    """The verification strip (crease triangles of 136 deg at the crease centre against square
    panels' 90 deg fans: a positive coupling on both crease edges) of one material and
    thickness: uniform k t."""
    mat = Material("k", youngs_modulus=2e9, thermal_conductivity=1.0)
    return make_mesh(strip_pattern(W=0.4, L=1.0, L1=1.0, L2=1.0, crease_thickness=0.01,
                                    panel_thickness=0.01, material=mat))


def test_linear_fields_are_reproduced_exactly_on_a_planar_sheet():
    mesh = _uniform_strip()
    tm = ThermalModel(mesh, _CHAIN_MONOTONE)
    x = mesh.nodes
    assert tm.monotone.n_steiner >= 2                    # the two crease edges were split
    A = tm.sheet_conduction(x).toarray()
    assert (A - np.diag(np.diag(A))).max() <= 1e-12 * np.abs(A).max()
    tri = mesh.triangles
    edges = {}
    for t in tri:
        for e in _edges(t):
            edges[e] = edges.get(e, 0) + 1
    outline = np.unique([v for e, k in edges.items() if k == 1 for v in e])
    inner = np.setdiff1d(np.arange(mesh.n_nodes), outline)
    assert len(inner) >= 3                               # the panel centres and Ctr
    for grad in ([1.0, 0.0, 0.0], [0.3, -2.0, 0.0]):
        u = x @ np.array(grad) + 0.5                      # a linear field
        # held at its values on the outline, the rest solves K u = 0 exactly
        free = inner
        sol = np.linalg.solve(A[np.ix_(free, free)], -A[np.ix_(free, outline)] @ u[outline])
        np.testing.assert_allclose(sol, u[free], rtol=1e-12, atol=1e-12)
        # and the condensed conduction gives the T3's flux on the outline nodes' rows too
        A0 = _assembled([tri], [t3_matrices(x[tri], tm.conduction.kt)], mesh.n_nodes)
        np.testing.assert_allclose((A @ u)[inner], 0.0, atol=1e-12 * np.abs(A0 @ u).max())


def test_sparse_assembly_of_the_condensed_groups_is_the_dense_one(devices):
    """The condensed groups are padded (a repeated node with zero entries): the sparse
    patterns of the free-node and full systems assemble them as the dense sum does."""
    model = devices["crane"]
    tm = ThermalModel(model.mesh, _CHAIN_MONOTONE)
    x, n = model.mesh.nodes, model.mesh.n_nodes
    values = tm.conduction.element_values(x, tm.conduction.t3(x)[0])
    dense = tm.sheet_conduction(x).toarray()
    free = tm._free_pattern.matrix([*values, np.zeros(len(tm.free_nodes))]).toarray()
    full = tm._full_pattern.matrix([*values, np.zeros((n * tm.chains.layers, 2, 2))])
    scale = np.abs(dense).max()
    np.testing.assert_allclose(free, dense[np.ix_(tm.free_nodes, tm.free_nodes)], rtol=0,
                               atol=1e-14 * scale)
    np.testing.assert_allclose(full.toarray()[:n, :n], dense, rtol=0, atol=1e-14 * scale)


def test_constant_fields_carry_no_heat(devices):
    model = devices["crane"]
    tm = ThermalModel(model.mesh, _CHAIN_MONOTONE)
    A = tm.sheet_conduction(model.mesh.nodes)
    assert np.abs(A @ np.ones(model.mesh.n_nodes)).max() <= 1e-12 * abs(A).max()


# ---------------------------------------------------------------- the setting
def test_conduction_setting_defaults_and_round_trip():
    chain = ThermalParameters(loss=ChainLoss(thickness=1e-3))
    assert chain.conduction is None and chain.conduction_method == "t3"       # the paper's
    assert ThermalParameters().conduction_method == "monotone"                # integral loss
    assert ThermalParameters(conduction="t3").conduction_method == "t3"
    given = ThermalParameters(loss=ChainLoss(thickness=1e-3), conduction="monotone")
    assert given.conduction_method == "monotone"
    assert ThermalParameters(**given.to_dict()) == given
    assert ThermalParameters(**chain.to_dict()).conduction is None


def test_bad_conduction_setting():
    with pytest.raises(ParameterError, match="conduction.*'t3', 'monotone'"):
        ThermalParameters(conduction="delaunay")


def test_t3_setting_keeps_the_triangles_matrices(devices):
    model = devices["gripper"]
    tm = ThermalModel(model.mesh, model.thermal)                 # the chains: T3
    assert tm.monotone is None
    x = model.mesh.nodes
    K = tm.structure_conductances(x)[0]
    A = _assembled([model.mesh.triangles], [K], model.mesh.n_nodes)
    np.testing.assert_allclose(tm.sheet_conduction(x).toarray(), A, rtol=0,
                               atol=1e-14 * np.abs(A).max())


def test_crane_pattern_has_no_positive_couplings_inside_regions():
    """Every positive T3 coupling of the crane is on a region boundary (panel against crease,
    or the outline): flips inside regions find nothing to do."""
    mesh = make_mesh(crane_pattern())
    out = delaunay_flips(mesh.nodes, mesh.triangles, _region(mesh))
    np.testing.assert_array_equal(out, mesh.triangles)
