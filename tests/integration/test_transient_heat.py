"""Transient heat transfer (theory 8.1): capacity, theta-method, schedules, step, errors."""

import dataclasses
import math

import numpy as np
import pytest
import scipy.sparse as sp

from simulator import AIR, WATER, Heat, Material, TransientHeat, get_case, simulate
from simulator.schedules import PiecewiseLinear, Ramp, Sine, SquareWave, StepPower
from simulator.thermal import ThetaStepper, capacity_vector, integrate_heat, theta_step
from simulator.errors import ParameterError, PatternError
from simulator.geometry.example_patterns import single_fold_pattern
from simulator.model.mesh import make_mesh
from simulator.geometry.pattern import Pattern
from simulator.thermal.schedules import crease_power_function
from simulator.thermal import thermal_model
from simulator.thermal import ChainLoss
from simulator.thermal import REFERENCE_BETA, ThermalModel, ThermalParameters
from simulator.thermal.transient import REFERENCE_THETA, environment_profile, heat_system


# ---------------------------------------------------------------- models
def reference_04_model(room_temperature=0.0):
    """The model of the reference's 04/Example01 (theory 10.9). Its capacity uses the panel
    CONDUCTIVITY as specific heat (theory 7.2), reproduced here with c = k numerically."""
    sub = Material("sub", 2e9, density=1200.0, thermal_conductivity=1.3, specific_heat=1.3)
    pan = Material("pan", 2e9, density=1200.0, thermal_conductivity=0.3, specific_heat=0.3)
    crease = Material("crease", 2e9, density=1200.0, thermal_conductivity=0.3,
                      specific_heat=2e6 / 1200)
    pat = single_fold_pattern(L=1e-3, W=400e-6, undercut=100e-6, panel_thickness=21e-6,
                              anchor_thickness=500e-6, crease_thickness=1e-6, panel_material=pan,
                              substrate_material=sub)
    mesh = make_mesh(dataclasses.replace(pat, crease_material=crease))
    prm = ThermalParameters(loss=ChainLoss(thickness=1500e-6, dissipation_angle=REFERENCE_BETA),
                            medium=AIR, boundary_panels=(2,), room_temperature_nodes=(0, 3),
                            room_temperature=room_temperature)
    return ThermalModel(mesh, prm)


def long_strip(panels=30, W=0.1, k=1.0, rho=1.0, c=1.0, t=0.01, width=0.5):
    """A row of unit panels (1-D conduction), ends at room temperature, no environment."""
    P = panels
    v = [(i, 0.0, 0.0) for i in range(P + 1)] + [(i, width, 0.0) for i in range(P + 1)]
    quads = [(i, i + 1, P + 2 + i, P + 1 + i) for i in range(P)]
    mat = Material("m", 2e9, density=rho, thermal_conductivity=k, specific_heat=c)
    mesh = make_mesh(Pattern(np.array(v, float), quads, crease_width=W, crease_thickness=t,
                              panel_thickness=t, panel_material=mat, crease_material=mat))
    x = mesh.nodes[:, 0]
    ends = tuple(int(i) for i in np.flatnonzero((x < 1e-12) | (x > P - 1e-12)))
    return ThermalModel(mesh, ThermalParameters(
        loss=ChainLoss(thickness=1.0, layers=1),
        medium=AIR.with_properties(thermal_conductivity=0.0), room_temperature=0.0,
        room_temperature_nodes=ends))


