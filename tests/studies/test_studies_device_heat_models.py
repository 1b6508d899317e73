"""Study device_heat_models (issue 19 item 5): the devices with both heat-loss models, checked
against the 3-D FE. The quick run: gripper cycle 9, double fold, 2 x 2 Miura lifter, FE level 0."""

import json

import numpy as np
import pytest

from simulator import IntegralLoss, Substrate
from simulator.cases import get_case
from simulator.thermal import ThermalModel
from studies import device_heat_models as study

pytest.importorskip("skfem")
pytest.importorskip("gmsh")


@pytest.fixture(scope="module")
def quick(quick_study):
    return quick_study("device_heat_models")


def _table(df, name):
    return df[df["table"] == name]


def test_quick_run_writes_its_files_stamped_quick(quick):
    _, out, df = quick
    assert (out / "device_heat_models.png").is_file()
    meta = json.loads((out / "meta.json").read_text())
    assert meta["study"] == "device_heat_models" and meta["settings"]["quick"] is True
    assert {"gripper", "sweep", "fe", "comparison"} <= set(df["table"])


def test_chain_model_reproduces_the_descent_and_integral_differs(quick):
    g = _table(quick[2], "gripper")
    chain, integral = (g[g["model"] == m].iloc[0] for m in ("chain", "integral"))
    assert chain["success"] and integral["success"]
    assert chain["full_function_power [mW]"] == pytest.approx(chain["descent_power [mW]"],
                                                              abs=1e-9)
    assert chain["measured_power [mW]"] == 21.6
    assert integral["full_function_power [mW]"] < chain["full_function_power [mW]"]


def test_every_difference_over_10_percent_has_an_fe_verdict(quick):
    c = _table(quick[2], "comparison")
    over = c[c["over_10pct"].astype(bool)]
    assert len(over) and set(over["closer"]) <= {"chain", "integral"}
    assert not over["closer"].isna().any() and not over["basis"].isna().any()
    assert c[~c["over_10pct"].astype(bool)]["closer"].isna().all()
    assert set(c["case"]) == {"gripper cycle 9", "double_fold", "miura_lifter"}


def test_fe_rows_compare_both_models_on_the_same_shapes(quick):
    fe = _table(quick[2], "fe")
    assert set(fe["shape"]) == {"chain", "integral"} and (fe["fe_level"] == 0).all()
    room = 21.0
    for m in ("chain", "integral"):
        err = 100 * ((fe[f"{m}_temperature [degC]"] - room)
                     / (fe["fe_temperature [degC]"] - room) - 1)
        assert np.allclose(err, fe[f"{m}_error [%]"])
    # the direction docs/heat_fe.md reports: the chains run cooler than the FE on these shapes
    assert (fe["chain_error [%]"] < 0).all()


def test_the_integral_model_stands_on_the_boundary_panels_plane():
    model = get_case("double_fold", thermal_steps=1).model
    thermal = study.integral_model(model, refinement=3).thermal
    assert thermal.loss == IntegralLoss(refinement=3) and thermal.substrate == Substrate()
    plane = ThermalModel(model.mesh, thermal).plane
    assert plane[0][2] == pytest.approx(-60e-6) and np.allclose(plane[1], (0, 0, 1))
    crane = get_case("crane", thermal_steps=1).model
    assert ThermalModel(crane.mesh, study.integral_model(crane).thermal).plane is None


def test_figure_redraws_from_the_csv(quick):
    from matplotlib.figure import Figure

    assert isinstance(study.plot(quick[2]), Figure)


class _Failed:
    """A simulation result that says it failed (the rest is the real result's)."""

    success, message = False, "Heat: Newton did not converge (test)"

    def __init__(self, res):
        self._res = res

    def __getattr__(self, name):
        return getattr(self._res, name)


def test_a_failing_model_is_a_row_not_an_exception(monkeypatch):
    case = get_case("double_fold", thermal_steps=2)
    monkeypatch.setattr(study, "_cases", lambda quick: {"double_fold": case})
    real = study.simulate

    def simulate(model, steps, **kw):
        res = real(model, steps, **kw)
        return _Failed(res) if model.thermal.loss.model == "integral" else res

    monkeypatch.setattr(study, "simulate", simulate)
    sweeps, fe, comparison = study._run_cases(True, 0, False)
    assert fe.empty and set(sweeps["model"]) == {"chain", "integral"}
    row = comparison.iloc[0]
    assert len(comparison) == 1 and row["quantity"] == "run" and row["over_10pct"] is None
    assert row["message"] == "the integral model failed: Heat: Newton did not converge (test)"


def test_no_verdict_without_both_values():
    row = study._verdict("gripper cycle 4", "full-function power", "mW",
                         {"chain": 42.4, "integral": None}, None, None, "")
    assert row["over_10pct"] is None and "closer" not in row
