"""Events are data (issue 18 item 4): limit points, bifurcations and snaps as typed records on
the step and simulation results, in ``meta.json`` and the tables, read by the design layer."""

import json
import math
from dataclasses import FrozenInstanceError, replace

import numpy as np
import pytest

import design.devices.power_search as ps
from design.devices.gripper import GripperDesign, GripperResult, StageResult, _Stage, make_gripper_model
from design.devices.power_search import HeatingTrial
from simulator import Load, NewtonOptions, get_case, simulate
from simulator.steps import EVENT_KINDS, Event
from simulator.errors import ParameterError

#: Newton gives up at the roof's limit point with this iteration cap (as in test_snap_through).
STALLS = NewtonOptions(max_iter=8)


@pytest.fixture(scope="module")
def roof():
    case = get_case("snap_through")
    return case, case.run()


def _load(case, scale):
    return {n: scale * np.asarray(f) for n, f in case.steps[0].forces.items()}


def _peak(res):
    lam = res.steps[0].load_factor
    return float(lam[np.argmax(np.diff(lam) < 0)])


# ------------------------------------------------------------------------ the record itself
def test_event_is_a_frozen_critical_point_with_si_fields():
    e = Event("snap", 0.5, 3, 2e-5, True, power_per_crease=np.array([1e-3, 2e-3]), jump=3e-4,
              temperature_max=150.0, node=7, message="snap")
    assert e.power_per_crease == (1e-3, 2e-3) and e.total_power == pytest.approx(3e-3)
    assert e == replace(e) and hash(e) == hash(replace(e))
    with pytest.raises(FrozenInstanceError):
        e.load_factor = 0.7
    d = e.to_dict(crease_ids=[11, 12])
    assert d["power_per_crease [W]"] == {"11": 1e-3, "12": 2e-3}
    assert d["jump [m]"] == 3e-4 and d["kind"] == "snap" and d["total_power [W]"] == 3e-3
    assert e.to_dict()["power_per_crease [W]"] == [1e-3, 2e-3]
    json.dumps(d)
    assert set(EVENT_KINDS) == {"limit_point", "bifurcation", "stability_change", "snap",
                                "branch_switch", "stability_lost", "panel_crossing",
                                "fold_past_flat"}