# ---------------------------------------------------------------- capacity (theory 7.2)
def test_capacity_matches_reference_example():
    tm = reference_04_model()
    n = tm.mesh.n_nodes
    C = capacity_vector(tm, tm.mesh.nodes)
    ref = [1.31535e-7, 2.32006e-7, 2.32006e-7, 1.31535e-7, 1.03266e-7, 2.79500e-9, 2.79500e-9,
           1.03266e-7, 9.40083e-7, 9.40093e-7, 8.82234e-7, 8.82224e-7, 6.69820e-8, 6.69820e-8,
           2.67923e-7, 2.63070e-7, 5.58999e-9, 1.82232e-6]
    np.testing.assert_allclose(C[:n], ref, rtol=5e-6)
    np.testing.assert_allclose(C[[n + 14, 10 * n + 14, n + 5]],
                               [2.61352e-9, 2.15643e-9, 3.12298e-9], rtol=5e-6)


def test_capacity_totals_are_the_conduction_volumes():
    """Solid: sum rho c t A_t; environment (beta = 0): rho c of air times 2 A_t t_air."""
    mesh = make_mesh(single_fold_pattern())
    tm = ThermalModel(mesh, ThermalParameters(loss=ChainLoss(thickness=300e-6,
                                                             dissipation_angle=0.0)))
    x = mesh.nodes.copy()
    x[[4, 5, 6, 7, mesh.panel_center[1]], 2] += 40e-6            # any shape
    C = capacity_vector(tm, x).reshape(tm.params.loss.layers + 1, -1)
    area = tm.triangle_areas(x)
    rho_c = np.array([m.density * m.specific_heat for m in mesh.pattern.panel_material])
    solid = np.where(mesh.triangle_panel >= 0, rho_c[mesh.triangle_panel],
                     mesh.pattern.crease_material.density
                     * mesh.pattern.crease_material.specific_heat) * tm.conduction.thickness * area
    t_air = tm.environment.geometry(x, area)[1]
    env = AIR.density * AIR.specific_heat * 2 * area * t_air
    assert C.sum() == pytest.approx(solid.sum() + env.sum(), rel=1e-12)
    assert np.all(C > 0)


# ---------------------------------------------------------------- theta-method
def _lumped_error(theta, steps, G=2.0, cap=0.5, q=3.0):
    """Error at t = tau of a single node (capacity cap, conductance G) heated by q."""
    tau = cap / G
    stepper = ThetaStepper(sp.csc_matrix([[G]]), [cap], tau / steps, theta)
    T = np.zeros(1)
    for _ in range(steps):
        T = stepper.step(T, [q], [q])
    return abs(T[0] - q / G * (1 - math.exp(-1.0)))


@pytest.mark.parametrize("theta, order", [(0.5, 2), (2 / 3, 1), (1.0, 1)])
def test_lumped_node_follows_exponential_to_the_schemes_order(theta, order):
    errors = [_lumped_error(theta, n) for n in (20, 40, 80)]
    rates = np.log2(np.array(errors[:-1]) / errors[1:])
    np.testing.assert_allclose(rates, order, atol=0.05)
    assert errors[-1] < (2e-5 if order == 2 else 5e-3)          # of 0.95 K


def test_theta_step_reuses_the_factorisation_and_matches_the_stepper():
    K, C = sp.csc_matrix([[2.0, -1.0], [-1.0, 3.0]]), np.array([0.5, 0.2])
    stepper = ThetaStepper(K, C, 0.1, 0.6)
    T1 = T2 = np.zeros(2)
    for k in range(5):
        T1 = stepper.step(T1, [1.0, 0.0], [1.0, 0.5])
        T2 = theta_step(K, C, T2, [1.0, 0.0], [1.0, 0.5], 0.1, 0.6)
    np.testing.assert_allclose(T1, T2, rtol=1e-14)
    lhs = np.diag(C / 0.1) + 0.6 * K.toarray()
    np.testing.assert_allclose(lhs @ stepper.step(T1, [0, 0], [0, 0]),
                               (np.diag(C / 0.1) - 0.4 * K.toarray()) @ T1, rtol=1e-12)


