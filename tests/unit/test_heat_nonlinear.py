"""The nonlinear heat losses (theory 4.12): a medium whose conductivity follows a table k(T)
(exact by the Kirchhoff transformation for the integral loss and the chains) and radiation
from both faces; the Newton solve, its Jacobian, the time domain and the bad inputs."""

import dataclasses
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.integrate import quad

from simulator import (AIR, WATER, ChainLoss, ConvergenceError, IntegralLoss, Material,
                       ParameterError, ThermalParameters, make_model)
from simulator.materials import SU8
from simulator.cases import single_fold_model
from simulator.geometry.materials import (AIR_CONDUCTIVITY_TABLE, KELVIN, Fluid,
                                          WATER_CONDUCTIVITY_TABLE)
from simulator.thermal import thermal_model
from simulator.thermal.nonlinear import (STEFAN_BOLTZMANN, NonlinearLoss, solve_heat_balance)
from simulator.thermal.refined import FineMesh
from simulator.thermal import ThermalModel
from simulator.thermal.transient import integrate_heat

sys.path.insert(0, str(Path(__file__).parent))
from test_integral_loss import disk_mesh  # noqa: E402

AIR_T = AIR.with_temperature_dependence()
ROOM = 21.0


def sheet_model(nodes, tris, params, material=SU8, thickness=5e-6) -> ThermalModel:
    """The thermal model of one flat panel triangulated as ``tris`` (no creases)."""
    edges = np.unique(np.sort(tris[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    pattern = SimpleNamespace(n_panels=1, panel_material=[material],
                              panel_thickness=np.array([thickness]),
                              crease_thickness=np.array([thickness]), crease_material=material)
    mesh = FineMesh(nodes=nodes, triangles=tris, triangle_panel=np.zeros(len(tris), int),
                    triangle_crease=-np.ones(len(tris), int), bars=edges,
                    bar_length=np.linalg.norm(nodes[edges[:, 1]] - nodes[edges[:, 0]], axis=1),
                    crease_ids=np.zeros(0, int), pattern=pattern)
    return ThermalModel(mesh, params)


def plate_mesh(side=1e-3, cells=6):
    """A square plate ``side`` [m] in the z = 0 plane, two triangles per cell."""
    g = np.linspace(0.0, side, cells + 1)
    X, Y = np.meshgrid(g, g)
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    i, j = np.meshgrid(np.arange(cells), np.arange(cells))
    a = (j * (cells + 1) + i).ravel()
    b, c, d = a + 1, a + cells + 1, a + cells + 2
    return nodes, np.vstack([np.column_stack([a, b, d]), np.column_stack([a, d, c])])


def chain_params(medium, thickness=300e-6):
    """Chains without spreading (beta 0): a 1-D slab of the medium on both faces."""
    return ThermalParameters(loss=ChainLoss(thickness=thickness, layers=4, dissipation_angle=0.0),
                             medium=medium, room_temperature=ROOM)


def kirchhoff_integral(fluid, T1, T0=ROOM):
    """int_{T0}^{T1} k(T) dT [W/m] by adaptive quadrature (the table's breakpoints given)."""
    points = [t for t, _ in fluid.conductivity_table if T0 < t < T1]
    return quad(lambda t: float(fluid.conductivity(t)), T0, T1, points=points or None,
                limit=200)[0]


def uniform_heat(tm, x, Q):
    """Nodal heat [W] totalling ``Q`` in proportion to each node's share of the area: a
    uniform plate temperature is then exact (the loss of every node has the same share)."""
    tri = tm.mesh.triangles
    a = np.bincount(tri.ravel(), np.repeat(tm.triangle_areas(x) / 3, 3), minlength=len(x))
    return Q * a / a.sum()


# ------------------------------------------------------------------ the medium's law
def test_air_table_is_incropera_and_the_law_integrates_exactly():
    assert AIR_T.conductivity(300 - KELVIN) == pytest.approx(0.0263)
    assert AIR_T.conductivity(400 - KELVIN) == pytest.approx(0.0338)
    assert WATER.with_temperature_dependence().conductivity(300 - KELVIN) == pytest.approx(0.613)
    rise = np.array([-30.0, 0.0, 50.0, 149.0, 900.0])
    phi, dphi = AIR_T.kirchhoff(rise, ROOM)
    expected = [kirchhoff_integral(AIR_T, ROOM + r) / AIR.thermal_conductivity if r > 0
                else -kirchhoff_integral(AIR_T, ROOM, ROOM + r) / AIR.thermal_conductivity
                for r in rise]
    assert phi == pytest.approx(expected, rel=1e-9, abs=1e-12)
    assert dphi == pytest.approx(AIR_T.conductivity(ROOM + rise) / AIR.thermal_conductivity)
    # the mean conductivity of air over 21-170 deg C that issue 30 estimated (about 0.031)
    assert kirchhoff_integral(AIR_T, 170.0) / 149.0 == pytest.approx(0.0314, abs=5e-4)


def test_constant_fluid_is_unchanged_by_the_law_field():
    assert AIR.to_dict() == {"name": "air", "density": 1.293, "specific_heat": 700.0,
                             "thermal_conductivity": 0.026}
    assert not AIR.temperature_dependent and AIR_T.temperature_dependent
    rise = np.array([0.0, 10.0])
    assert AIR.kirchhoff(rise, ROOM)[0] is not None
    assert np.array_equal(AIR.kirchhoff(rise, ROOM)[0], rise)
    assert AIR_T.to_dict()["conductivity_table"][1] == pytest.approx([300 - KELVIN, 0.0263])
    assert Fluid(**AIR_T.to_dict()) == AIR_T
    assert AIR_T.with_properties(thermal_conductivity=0.03).conductivity_table \
        == AIR_CONDUCTIVITY_TABLE
    assert WATER.with_temperature_dependence().conductivity_table == WATER_CONDUCTIVITY_TABLE


# ------------------------------------------------------------------ (a) the isothermal disk
@pytest.mark.parametrize("T1", [60.0, 170.0])
def test_isothermal_disk_loses_8_a_times_the_integral_of_k(T1):
    """An isothermal disk in an unbounded medium with k(T) loses Q = 8 a int_{T0}^{T1} k dT
    (the constant-k disk, 8 k a, is test_integral_loss's): within 0.5 %."""
    a = 1e-3
    nodes, tris = disk_mesh(a)
    params = ThermalParameters(loss=IntegralLoss(refinement=1, extrapolation=False),
                               medium=AIR_T, substrate=None, room_temperature=ROOM,
                               sheet_refinement=1)
    tm = sheet_model(nodes, tris, params)
    Q = tm.environment_loss(nodes, np.full(len(nodes), T1)).sum()
    assert Q == pytest.approx(8 * a * kirchhoff_integral(AIR_T, T1), rel=5e-3)


# ------------------------------------------------------------------ (b) radiation of a plate
@pytest.mark.parametrize("eps", [0.03, 0.5, 0.9])
def test_uniform_plate_radiates_2_A_eps_sigma_T4(eps):
    nodes, tris = plate_mesh()
    tm = sheet_model(nodes, tris, chain_params(AIR), SU8_with(eps))
    T = 150.0
    A = 1e-6
    exact = 2 * A * eps * STEFAN_BOLTZMANN * ((T + KELVIN) ** 4 - (ROOM + KELVIN) ** 4)
    assert tm.radiation_loss(nodes, np.full(len(nodes), T)).sum() == pytest.approx(exact,
                                                                                  rel=1e-13)


def SU8_with(eps):
    return dataclasses.replace(SU8, name=f"SU-8 eps {eps}", emissivity=eps)


def test_heated_plate_balances_power_with_radiation_and_k_of_T():
    """Chains without spreading and radiation: a plate heated in proportion to its area
    stays uniform at the T solving Q = (2 A / t) int k + 2 A eps sigma (T^4 - T0^4), and the
    Newton solve's losses balance the power to 1e-9."""
    nodes, tris = plate_mesh()
    t, eps, A, Q = 300e-6, 0.9, 1e-6, 2e-3
    tm = sheet_model(nodes, tris, chain_params(AIR_T, t), SU8_with(eps))
    assert tm.nonlinear
    T = tm.solve(nodes, uniform_heat(tm, nodes, Q))
    assert np.ptp(T) < 1e-9
    lost = tm.environment_loss(nodes, T).sum() + tm.radiation_loss(nodes, T).sum()
    assert lost == pytest.approx(Q, rel=1e-9)
    T1 = T.mean()
    analytic = (2 * A / t * kirchhoff_integral(AIR_T, T1)
                + 2 * A * eps * STEFAN_BOLTZMANN * ((T1 + KELVIN) ** 4 - (ROOM + KELVIN) ** 4))
    assert analytic == pytest.approx(Q, rel=1e-9)


# ------------------------------------------------------------------ (c) the Jacobian
def test_jacobian_of_the_losses_matches_finite_differences():
    rng = np.random.default_rng(3)
    m = 7
    B = rng.random((m, m))
    B = B @ B.T * 1e-5
    loss = NonlinearLoss(AIR_T, ROOM, B=B, g=rng.random(m) * 1e-5,
                         emissive=rng.random(m) * 1e-7)
    u = rng.random(m) * 200
    full, d = loss.jacobian(u)
    J = full + np.diag(d)
    h = 1e-4
    fd = np.column_stack([(loss.flux(u + h * e) - loss.flux(u - h * e)) / (2 * h)
                          for e in np.eye(m)])
    assert J == pytest.approx(fd, rel=1e-7, abs=1e-14)


def test_model_jacobian_at_the_solution_matches_finite_differences():
    """The whole steady heat balance of a heated single fold with k(T) and radiation: its
    Jacobian K + L diag(Phi') + diag(4 sigma e T^3) against central differences."""
    tm, x, q = single_fold(IntegralLoss(), sheet_refinement=1)
    A, loss, nodes = tm.nonlinear_system(x)
    u = tm.solve(x, q)[nodes] - ROOM
    full, d = loss.jacobian(u)
    J = A + full + np.diag(d)
    F = lambda v: A @ v + loss.flux(v)  # noqa: E731
    h = 1e-3
    fd = np.column_stack([(F(u + h * e) - F(u - h * e)) / (2 * h) for e in np.eye(len(u))])
    assert np.abs(J - fd).max() <= 1e-7 * np.abs(J).max()
    assert np.abs(F(u) - q[nodes]).max() <= 1e-11 * np.abs(q).sum()


# ------------------------------------------------------------------ (d) the chains' slab
@pytest.mark.parametrize("fluid", [AIR_T, WATER.with_temperature_dependence()])
def test_chains_with_k_of_T_conduct_as_the_1d_slab(fluid):
    """Without spreading a chain is a slab of thickness t on each face: the flux through it
    at a surface temperature T1 is int_{T0}^{T1} k dT / t, whatever the layers."""
    nodes, tris = plate_mesh()
    t, A, Q = 300e-6, 1e-6, 5e-3 if fluid is AIR_T else 5e-2
    tm = sheet_model(nodes, tris, chain_params(fluid, t))
    T = tm.solve(nodes, uniform_heat(tm, nodes, Q))
    assert 2 * A / t * kirchhoff_integral(fluid, T.mean()) == pytest.approx(Q, rel=1e-9)
    assert np.ptp(T) < 1e-9


# ------------------------------------------------------------------ (e) the paper setting
def test_paper_setting_is_linear_and_bitwise_the_linear_solve():
    tm, x, q = single_fold(IntegralLoss(), medium=AIR, eps=0.0, sheet_refinement=1)
    assert not tm.nonlinear
    rise = np.zeros(len(x))
    rise[tm.free_nodes] = tm.factorized(x)(q[tm.free_nodes])
    assert np.array_equal(tm.solve(x, q), ROOM + rise)


def test_a_constant_table_gives_the_linear_answer():
    const = AIR.with_temperature_dependence(((0.0, 0.026), (500.0, 0.026)))
    lin, x, q = single_fold(IntegralLoss(), medium=AIR, eps=0.0)
    tm, _, _ = single_fold(IntegralLoss(), medium=const, eps=0.0)
    assert tm.nonlinear
    assert tm.solve(x, q) == pytest.approx(lin.solve(x, q), rel=1e-12, abs=1e-9)


# ------------------------------------------------------------------ the physics' direction
@pytest.mark.parametrize("loss", [IntegralLoss(), ChainLoss(thickness=0.75e-3)])
def test_hot_air_and_radiation_cool_the_fold(loss):
    refine = 1 if loss.model == "chain" else None
    base, x, q = single_fold(loss, medium=AIR, eps=0.0, sheet_refinement=refine)
    hot, _, _ = single_fold(loss, medium=AIR_T, eps=0.0, sheet_refinement=refine)
    rad, _, _ = single_fold(loss, medium=AIR, eps=0.9, sheet_refinement=refine)
    T0, T1, T2 = (m.solve(x, q).max() - ROOM for m in (base, hot, rad))
    assert T1 < T0 and T2 < T0


# ------------------------------------------------------------------ (f) the time domain
@pytest.mark.parametrize("loss", [IntegralLoss(), ChainLoss(thickness=0.75e-3)])
def test_transient_ends_at_the_steady_state(loss):
    tm, x, q = single_fold(loss, medium=AIR_T, eps=0.9, sheet_refinement=1)
    steady = tm.solve(x, q)
    run = integrate_heat(tm, x, {2: 20e-3}, t_end=20.0, dt=0.5)   # the anchor: ~5 s
    assert run.success
    end = run.temperature[-1]
    assert np.abs(end - steady).max() <= 0.01 * (steady.max() - ROOM)
    # the heat balance of the linearised steps is exact
    stored = run.heat_stored - run.heat_stored[0]
    assert stored[-1] == pytest.approx(run.heat_in[-1] - run.heat_out[-1], rel=1e-9)


def test_refined_sheet_in_time_refuses_the_nonlinear_physics():
    tm, x, _ = single_fold(IntegralLoss(), medium=AIR_T, eps=0.0)
    assert tm.sheet is not None
    with pytest.raises(ParameterError, match="sheet_refinement=1"):
        integrate_heat(tm, x, {2: 1e-3}, t_end=0.1, dt=0.05)


def test_refined_sheet_solves_the_nonlinear_balance_on_its_fine_nodes():
    tm, x, q = single_fold(IntegralLoss(), medium=AIR_T, eps=0.9)
    T = tm.solve(x, q)
    fine = tm.fine_model
    assert fine.nonlinear
    X = tm.sheet.positions(x)
    TF = tm.fine_temperatures
    lost = (fine.environment_loss(X, TF).sum() + fine.radiation_loss(X, TF).sum())
    held = fine.held_nodes(X)
    assert lost < q.sum() and T.max() > ROOM
    assert tm.radiation_loss(x, T).sum() == pytest.approx(fine.radiation_loss(X, TF).sum())
    assert len(held)


# ------------------------------------------------------------------ errors
@pytest.mark.parametrize("eps", [-0.1, 1.2, float("nan")])
def test_bad_emissivity_is_refused(eps):
    with pytest.raises(ParameterError, match=r"emissivity = .* must be a number in \[0, 1\]"):
        Material("m", youngs_modulus=1e9, emissivity=eps)


@pytest.mark.parametrize("table, match", [
    (((20.0, 0.02), (20.0, 0.03)), "must increase strictly; T = 20 deg C is followed by 20"),
    (((50.0, 0.02), (20.0, 0.03)), "must increase strictly"),
    (((20.0, 0.02), (50.0, 0.0)), r"k = 0 W/\(m K\) at T = 50 deg C must be > 0"),
    (((20.0, -0.02), (50.0, 0.03)), "must be > 0"),
    (((20.0, 0.02),), "at least two finite pairs"),
    ("hot", "at least two finite pairs"),
])
def test_bad_conductivity_table_is_refused(table, match):
    with pytest.raises(ParameterError, match=match):
        AIR.with_temperature_dependence(table)


def test_table_without_reference_conductivity_and_unknown_fluid_are_refused():
    with pytest.raises(ParameterError, match="reference conductivity > 0"):
        Fluid("gas", 1.0, 1000.0, 0.0, ((0.0, 0.02), (100.0, 0.03)))
    with pytest.raises(ParameterError, match="no literature table"):
        Fluid("oil", 900.0, 2000.0, 0.15).with_temperature_dependence()


def test_several_heat_inputs_and_the_linear_solver_are_refused():
    tm, x, q = single_fold(IntegralLoss(), medium=AIR_T, eps=0.0, sheet_refinement=1)
    with pytest.raises(ParameterError, match="do not superpose"):
        tm.solve(x, np.column_stack([q, q]))
    with pytest.raises(ParameterError, match="no linear solver"):
        tm.factorized(x)


def test_fast_path_refuses_the_nonlinear_physics():
    tm, x, q = single_fold(IntegralLoss(operator="fast"), medium=AIR_T, eps=0.0,
                           sheet_refinement=1)
    with pytest.raises(ParameterError, match="operator='dense'"):
        tm.solve(x, q)


def test_non_convergence_is_reported_not_silent():
    loss = NonlinearLoss(AIR, ROOM, emissive=np.array([1.0]))
    out = solve_heat_balance(np.array([[1e-30]]), loss, np.array([1e30]))
    assert not out.success and out.status == "failed" and "did not converge" in out.message
    tm, x, q = single_fold(IntegralLoss(), medium=AIR, eps=0.9, sheet_refinement=1)
    with pytest.raises(ConvergenceError, match="did not converge"):
        tm.solve(x, 1e12 * q)


# ------------------------------------------------------------------ helpers
def single_fold(loss, medium=AIR_T, eps=0.9, sheet_refinement=None):
    """The flat reference single fold in ``medium`` with all its materials at emissivity
    ``eps``: its thermal model, positions and the nodal heat of 20 mW on the crease."""
    params = ThermalParameters(loss=loss, medium=medium, boundary_panels=(2,),
                               room_temperature=ROOM, sheet_refinement=sheet_refinement)
    model = single_fold_model(thermal=params)
    pat = model.mesh.pattern
    if eps:
        mats = [dataclasses.replace(m, emissivity=eps) for m in pat.panel_material]
        pat = dataclasses.replace(pat, panel_material=mats,
                                  crease_material=dataclasses.replace(pat.crease_material,
                                                                      emissivity=eps))
        model = make_model(pat, model.supports, model.params, thermal=params)
    tm = thermal_model(model)
    x = model.mesh.nodes
    power = np.zeros(model.mesh.n_creases)
    power[model.mesh.crease_row[2]] = 20e-3
    return tm, x, tm.heat_vector(power)


def test_a_heat_step_reports_a_heat_balance_that_did_not_converge(monkeypatch):
    from simulator import simulate
    from simulator.cases import get_case

    case = get_case("single_fold", thermal_steps=2)

    def no_balance(self, x, q, room_temperature=None):
        raise ConvergenceError("the nonlinear heat balance did not converge: (a test)")
    monkeypatch.setattr(ThermalModel, "solve", no_balance)
    result = simulate(case.model, case.steps)
    assert not result.success
    assert "increment 1/2" in result.message and "did not converge: (a test)" in result.message
