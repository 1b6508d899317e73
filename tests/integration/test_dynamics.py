"""Lumped masses, the implicit time integrator and the Dynamics step.

The reference case is the single fold without substrate or contact: a 21 um SU-8 panel on a
0.5 um, 200 um wide crease, anchored by a thick panel. Its lowest mode is the panel rotating on
the crease; the analytic frequency comes from a hinge chain (the crease's two edge lines and its
centre line, springs E t^3 L / (4 W) each, joined by rigid strips of width W / 2) carrying the
lumped nodal masses. (The textbook sqrt(k / I) with the series stiffness E t^3 L / (12 W) about
the centre line is 2 % high: the panel's inertia force bends the crease unevenly across its
width.)
"""

import numpy as np
import pytest
import scipy.linalg

from simulator import (Dynamics, DynamicsOptions, Load, Material, ParameterError, SelfFold,
                       make_model, natural_modes, simulate)
from simulator.model import lumped_masses
from simulator.solvers import TimeIntegrator, integrate
from simulator.cases import single_fold_model
from simulator.geometry.example_patterns import single_fold_pattern
from simulator.mechanics.kinematics import fold_angles
from simulator.mechanics import equilibrium_system
from simulator.steps import initial_state


@pytest.fixture(scope="module")
def fold():
    return single_fold_model(contact=False, substrate=False)


def chain_frequency(model) -> float:
    """Lowest frequency [Hz] of the hinge-chain model of the single fold (module docstring)."""
    mesh = model.mesh
    pat, c = mesh.pattern, mesh.crease_ids[0]
    W, t, E = pat.crease_width[c], pat.crease_thickness[c], pat.crease_material.youngs_modulus
    L = mesh.bar_length[mesh.crease_edge_bars[0, 0]]
    k_line = E * t**3 * L / (4 * W)
    x_edge = mesh.nodes[mesh.crease_nodes[0, 0], 0]
    hinges = x_edge + np.array([0.0, W / 2, W])
    arm = np.clip(mesh.nodes[:, 0, None] - hinges[None, :], 0, None)   # z = arm @ rotations
    m = lumped_masses(mesh)
    w2 = scipy.linalg.eigh(k_line * np.eye(3), arm.T @ (m[:, None] * arm), eigvals_only=True)
    return float(np.sqrt(w2[0]) / (2 * np.pi))


def free_vibration(model, periods, steps_per_period, options=DynamicsOptions(), amplitude=1e-3):
    """Start from the first mode shape with a fold-angle velocity amplitude * omega."""
    modes = natural_modes(model, count=1)
    f = modes.frequency[0]
    shape = modes.shapes[0]
    mesh = model.mesh
    theta = fold_angles(mesh, mesh.nodes + 1e-9 * shape / np.abs(shape).max())[0]
    v0 = shape * (amplitude / theta * 1e-9 / np.abs(shape).max()) * 2 * np.pi * f
    s0 = initial_state(model)
    T = 1 / f
    res = integrate(equilibrium_system(model), s0.u, v0, periods * T, T / steps_per_period,
                    np.zeros(mesh.n_dof), s0.spring_rest, options)
    angle = np.array([fold_angles(mesh, mesh.nodes + u)[0] for u in res.u])
    return res, angle, f


def crossings(t, x):
    """Times of upward zero crossings (linear interpolation)."""
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


# ------------------------------------------------------------------------------ masses
def test_lumped_masses_match_the_reference_single_fold():
    """Theory 7.1 (reference, Octave): L = 1 mm, W = 400 um, t_p = 500/21/500 um, t_c = 1 um."""
    pattern = single_fold_pattern(L=1e-3, W=400e-6, panel_thickness=21e-6,
                                  anchor_thickness=500e-6, crease_thickness=1e-6)
    m = lumped_masses(make_model(pattern).mesh)
    reference = [5.0e-8, 5.006e-8, 5.006e-8, 5.0e-8, 2.16e-9, 2.1e-9, 2.1e-9, 2.16e-9,
                 3.03125e-7, 3.03125e-7, 2.84375e-7, 2.84375e-7, 4.0e-11, 4.0e-11, 1.6e-10,
                 4.0e-7, 1.68e-8, 2.35e-6]
    np.testing.assert_allclose(m, reference, rtol=1e-12)
    assert m.sum() == pytest.approx(4.15068e-6, rel=1e-12)


def test_missing_density_is_a_clear_error():
    massless = Material("massless SU-8", youngs_modulus=2e9)
    model = single_fold_model(contact=False, substrate=False, panel_material=massless)
    with pytest.raises(ParameterError, match="'massless SU-8' have density 0"):
        TimeIntegrator(equilibrium_system(model))
    with pytest.raises(ParameterError, match="density"):
        natural_modes(model)