def test_first_steps_match_reference_transient():
    """04/Example01 with RT = 0 (theory 10.9): T of Ctr after steps 1 and 2 of 2 us at 20 mW
    (the shape has not moved yet; later steps differ by the reference's mechanical coupling)."""
    tm = reference_04_model()
    r = integrate_heat(tm, tm.mesh.nodes, {2: 20e-3}, 4e-6, 2e-6, theta=REFERENCE_THETA)
    np.testing.assert_allclose(r.temperature[1:, 14], [0.049626159, 0.099080744], rtol=2e-8)
    np.testing.assert_allclose(r.temperature[1, [12, 1, 16]],               # printed to 1e-9
                               [0.049624627, 0.021362135, 0.000107962], rtol=0, atol=1e-9)


def _series(x, t, ell, x0, W, Q, k, A, kappa, modes=4000):
    """1-D rod [0, ell], ends at 0, source Q spread uniformly over [x0 - W/2, x0 + W/2]."""
    lam = np.arange(1, modes + 1) * np.pi / ell
    s_n = (2 / ell) * (Q / W) * (np.cos(lam * (x0 - W / 2)) - np.cos(lam * (x0 + W / 2))) / lam
    b = s_n / (k * A * lam**2)
    return np.array([(b * (1 - np.exp(-kappa * lam**2 * ti))) @ np.sin(np.outer(lam, x))
                     for ti in t])


def test_strip_matches_series_solution():
    P, W, Q, t, width = 30, 0.1, 1.0, 0.01, 0.5
    tm = long_strip(P, W, t=t, width=width)
    mesh = tm.mesh
    ctr = mesh.crease_nodes[:, 6]
    row = int(np.argmin(abs(mesh.nodes[ctr, 0] - P / 2)))
    tau = P**2 / math.pi**2                                    # slowest time constant
    times = np.array([0.05, 0.1, 0.3, 1.0]) * tau
    r = integrate_heat(tm, mesh.nodes, {int(mesh.crease_ids[row]): Q}, times[-1], tau / 2000,
                       theta=1.0, record_every=10)
    got = r.temperature[[int(np.argmin(abs(r.time - ti))) for ti in times]]
    exact = _series(mesh.nodes[:, 0], times, P, P / 2, W, Q, 1.0, t * width, 1.0)
    hot = ctr[row]
    np.testing.assert_allclose(got[:, hot], exact[:, hot], rtol=0.01)
    profile_error = np.max(abs(got - exact), axis=1) / exact.max(axis=1)
    assert np.all(profile_error[1:] < 0.01)                  # the whole strip from 0.1 tau on


@pytest.mark.parametrize("name", ["single_fold", "crane"])
@pytest.mark.parametrize("theta", [1.0, 2 / 3])
def test_long_time_equals_steady_solver(name, theta):
    case = get_case(name)
    heat, model = case.steps[-1], case.model
    tm, x = thermal_model(model), model.mesh.nodes
    steady = tm.solve(x, tm.heat_vector(heat.power_array(model.mesh)))
    slowest = {"single_fold": 3.0, "crane": 4.8}[name]            # slowest rate [1/s]
    t_end = 40 / slowest
    r = integrate_heat(tm, x, dict(heat.power), t_end, t_end / 200, theta=theta,
                       record_every=100)
    assert r.success and r.steps == 200 and r.assemblies == 1
    rise = steady - tm.params.room_temperature
    assert np.max(abs(r.temperature[-1] - steady)) < 1e-8 * rise.max()


