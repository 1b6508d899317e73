"""Natural modes: solvers, zero modes, states, files, plots and bad inputs."""

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from simulator import (Gravity, ParameterError, SelfFold, Supports, make_model, natural_modes,
                       simulate)
from simulator.steps import initial_state
from simulator.cases import single_fold_model
from simulator.geometry.example_patterns import miura_sheet_pattern
from design.cli._plots import plot_mode_shape, save_mode_plots


@pytest.fixture(scope="module")
def fold():
    return single_fold_model(contact=False, substrate=False)


@pytest.fixture(scope="module")
def miura():
    model = make_model(miura_sheet_pattern(m=3, n=3))
    return make_model(model.mesh, Supports.nodes(model.mesh.panel_nodes(0)))


def test_dense_and_shift_invert_agree_and_are_mass_orthonormal(miura):
    dense = natural_modes(miura, count=8, method="dense")
    sparse = natural_modes(miura, count=8, method="sparse")
    assert dense.success and sparse.success
    assert (dense.solver, sparse.solver) == ("dense", "shift-invert")
    # the dense solver's absolute error in omega^2 is ~eps * omega_max^2 (stiff crease bars:
    # ~0.1 (rad/s)^2 here), i.e. ~2e-6 relative on the lowest frequency
    np.testing.assert_allclose(sparse.frequency, dense.frequency, rtol=1e-5)
    assert np.all(np.diff(dense.frequency) >= 0) and not dense.zero_mode.any()
    m3 = np.repeat(dense.masses, 3)
    for res in (dense, sparse):
        phi = res.shapes.reshape(res.count, -1)
        np.testing.assert_allclose(phi @ (m3 * phi).T, np.eye(res.count), atol=1e-6)
    fixed = miura.fixed_mask
    assert np.all(dense.shapes[:, fixed] == 0)


def test_unsupported_structure_has_six_rigid_body_modes(fold):
    free = make_model(fold.mesh, None)
    for method in ("dense", "sparse"):
        res = natural_modes(free, count=8, method=method)
        assert res.zero_mode.tolist() == [True] * 6 + [False] * 2
        assert np.all(res.frequency[:6] == 0) and res.frequency[6] > 10
        assert "6 zero-frequency" in res.message


def test_modes_about_a_folded_state_under_gravity(fold):
    """Folded upright (90 deg), the panel under gravity is an inverted pendulum: linearising
    about that state lowers omega^2 by about m g h / I (h height of the panel's mass centre
    and I its inertia about the crease centre line)."""
    upright = simulate(fold, [SelfFold({2: np.pi / 2}, increments=10)]).state
    loaded = simulate(fold, [Gravity(g=9.8, panels=[1], increments=5)], state=upright).state
    f_up = natural_modes(fold, upright, count=2)
    f_g = natural_modes(fold, loaded, count=2)
    assert f_g.success and not f_g.zero_mode.any()
    mesh, panel = fold.mesh, fold.mesh.panel_nodes(1)
    m = f_g.masses[panel]
    x = (mesh.nodes + upright.u)[panel] - mesh.nodes[mesh.crease_nodes[0, 6]]
    inertia, mgh = np.sum(m * np.sum(x**2, axis=1)), 9.8 * np.sum(m * x[:, 2])
    predicted = np.sqrt((2 * np.pi * f_up.frequency[0]) ** 2 - mgh / inertia) / (2 * np.pi)
    assert f_g.frequency[0] < 0.9 * f_up.frequency[0]
    assert f_g.frequency[0] == pytest.approx(predicted, rel=0.05)


def test_save_writes_modes_csv_and_shapes(fold, tmp_path):
    res = natural_modes(fold, count=4)
    out = res.save(tmp_path / "modes")
    df = pd.read_csv(out / "modes.csv")
    assert list(df.columns[:2]) == ["mode", "frequency [Hz]"]
    assert df["mode"].tolist() == [1, 2, 3, 4]
    np.testing.assert_allclose(df["frequency [Hz]"], res.frequency)
    with np.load(out / "modes.npz") as npz:
        assert npz["shapes"].shape == (4, fold.mesh.n_nodes, 3)
    assert (out / "meta.json").exists()


def test_mode_shape_plots(fold, tmp_path):
    res = natural_modes(fold, count=2)
    assert isinstance(plot_mode_shape(res, 1), Figure)
    paths = save_mode_plots(res, tmp_path, count=2)
    assert [p.name for p in paths] == ["modes.png", "mode_1.png", "mode_2.png"]
    assert all(p.stat().st_size > 0 for p in paths)


def test_bad_inputs_are_clear_errors(fold):
    for count in (0, -3, 2.5, 10**6):
        with pytest.raises(ParameterError, match="count"):
            natural_modes(fold, count=count)
    with pytest.raises(ParameterError, match="method"):
        natural_modes(fold, method="lanczos")
    with pytest.raises(ParameterError, match="SimulationState"):
        natural_modes(fold, state=initial_state(fold).u)
    with pytest.raises(ParameterError, match="make_model"):
        natural_modes(fold.mesh)


def test_shift_invert_in_nested_dissection_order_finds_the_same_modes(miura, monkeypatch):
    from simulator.linalg import ladder, linsolve, pardiso, thresholds

    monkeypatch.setattr(pardiso, "_library", ())            # the SuperLU path
    ref = natural_modes(miura, count=6, method="sparse")
    used = []
    original = linsolve.nd_factors
    monkeypatch.setattr(thresholds, "ND_LIMIT", 10)
    monkeypatch.setattr(linsolve, "nd_factors", lambda A: used.append(original(A)) or used[-1])
    nd = natural_modes(miura, count=6, method="sparse")
    assert used and used[0] is not None and nd.success
    assert ladder.last_backend() == "superlu-nd"
    np.testing.assert_allclose(nd.frequency, ref.frequency, rtol=1e-9)


def test_a_moving_state_is_not_an_equilibrium(fold, tmp_path, caplog):
    """Half a swing after a sudden fold the panel is far from rest: the modes about that state
    say so (also in meta.json); the flat state before it is an equilibrium."""
    import json
    import logging

    from simulator import Dynamics
    from simulator.solvers import check_equilibrium

    flat = natural_modes(fold, count=2)
    assert flat.status == "converged" and flat.equilibrium.in_equilibrium
    assert flat.residual_norm < 1e-15                           # [N] unloaded: exactly 0
    T = 1 / flat.frequency[0]
    moving = simulate(fold, [Dynamics(duration=T / 4, dt=T / 40, folds={2: 0.2})]).state
    check = check_equilibrium(fold, moving)
    assert not check.in_equilibrium and check.status == "not in equilibrium"
    with caplog.at_level(logging.WARNING, logger="simulator"):
        res = natural_modes(fold, moving, count=2)
    assert res.status == "not in equilibrium" and res.success
    assert any("natural_modes" in r.getMessage() for r in caplog.records)
    meta = json.loads((res.save(tmp_path) / "meta.json").read_text())
    assert meta["status"] == "not in equilibrium"
    assert meta["equilibrium"]["in_equilibrium"] is False
    assert meta["equilibrium"]["residual_norm [N]"] == pytest.approx(check.residual_norm)
    with pytest.raises(ParameterError, match="tolerance = 0"):
        check_equilibrium(fold, moving, tolerance=0)