# ------------------------------------------------------------------------------ integrator
def test_average_acceleration_conserves_energy_over_1000_steps(fold):
    """Undamped Newmark (beta 1/4, gamma 1/2) conserves energy exactly for linear systems; at a
    fold amplitude of 1e-3 rad the bar-and-hinge model is linear to ~1e-8."""
    res, angle, _ = free_vibration(fold, periods=10, steps_per_period=100)
    assert res.success and len(res.time) == 1001
    total = res.kinetic + res.strain
    assert np.ptp(total) / total[0] < 1e-6
    assert np.abs(res.numerical_dissipation).max() / total[0] < 1e-6
    assert np.abs(angle).max() == pytest.approx(1e-3, rel=1e-2)


def test_free_vibration_matches_modes_and_the_hinge_chain(fold):
    f_chain = chain_frequency(fold)
    f_modes = natural_modes(fold, count=1).frequency[0]
    assert f_modes == pytest.approx(f_chain, rel=1e-3)
    res, angle, _ = free_vibration(fold, periods=4, steps_per_period=100)
    f_vib = 1 / np.mean(np.diff(crossings(res.time, angle)))
    assert f_vib == pytest.approx(f_modes, rel=1e-2)
    assert f_vib == pytest.approx(f_chain, rel=1e-2)


@pytest.mark.parametrize("damping", ["rayleigh", "stiffness", "air"])
def test_damped_panel_decays_at_the_analytic_rate(fold, damping):
    """Log decrement 2 pi zeta / sqrt(1 - zeta^2) and damped frequency f sqrt(1 - zeta^2)."""
    f = chain_frequency(fold)
    omega, zeta = 2 * np.pi * f, 0.05
    if damping == "rayleigh":
        options = DynamicsOptions(rayleigh_alpha=2 * zeta * omega)
    elif damping == "stiffness":
        options = DynamicsOptions(rayleigh_beta=2 * zeta / omega)
    else:   # modal damping ratio of area-proportional damping: c phi.A phi / (2 omega)
        from simulator.model.mass import lumped_areas
        phi = natural_modes(fold, count=1).shapes[0]
        modal = np.sum(lumped_areas(fold.mesh)[:, None] * phi**2)
        options = DynamicsOptions(air_damping=2 * zeta * omega / modal)
    res, angle, _ = free_vibration(fold, periods=4, steps_per_period=100, options=options)
    up = crossings(res.time, angle)
    f_d = 1 / np.mean(np.diff(up))
    assert f_d == pytest.approx(f * np.sqrt(1 - zeta**2), rel=1e-2)
    # amplitude decay: peaks of the interpolated envelope one period apart
    peaks = np.array([np.abs(angle[(res.time > a) & (res.time < b)]).max()
                      for a, b in zip(up[:-1], up[1:])])
    decrement = np.mean(np.log(peaks[:-1] / peaks[1:]))
    assert decrement == pytest.approx(2 * np.pi * zeta / np.sqrt(1 - zeta**2), rel=2e-2)
    assert res.dissipated[-1] > 0.9 * (res.kinetic[0] - res.kinetic[-1] - res.strain[-1])


@pytest.mark.parametrize("method,rho", [("hht", 0.7), ("generalized_alpha", 0.5)])
def test_dissipative_schemes_keep_the_low_mode_and_lose_energy(fold, method, rho):
    res, angle, f = free_vibration(fold, periods=3, steps_per_period=50,
                                   options=DynamicsOptions(method=method, rho_inf=rho))
    assert res.success
    f_vib = 1 / np.mean(np.diff(crossings(res.time, angle)))
    assert f_vib == pytest.approx(f, rel=1e-2)
    total = res.kinetic + res.strain
    assert total.max() <= total[0] and res.numerical_dissipation[-1] > 0
    assert total[-1] > 0.99 * total[0]         # second-order accurate: the low mode is kept


def test_unconverged_step_is_reported_not_raised(fold):
    s0 = initial_state(fold)
    v0 = np.zeros((fold.mesh.n_nodes, 3))
    v0[5:7, 2] = 1e-3
    res = integrate(equilibrium_system(fold), s0.u, v0, 1e-3, 1e-4, np.zeros(fold.mesh.n_dof),
                    s0.spring_rest, DynamicsOptions(max_iter=1, max_cuts=2))
    assert not res.success and res.status == "failed"
    assert "halvings" in res.message and res.cuts >= 2