def test_energy_balance_and_steady_start():
    tm = reference_04_model(room_temperature=21.0)
    x = tm.mesh.nodes
    r = integrate_heat(tm, x, {2: SquareWave(20e-3, 2e-3, 0.3)}, 0.02, 1e-4)
    stored = r.heat_stored - r.heat_stored[0]
    np.testing.assert_allclose(stored, r.heat_in - r.heat_out, rtol=1e-9, atol=1e-12 * r.heat_in[-1])
    assert r.heat_in[-1] == pytest.approx(0.3 * 20e-3 * 0.02, rel=1e-9)
    pwm = SquareWave(20e-3, 0.3e-4, 0.3)                                  # pulses shorter than dt
    fast = integrate_heat(tm, x, {2: pwm}, 0.02, 1e-4)
    assert fast.heat_in[-1] == pytest.approx(pwm.mean(0.0, 0.02) * 0.02, rel=1e-9)
    assert pwm.mean(0.0, 0.02) == pytest.approx(0.3 * 20e-3, rel=1e-3)
    steady = tm.solve(x, tm.heat_vector([5e-3]))
    r = integrate_heat(tm, x, {2: 5e-3}, 0.01, 1e-3, T0=steady)       # quasi-steady environment
    np.testing.assert_allclose(r.temperature, steady[None].repeat(len(r.time), 0), rtol=1e-12)
    full = environment_profile(tm, x, steady - 21.0)
    assert full.shape == (tm.n_dof,) and np.all(full[-tm.mesh.n_nodes:] == 0)


def test_shape_changes_reassemble():
    tm = reference_04_model(room_temperature=21.0)
    mesh = tm.mesh
    moved = mesh.nodes.copy()
    moved[[4, 5, 6, 7, mesh.panel_center[1]], 2] += 200e-6

    def shape(t):
        return mesh.nodes if t < 0.05 else moved

    r = integrate_heat(tm, shape, {2: 10e-3}, 1.5, 0.01, theta=1.0, record_every=50)
    assert r.assemblies == 2
    np.testing.assert_allclose(r.temperature[-1], tm.solve(moved, tm.heat_vector([10e-3])),
                               rtol=1e-9)


# ---------------------------------------------------------------- schedules
def test_schedule_values():
    t = np.array([-1.0, 0.0, 0.04, 0.1, 0.24, 0.26, 0.5, 2.0])
    np.testing.assert_allclose(StepPower(2.0, t_on=0.0, t_off=0.25)(t), [0, 2, 2, 2, 2, 0, 0, 0])
    np.testing.assert_allclose(Ramp(1.0, duration=0.5)(t), [0, 0, 0.08, 0.2, 0.48, 0.52, 1, 1])
    pwm = SquareWave(3.0, period=0.2, duty=0.25)
    np.testing.assert_allclose(pwm(t), [0, 3, 3, 0, 3, 0, 0, 3])
    fine = np.linspace(0, 10, 200001)[:-1]
    assert pwm(fine).mean() == pytest.approx(0.75, rel=1e-3)
    s = Sine(amplitude=1.0, frequency=2.0)
    assert s(0.125) == pytest.approx(2.0) and s(0.375) == pytest.approx(0.0, abs=1e-12)
    pl = PiecewiseLinear((0.0, 1.0, 3.0), (0.0, 2.0, 1.0))
    np.testing.assert_allclose(pl([-1.0, 0.5, 2.0, 5.0]), [0.0, 1.0, 1.5, 1.0])
    assert isinstance(pl(0.5), float) and pl(np.zeros((2, 3))).shape == (2, 3)


def test_powers_per_crease_and_circuit():
    mesh = get_case("crane").model.mesh
    f = crease_power_function(mesh, {(6, 7): Ramp(2.0, 1.0), 7: 1.0})
    p = f(np.array([0.0, 0.5]))
    assert p.shape == (2, mesh.n_creases)
    r6, r7 = mesh.crease_row_of(6), mesh.crease_row_of(7)
    np.testing.assert_allclose(p[:, [r6, r7]], [[0.0, 1.0], [1.0, 2.0]])
    assert p.sum() == pytest.approx(4.0) and f(0.5).shape == (mesh.n_creases,)


