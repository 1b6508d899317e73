"""One simulation clock: time-domain steps continue ``SimulationState.time``; quasi-static
steps leave the structure at rest."""

import numpy as np

from simulator import Dynamics, Heat, TransientHeat, get_case, simulate


def test_time_continues_across_time_domain_steps_and_heat_leaves_the_structure_at_rest():
    model = get_case("single_fold", thermal_steps=2).model
    res = simulate(model, [TransientHeat({2: 1e-3}, duration=0.01, dt=5e-3),
                           TransientHeat({2: 1e-3}, duration=0.01, dt=5e-3),
                           Dynamics(duration=2e-4, dt=1e-4, velocity={5: (0, 0, 1e-4)}),
                           Heat({2: 1e-4}, increments=1)])
    assert res.success, res.message
    t1, t2, t3 = (s.columns["time [s]"] for s in res.steps[:3])
    np.testing.assert_allclose(t1, [0.0, 0.005, 0.01])      # each begins with its start
    np.testing.assert_allclose(t2, [0.01, 0.015, 0.02])
    np.testing.assert_allclose(t3, [0.02, 0.0201, 0.0202])
    assert res.steps[2].state.velocity is not None
    assert res.steps[3].state.velocity is None and res.state.time == res.steps[2].state.time


def test_time_integration_steps_record_velocities(tmp_path):
    model = get_case("single_fold", thermal_steps=2).model
    res = simulate(model, [Heat({2: 1e-4}, increments=2),
                           Dynamics(duration=3e-4, dt=1e-4, velocity={5: (0, 0, 1e-4)})])
    assert res.success, res.message
    v = res.history["velocity"]
    assert v.shape == res.history["u"].shape
    np.testing.assert_array_equal(v[:3], 0)                # initial and quasi-static: at rest
    dyn = res.steps[1]
    np.testing.assert_array_equal(v[3:], dyn.velocity_history)
    assert np.abs(v[3, 5, 2]) > 0
    # kinetic energy of the records equals 1/2 m v^2 of the recorded velocities
    from simulator.model import lumped_masses
    m = lumped_masses(model.mesh)
    ke = 0.5 * np.einsum("n,kni,kni->k", m, v[3:], v[3:])
    np.testing.assert_allclose(ke, dyn.columns["kinetic_energy [J]"], rtol=1e-9, atol=1e-30)
    res.save(tmp_path)
    assert np.load(tmp_path / "nodes.npz")["velocity"].shape == v.shape


def test_time_series_begins_on_the_start_state_of_the_time_domain_step(tmp_path):
    """single_fold_step_response: self-fold and gravity (quasi-static, no time), then the power
    step, whose first record is the state gravity left, at t = 0, increment 0 - no jump."""
    import pandas as pd

    case = get_case("single_fold_step_response", t_on=1e-3, t_off=1e-3)
    res = case.run()
    assert res.success, res.message
    et = res.steps[-1]
    assert (et.first_increment, et.increment_numbers[0]) == (0, 0)
    assert [s.first_increment for s in res.steps[:-1]] == [1, 1]
    start = len(res.history["stage"]) - et.increments           # record of the step's start
    time = res.history["columns"]["time [s]"]
    assert all(t is None for t in time[:start])                  # initial and quasi-static
    assert time[start] == 0.0 and all(t > 0 for t in time[start + 1:])
    np.testing.assert_array_equal(res.history["u"][start], res.history["u"][start - 1])
    np.testing.assert_array_equal(et.u_history[0], res.steps[-2].state.u)
    cols = et.columns
    assert cols["dt [s]"][0] is None and cols["heat_in [J]"][0] == 0.0
    assert cols["kinetic_energy [J]"][0] == 0.0                  # at rest after gravity
    np.testing.assert_allclose(np.diff(time[start:]), cols["dt [s]"][1:].astype(float))
    # the saved table: empty time before the step, and no jump between its first two rows
    res.save(tmp_path)
    df = pd.read_csv(tmp_path / "creases.csv")
    timed = df.dropna(subset=["time [s]"])
    assert df["time [s]"].isna().sum() == start * len(case.model.mesh.crease_ids)
    assert timed["step"].iloc[0] == start and timed["increment"].iloc[0] == 0
    assert timed["time [s]"].iloc[0] == 0.0
    before = df.loc[df["step"] == start - 1, "fold_angle [deg]"].to_numpy()
    assert timed["fold_angle [deg]"].iloc[0] == before[0]
    assert abs(timed["fold_angle [deg]"].iloc[1] - before[0]) < 0.01   # deg in 0.125 ms


def test_transient_heat_records_its_start_with_zero_heat():
    model = get_case("single_fold", thermal_steps=2).model
    res = simulate(model, [Heat({2: 1e-4}, increments=2),
                           TransientHeat({2: 1e-3}, duration=0.01, dt=5e-3)])
    assert res.success, res.message
    th = res.steps[1]
    np.testing.assert_array_equal(th.temperature_history[0], res.steps[0].state.temperature)
    assert th.columns["heat_in [J]"][0] == 0.0 and th.columns["heat_stored [J]"][0] == 0.0
    assert res.history["columns"]["time [s]"][:3] == [None, None, None]
    assert th.to_frame()["increment"].tolist() == [0, 1, 2]
