"""The sensitivity report of fabrication tolerances (design.analysis.tolerance_report): the
table is the exact gradients times the tolerances, the first-order (FOSM) spread and
probabilities follow from it, and a Monte Carlo run of full simulations of the double fold
agrees with them within its own sampling error.

Tolerances of the Monte Carlo check: the sample standard deviation's chi-square interval and
the fraction's Wilson interval at confidence 0.999 (a correct first-order value falls outside
with probability 1e-3 per output); the linearisation's own error, sample by sample, must stay
below the sampling error of the standard deviation, ``sigma / sqrt(2 (n - 1))``, so that the
comparison tests the gradients and not the model's curvature.
"""

from __future__ import annotations

import dataclasses
import io
import math

import numpy as np
import pandas as pd
import pytest
from scipy.stats import norm

from design import SensitivityReport, sensitivity_report
from design.analysis import monte_carlo_comparison, perturbed_protocol, plot_tornado
from simulator import Heat, ParameterError, SelfFold, simulate
from simulator.cases import get_case
from simulator.sensitivity import FoldAngle, differentiate

CONFIDENCE = 0.999
N_SAMPLES = 60
#: 1-sigma tolerances [SI]: small enough that the double fold responds nearly linearly.
TOLERANCES = {"power[2]": 1e-4, "power[5]": 1.2e-4, "rest_offset[2]": math.radians(0.5),
              "rest_offset[5]": math.radians(0.5), "delta_alpha[5]": 0.02 * 38e-6,
              "t1": 0.02 * 0.2e-6, "t2": 0.02 * 0.9e-6, "medium_conductivity": 0.03 * 0.026}


def _steps():
    gravity = get_case("double_fold").steps[1]
    return [SelfFold({2: 0.0, 5: 0.0}, increments=10),
            dataclasses.replace(gravity, increments=10),
            Heat({2: 0.01, 5: 0.012}, increments=5, coupling="settled")]


@pytest.fixture(scope="module")
def heated():
    model = get_case("double_fold").model
    result = simulate(model, _steps())
    assert result.success, result.message
    return result


@pytest.fixture(scope="module")
def report(heated):
    plain = sensitivity_report(heated, TOLERANCES)
    y, s = plain.values, plain.sigma
    return sensitivity_report(heated, TOLERANCES, limits={
        "fold_5": (y["fold_5"] - 0.5 * s["fold_5"], None),
        "temperature_5": (None, y["temperature_5"] + s["temperature_5"])})


def test_table_is_the_gradients_times_the_tolerances_largest_first(heated, report):
    assert report.success and report.status == "converged", report.message
    assert set(report.outputs) == {"fold_2", "fold_5", "temperature_2", "temperature_5"}
    exact = differentiate(heated, FoldAngle(5), ("power", "rest_offset", "delta_alpha",
                                                 "bimorph", "medium_conductivity"))
    df = report.to_frame(sort_by="fold_5")
    col = "d fold_5 [deg] per tolerance"
    assert report.column("fold_5") == col
    effect = dict(zip(df["parameter"], df[col]))
    for p, t in TOLERANCES.items():
        assert effect[p] == pytest.approx(math.degrees(exact.gradient[p] * t), rel=1e-6)
    assert list(df[col].abs()) == sorted(df[col].abs(), reverse=True)
    assert df["fold_5 variance share [-]"].sum() == pytest.approx(1.0, rel=1e-12)
    assert report.sigma["fold_5"] == pytest.approx(
        math.radians(math.sqrt((df[col] ** 2).sum())), rel=1e-12)
    row = df.set_index("parameter").loc["power[5]"]
    assert (row["unit"], row["nominal"], row["tolerance"]) == ("mW", pytest.approx(12.0),
                                                               pytest.approx(0.12))
    assert df.set_index("parameter").loc["t1", "unit"] == "um"


def test_first_order_probabilities_are_the_normal_ones(report):
    s, y = report.sigma, report.values
    assert report.probability["fold_5"] == pytest.approx(norm.cdf(0.5), rel=1e-9)
    assert report.probability["temperature_5"] == pytest.approx(norm.cdf(1.0), rel=1e-9)
    both = report.probability_all
    p = report.probability
    assert max(0.0, p["fold_5"] + p["temperature_5"] - 1) <= both <= min(p.values())
    # the hotter crease folds more: the two outputs are positively correlated, so meeting
    # "fold high" and "temperature low" together is rarer than if they were independent
    assert both < p["fold_5"] * p["temperature_5"]
    summary = report.summary().set_index("output")
    assert summary.loc["fold_5", "low"] == pytest.approx(
        math.degrees(y["fold_5"] - 0.5 * s["fold_5"]))
    assert summary.loc["temperature_5", "unit"] == "degC"
    assert summary.loc["all limits", "P(meet) (FOSM) [-]"] == both


