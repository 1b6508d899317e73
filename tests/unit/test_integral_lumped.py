"""The lumped integral loss conductance (``IntegralLoss(lumped=True)``, theory 4.9): the
positive couplings of the final conductance (plain, extrapolated, corrected between rebuilds)
moved onto the diagonal; symmetric, row sums and energy balance kept."""

import dataclasses

import numpy as np
import pytest

from design.devices.gripper import (BASE_CREASES, GripperDesign, GripperHeatModel,
                                    make_gripper_model)
from simulator import IntegralLoss, ParameterError
from simulator.model.heat_loss import heat_loss_from_dict
from simulator.thermal.integral import IntegralOperator, lump_couplings
from simulator.thermal.integral_levels import CorrectedLoss, ExtrapolatedLoss
from simulator.thermal import ThermalModel

#: the three operators the loss can be: (fields of IntegralLoss, class of ThermalModel.integral)
OPERATORS = {"plain": ({"refinement": 2, "correction_tol": 0.0}, IntegralOperator),
             "extrapolated": ({"refinement": 3, "correction_tol": 0.0}, ExtrapolatedLoss),
             "corrected": ({}, CorrectedLoss)}


def _gripper(lumped, **fields):
    """The flat default gripper's model with the integral loss, and its thermal model."""
    model, _ = make_gripper_model(GripperDesign(), heat=GripperHeatModel(sheet_refinement=1))
    thermal = model.thermal.with_loss(lumped=lumped, **fields)
    return model, ThermalModel(model.mesh, thermal)


def _shapes(model):
    """The flat gripper and the same stretched by 4 % along x in its plane (the m = 1
    operator rebuilt, the accurate one kept: the corrected operator's path L_acc(x0) +
    L_1(x) - L_1(x0))."""
    x = model.mesh.nodes
    stretched = x.copy()
    stretched[:, 0] = x[:, 0].mean() + 1.04 * (x[:, 0] - x[:, 0].mean())
    return x, stretched


def test_lump_couplings_moves_positive_couplings_onto_the_diagonal():
    A = np.array([[4.0, 1.0, -0.5], [1.0, 3.0, 0.25], [-0.5, 0.25, 2.0]])
    L = lump_couplings(A)
    np.testing.assert_array_equal(L, [[5.0, 0.0, -0.5], [0.0, 4.25, 0.0], [-0.5, 0.0, 2.25]])
    np.testing.assert_array_equal(A[0], [4.0, 1.0, -0.5])              # a new array


@pytest.mark.parametrize("kind", OPERATORS)
def test_lumped_conductance_has_no_positive_coupling_and_keeps_row_sums(kind):
    fields, cls = OPERATORS[kind]
    model, consistent = _gripper(False, **fields)
    _, lumped = _gripper(True, **fields)
    assert isinstance(lumped.integral, cls) and lumped.integral.lumped
    for x in _shapes(model):
        L0, L = consistent.integral_loss_matrix(x), lumped.integral_loss_matrix(x)
        off = L - np.diag(np.diag(L))
        assert off.max() <= 0 and (L0 - np.diag(np.diag(L0))).max() > 0
        assert (off < 0).any()                             # not diagonal: far couplings kept
        np.testing.assert_array_equal(L, L.T)
        assert L0.sum(axis=1).min() > 0                   # every node loses heat
        np.testing.assert_allclose(L.sum(axis=1), L0.sum(axis=1), rtol=1e-12, atol=0)
        np.testing.assert_array_equal(L, lump_couplings(L0))         # the final one lumped
    if kind == "corrected":
        assert (lumped.integral.builds, lumped.integral.base_builds) == (1, 2)


@pytest.mark.parametrize("kind", OPERATORS)
def test_energy_balance_closes_with_the_lumped_conductance(kind):
    model, tm = _gripper(True, **OPERATORS[kind][0])
    x = model.mesh.nodes
    p = np.zeros(model.mesh.n_creases)
    p[[model.mesh.crease_row_of(c) for c in BASE_CREASES]] = 15e-3
    q = tm.heat_vector(p)
    T = tm.solve(x, q)
    rise = T - model.thermal.room_temperature
    loss = tm.environment_loss(x, T)
    free = np.setdiff1d(np.arange(model.mesh.n_nodes), tm.held_nodes(x))
    K = tm.sheet_conduction(x).toarray()
    # every free node: heat in = conducted away + lost to the medium
    np.testing.assert_allclose((K @ rise + loss)[free], q[free], atol=1e-12 * q.max())
    # the medium takes the same total as with the consistent conductance (1^T L T)
    _, consistent = _gripper(False, **OPERATORS[kind][0])
    L0 = consistent.integral_loss_matrix(x)
    nodes = tm.integral.nodes
    assert loss.sum() == pytest.approx((L0 @ rise[nodes]).sum(), rel=1e-12)
    assert rise.min() >= -1e-9


def test_the_option_is_named_in_the_dict_and_the_description():
    loss = IntegralLoss(lumped=True)
    assert loss.to_dict()["lumped"] is True
    assert heat_loss_from_dict(loss.to_dict()) == loss
    assert loss.describe() == "integral model (calibration-free; m = 3, extrapolated, lumped)"
    default = IntegralLoss()
    assert "lumped" not in default.to_dict() and not default.lumped      # dicts as before
    assert heat_loss_from_dict(default.to_dict()) == default
    old = {"model": "integral", "refinement": 3, "extrapolation": None, "shape_tol": 0.02,
           "correction_tol": 0.1}                                      # written before it
    assert heat_loss_from_dict(old) == default
    assert IntegralLoss(lumped=np.bool_(True)).lumped is True


def test_a_bad_lumped_value_is_named():
    with pytest.raises(ParameterError, match=r"IntegralLoss.lumped = 'yes' must be True"):
        IntegralLoss(lumped="yes")


def test_thermal_parameters_carry_it():
    model, tm = _gripper(True)
    assert tm.params.loss.lumped
    params = dataclasses.replace(model.thermal, loss=IntegralLoss(lumped=True))
    assert params.to_dict()["loss"]["lumped"] is True
