"""Gripper evaluation against the reference implementation (theory 10.6, reference data G2)."""

import numpy as np
import pandas as pd
import pytest

from design.devices.gripper import (REFERENCE_NEWTON, GripperDesign, GripperHeatModel,
                                    StageResult, evaluate_gripper, make_gripper_model)
from simulator.errors import ParameterError

DATA = __import__("pathlib").Path(__file__).resolve().parents[1] / "data"
#: The reference's design G2 in the paper setting (its chain heat loss; the default since 7 Dec
#: 2026 is the integral loss).
G2 = GripperDesign(W=300e-6, La=1500e-6, L1=500e-6, L2=500e-6)
PAPER = GripperDesign()
CHAIN = GripperHeatModel(loss_model="chain")


@pytest.fixture(scope="module")
def g2_staircase():
    trace = []
    return evaluate_gripper(G2, mode="staircase", callback=trace.append, heat=CHAIN), trace


def test_g2_staircase_reproduces_reference_powers_and_temperatures(g2_staircase):
    res, _ = g2_staircase
    assert res.success and res.status == "met"
    assert res.assembly.power_per_crease == pytest.approx(9.1e-3)
    assert res.grip.power_per_crease == pytest.approx(0.8e-3)
    assert (res.assembly.simulations, res.grip.simulations) == (91, 8)
    assert res.assembly.temperature == pytest.approx(153.28, abs=0.05)
    assert res.grip.temperature == pytest.approx(39.31, abs=0.05)


def test_g2_staircase_follows_the_reference_call_by_call(g2_staircase):
    """Per-call base fold and temperatures against the reference's G2 trace.

    Measured: identical (< 1e-4 rad) for the first calls and from call 60 to the stop; in
    between our fold runs up to 0.011 rad (0.6 deg) ahead of the reference and the crease
    temperature up to 0.09 degC higher. The cause is the reference's under-converged
    equilibria (see the ``reference_loop`` test below); the bounds below pin the measured
    deviation so that any change to it is noticed.
    """
    _, trace = g2_staircase
    frame = pd.DataFrame(trace)
    base = pd.read_csv(DATA / "gripper_G2_base.csv")
    grip = pd.read_csv(DATA / "gripper_G2_grip.csv")
    ours = frame[frame.stage == "assembly"]
    np.testing.assert_allclose(ours["power_per_crease [W]"] * 1e3, base.power_per_crease_mW)
    dev = np.abs(ours["measure"].to_numpy() - base.base_fold_rad.to_numpy())
    assert dev.max() < 0.012
    assert dev[59:].max() < 1e-4
    ref_t = np.maximum(base["T_ave_nodes25-27_C"], base["T_ave_nodes31-33_C"]).to_numpy()
    dev_t = np.abs(ours["temperature [degC]"].to_numpy() - ref_t)
    assert dev_t.max() < 0.1 and dev_t[59:].max() < 1e-3
    # grip stage: temperatures agree to 1e-3 degC; the reference's tip distance closes by
    # irregular amounts per call (67-86 um) while ours closes smoothly (70-76 um), a sign of
    # incompletely converged reference equilibria: ours stays within 15 um of it.
    ours = frame[frame.stage == "grip"]
    tip = ours["measure"].to_numpy() * 1e6
    np.testing.assert_allclose(tip, grip.tip_distance_um, atol=15.0)
    steps = -np.diff(tip)
    assert np.all(steps > 65) and steps.max() - steps.min() < 10
    ref_t = np.maximum(grip["T_ave_nodes34-36_C"], grip["T_ave_nodes28-30_C"])
    np.testing.assert_allclose(ours["temperature [degC]"], ref_t, atol=2e-3)
    np.testing.assert_allclose(ours["max_crease_temperature [degC]"], grip.T_node_max_C,
                               atol=2e-3)


