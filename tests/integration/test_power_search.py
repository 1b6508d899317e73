"""Power searches following snaps (issue 9 item 5): the shared heating trial
(:func:`design.devices.power_search.heating_trial`) and the snap bookkeeping of
:class:`design.devices.power_search.HeatingStage` in both searches."""

import math
from dataclasses import replace

import numpy as np
import pytest

import design.devices.power_search as ps
from design.devices.gripper import BASE_CREASES, GripperDesign, make_gripper_model
from design.devices.power_search import HeatingStage, HeatingTrial, bisect_search, staircase_search
from simulator import Heat, simulate


def test_trial_is_plain_load_control_where_load_control_converges():
    """Continuation only acts after a failure: a gripper trial equals a load-controlled Heat."""
    model, pre = make_gripper_model(GripperDesign())
    start = simulate(model, pre).state
    trial = ps.heating_trial(model, BASE_CREASES, start, 5e-3)
    plain = simulate(model, [Heat({BASE_CREASES: 5e-3}, increments=1, coupling="staggered")],
                     state=start)
    assert trial.success and trial.snap is None and trial.increments == 1
    np.testing.assert_array_equal(trial.state.u, plain.state.u)
    np.testing.assert_array_equal(trial.state.temperature, plain.state.temperature)


class _Fold(HeatingStage):
    """A stage whose criterion holds from 2 mW per crease; trials reaching past 1.5 mW from
    below it snap there (a stand-in for a simulation, to check the bookkeeping)."""

    def look(self, state):
        p = float(state.crease_power.max())
        return p, p >= 2e-3 - 1e-12, 0.0, 0.0

    def result(self, status, power, state, message):
        return status, power, self.after_snaps(message, state) if status == "met" else message


@pytest.fixture()
def fake_trials(monkeypatch):
    def trial(model, creases, state, dp, increments=1, coupling="staggered", options=None,
              follow_snaps=True):
        p0 = float(state.crease_power.max())
        new = replace(state, crease_power=state.crease_power + dp)   # a new state object
        snap = "snap at 1.5 mW per crease: displacement jumps 300 um" \
            if p0 < 1.5e-3 <= p0 + dp else None
        return HeatingTrial(new, True, "all steps converged", snap, increments)

    monkeypatch.setattr(ps, "heating_trial", trial)
    model, _ = make_gripper_model(GripperDesign())
    return model, simulate(model, []).state


@pytest.mark.parametrize("search", ["staircase", "bisect"])
def test_met_after_a_snap_reports_the_snap_of_its_path(fake_trials, search):
    model, start = fake_trials
    stage = _Fold(model, BASE_CREASES)
    if search == "staircase":
        (status, power, msg), state = staircase_search(stage, start, 0.1e-3, 40e-3)
        assert power == pytest.approx(2e-3)
    else:
        (status, power, msg), state = bisect_search(stage, start, 0.1e-3, 0.01e-3, 40e-3,
                                                    0.4e-3)
        assert 2e-3 <= power < 2.01e-3
    assert status == "met"
    assert msg == "criterion met after a snap (snap at 1.5 mW per crease: displacement " \
                  "jumps 300 um)"
    assert stage.snaps(start) == ()                         # nothing led to the start state


def test_snaps_belong_to_the_states_they_led_to(fake_trials):
    """A trial that snapped does not mark a state reached without passing the snap."""
    model, start = fake_trials
    stage = _Fold(model, BASE_CREASES)
    high, _, _ = stage.heat(start, 3e-3)                    # passes 1.5 mW: snapped
    low, _, _ = stage.heat(start, 1e-3)                     # stays below it
    higher, _, _ = stage.heat(high, 1e-3)                   # after the snap, from a saved state
    assert len(stage.snaps(high)) == 1 and stage.snaps(higher) == stage.snaps(high)
    assert stage.snaps(low) == ()
    assert stage.after_snaps("criterion met", low) == "criterion met"


class _Calls(_Fold):
    """Records (dp, follow_snaps) of every trial; trials with follow_snaps=False fail when
    they would pass the snap at 1.5 mW (plain load control)."""

    def __init__(self, *a):
        super().__init__(*a)
        self.calls = []

    def heat(self, state, dp, increments=1, coupling="staggered", follow_snaps=True):
        self.calls.append((round(dp * 1e3, 6), follow_snaps))
        p0 = float(state.crease_power.max())
        if not follow_snaps and p0 < 1.5e-3 <= p0 + dp:
            return state, False, "increment 1/1: gave up (load control)"
        return super().heat(state, dp, increments, coupling, follow_snaps)


def test_bisect_follows_snaps_only_where_a_failure_is_not_retried_smaller(fake_trials):
    """Growth trials larger than ``step`` run plain load control (a failure is retried with a
    smaller step, as before snaps were followed); the ``step`` trial and the bisection follow
    the snap by arc length."""
    model, start = fake_trials
    stage = _Calls(model, BASE_CREASES)
    (status, power, msg), _ = bisect_search(stage, start, 0.1e-3, 0.01e-3, 40e-3, 0.4e-3)
    assert status == "met" and 2e-3 <= power < 2.01e-3 and "after a snap" in msg
    growth = [(0.1, True), (0.2, False), (0.4, False), (0.4, False),   # 0.1, 0.3, 0.7, 1.1 mW
              (0.4, False), (0.1, True), (0.2, False),                # 1.5 fails; 1.2, 1.4
              (0.4, False), (0.1, True),                              # 1.8 fails; 1.5 snaps
              (0.2, False), (0.4, False)]                             # 1.7, 2.1 met
    assert stage.calls[:len(growth)] == growth
    assert len(stage.calls) > len(growth)
    assert all(follow for _, follow in stage.calls[len(growth):])     # bisection: 1.7..2.1


def test_heating_trial_without_following_snaps_is_plain_load_control(monkeypatch):
    """``follow_snaps=False`` runs the Heat step with ``on_limit_point="stop"``."""
    seen = []
    monkeypatch.setattr(ps, "simulate", lambda model, steps, **kw: seen.append(steps[0]) or
                        simulate(model, [], state=kw["state"]))
    model, _ = make_gripper_model(GripperDesign())
    start = simulate(model, []).state
    for follow in (True, False):
        ps.heating_trial(model, BASE_CREASES, start, 1e-3, follow_snaps=follow)
    assert [s.on_limit_point for s in seen] == ["continue", "stop"]


@pytest.mark.slow
def test_heating_trial_follows_the_heated_miura_snap():
    """The Miura lifter of the ``snap_through`` case (a = 0.5 mm, gamma = 45 deg, W = 300 um)
    snaps near 9.2 mW per crease (~20 s): the trial reaches 12 mW and reports the snap. On the
    case's heat loss, the paper's chains (with the integral loss, MiuraDesign's default since
    7 Dec 2026, this Miura stops at about half the ramp: a path of its own)."""
    from design.devices.miura import MiuraDesign, heated_creases, make_miura_model

    d = MiuraDesign(a=0.5e-3, gamma=math.radians(45), W=300e-6, loss_model="chain")
    model = make_miura_model(d)
    trial = ps.heating_trial(model, tuple(heated_creases(d)), simulate(model, []).state,
                             12e-3, increments=30)
    assert trial.success and trial.snap is not None and trial.increments > 30
    power = float(trial.snap.split("snap at ")[1].split(" mW")[0])
    assert 9.0 < power < 9.4 and "displacement jumps" in trial.snap
    assert trial.state.crease_power.max() == pytest.approx(12e-3)