def test_fluids_and_materials_have_heat_data():
    from simulator.materials import GOLD, SILICON, SPR, SU8, SUBSTRATE
    for m in (SU8, SPR, SUBSTRATE, GOLD, SILICON):
        assert m.density > 0 and m.specific_heat > 0
    assert SU8.density * SU8.specific_heat == pytest.approx(2e6)
    medium = ThermalParameters(loss=ChainLoss(thickness=1e-3), medium=WATER).medium
    assert (medium.thermal_conductivity, medium.density, medium.specific_heat) == (0.6, 998.0,
                                                                                   4182.0)


# ---------------------------------------------------------------- the step
def test_transient_heat_step_in_simulate():
    case = get_case("single_fold")
    r = simulate(case.model, [Heat({2: 5e-3}, increments=2),
                              TransientHeat({2: SquareWave(10e-3, 0.01, 0.5)}, duration=0.05,
                                            dt=1e-3, record_every=5)])
    assert r.success, r.message
    step = r.steps[-1]
    np.testing.assert_allclose(step.columns["time [s]"], np.arange(0, 11) * 5e-3)
    np.testing.assert_allclose(step.columns["heat_stored [J]"],
                               step.columns["heat_in [J]"] - step.columns["heat_out [J]"],
                               rtol=1e-9)
    df = r.to_frame()
    # the initial and the two quasi-static Heat records have no time (issue 28); the transient
    # step begins on the state Heat left, at t = 0
    assert df["time [s]"].isna().tolist() == [True] * 3 + [False] * 11
    assert df["time [s]"].iloc[3] == 0.0 and df["time [s]"].max() == pytest.approx(0.05)
    np.testing.assert_array_equal(step.temperature_history[0], r.steps[0].state.temperature)
    assert np.all(step.power_history >= 5e-3 - 1e-15)           # added on top of the 5 mW
    np.testing.assert_array_equal(r.state.temperature, step.temperature_history[-1])
    hot = case.model.mesh.crease_nodes[0, 6]                 # hotter on average than at 5 mW
    assert step.temperature_history[:, hot].mean() > r.steps[0].state.temperature[hot] + 1.0
    np.testing.assert_array_equal(r.state.u, r.steps[0].state.u)


def test_transient_result_saves(tmp_path):
    import json
    model = get_case("single_fold").model
    r = simulate(model, [TransientHeat({2: StepPower(5e-3, t_off=0.01), (2,): Ramp(1e-3, 0.02)},
                                       duration=0.02, dt=2e-3)])
    r.save(tmp_path)
    meta = json.loads((tmp_path / "meta.json").read_text())
    settings = meta["steps"][0]
    assert settings["dt [s]"] == 2e-3 and settings["power_added"]["2"]["t_off"] == 0.01
    text = (tmp_path / "creases.csv").read_text().splitlines()
    header, first = text[0].split(","), text[1].split(",")
    assert first[header.index("time [s]")] == "0.0"                # initial record: time 0,
    assert text[1].endswith(",,,,")                                 # no step values
    direct = integrate_heat(model, model.mesh.nodes, {2: StepPower(5e-3, t_off=0.01),
                                                      (2,): Ramp(1e-3, 0.02)}, 0.02, 2e-3)
    np.testing.assert_allclose(r.steps[0].temperature_history, direct.temperature,
                               rtol=1e-12)                       # record 0: the start


