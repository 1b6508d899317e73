"""Concentrated hinges (sharp creases, theory 2.6 and 3.11): closed forms and every mechanical step.

A single sharp crease with a rigid free panel is a one-degree-of-freedom rotational spring:
statics ``k phi = F L cos(phi)`` under a dead tip load, ``k phi = g cos(phi) sum(m_i r_i)``
under gravity, free vibration ``omega^2 = k / I`` with ``I = M L^2 / 3``, and the steady
amplitude of a sinusoidal rest-angle drive ``A / sqrt((1 - r^2)^2 + (2 zeta r)^2)``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from simulator import (ArcLengthLoad, DisplacementControl, Dynamics, DynamicsOptions, Gravity,
                       Heat, Load, Material, ParameterError, Pattern, SelfFold, Supports,
                       natural_modes, simulate)
from simulator.model.mass import lumped_masses
from simulator.model.sharp import SharpHingeParameters, sharp_model
from simulator.schedules import SineSignal
from simulator.steps import initial_state

L, T, RHO, E = 1e-3, 10e-6, 1200.0, 2e9
K_F = 1e-6                                   # fold stiffness per length [N m/rad/m]
K = K_F * L                                  # the crease's spring [N m/rad]
PANEL = Material("panel", youngs_modulus=E, poisson_ratio=0.3, density=RHO)
STIFF = SharpHingeParameters(fold_stiffness=K_F, panel_bending_width=1e-6)
TIP = (4, 5)                                 # the free panel's far corners
CREASE = 2                                   # edge id of the crease


def single_crease(params=STIFF):
    """Two L x L panels on a sharp crease along the y axis (vertices 1-2); panel 0 clamped."""
    v = np.array([[-L, 0], [0, 0], [0, L], [-L, L], [L, 0], [L, L]], float)
    pattern = Pattern(v, [[0, 1, 2, 3], [1, 4, 5, 2]], crease_width=100e-6,
                      crease_thickness=1e-6, panel_thickness=T, panel_material=PANEL,
                      crease_material=PANEL)
    model = sharp_model(pattern, params=params)
    clamped = model.mesh.panel_nodes(0)
    return sharp_model(pattern, Supports.nodes(clamped), params)


def tip_load(total):
    return {n: (0.0, 0.0, -total / 2) for n in TIP}


def spring_angle(F):
    """Rotation phi >= 0 of a rigid panel on a rotational spring under a dead tip load F."""
    return brentq(lambda p: K * p - F * L * math.cos(p), 0.0, math.pi / 2)


def crease_fold(result):
    return result.fold_angle[:, 0]


def test_mesh_of_a_single_crease():
    m = single_crease().mesh
    assert m.n_nodes == 8 and len(m.bars) == 7 + 8 and len(m.springs) == 1 + 8
    assert m.crease_nodes.tolist() == [[1, 2]] and set(m.springs[0, 1:3]) == {1, 2}
    assert set(m.springs[0, [0, 3]]) == set(m.panel_center)
    masses = lumped_masses(m)
    assert masses.sum() == pytest.approx(2 * RHO * T * L * L, rel=1e-12)
    assert masses[m.panel_center[1]] == pytest.approx(2 / 3 * RHO * T * L * L, rel=1e-12)


def test_tip_load_follows_the_rotational_spring_closed_form():
    F = 2.5 * K / L
    res = simulate(single_crease(), [Load(tip_load(F), increments=10)])
    assert res.success, res.message
    lam = np.r_[0.0, np.arange(1, 11) / 10]
    exact = np.array([spring_angle(F * s) for s in lam])
    err = np.abs(-crease_fold(res) - exact).max()
    assert exact[-1] > 0.9                       # large rotation: about 55 deg
    assert err < 1e-4, err


def test_arc_length_reaches_the_same_closed_form():
    F = 2.5 * K / L
    res = simulate(single_crease(), [ArcLengthLoad(tip_load(F), arc_length=0.2,
                                                   target_load_factor=1.0)])
    assert res.success, res.message
    assert abs(-crease_fold(res)[-1] - spring_angle(F)) < 1e-4


def test_displacement_control_reaction_is_the_spring_moment():
    # drive one tip corner down by half a panel; the other tip corner carries no load, so use
    # a reference load on both corners and control one of them
    target = -0.5 * L
    res = simulate(single_crease(), [DisplacementControl(
        node=TIP[0], direction="z", target=target, increments=10,
        forces=tip_load(1.0))])
    assert res.success, res.message
    phi = -crease_fold(res)[-1]
    assert phi == pytest.approx(math.asin(0.5), abs=1e-4)
    reaction = res.state.applied_load[list(TIP), 2].sum()      # total tip load [N]
    assert -reaction * L * math.cos(phi) == pytest.approx(K * phi, rel=1e-3)


def test_gravity_bends_the_crease_by_the_closed_form():
    model = single_crease()
    m = lumped_masses(model.mesh)
    free = [4, 5, int(model.mesh.panel_center[1])]
    moment_arm = float(sum(m[n] * model.mesh.nodes[n, 0] for n in free))   # sum m_i r_i
    g = 0.8 * K / moment_arm
    res = simulate(model, [Gravity(g=g, increments=5)])
    assert res.success, res.message
    exact = brentq(lambda p: K * p - g * moment_arm * math.cos(p), 0, math.pi / 2)
    assert abs(-crease_fold(res)[-1] - exact) < 1e-4


def test_self_fold_reaches_its_rest_angle_without_load():
    res = simulate(single_crease(), [SelfFold({CREASE: 1.2}, increments=6)])
    assert res.success, res.message
    assert crease_fold(res)[-1] == pytest.approx(1.2, abs=1e-9)


def natural_frequency():
    M = RHO * T * L * L
    return math.sqrt(K / (M * L * L / 3)) / (2 * math.pi)


def test_natural_frequency_is_that_of_the_rotational_spring():
    modes = natural_modes(single_crease(), count=1)
    assert modes.success
    assert modes.frequency[0] == pytest.approx(natural_frequency(), rel=1e-4)


@pytest.mark.parametrize("ratio", [0.5, 1.0, 2.0])
def test_driven_rest_angle_gives_the_damped_oscillator_amplitude(ratio):
    fn, zeta, A = natural_frequency(), 0.1, 0.02
    f = ratio * fn
    alpha = 2 * zeta * 2 * math.pi * fn                       # Rayleigh mass damping: c = alpha I
    periods, per = 40, 80
    step = Dynamics(duration=periods / f, dt=1 / (f * per),
                    folds={CREASE: SineSignal(amplitude=A, frequency=f)},
                    options=DynamicsOptions(rayleigh_alpha=alpha))
    res = simulate(single_crease(), [step])
    assert res.success, res.message
    fold = crease_fold(res)[-8 * per:]                        # the last eight periods
    amplitude = 0.5 * (fold.max() - fold.min())
    exact = A / math.sqrt((1 - ratio**2) ** 2 + (2 * zeta * ratio) ** 2)
    assert amplitude == pytest.approx(exact, rel=0.02), (amplitude, exact)


def test_heating_a_sharp_model_is_refused_with_a_clear_message():
    model = single_crease()
    with pytest.raises(ParameterError, match="concentrated hinges"):
        simulate(model, [Heat({CREASE: 1e-3})])


def test_sharp_model_refuses_bad_input():
    with pytest.raises(ParameterError, match="panel_mesh"):
        SharpHingeParameters(panel_mesh="N9")
    with pytest.raises(ParameterError, match="fold_stiffness"):
        SharpHingeParameters(fold_stiffness=-1.0)
    with pytest.raises(ParameterError, match="Pattern"):
        sharp_model("not a pattern")
    assert initial_state(single_crease()).crease_rest.tolist() == [math.pi]


# ------------------------------------------------------------------ Miura rigid-origami kinematics
GAMMA = math.radians(60.0)


def miura_sheet(panel_mesh, soft_zigzag):
    """3 x 3 Miura sheet with sharp creases and stiff panels, its centre panel clamped; the
    collinear creases (along y in the flat sheet) and the zig-zag ones."""
    from simulator.geometry.example_patterns import miura_sheet_pattern

    pat = miura_sheet_pattern(L, L, GAMMA, 3, 3, W=100e-6, crease_thickness=1e-6,
                              panel_thickness=T, material=PANEL)
    d = np.diff(pat.vertices[pat.edges[pat.creases]], axis=1)[:, 0]
    collinear = np.abs(d[:, 0]) < 1e-12 * np.linalg.norm(d, axis=1)
    soft = {int(c): 1e-9 for c in pat.creases[~collinear]} if soft_zigzag else None
    params = SharpHingeParameters(fold_stiffness=soft, panel_bending_width=1e-6,
                                  panel_mesh=panel_mesh)
    centre = sharp_model(pat, params=params).mesh.panel_nodes(4)
    return sharp_model(pat, Supports.nodes(centre), params), collinear


@pytest.mark.parametrize("panel_mesh, soft_zigzag, target, reached", [
    ("N5B8", True, 2.4, 2.39), ("N4B5", True, 2.4, 2.39), ("N5B8", False, 2.0, 0.46)])
def test_miura_sheet_folds_along_the_rigid_origami_kinematics(panel_mesh, soft_zigzag, target,
                                                               reached):
    """tan(rho_z / 2) = tan(rho_c / 2) / cos(gamma) (theory 3.11) at every increment, when only
    the collinear creases are driven (their rest angles) and the zig-zag creases follow."""
    from simulator.cases import miura_fold_signs

    model, collinear = miura_sheet(panel_mesh, soft_zigzag)
    signs = miura_fold_signs(L, L, GAMMA, 3, 3)
    creases = model.mesh.crease_ids
    folds = {int(c): signs[int(c)] * target for c in creases[collinear]}
    res = simulate(model, [SelfFold(folds, increments=20)])
    assert res.success, res.message
    rho = np.abs(res.fold_angle)
    rho_c = rho[:, collinear].mean(axis=1)
    predicted = 2 * np.arctan(np.tan(rho_c / 2) / math.cos(GAMMA))
    assert rho_c[-1] > reached                                # the folding range covered
    assert np.abs(rho[:, collinear] - rho_c[:, None]).max() < 1e-4
    assert np.abs(rho[:, ~collinear] - predicted[:, None]).max() < 1e-4
    signs_now = np.sign(res.fold_angle[-1])
    assert all(signs_now[k] == signs[int(c)] for k, c in enumerate(creases))
