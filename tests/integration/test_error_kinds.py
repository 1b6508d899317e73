"""ParameterError is for bad input only; numerical failures raise SolverError or
ConvergenceError. And Heat's coupling settings are its own fields (no public Coupling)."""

import types

import numpy as np
import pytest

import simulator
from simulator import (ChainLoss, ConvergenceError, EtorigamiError, Heat, ParameterError,
                       SolverError, ThermalParameters, simulate)
from simulator.steps import initial_state
from simulator.cases import single_fold_model
from simulator.thermal import thermal_model

ACTUATORS = simulator.Actuators(simulator.Bimorph(79e9, 0.2e-6, 2e9, 0.8e-6), {2: 3.8e-5})


def test_solver_error_is_not_an_input_error():
    assert issubclass(SolverError, EtorigamiError) and issubclass(SolverError, RuntimeError)
    assert not issubclass(SolverError, ValueError)
    assert "SolverError" in simulator.__all__


def test_failed_lapack_thermal_solve_is_a_solver_error(monkeypatch):
    from simulator.linalg.small_solve import DenseFactor

    model = single_fold_model(thermal=ThermalParameters(loss=ChainLoss(thickness=1e-3)))
    tm = thermal_model(model)
    x = model.mesh.nodes
    q = tm.heat_vector(np.full(model.mesh.n_creases, 1e-3))
    good = tm.solve(x, q)
    monkeypatch.setattr(DenseFactor, "solve_info", lambda self, b: (b, 3))   # the dense rung
    with pytest.raises(SolverError, match="LAPACK dpotrs info 3"):
        thermal_model(single_fold_model(
            thermal=ThermalParameters(loss=ChainLoss(thickness=1e-3)))).solve(x, q)
    assert np.all(np.isfinite(good))


def test_failed_sensitivity_solve_is_a_convergence_error(monkeypatch):
    import design.analysis._heater_lp as lp

    failed = types.SimpleNamespace(success=False, message="no convergence in 30 iterations")
    monkeypatch.setattr(lp, "solve_equilibrium", lambda *args, **kwargs: failed)
    model = single_fold_model(contact=False, substrate=False)
    with pytest.raises(ConvergenceError, match="equilibrium not found") as err:
        lp.fold_sensitivity(model, initial_state(model))
    assert err.value.result is failed and not isinstance(err.value, ParameterError)


def test_unsolved_allocation_lp_is_a_solver_error(monkeypatch):
    import design.analysis._heater_lp as lp

    monkeypatch.setattr(lp, "solve_lp", lambda *args: (None, None, "infeasible"))
    monkeypatch.setattr(lp, "linear_model", lambda model, state, table, rows:
                        (np.eye(1), np.ones((7, 1)), np.zeros(1)))
    monkeypatch.setattr(lp, "check_targets", lambda model, targets, rot: [0])
    model = single_fold_model(thermal=ThermalParameters(loss=ChainLoss(thickness=1e-3)),
                              actuators=ACTUATORS)
    with pytest.raises(SolverError, match=r"LP not solved \(infeasible\)"):
        lp.linear_allocation(model, {2: 0.3})


# ------------------------------------------------------------------ Coupling
def test_coupling_is_not_public():
    assert "Coupling" not in simulator.__all__ and "Coupling" not in simulator.steps.__all__
    with pytest.raises(AttributeError):
        simulator.Coupling  # noqa: B018


def test_heat_takes_its_coupling_settings_as_fields():
    model = single_fold_model(thermal=ThermalParameters(loss=ChainLoss(thickness=1e-3)),
                              actuators=ACTUATORS)
    staggered = simulate(model, [Heat({2: 2e-3}, increments=3)])
    iterated = simulate(model, [Heat({2: 2e-3}, increments=3, coupling="iterated",
                                     coupling_tol=1e-9, max_coupling_iterations=30)])
    assert staggered.success and iterated.success
    assert iterated.steps[0].settings["coupling"] == "iterated"
    # temperatures on the final shape: iterating changes the answer a little, not much
    assert np.allclose(staggered.fold_angle[-1], iterated.fold_angle[-1], atol=1e-2)


@pytest.mark.parametrize("kwargs, match", [
    ({"coupling": object()}, r"Heat.coupling = .* must be one of 'staggered', 'iterated', 'settled'; "
                             r"the tolerance .* coupling_tol and max_coupling_iterations"),
    ({"coupling_tol": 0.0}, r"Heat.coupling_tol = 0.0 must be a finite number > 0 \[K\]"),
    ({"max_coupling_iterations": 0}, r"Heat.max_coupling_iterations = 0 must be a positive"),
])
def test_heat_coupling_settings_are_checked(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        Heat({2: 1e-3}, **kwargs)