def test_monte_carlo_agrees_with_first_order_within_its_sampling_error(report):
    mc = monte_carlo_comparison(report, _steps(), n_samples=N_SAMPLES, seed=7,
                                confidence=CONFIDENCE)
    assert mc.success and mc.n_failed == 0, mc.message
    table = mc.table.set_index("output")
    n = N_SAMPLES
    for o in report.outputs:
        row = table.loc[o]
        assert row["sigma_low (MC)"] <= row["sigma (FOSM)"] <= row["sigma_high (MC)"], o
        # the interval is narrow enough to reject a first-order spread off by half
        assert not row["sigma_low (MC)"] <= 1.5 * row["sigma (FOSM)"] <= \
            row["sigma_high (MC)"], o
        assert row["linearisation error (rms)"] <= row["sigma (FOSM)"] / math.sqrt(2 * (n - 1))
        assert abs(row["mean (MC)"] - row["nominal"]) <= \
            norm.ppf(0.5 + CONFIDENCE / 2) * row["sigma (FOSM)"] / math.sqrt(n)
    for o in ("fold_5", "temperature_5", "all limits"):
        row = table.loc[o]
        assert row["P_low (MC) [-]"] <= row["P(meet) (FOSM) [-]"] <= row["P_high (MC) [-]"], o
    samples = mc.samples
    assert len(samples) == n and samples["success"].all()
    assert samples["d power[5] [mW]"].std() == pytest.approx(0.12, rel=0.5)


def test_samples_are_seeded(report):
    a = monte_carlo_comparison(report, _steps(), n_samples=3, seed=3)
    b = monte_carlo_comparison(report, _steps(), n_samples=3, seed=3)
    pd.testing.assert_frame_equal(a.samples, b.samples)
    c = monte_carlo_comparison(report, _steps(), n_samples=3, seed=4)
    assert not np.allclose(a.samples["d t1 [um]"], c.samples["d t1 [um]"])


def test_perturbed_protocol_moves_each_parameter():
    model = get_case("double_fold").model
    steps = [SelfFold({2: 0.1}, increments=10), Heat({(2, 5): 0.01}, increments=5)]
    new, new_steps = perturbed_protocol(model, steps, {
        "power[5]": 1e-3, "rest_offset[5]": 0.05, "rest_offset[2]": 0.01,
        "delta_alpha[2]": 1e-6, "t1": 1e-8, "E2": 1e8, "medium_conductivity": 0.002})
    assert new_steps[1].power == {2: 0.01, 5: 0.011}
    assert new_steps[0].folds == pytest.approx({2: 0.11, 5: 0.05})
    assert new.actuators.delta_alpha[2] == pytest.approx(39e-6)
    assert new.actuators.delta_alpha[5] == pytest.approx(38e-6)
    assert new.actuators.bimorph.t1 == pytest.approx(0.21e-6)
    assert new.actuators.bimorph.E2 == pytest.approx(2.1e9)
    assert new.thermal.medium.thermal_conductivity == pytest.approx(0.028)
    assert steps[1].power == {(2, 5): 0.01} and model.actuators.bimorph.t1 == 0.2e-6
    with pytest.raises(ParameterError, match="rest_offset needs a SelfFold"):
        perturbed_protocol(model, steps[1:], {"rest_offset[2]": 0.01})
    with pytest.raises(ParameterError, match="must be a Heat step"):
        perturbed_protocol(model, steps, {}, heat_step=0)


def test_bad_input_is_refused_naming_the_field(heated):
    with pytest.raises(ParameterError, match="unknown parameter 'power_2'"):
        sensitivity_report(heated, {"power_2": 1e-4})
    with pytest.raises(ParameterError, match=r"tolerances\['t1'\] = -1e-08"):
        sensitivity_report(heated, {"t1": -1e-8})
    with pytest.raises(ParameterError, match=r"\['power\[9\]'\] are not parameters"):
        sensitivity_report(heated, {"power[9]": 1e-4})
    with pytest.raises(ParameterError, match="'fold_3' is not an output"):
        sensitivity_report(heated, {"t1": 1e-8}, limits={"fold_3": (0.1, None)})
    with pytest.raises(ParameterError, match="give low < high"):
        sensitivity_report(heated, {"t1": 1e-8}, limits={"fold_5": (1.0, 0.5)})
    with pytest.raises(ParameterError, match="n_samples = 2"):
        monte_carlo_comparison(sensitivity_report(heated, {"t1": 1e-8}), _steps(),
                               n_samples=2)


