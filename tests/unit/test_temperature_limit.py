"""The crease temperature limit (theory 5.4): one measure, the crease centre-line mean, and one
verdict, whose message names the crease, its temperature and the limit."""

import numpy as np
import pytest

from simulator import ParameterError, PatternError, get_case
from simulator.materials import SU8
from simulator.thermal import (LIMIT_MEASURES, TemperatureLimit, TemperatureVerdict,
                               crease_limit_temperatures, crease_temperatures)

LIMIT = TemperatureLimit.of_glass_transition(SU8.glass_transition)


@pytest.fixture(scope="module")
def single_fold():
    """The single fold heated to 400 mW in 20 increments, above 1.2 T_g in its last records;
    prefolded to -90 deg so that it ends at +155 deg (from flat it would fold past 180 deg at
    300 mW, where the heating step stops: issue 28)."""
    res = get_case("single_fold", thermal_steps=20, power_mW=400.0, residual_fold_deg=-90.0).run()
    assert res.success, res.message
    return res


def test_the_measure_is_the_mean_of_a_b_ctr_or_the_hottest_node(single_fold):
    mesh, t = single_fold.model.mesh, single_fold.state.temperature
    cn = mesh.crease_nodes
    np.testing.assert_array_equal(crease_limit_temperatures(t, mesh),
                                  crease_temperatures(t, mesh, "centre_line"))
    np.testing.assert_array_equal(crease_limit_temperatures(t, mesh, "crease_max"),
                                  t[cn].max(axis=1))
    rises = np.column_stack([t - 21.0, 2 * (t - 21.0)])          # (n, k): linear, columnwise
    np.testing.assert_allclose(crease_limit_temperatures(rises, mesh)[:, 1],
                               2 * (crease_limit_temperatures(t, mesh) - 21.0), rtol=1e-14)
    assert tuple(LIMIT_MEASURES) == ("centre_line", "crease_max")


def test_limit_of_the_material_is_1_2_tg():
    assert LIMIT == TemperatureLimit(252.0, "1.2 T_g", "centre_line")
    assert LIMIT.text == "1.2 T_g = 252 degC"
    assert TemperatureLimit.of_material(SU8) == LIMIT
    assert TemperatureLimit.of_material(SU8, measure="crease_max").measure_words == "hottest node"
    assert TemperatureLimit.of_material(SU8.__class__("x", 1e9)) is None     # no T_g known


def test_a_history_is_judged_over_all_records(single_fold):
    res, mesh = single_fold, single_fold.model.mesh
    v = LIMIT.judge(res.history["temperature"], mesh)
    centre = res.crease_temperature_centre_line
    assert v.status == "exceeded" and not v.success and v.crease == 2
    assert v.temperature == centre.max() and v.record == int(np.argmax(centre[:, 0]))
    assert v.hottest_node == res.crease_temperature_max.max() > v.temperature
    assert v.first_record == int(np.flatnonzero(centre[:, 0] > 252.0)[0]) and v.first_crease == 2
    assert v.message == f"crease 2: centre-line mean {v.temperature:.2f} degC > 1.2 T_g = 252 degC"
    assert v.constraint == pytest.approx((v.temperature - 252.0) / 252.0) and v.margin < 0
    assert v.information().endswith("(crease 2, information: the limit is judged on the crease "
                                     "centre-line mean)")
    one = LIMIT.judge(res.history["temperature"][5], mesh)        # one state: no records
    assert one.success and one.status == "met" and one.record is None and one.first_record is None
    assert "<= 1.2 T_g = 252 degC" in one.message


def test_the_verdict_on_the_hottest_node_needs_no_information_line(single_fold):
    strict = TemperatureLimit(252.0, measure="crease_max")
    v = strict.judge(single_fold.state.temperature, single_fold.model.mesh)
    assert v.temperature == v.hottest_node and v.information() == ""
    assert v.message.startswith("crease 2: hottest node ") and v.message.endswith(
        " > limit = 252 degC")


def test_a_verdict_from_kept_values_takes_the_measure_of_its_limit():
    centre, node = (250.06, 5), (266.67, 5)
    v = TemperatureVerdict.of(LIMIT, centre, node)
    assert v.success and v.temperature == 250.06 and v.hottest_node == 266.67
    strict = TemperatureVerdict.of(TemperatureLimit(252.0, measure="crease_max"), centre, node)
    assert not strict.success and strict.temperature == 266.67


def test_bad_requests_are_refused_with_what_to_give(single_fold):
    mesh = single_fold.model.mesh
    with pytest.raises(ParameterError, match="temperature_measure = 'hottest'.*centre_line"):
        TemperatureLimit(252.0, measure="hottest")
    with pytest.raises(ParameterError, match="TemperatureLimit.value = nan"):
        TemperatureLimit(float("nan"))
    with pytest.raises(ParameterError, match=r"temperature has shape \(3,\); give the nodal"):
        LIMIT.judge(np.zeros(3), mesh)
    with pytest.raises(ParameterError, match="no crease to judge"):
        LIMIT.judge(single_fold.state.temperature, mesh, creases=())
    with pytest.raises(PatternError, match="Unknown crease id 99: .* interior creases are \\[2\\]"):
        LIMIT.judge(single_fold.state.temperature, mesh, creases=(99,))