@pytest.mark.parametrize("kwargs, match", [
    ({"kind": "jump"}, "Event.kind = 'jump'"),
    ({"load_factor": float("nan")}, "Event.load_factor"),
])
def test_event_rejects_bad_fields(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        Event(**{"kind": "limit_point", "load_factor": 0.5, **kwargs})


# ------------------------------------------------------------- events of the steps and results
def test_arc_length_limit_points_are_events(roof, tmp_path):
    case, res = roof
    step = res.steps[0]
    assert step.events == res.events and [e.kind for e in res.events] == ["limit_point"] * 2
    top, bottom = res.events
    assert top.maximum and not bottom.maximum                 # parabola vertex above the peak
    assert _peak(res) <= top.load_factor == pytest.approx(_peak(res), rel=1e-3)
    for e in res.events:
        assert (e.step, e.step_index) == ("arc_length_load", 0) and e.message in step.message
        assert e.node == int(case.model.mesh.crease_nodes[0][6])       # the monitored ridge
        k = e.increment                   # first record past it: the turn lies between
        near = step.load_factor[k - 1:k + 1]
        assert (e.load_factor >= near.max()) if e.maximum else (e.load_factor <= near.min())
        assert e.displacement == pytest.approx(step.columns["displacement [m]"][k], rel=0.1)
        assert e.power_per_crease == tuple(step.power_history[k])
        assert e.temperature_max == pytest.approx(21.0) and e.jump is None
    df = res.events_frame()
    assert list(df["kind"]) == ["limit_point", "limit_point"]
    assert list(df["step"]) == [e.increment + 1 for e in res.events]  # record 0 = initial
    assert df["displacement [um]"].iloc[0] == pytest.approx(1e6 * top.displacement)
    path = res.path_frame()
    assert list(path.loc[path["event"].notna(), "step"]) == list(df["step"])
    res.save(tmp_path)
    meta = json.loads((tmp_path / "meta.json").read_text())
    assert [m["load_factor"] for m in meta["events"]] == [e.load_factor for e in res.events]
    assert meta["events"][0]["displacement [m]"] == top.displacement


def test_limit_point_stop_is_an_event_beyond_the_records(roof):
    case, res = roof
    peak = _peak(res)
    out = simulate(case.model, [Load(_load(case, 1.1 * peak), increments=20)], options=STALLS)
    assert out.status == "limit_point"
    (e,) = out.events
    assert e.kind == "limit_point" and e.maximum and e.increment is None
    assert e.load_factor * 1.1 * peak == pytest.approx(peak, rel=5e-3)
    assert out.message.startswith(f"step 'load': {e.message}: load control cannot pass it")
    assert f"{e.load_factor:.6g}" in e.message and e.step == "load"
    df = out.events_frame()
    assert len(df) == 1 and df["step"].isna().all() and df["increment"].isna().all()


def test_snap_under_load_control_is_an_event_with_its_jump(roof):
    case, res = roof
    out = simulate(case.model, [Load(_load(case, 1.5 * _peak(res)), increments=20,
                                     on_limit_point="continue")], options=STALLS)
    assert out.success, out.message
    step = out.steps[0]
    kinds = [e.kind for e in step.events]
    assert kinds == ["limit_point", "snap", "limit_point"]           # in path order
    top, snap, _ = step.events
    assert replace(snap, kind="limit_point", jump=None, message=top.message) == top
    assert snap.message in step.message and snap.jump > 0
    # the jump: from the limit point to where the path crosses its load factor again
    lam, m = step.load_factor, step.columns["displacement [m]"]
    j = next(j for j in range(snap.increment + 1, len(lam))
             if None not in (m[j - 1], m[j]) and lam[j - 1] < snap.load_factor <= lam[j])
    a = (snap.load_factor - lam[j - 1]) / (lam[j] - lam[j - 1])
    assert snap.displacement + snap.jump == pytest.approx(m[j - 1] + a * (m[j] - m[j - 1]),
                                                          rel=1e-12)
    df = out.events_frame()
    assert df.loc[df["kind"] == "snap", "jump [um]"].item() == pytest.approx(1e6 * snap.jump)
    path = out.path_frame()
    assert path.loc[path["step"] == snap.increment + 1, "event"].item() == "limit_point; snap"


def test_steps_without_limit_points_have_no_events():
    res = get_case("single_fold", thermal_steps=2).run()
    assert res.success and res.events == () and all(s.events == () for s in res.steps)
    df = res.events_frame()
    assert len(df) == 0 and "power [mW]" in df.columns


# ------------------------------------------------------------------- the design layer reads them
@pytest.fixture()
def snapping_trials(monkeypatch):
    """Heating trials that pass a snap at 1.5 mW per crease, reported as an event only (no
    message mentions it)."""
    def trial(model, creases, state, dp, increments=1, coupling="staggered", options=None,
              follow_snaps=True):
        p0 = float(state.crease_power.max())
        new = replace(state, crease_power=state.crease_power + dp)
        snaps = (Event("snap", (1.5e-3 - p0) / dp, 1, 1e-4, True,
                       power_per_crease=np.full(model.mesh.n_creases, 1.5e-3), jump=2e-7),) \
            if p0 < 1.5e-3 <= p0 + dp else ()
        return HeatingTrial(new, True, "all steps converged", "a snap" if snaps else None,
                            increments, snaps)

    monkeypatch.setattr(ps, "heating_trial", trial)
    model, _ = make_gripper_model(GripperDesign())
    return model, simulate(model, []).state


def test_stage_results_carry_the_snap_events_of_their_path(snapping_trials):
    model, start = snapping_trials
    stage = _Stage(model, "grip")
    low, _, _ = stage.heat(start, 1e-3)
    high, _, _ = stage.heat(low, 1e-3)                      # passes 1.5 mW
    higher, _, _ = stage.heat(high, 1e-3)
    assert stage.snap_events(low) == () and stage.snap_events(start) == ()
    (e,) = stage.snap_events(higher)
    assert e.kind == "snap" and e.power_per_crease[0] == 1.5e-3
    met = stage.result("met", 3e-3, higher, "criterion met")
    assert met.snaps == (e,) and stage.result("met", 1e-3, low, "criterion met").snaps == ()
    assert stage.result("not_met", 3e-3, higher, "cap").snaps == ()
    plain = StageResult(True, "met", "criterion met", 9e-3, 1.6, 150.0, 160.0, 30, 30)
    both = GripperResult(GripperDesign(), "bisect", plain, met)
    assert both.message.startswith("both stages met; grip: criterion met after a snap")
    # the message of a stage is not read: without events there is no snap to name
    said = replace(met, snaps=())
    assert GripperResult(GripperDesign(), "bisect", plain, said).message == "both stages met"


def test_trial_snap_text_comes_from_the_step_events(monkeypatch):
    """:func:`heating_trial` words the snaps of its Heat step's events (power of the stage's
    first crease, jump), whatever the step's message says."""
    class _Step:
        increments, message = 5, "reworded: no snap mentioned"
        events = (Event("limit_point", 0.5, 2, 1e-4, True, power_per_crease=(1e-3,) * 2),
                  Event("snap", 0.5, 2, 1e-4, True, power_per_crease=(1e-3, 2.5e-3),
                        jump=3.028e-4))

    class _Result:
        success, message, steps, state = True, "all steps converged", [_Step()], None

    monkeypatch.setattr(ps, "simulate", lambda *a, **k: _Result())

    class _Mesh:
        crease_row = {4: 1, 9: 0}

    model = type("M", (), {"mesh": _Mesh()})()
    trial = ps.heating_trial(model, (4, 9), None, 1e-3)
    assert trial.snap == "snap at 2.5 mW per crease: displacement jumps 302.8 um"
    assert trial.snaps == (_Step.events[1],) and trial.increments == 5


@pytest.mark.slow
def test_heated_miura_snap_is_an_event():
    """The heated Miura of the ``snap_through`` case (a = 0.5 mm, gamma = 45 deg, W = 300 um,
    12 mW per crease) snaps near 9.2 mW per crease: one snap event with its power, jump and
    temperature, the same as the power search's trial reads (~40 s)."""
    from design.devices.miura import MiuraDesign, heated_creases, make_miura_model

    case = get_case("snap_through", variant="heated")
    res = case.run()
    assert res.success, res.message
    snaps = [e for e in res.events if e.kind == "snap"]
    snap = max(snaps, key=lambda e: e.jump)     # the main snap; the path's small folds near
    # 11.05 and 11.93 mW pass as snaps of 1-5 um (test_heated_miura_passes_its_snap)
    assert [e for e in snaps if max(e.power_per_crease) < 11e-3] == [snap]
    assert all(e.step == res.steps[0].name for e in snaps)
    assert 9.0e-3 < max(snap.power_per_crease) < 9.4e-3
    assert snap.load_factor * 12e-3 == pytest.approx(max(snap.power_per_crease), rel=1e-12)
    assert snap.jump > 0 and snap.temperature_max > 100.0     # the jump's size depends on
    # how finely the continuation resolves the snap (95 um at 30 increments today)
    assert any(e.kind == "limit_point" and e.load_factor == snap.load_factor
               for e in res.events)
    # every snap is the copy of its own limit point, a maximum of the load factor (the copy
    # was taken by position among the step's events, and fold_past_flat events recorded
    # after the limit points shifted it onto a minimum: 0.988176 for the 11.93 mW snap)
    maxima = {e.load_factor for e in res.events if e.kind == "limit_point" and e.maximum}
    assert all(e.maximum and e.load_factor in maxima for e in snaps)
    row = res.events_frame().query("kind == 'snap'").iloc[0]
    assert row["power [mW]"] == pytest.approx(1e3 * max(snap.power_per_crease))
    assert row["total_power [mW]"] == pytest.approx(1e3 * snap.total_power)
    assert row["stage"] == res.steps[0].name and row["jump [um]"] == pytest.approx(1e6 * snap.jump)
    # the case's heat loss, the paper's chains (MiuraDesign's default became the integral
    # loss on 7 Dec 2026; with it this Miura stops at 0.77 of the ramp, a path of its own)
    d = MiuraDesign(a=0.5e-3, gamma=math.radians(45), W=300e-6, loss_model="chain")
    model = make_miura_model(d)
    assert model.thermal.loss == case.model.thermal.loss
    trial = ps.heating_trial(model, tuple(heated_creases(d)), simulate(model, []).state,
                             12e-3, increments=60)
    t = max(trial.snaps, key=lambda e: e.jump)
    assert len(trial.snaps) == len(snaps) and t.jump == pytest.approx(snap.jump, rel=1e-9)
    assert t.total_power == pytest.approx(snap.total_power, rel=1e-3)
    assert trial.snap.split("; ")[0] == (f"snap at {1e3 * max(t.power_per_crease):.4g} mW per "
                                         f"crease: displacement jumps {1e6 * t.jump:.4g} um")