# ---------------------------------------------------------------- errors
@pytest.mark.parametrize("make, match", [
    (lambda: TransientHeat({2: 1e-3}, duration=1.0, dt=0.0), "time step"),
    (lambda: TransientHeat({2: 1e-3}, duration=1.0, dt=-1e-3), "time step"),
    (lambda: TransientHeat({2: 1e-3}, duration=0.0), "duration"),
    (lambda: TransientHeat({2: 1e-3}, theta=0.3), "theta"),
    (lambda: TransientHeat({2: -1e-3}), "constant power >= 0"),
    (lambda: TransientHeat({"a": 1e-3}), "crease id"),
    (lambda: TransientHeat({2: 1e-3}, record_every=0), "record_every"),
    (lambda: SquareWave(1.0, period=0.1, duty=0.0), "duty"),
    (lambda: SquareWave(1.0, period=0.1, duty=1.0), "duty"),
    (lambda: SquareWave(1.0, period=0.0), "period"),
    (lambda: PiecewiseLinear((0.0, 2.0, 1.0), (1.0, 2.0, 3.0)), "strictly increasing"),
    (lambda: PiecewiseLinear((0.0, 1.0), (1.0,)), "equal length"),
    (lambda: PiecewiseLinear((0.0, 1.0), (1.0, -2.0)), r"values\[1\]"),
    (lambda: StepPower(1.0, t_on=1.0, t_off=0.5), "t_off"),
    (lambda: StepPower(math.nan), "power"),
    (lambda: Ramp(1.0, duration=-1.0), "duration"),
    (lambda: Sine(2.0, 1.0, offset=1.0), "offset"),
    (lambda: Material("m", 2e9, specific_heat=-1.0), "specific_heat"),
    (lambda: AIR.with_properties(density=-1.0), "density = -1.0"),
])
def test_bad_inputs(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


def test_missing_density_and_bad_integration_inputs():
    mat = Material("no-density", 2e9, thermal_conductivity=0.3)
    mesh = make_mesh(single_fold_pattern(panel_material=mat))
    tm = ThermalModel(mesh, ThermalParameters(loss=ChainLoss(thickness=1e-3)))
    with pytest.raises(ParameterError, match="no-density.*density = 0.0"):
        integrate_heat(tm, mesh.nodes, {2: 1e-3}, 1.0, 0.1)
    tm = ThermalModel(make_mesh(single_fold_pattern()),
                      ThermalParameters(loss=ChainLoss(thickness=1e-3),
                                        medium=AIR.with_properties(density=0.0)))
    with pytest.raises(ParameterError, match="the medium.s density 0.0"):
        heat_system(tm, tm.mesh.nodes)
    tm = reference_04_model()
    x = tm.mesh.nodes
    for kw, match in [(dict(t_end=1.0, dt=0.0), "time step"), (dict(t_end=-1.0, dt=0.1), "t_end"),
                      (dict(t_end=1.0, dt=0.1, theta=1.5), "theta"),
                      (dict(t_end=1.0, dt=0.1, T0=np.zeros(3)), "T0")]:
        with pytest.raises(ParameterError, match=match):
            integrate_heat(tm, x, {2: 1e-3}, **kw)
    with pytest.raises(PatternError, match="Unknown crease id 99"):
        integrate_heat(tm, x, {99: 1e-3}, 1.0, 0.1)
    with pytest.raises(ParameterError, match="C > 0"):
        ThetaStepper(sp.csc_matrix([[1.0]]), [0.0], 0.1)


def test_callable_powers_and_callback_stop():
    tm = reference_04_model(room_temperature=21.0)
    x = tm.mesh.nodes
    a = integrate_heat(tm, x, {2: 5e-3}, 0.01, 1e-3)
    b = integrate_heat(tm, x, lambda t: np.array([5e-3]), 0.01, 1e-3)
    np.testing.assert_allclose(a.temperature, b.temperature, rtol=1e-12)
    seen = []
    c = integrate_heat(tm, x, {2: 5e-3}, 0.01, 1e-3,
                       callback=lambda k, n, t, T: seen.append((k, n)) or k == 3)
    assert (c.success, c.status, c.steps, seen[-1]) == (False, "stopped", 3, (3, 10))
    np.testing.assert_allclose(c.temperature[-1], a.temperature[3], rtol=1e-12)
    df = a.to_frame()
    assert len(df) == 11 * tm.mesh.n_nodes and df["time [s]"].iloc[-1] == pytest.approx(0.01)
    np.testing.assert_allclose(df["temperature [degC]"].to_numpy()[-tm.mesh.n_nodes:],
                               a.temperature[-1])
