"""One result interface: every public result type has success, status, message, to_frame()
and save(directory) (CSV + meta.json)."""

import json
import math

import numpy as np
import pandas as pd
import pytest

import design
import simulator
from doors import public_names
from simulator import SelfFold, simulate
from simulator.cases import single_fold_model
from simulator.solvers import Stability


@pytest.fixture(scope="module")
def run():
    """A short self-fold of the single fold and its modes."""
    model = single_fold_model()
    res = simulate(model, [SelfFold({2: 0.5}, increments=3)])
    return model, res


def _u(n=4):
    return np.zeros((n, 3))


def _stage(success=True):
    return design.StageResult(success, "met" if success else "not_met",
                              "criterion met" if success else "power cap",
                              1e-3 if success else None, 0.1, 80.0, 90.0, 3, 30)


def _results(run):
    model, res = run
    stab = Stability(0, 12.5, np.ones(3) / math.sqrt(3))
    yield "SimulationResult", res
    yield "StepResult", res.steps[0]
    yield "ContinuationResult", simulator.solvers.ContinuationResult(
        True, "converged", "target reached", _u(), 1.0, 5, 0,
        history=[(0.5, _u(), 3), (1.0, _u() + 1e-6, 2)], stability=[stab, stab],
        temperatures=[None, np.full(4, 30.0)],
        critical_points=(simulator.solvers.CriticalPoint("limit_point", 0.7, 1),))
    yield "DynamicsResult", simulator.solvers.DynamicsResult(
        True, "converged", "reached the end", np.array([0.0, 1e-3]), np.zeros((2, 4, 3)),
        np.zeros((2, 4, 3)), np.zeros((2, 4, 3)), np.zeros(2), np.zeros(2), np.zeros(2),
        np.zeros(2), np.array([0, 2]), 0, None)
    yield "TransientHeatResult", simulator.thermal.TransientHeatResult(
        True, "converged", "reached t_end", np.array([0.0, 0.1]), np.full((2, 4), 21.0),
        np.zeros((2, 1)), np.zeros(2), np.zeros(2), np.zeros(2), np.full(8, 21.0), 0.1, 2 / 3,
        1, 1)
    yield "ModesResult", simulator.natural_modes(model, res.state, count=3)
    yield "Stability", stab
    yield "Evaluation", design.Evaluation({"W": 2e-4}, 1.5, {"T": -1.0}, {"power [mW]": 3.0})
    yield "OptimizationResult", design.OptimizationResult(
        "cd", {"W": 2e-4}, 1.5, {"T": -1.0}, True, "converged", "converged", 2, 2, 0, 0.1,
        pd.DataFrame({"x.W": [2e-4, 2.1e-4], "objective": [1.5, 1.6]}), None)
    yield "StageResult", _stage()
    yield "GripperResult", design.GripperResult(design.GripperDesign(), "bisect", _stage(),
                                                _stage(False))
    yield "LiftPowerResult", design.LiftPowerResult(True, "met", "lifted", 2e-3, 8e-3, 5e-5,
                                                    60.0, 4, 4)
    yield "HeaterAllocation", design.HeaterAllocation(
        True, "converged", "targets met", {"h1": (2,)}, np.array([1e-3]), 2, {2: 0.3},
        achieved={2: 0.3}, max_temperature=60.0, temperature_limit=200.0,
        history=({"round": 1, "total_power [mW]": 1.0},))
    yield "TemperatureVerdict", simulator.thermal.TemperatureVerdict(
        simulator.thermal.TemperatureLimit(252.0, "1.2 T_g"), 5, 250.06, 266.67, 5)


NAMES = ["SimulationResult", "StepResult", "ContinuationResult", "DynamicsResult",
         "TransientHeatResult", "ModesResult", "Stability", "Evaluation", "OptimizationResult",
         "StageResult", "GripperResult", "LiftPowerResult", "HeaterAllocation",
         "TemperatureVerdict"]


def test_every_public_result_type_is_covered(run):
    assert [name for name, _ in _results(run)] == NAMES
    for name in NAMES:               # each is a public name of its package's door or namespaces
        assert name in public_names(simulator) or name in public_names(design), name


@pytest.mark.parametrize("name", NAMES)
def test_result_interface(run, name, tmp_path):
    result = dict(_results(run))[name]
    assert isinstance(result.success, (bool, np.bool_))
    assert isinstance(result.status, str) and result.status
    assert isinstance(result.message, str)
    frame = result.to_frame()
    assert isinstance(frame, pd.DataFrame) and len(frame) >= 1 and len(frame.columns) >= 2
    out = result.save(tmp_path / name)
    assert out == tmp_path / name
    meta = json.loads((out / "meta.json").read_text())
    assert meta["status"] == result.status and meta["message"] == result.message
    assert "etorigami_version" in meta
    csvs = sorted(out.glob("*.csv"))
    assert csvs, "save() wrote no table"
    first = pd.read_csv(csvs[0]) if name != "OptimizationResult" else \
        pd.read_csv(out / "history.csv")
    assert len(first) >= 1


def test_step_result_table_has_one_row_per_increment(run):
    _, res = run
    step = res.steps[0]
    frame = step.to_frame()
    assert step.increments >= 3                  # 3 nominal increments, maybe cut
    assert list(frame["increment"]) == list(range(1, step.increments + 1))
    np.testing.assert_array_equal(frame["load_factor"], step.load_factor)
    np.testing.assert_array_equal(frame["iterations"], step.increment_iterations)
    assert (frame["power [mW]"] == 0).all()


def test_continuation_table_and_meta(run, tmp_path):
    result = dict(_results(run))["ContinuationResult"]
    frame = result.to_frame()
    assert list(frame["load_factor"]) == [0.5, 1.0]
    assert list(frame["stable"]) == [True, True]
    assert frame["max_displacement [m]"].iloc[1] == pytest.approx(math.sqrt(3) * 1e-6)
    assert frame["max_temperature [degC]"].isna().iloc[0]
    meta = json.loads((result.save(tmp_path) / "meta.json").read_text())
    assert meta["critical_points"][0]["kind"] == "limit_point"
    assert meta["result"] == "ContinuationResult" and meta["tables"] == ["path.csv"]


def test_stability_outcome_words():
    stable, unstable = Stability(0, 1.0, np.ones(1)), Stability(2, -3.0, np.ones(1), False)
    assert (stable.success, stable.status) == (True, "stable")
    assert unstable.status == "unstable" and "at least 2 negative" in unstable.message
    assert unstable.to_frame().loc[0, "negative_eigenvalues"] == 2


def test_modes_save_keeps_its_arrays(run, tmp_path):
    modes = dict(_results(run))["ModesResult"]
    out = modes.save(tmp_path)
    assert {p.name for p in out.iterdir()} == {"modes.csv", "modes.npz", "meta.json"}
    meta = json.loads((out / "meta.json").read_text())
    assert meta["count"] == 3 and meta["solver"] == modes.solver


def test_unmet_values_are_empty_in_csv(tmp_path):
    stage = _stage(False)
    stage.save(tmp_path)
    row = pd.read_csv(tmp_path / "stage.csv")
    assert row["power_per_crease [mW]"].isna().all()
    assert not row["success"].iloc[0]
