"""The concentrated-hinge mesh and its properties (theory 2.6, 3.11)."""

import math

import numpy as np
import pytest

from simulator import Material, ParameterError, Pattern, Supports, make_model, simulate
from simulator.model import SharpHingeParameters, build_sharp_mesh, sharp_model
from simulator.geometry.example_patterns import miura_sheet_pattern
from simulator.mechanics.kinematics import crease_rotations, fold_angles
from simulator.model.mass import lumped_masses
from simulator.model import spring_rest_angles
from simulator.mechanics import equilibrium_system
from simulator.steps import initial_state

MAT = Material("m", youngs_modulus=2e9, poisson_ratio=0.3, density=1000.0)


def mixed_pattern():
    """A square, a triangle and a pentagon (creases: vertices 1-2 and 2-4)."""
    v = [[0, 0], [1, 0], [1, 1], [0, 1], [2, 0.5], [2, 1.5], [1.5, 2.2], [0.8, 2]]
    panels = [[0, 1, 2, 3], [1, 4, 2], [2, 4, 5, 6, 7]]
    return Pattern(np.array(v) * 1e-3, panels, crease_width=100e-6, crease_thickness=1e-6,
                   panel_thickness=10e-6, panel_material=MAT, crease_material=MAT)


@pytest.mark.parametrize("panel_mesh, centres, inner", [("N5B8", 2, 9), ("N4B5", 1, 6)])
def test_mixed_panels_are_meshed_by_their_rule(panel_mesh, centres, inner):
    pat = mixed_pattern()
    mesh = build_sharp_mesh(pat, panel_mesh)
    assert mesh.n_nodes == pat.n_vertices + centres
    assert len(mesh.bars) == pat.n_edges + inner
    assert len(mesh.springs) == mesh.n_creases + (inner if panel_mesh == "N5B8" else 6)
    assert mesh.panel_center[1] == -1 and mesh.panel_center[2] >= pat.n_vertices
    # every fold spring's axis is its crease, its wings lie in the two panels
    for row, c in enumerate(mesh.crease_ids):
        i, j, k, l = mesh.springs[row]
        assert {j, k} == set(pat.edges[c])
        n1, n2 = (set(mesh.panel_nodes(p).tolist()) for p in pat.edge_panels[c])
        assert (i in n1 - {j, k} and l in n2 - {j, k}) or (i in n2 - {j, k} and l in n1 - {j, k})
    for row, tris in enumerate(mesh.crease_triangles):
        edge = set(mesh.crease_nodes[row])
        assert all(edge <= set(mesh.triangles[t]) for t in tris)
    # masses: panel mass conserved, no crease mass
    assert lumped_masses(mesh).sum() == pytest.approx(
        float(np.sum(MAT.density * 10e-6 * _areas(pat))), rel=1e-12)