def test_reference_loop_explains_the_g2_trace_deviation():
    """With the reference's own Newton loop the G2 trace comes 8x closer to its data.

    The reference stops at a 5e-7 N residual, above the gripper's forces (a base panel weighs
    1.5e-8 N), so it takes one to a few Newton updates per call and lags the equilibrium.
    Emulating that loop (``REFERENCE_NEWTON``) brings the assembly fold within 0.0013 rad of
    the reference (0.0105 fully converged) and gives the irregular grip steps of its data
    (reference 67-87 um per call, ours fully converged 70-76 um). What remains comes from the
    reference's inexact contact Hessians (theory 3.7), which steer its under-converged
    iterates wherever contact is active (two pairs during part of the run).
    """
    trace = []
    res = evaluate_gripper(G2, mode="staircase", callback=trace.append,
                           options=REFERENCE_NEWTON, heat=CHAIN)
    assert (res.assembly.simulations, res.grip.simulations) == (91, 8)
    frame = pd.DataFrame(trace)
    base = pd.read_csv(DATA / "gripper_G2_base.csv")
    dev = np.abs(frame[frame.stage == "assembly"]["measure"].to_numpy()
                 - base.base_fold_rad.to_numpy())
    assert dev.max() < 0.0015
    steps = -np.diff(frame[frame.stage == "grip"]["measure"].to_numpy() * 1e6)
    assert steps.max() - steps.min() > 10


def test_start_design_staircase_is_the_same_under_both_solver_loops():
    """Start design (W 200, L1 L2 1000, La 700 um): 26.5 + 5.9 mW per crease (265 + 59 calls).

    The reference's stopping calls do not depend on its under-convergence: its own loop
    (emulated) stops at the same calls with temperatures within 0.01 degC of ours.
    """
    ours = evaluate_gripper(PAPER, mode="staircase", heat=CHAIN)
    ref = evaluate_gripper(PAPER, mode="staircase", options=REFERENCE_NEWTON, heat=CHAIN)
    for r in (ours, ref):
        assert r.success
        assert (r.assembly.simulations, r.grip.simulations) == (265, 59)
        assert r.assembly.power_per_crease == pytest.approx(26.5e-3)
        assert r.grip.power_per_crease == pytest.approx(5.9e-3)
    assert ours.assembly.temperature == pytest.approx(ref.assembly.temperature, abs=0.01)
    assert ours.grip.temperature == pytest.approx(ref.grip.temperature, abs=0.01)


def test_bisect_agrees_within_one_step_with_fewer_simulations(g2_staircase):
    stair, _ = g2_staircase
    bis = evaluate_gripper(G2, mode="bisect", heat=CHAIN)
    assert bis.success
    for a, b in ((stair.assembly, bis.assembly), (stair.grip, bis.grip)):
        assert 0 <= a.power_per_crease - b.power_per_crease < 0.1e-3 + 1e-12
        assert b.simulations < a.simulations or a.simulations < 12
    assert bis.assembly.simulations + bis.grip.simulations < \
        stair.assembly.simulations + stair.grip.simulations


def test_power_cap_gives_unmet_result_with_reason():
    res = evaluate_gripper(G2, mode="bisect", power_cap=2e-3, heat=CHAIN)
    assert not res.success and res.status == "not_met"
    assert res.total_power is None                       # unmet: None, never 0 or inf
    assert "power cap" in res.message and res.assembly.power_per_crease is None
    assert res.assembly.status == "not_met" and not res.assembly.success
    assert "not attempted" in res.grip.message and res.grip.status == "not_attempted"
    d = res.to_dict()
    assert d["success"] is False and d["status"] == "not_met" and "power cap" in d["message"]
    assert d["total_power [mW]"] is None and d["assembly_power [mW]"] is None


def test_stage_result_contract_is_checked():
    with pytest.raises(ParameterError, match="status = 'met' with success = False"):
        StageResult(False, "met", "", None, 0.0, 20.0, 20.0, 1, 1)
    with pytest.raises(ParameterError, match="power_per_crease = 0.0 with success = False"):
        StageResult(False, "not_met", "", 0.0, 0.0, 20.0, 20.0, 1, 1)