@pytest.mark.parametrize("dt", [0.0, -1e-5, float("nan")])
def test_bad_time_step_is_a_clear_error(fold, dt):
    with pytest.raises(ParameterError, match="dt"):
        Dynamics(duration=1e-3, dt=dt)
    s0 = initial_state(fold)
    with pytest.raises(ParameterError, match="time step dt"):
        integrate(equilibrium_system(fold), s0.u, s0.u, 1e-3, dt, np.zeros(fold.mesh.n_dof),
                  s0.spring_rest)


def test_bad_options_are_clear_errors():
    with pytest.raises(ParameterError, match="method"):
        DynamicsOptions(method="euler")
    with pytest.raises(ParameterError, match="rho_inf"):
        DynamicsOptions(method="hht", rho_inf=0.2)
    with pytest.raises(ParameterError, match="rayleigh_beta"):
        DynamicsOptions(rayleigh_beta=-1.0)
    with pytest.raises(ParameterError, match="duration"):
        Dynamics(duration=0.0, dt=1e-5)


# ------------------------------------------------------------------------------ the step
def test_dynamics_step_releases_a_loaded_panel(fold):
    """Load the panel tip statically, then remove the load suddenly: the panel swings back
    through flat; energy is conserved (undamped) and velocities persist in the state."""
    tip = {5: (0, 0, 2e-9), 6: (0, 0, 2e-9)}
    release = {n: tuple(-np.asarray(f)) for n, f in tip.items()}
    T = 1 / chain_frequency(fold)
    result = simulate(fold, [Load(tip, increments=2),
                             Dynamics(duration=T, dt=T / 40, forces=release)])
    assert result.success
    step = result.steps[1]
    cols = step.columns
    assert len(cols["time [s]"]) == step.increments == 41        # the start and 40 steps
    assert cols["time [s]"][0] == 0.0 and cols["time [s]"][-1] == pytest.approx(T)
    np.testing.assert_array_equal(step.u_history[0], result.steps[0].state.u)
    e0 = result.steps[0].energies
    total = cols["kinetic_energy [J]"] + cols["strain_energy [J]"]
    # fold amplitude ~2.7 deg: the trapezoidal rule conserves energy only to O(nonlinearity)
    np.testing.assert_allclose(total, sum(e0.values()), rtol=2e-3)
    z = step.u_history[:, 5, 2]
    assert z.min() < 0 < result.steps[0].state.u[5, 2]      # swings through flat
    state = result.state
    assert state.velocity is not None and state.time == pytest.approx(T)
    np.testing.assert_allclose(state.applied_load, 0.0, atol=1e-20)
    again = simulate(fold, [SelfFold({2: 0.1}, increments=2)], state=state)
    assert again.state.velocity is None and again.state.time == pytest.approx(T)


@pytest.mark.slow
def test_sudden_fold_lands_on_the_substrate():
    """A -40 deg rest-angle jump swings the panel onto the substrate (contact on). With the
    L-stable generalized-alpha (rho_inf = 0) and a little stiffness damping for the crease-node
    modes the jump excites, the panel comes to rest on its contact layer without tunnelling."""
    model = single_fold_model(contact=True)
    T = 1 / natural_modes(model, count=1).frequency[0]
    options = DynamicsOptions(method="generalized_alpha", rho_inf=0.0, rayleigh_beta=1e-6)
    result = simulate(model, [Dynamics(duration=1.5 * T, dt=T / 50,
                                       folds={2: np.radians(-40)}, options=options)])
    assert result.success
    step = result.steps[0]
    tip_z = step.u_history[:, 5, 2]
    substrate, d0 = -150e-6, model.contact.d0_corner
    assert tip_z.min() > substrate and tip_z.min() < substrate + d0     # held by the contact
    energy = step.columns["kinetic_energy [J]"] + step.columns["strain_energy [J]"]
    assert energy[-1] < 0.6 * energy[0]


def test_bad_vectors_are_clear_errors(fold):
    integ = TimeIntegrator(equilibrium_system(fold))
    s0 = initial_state(fold)
    with pytest.raises(ParameterError, match="external load must be"):
        integ.initial_state(s0.u, s0.u, np.zeros(5), s0.spring_rest)
    with pytest.raises(ParameterError, match="initial velocities .* NaN"):
        integ.initial_state(s0.u, np.full_like(s0.u, np.nan), np.zeros(fold.mesh.n_dof),
                            s0.spring_rest)
    with pytest.raises(ParameterError, match="Dynamics: velocity must be"):
        simulate(fold, [Dynamics(duration=1e-3, dt=1e-4, velocity=np.zeros(3))])