def _areas(pat):
    out = []
    for p in pat.panels:
        x, y = pat.vertices[list(p), 0], pat.vertices[list(p), 1]
        out.append(0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    return np.array(out)


def test_fold_angle_is_positive_towards_plus_z_and_rest_angles_take_the_change():
    pat = miura_sheet_pattern(1e-3, 1e-3, math.radians(60), 1, 2, material=MAT)
    mesh = build_sharp_mesh(pat)
    c = mesh.crease_ids[0]
    a, b = pat.edges[c]
    moving = pat.edge_panels[c, 1]
    # rotate the second panel about the crease line by +0.2 rad so that it rises towards +z
    x = mesh.nodes.copy()
    axis = (x[b] - x[a]) / np.linalg.norm(x[b] - x[a])
    nodes = np.setdiff1d(mesh.panel_nodes(moving), [a, b])
    for sign in (1, -1):
        r = _rotate(x[nodes] - x[a], axis, sign * 0.2) + x[a]
        if r[:, 2].mean() > 0:
            break
    x[nodes] = r
    # (the generator's sheet is flat to ~1e-11 m, the reference's round-off: ~1e-7 rad)
    assert fold_angles(mesh, x)[0] == pytest.approx(0.2, abs=1e-6)
    assert crease_rotations(mesh, x)[0] == fold_angles(mesh, x)[0]
    rest = spring_rest_angles(mesh, np.full(mesh.n_creases, np.pi) + 0.3)
    np.testing.assert_allclose(rest[:mesh.n_creases], np.pi + 0.3)
    np.testing.assert_allclose(rest[mesh.n_creases:], np.pi, atol=1e-12)


def _rotate(v, k, angle):
    """Rodrigues rotation of the rows of v about the unit axis k."""
    return (v * math.cos(angle) + np.cross(k, v) * math.sin(angle)
            + np.outer(v @ k, k) * (1 - math.cos(angle)))


def test_internal_force_is_the_gradient_of_the_energy():
    model = sharp_model(mixed_pattern(), Supports.nodes([0, 3]),
                        SharpHingeParameters(panel_mesh="N4B5"))
    sys = equilibrium_system(model)
    rng = np.random.default_rng(1)
    u = 2e-5 * rng.standard_normal((model.mesh.n_nodes, 3))
    rest = initial_state(model).spring_rest + 0.1
    ev = sys.evaluate(u, rest)
    energy = lambda uu: sum(sys.evaluate(uu, rest, hessian=False).energies.values())  # noqa
    h = 1e-9
    for dof in rng.choice(model.mesh.n_dof, 6, replace=False):
        du = np.zeros(model.mesh.n_dof)
        du[dof] = h
        fd = (energy(u + du.reshape(u.shape)) - energy(u - du.reshape(u.shape))) / (2 * h)
        assert fd == pytest.approx(ev.f_int[dof], rel=1e-5, abs=1e-9 * np.abs(ev.f_int).max())


def test_compliant_builders_and_heating_refuse_a_sharp_mesh():
    mesh = build_sharp_mesh(mixed_pattern())
    with pytest.raises(ParameterError, match="sharp_model"):
        make_model(mesh)
    model = sharp_model(mixed_pattern(), Supports.nodes([0, 1, 3]))
    from simulator import ElectroThermal, TransientHeat

    for step in (TransientHeat({int(model.mesh.crease_ids[0]): 1e-3}, duration=1e-3, dt=1e-4),
                 ElectroThermal(duration=1e-3, dt=1e-4)):
        with pytest.raises(ParameterError, match="concentrated hinges"):
            simulate(model, [step])


def test_fold_stiffness_rules():
    pat = mixed_pattern()
    mesh = build_sharp_mesh(pat)
    length = mesh.bar_length[mesh.spring_bar[:mesh.n_creases]]
    default = sharp_model(pat).properties.spring_stiffness[:mesh.n_creases]
    np.testing.assert_allclose(default, length * 2e9 * 1e-18 / (12 * 100e-6), rtol=1e-12)
    c0 = int(mesh.crease_ids[0])
    mixed = sharp_model(pat, params=SharpHingeParameters(fold_stiffness={c0: 3.0}))
    k = mixed.properties.spring_stiffness[:mesh.n_creases]
    assert k[0] == pytest.approx(3.0 * length[0]) and k[1] == pytest.approx(default[1])
    assert SharpHingeParameters(fold_stiffness={c0: 3.0}).to_dict()["crease_model"] == "sharp"


def test_make_model_chooses_the_crease_model():
    pat = mixed_pattern()
    model = make_model(pat, {0: "xyz"}, crease_model="sharp")
    assert model.mesh.sharp and model.mesh.n_nodes == build_sharp_mesh(pat).n_nodes
    np.testing.assert_array_equal(model.properties.spring_stiffness,
                                  sharp_model(pat).properties.spring_stiffness)
    with pytest.raises(ParameterError, match="crease_model"):
        make_model(pat, crease_model="hinged")
    with pytest.raises(ParameterError, match="no contact"):
        make_model(pat, contact=True, crease_model="sharp")


def test_a_folded_start_shape_is_stress_free():
    """A 3-D start (theory 2.5): the crease keeps its initial angle as rest angle."""
    phi = 0.7
    v = [[-1, 0, 0], [0, 0, 0], [0, 1, 0], [-1, 1, 0],
         [math.cos(phi), 0, math.sin(phi)], [math.cos(phi), 1, math.sin(phi)]]
    pat = Pattern(np.array(v) * 1e-3, [[0, 1, 2, 3], [1, 4, 5, 2]], crease_width=1e-4,
                  crease_thickness=1e-6, panel_thickness=1e-5, panel_material=MAT,
                  crease_material=MAT)
    model = sharp_model(pat, Supports.nodes([0, 1, 2, 3]))
    state = initial_state(model)
    assert abs(state.crease_rest[0] - np.pi) == pytest.approx(phi, abs=1e-12)
    ev = equilibrium_system(model).evaluate(state.u, state.spring_rest, hessian=False)
    assert np.abs(ev.f_int).max() < 1e-18