def test_gripper_message_names_a_stage_met_after_a_snap():
    from design.devices.gripper import GripperResult
    from simulator.steps import Event

    plain = StageResult(True, "met", "criterion met", 9e-3, 1.6, 150.0, 160.0, 30, 30)
    event = Event("snap", 0.5, 10, 3e-5, True, power_per_crease=(5e-5,) * 4, jump=2e-7)
    snap = StageResult(True, "met", "criterion met after a snap (snap at 0.05 mW per crease: "
                       "displacement jumps 0.2 um)", 1e-4, 4e-5, 24.0, 130.0, 1, 21, (event,))
    assert GripperResult(G2, "bisect", plain, plain).message == "both stages met"
    res = GripperResult(G2, "bisect", plain, snap)
    assert res.message == ("both stages met; grip: criterion met after a snap (snap at "
                           "0.05 mW per crease: displacement jumps 0.2 um)")
    assert res.to_dict()["message"] == res.message and res.success


def test_model_matches_reference_setup():
    model, pre = make_gripper_model(GripperDesign())
    mesh = model.mesh
    assert (mesh.n_nodes, len(mesh.bars)) == (42, 88)
    # node edits move geometry but keep the meshed bar lengths (theory 2.2)
    assert not np.allclose(mesh.nodes[13], mesh.pattern.vertices[9] * 0)  # edited nodes exist
    assert sum(abs(p.forces[:, 2].sum()) for p in pre if hasattr(p, "forces")) > 0


@pytest.mark.parametrize("kwargs, match", [
    ({"W": -1e-6}, "W"), ({"L1": float("nan")}, "L1"), ({"W": 2e-3}, "crease width"),
])
def test_bad_design(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        GripperDesign(**kwargs)


def test_bad_mode():
    with pytest.raises(ParameterError, match="mode"):
        evaluate_gripper(G2, mode="golden")


def test_grip_of_a_design_whose_large_growth_trial_fails_is_found_by_smaller_steps():
    """Coordinate-descent design 60 (W 300, La 1200, L1 500, L2 550 um): the grip trial from
    1.1 to 1.5 mW per crease stalls under load control near 1.44 mW. Arc length from there
    jumped to a branch whose arm tips open with more power (grip failed at 7.4 mW); a growth
    trial larger than the first step is retried smaller instead, and the grip is met at
    1.10625 mW as before snaps were followed (commit ec2be81)."""
    res = evaluate_gripper(GripperDesign(W=300e-6, La=1200e-6, L1=500e-6, L2=550e-6),
                           heat=CHAIN)
    assert res.success and res.message == "both stages met"
    assert res.assembly.power_per_crease == pytest.approx(10.00625e-3, abs=1e-9)
    assert res.grip.power_per_crease == pytest.approx(1.10625e-3, abs=1e-9)


@pytest.mark.slow
def test_grip_after_a_snap_is_met_where_load_control_failed():
    """Issue 9 item 5: start design with a residual fold of +45 deg (outside the paper's
    -20..+10 deg, where no heating trial fails). After assembly (13.2 mW per crease, as the
    staircase finds), the first grip step (0.1 mW) fails under plain load control; the stage
    follows the snap of the closing arm tips by arc length (~50 s)."""
    import math

    from design.devices.gripper import ARM_CREASES, BASE_CREASES, GripperResult, _Stage
    from simulator import Heat, simulate

    model, pre = make_gripper_model(GripperDesign(residual_fold=math.radians(45)), heat=CHAIN)
    start = simulate(model, pre + [Heat({BASE_CREASES: 13.2e-3}, increments=33,
                                        coupling="staggered")])
    assert start.success and _Stage(model, "assembly").look(start.state)[1]
    plain = simulate(model, [Heat({ARM_CREASES: 0.1e-3}, increments=1, coupling="staggered")],
                     state=start.state)
    assert not plain.success                                    # main before issue 9 item 5
    grip = _Stage(model, "grip")
    state, ok, _ = grip.heat(start.state, 0.1e-3)
    assert ok and grip.look(state)[1] and grip.increments > 1
    res = grip.result("met", 0.1e-3, state, "criterion met")
    assert res.success and res.measure < 100e-6
    note = res.message.split("after a snap (snap at ")[1]
    assert 0.04 < float(note.split(" mW")[0]) < 0.07 and "displacement jumps" in note
    both = GripperResult(PAPER, "staircase", res, res)
    assert both.message.startswith("both stages met; assembly: criterion met after a snap")