def test_a_state_that_is_not_steady_is_reported_not_raised():
    model = get_case("double_fold").model
    steps = [*_steps()[:2], Heat({2: 0.01, 5: 0.012}, increments=5, coupling="staggered")]
    report = sensitivity_report(simulate(model, steps), {"power[5]": 1e-4})
    assert not report.success and report.status == "not_steady"
    assert report.message.startswith("fold_2: the state does not solve the heat balance")
    with pytest.raises(ParameterError, match="result = dict: give the SimulationResult"):
        sensitivity_report({}, {"power[5]": 1e-4})
    with pytest.raises(ParameterError, match="step = 7; the result has 3 steps"):
        sensitivity_report(simulate(model, steps), {"power[5]": 1e-4}, step=7)


def test_integral_loss_report_is_the_adjoint_gradient_times_the_tolerance():
    """With the integral heat loss (differentiated since theory 12.6) the report's spread of
    a single tolerance is the gradient times it, and it names the first output's status."""
    case = get_case("double_fold", loss_model="integral")
    steps = [SelfFold({2: 0.0, 5: 0.0}, increments=5),
             Heat({2: 0.005}, increments=2, coupling="settled")]
    result = simulate(case.model, steps)
    report = sensitivity_report(result, {"power[2]": 1e-4})
    assert report.status == "converged"
    g = differentiate(result, FoldAngle(2), "power")
    assert g.success and g.gradient["power[2]"] > 0
    assert report.sigma["fold_2"] == pytest.approx(abs(g.gradient["power[2]"]) * 1e-4,
                                                   rel=1e-12)


def test_tornado_puts_the_largest_effect_on_top_and_names_the_physics(report):
    fig = plot_tornado(report, ["fold_5", "temperature_5"], mc_sigma={"fold_5": 1.0})
    ax = fig.axes[0]
    labels = [t.get_text().split(" ")[0] for t in ax.get_yticklabels()]
    ticks = list(ax.get_yticks())
    top = labels[int(np.argmax(ticks))]
    assert top == report.to_frame(sort_by="fold_5")["parameter"][0]
    footer = " ".join(t.get_text() for t in fig.texts)
    assert "heat loss: chain model" in footer and "medium: air" in footer
    assert "Monte Carlo sigma 1 deg" in ax.get_title()
    # from the table read back from a CSV, with the physics given
    csv = io.StringIO(report.to_frame().to_csv(index=False))
    fig = plot_tornado(pd.read_csv(csv), footer="heat loss: x; medium: y")
    assert len(fig.axes) == 4
    with pytest.raises(ValueError, match="the table has"):
        plot_tornado(report, ["fold_9"])


def test_report_is_a_frozen_result(report):
    assert isinstance(report, SensitivityReport)
    with pytest.raises(dataclasses.FrozenInstanceError):
        report.status = "x"
    cov = report.covariance()
    names = list(report.outputs)
    i = names.index("fold_5")
    assert cov[i, i] == pytest.approx(report.sigma["fold_5"] ** 2, rel=1e-12)


def test_a_problem_at_a_design_point_reports_its_constraints():
    """FoldTargetProblem: the outputs and limits are its constraints, and the report's
    gradients are its constraint gradients unscaled (g = sign (output - bound) / bound)."""
    from design.analysis import problem_sensitivity_report
    from design.devices import FoldTargetProblem

    targets = {2: math.radians(30), 5: math.radians(80)}
    problem = FoldTargetProblem(targets, temperature_limit=250.0)
    x = [0.01, 0.012]
    report = problem_sensitivity_report(problem, x, {"power[2]": 1e-4, "power[5]": 1e-4,
                                                     "t2": 1e-8})
    assert report.success, report.message
    assert report.limits == {"fold_2": (targets[2], None), "fold_5": (targets[5], None),
                             "temperature_2": (None, 250.0), "temperature_5": (None, 250.0)}
    ev = problem.evaluate_with_gradient(x)
    for name, grads in ev.constraint_gradients.items():
        c = int(name.rsplit("_", 1)[1])
        scale = -targets[c] if name.startswith("fold") else 250.0
        for k in problem.creases:
            assert report.gradients[name][f"power[{k}]"] == pytest.approx(
                grads[f"power_{k}"] * scale, rel=1e-9)
    mc = monte_carlo_comparison(report, problem.steps(x), n_samples=3, seed=0)
    assert mc.success and mc.n_failed == 0
    with pytest.raises(ParameterError, match="has no simulate, outputs, limits"):
        problem_sensitivity_report(object(), x, {"t2": 1e-8})
