"""Issue 19 acceptance on folded shapes (slow: 10-25 s each; CI runs them as -m fe_accuracy):
the integral model within 5 % of the 3-D FE in crease temperatures, on the double fold at 10 mW
per crease after heating and the gripper (default design) at assembly with 3 mW per base crease.

All models solve the same fixed shape and heat (``fixed_shape_temperatures``); the FE reference
is the Richardson extrapolation ``2 T_1 - T_0`` of levels 0 and 1 (first order in the mesh
size, docs/heat_fe.md), and the error is that of the temperature rise over room temperature.
Measured (6 Dec 2026), the integral model at its defaults (m = 3, Richardson-extrapolated from
2 and 3) against it, 7-node / centre line: double fold +0.3 / -0.2 % (fold 1), +0.5 / +0.1 %
(fold 2); gripper base creases +1.0 / +0.9 % and +1.0 / +1.1 % (the chain model: -38 / -36 %,
-20 / -6 %; -42 / -32 %, -42 / -32 %; the plain m = 2, the default before: +6.2 / +7.1 %,
+3.9 / +4.8 %; +6.7 / +7.0 %, +6.7 / +7.2 %; m = 4 extrapolated: within 1.0 %).
Since the integral loss refines the sheet by default (theory 4.11) the comparison sets
``sheet_refinement=1``, the FE's sheet: measured 7 Dec 2026, double fold +0.4 / -0.1 % (fold 1),
+1.3 / +0.3 % (fold 2); gripper base creases +1.2 / +1.2 % and +1.3 / +1.3 % (at the refined
default fold 1 was -11 / -15 %, the comparison of two different sheets).
"""

import dataclasses

import numpy as np
import pytest

pytest.importorskip("skfem")
pytest.importorskip("gmsh")

from simulator.thermal import fixed_shape_temperatures  # noqa: E402

pytestmark = [pytest.mark.slow, pytest.mark.fe_accuracy]    # in CI: .ci/run


def _rises(model, power, x):
    """Crease rises [K] (7-node, centre line) of the FE reference and the integral model, both
    on the mesh triangles: the FE meshes the air around that sheet, so the integral loss is
    compared on it (``sheet_refinement=1``; the default refines the sheet, theory 4.11, whose
    heated creases run 10-15 % cooler than on the mesh triangles: another sheet)."""
    fe = [fixed_shape_temperatures(model, "fe", power, positions=x, fe_level=lv) for lv in (0, 1)]
    assert all(r.success for r in fe)
    thermal = dataclasses.replace(model.thermal.with_loss("integral"), sheet_refinement=1)
    integral = fixed_shape_temperatures(dataclasses.replace(model, thermal=thermal), "integral",
                                        power, positions=x)        # the loss at its defaults
    rt = integral.room_temperature

    def pair(r):
        return np.array([r.crease_temperature, r.crease_t_ave]) - rt
    return 2 * pair(fe[1]) - pair(fe[0]), pair(fe[1]), pair(integral)


def _check(reference, level_1, integral, creases):
    err = integral[:, creases] / reference[:, creases] - 1
    assert np.all(np.abs(err) < 0.05), err
    assert np.all(np.abs(integral[:, creases] / level_1[:, creases] - 1) < 0.05)
    assert np.all(np.abs(level_1[:, creases] / reference[:, creases] - 1) < 0.03)  # FE settled


def test_double_fold_integral_model_within_5_percent_of_fe():
    from simulator import get_case

    case = get_case("double_fold", thermal_steps=20)
    sim = case.run()
    assert sim.success
    x = case.model.mesh.nodes + sim.state.u
    assert np.allclose(sim.state.crease_power, 0.01)
    ref, lv1, integral = _rises(case.model, sim.state.crease_power, x)
    _check(ref, lv1, integral, [0, 1])
    assert integral[0, 1] > integral[0, 0]                   # fold 2 hotter than fold 1


def test_gripper_at_assembly_integral_model_within_5_percent_of_fe():
    from design.devices.gripper import GripperDesign, _Stage, make_gripper_model
    from design.devices.power_search import bisect_search
    from simulator import simulate

    model, pre = make_gripper_model(GripperDesign())
    start = simulate(model, pre)
    assert start.success
    result, state = bisect_search(_Stage(model, "assembly"), start.state, 0.1e-3, 0.01e-3,
                                  40e-3, 0.4e-3)
    assert result.success
    power = np.array([3e-3, 0.0, 3e-3, 0.0])                 # base creases (rows 0, 2)
    ref, lv1, integral = _rises(model, power, model.mesh.nodes + state.u)
    _check(ref, lv1, integral, [0, 2])
