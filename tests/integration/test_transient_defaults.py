"""Time-domain defaults that cannot go below ambient (issue 21, item 7): the default scheme is
backward Euler (L-stable), theta = 2/3 stays available for reference comparisons; the docs'
time-domain example (docs/time-domain.md) never reports a temperature below room temperature; ``power [mW]`` is the
value at the record and ``mean_power [mW]`` the mean over the step; time 0 on the first
record."""

import pathlib
import re

import numpy as np
import pytest

from simulator import ElectroThermal, TransientHeat, get_case, simulate
from simulator.schedules import SquareWave
from simulator.thermal import DEFAULT_THETA, REFERENCE_THETA, integrate_heat

PAGE = pathlib.Path(__file__).resolve().parents[2] / "docs" / "time-domain.md"


def _docs_time_domain_example() -> str:
    text = PAGE.read_text(encoding="utf-8")
    section = text[text.index("## Time domain"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_docs_time_domain_example_never_goes_below_21_degc(capsys):
    code = _docs_time_domain_example()
    assert "TransientHeat" in code and "SquareWave" in code
    namespace = {}
    exec(compile(code, "time-domain.md (time domain)", "exec"), namespace)      # the example itself
    res = namespace["res"]
    frame = res.to_frame()
    assert frame["temperature [degC]"].min() >= 21.0
    assert res.history["temperature"].min() >= 21.0                      # every node
    assert "time [s]" in capsys.readouterr().out


def test_reference_theta_is_the_one_that_dips_below_room_temperature():
    """Why the default changed: theta = 2/3 on the same example undershoots."""
    model = get_case("single_fold").model
    res = simulate(model, [TransientHeat({2: SquareWave(10e-3, period=0.01, duty=0.5)},
                                         duration=0.03, dt=1e-3, theta=REFERENCE_THETA)])
    assert res.history["temperature"].min() < 21.0 - 0.5


def test_defaults_are_backward_euler():
    assert DEFAULT_THETA == 1.0 and REFERENCE_THETA == pytest.approx(2 / 3)
    assert TransientHeat({2: 1e-3}).theta == DEFAULT_THETA
    assert ElectroThermal({2: 1e-3}).theta == DEFAULT_THETA
    assert integrate_heat.__defaults__[0] == DEFAULT_THETA


def test_power_column_is_the_value_at_the_record_and_mean_power_the_step_mean():
    model = get_case("single_fold").model
    wave = SquareWave(10e-3, period=0.01, duty=0.5)                  # on 0-5 ms, off 5-10 ms
    res = simulate(model, [TransientHeat({2: wave}, duration=0.01, dt=1e-3)])
    f = res.to_frame()
    row = f[np.isclose(f["time [s]"], 0.005)].iloc[0]
    assert row["power [mW]"] == 0.0                    # switched off at 5 ms: value there
    assert row["mean_power [mW]"] == pytest.approx(10.0)   # it heated from 4 to 5 ms
    half = SquareWave(10e-3, period=2e-3, duty=0.5)       # on 1 ms of every 2 ms
    res = simulate(model, [TransientHeat({2: half}, duration=4e-3, dt=2e-3)])
    means = res.to_frame()["mean_power [mW]"].dropna()
    np.testing.assert_allclose(means, 5.0)             # the exact mean over each step


def test_first_record_has_time_zero():
    model = get_case("single_fold").model
    res = simulate(model, [TransientHeat({2: 1e-3}, duration=2e-3, dt=1e-3)])
    times = res.to_frame()["time [s]"]
    assert times.iloc[0] == 0.0 and not times.isna().any()
