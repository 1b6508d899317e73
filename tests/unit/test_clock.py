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
    np.testing.assert_allclose(t1, [0.005, 0.01])
    np.testing.assert_allclose(t2, [0.015, 0.02])
    np.testing.assert_allclose(t3, [0.0201, 0.0202])
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
    from simulator import lumped_masses
    m = lumped_masses(model.mesh)
    ke = 0.5 * np.einsum("n,kni,kni->k", m, v[3:], v[3:])
    np.testing.assert_allclose(ke, dyn.columns["kinetic_energy [J]"], rtol=1e-9, atol=1e-30)
    res.save(tmp_path)
    assert np.load(tmp_path / "nodes.npz")["velocity"].shape == v.shape
