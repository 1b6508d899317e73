"""No accepted state with a node below the substrate (theory 6.11, issue 29).

The reference single fold (``single_fold_model``): anchor panel 0, folding panel 1, crease 2
(crease nodes 12, 13, 14: A, B and centre), substrate panel 2 fixed 150 um below the sheet with
panel contact. Contact holds panel corners and centres above the substrate, not crease nodes:
pushed down hard enough, the crease's centre node goes through it."""

import numpy as np
import pytest

from simulator import simulate
from simulator.cases import miura_sheet_model, single_fold_model
from simulator.events import CrossingWatch, stops
from simulator.mechanics.substrate import BELOW_RTOL, substrate_breaches, substrate_of
from simulator.steps import Load

CREASE_CENTRE = 14                     # crease node (not a contact point), at (600, 250, 0) um
SUBSTRATE_Z = -150e-6                  # the substrate panel's plane [m]
PUSH = 0.05                            # [N] on the crease centre: through the substrate


@pytest.fixture(scope="module")
def fold():
    return single_fold_model()


def _lowest(model, u) -> float:
    """Lowest z [m] of the nodes not of the substrate panel at displacements u."""
    sub = substrate_of(model.mesh, model.supports)
    return float(np.min((model.mesh.nodes + u)[sub.nodes, 2]))


def test_substrate_is_the_fixed_panel_with_the_sheet_on_one_side(fold):
    sub = substrate_of(fold.mesh, fold.supports)
    assert set(sub.panels) == {2}
    assert np.allclose(sub.normal, [0, 0, 1])               # towards the sheet
    assert not set(sub.nodes) & {8, 9, 10, 11, 17}         # its own nodes are not tested
    assert substrate_of(single_fold_model(substrate=False).mesh,
                        single_fold_model(substrate=False).supports) is None
    # the Miura lifter: its clamped first column is in the sheet's plane, not a substrate
    miura = miura_sheet_model(cells_x=2, cells_y=1, substrate=True)
    n = miura.mesh.pattern.n_panels
    assert set(substrate_of(miura.mesh, miura.supports).panels) == {n - 1}


def test_breaches_count_depth_inside_the_outline_only(fold):
    sub = substrate_of(fold.mesh, fold.supports)
    x = fold.mesh.nodes.copy()
    assert len(substrate_breaches(sub, x)) == 0
    x[CREASE_CENTRE, 2] = SUBSTRATE_Z - 10e-6
    rows = substrate_breaches(sub, x)
    assert rows.shape == (1, 3) and rows[0, :2].tolist() == [CREASE_CENTRE, 2]
    assert rows[0, 2] == pytest.approx(10e-6)
    x[CREASE_CENTRE, 2] = SUBSTRATE_Z - 0.5 * sub.tol      # within the tolerance
    assert len(substrate_breaches(sub, x)) == 0
    assert sub.tol == pytest.approx(BELOW_RTOL * 1.25e-3)
    x[CREASE_CENTRE] = [1300e-6, 250e-6, SUBSTRATE_Z - 10e-6]   # beyond its edge (x 1250 um)
    assert len(substrate_breaches(sub, x)) == 0


def test_crossing_watch_stops_on_a_node_below_the_substrate(fold):
    u = np.zeros_like(fold.mesh.nodes)
    u[CREASE_CENTRE, 2] = SUBSTRATE_Z - 5e-6
    event = CrossingWatch(fold.mesh, np.zeros_like(u), fold.supports).check(u, 3, 0.5)
    assert stops(event) and event.kind == "panel_crossing" and 2 in event.panels
    assert "crease node 14 5 um below substrate panel 2" in event.message
    assert "increment 4 (load factor 0.5)" in event.message
    assert CrossingWatch(fold.mesh, np.zeros_like(u)).check(u, 3, 0.5) is None   # no supports


def test_load_control_never_converges_through_the_substrate(fold):
    """On main before the fix the step converged with the crease centre 18.8 um below the
    substrate. Now each increment that ends there is halved, and the step fails saying why,
    its end state above the substrate."""
    step = simulate(fold, [Load({CREASE_CENTRE: (0, 0, -PUSH)}, increments=5)]).steps[0]
    assert not step.success and step.status == "failed"
    assert "crease node 14" in step.message and "below substrate panel 2" in step.message
    assert "the step cannot go on" in step.message
    sub = substrate_of(fold.mesh, fold.supports)
    assert _lowest(fold, step.state.u) >= SUBSTRATE_Z - sub.tol
    for u in step.u_history:
        assert len(substrate_breaches(sub, fold.mesh.nodes + u)) == 0
    # a push that the crease carries above the substrate still converges
    ok = simulate(fold, [Load({CREASE_CENTRE: (0, 0, -1e-3)}, increments=5)]).steps[0]
    assert ok.success and _lowest(fold, ok.state.u) > SUBSTRATE_Z



def test_continued_past_the_refusal_arc_length_refuses_too_and_the_message_says_why(fold):
    """With ``on_limit_point="continue"`` arc length takes over where load control gave up;
    it refuses the same states, and the step's message names what load control refused."""
    step = simulate(fold, [Load({CREASE_CENTRE: (0, 0, -PUSH)}, increments=5,
                                on_limit_point="continue")]).steps[0]
    assert not step.success
    assert "(not physical beyond: crease node 14" in step.message
    sub = substrate_of(fold.mesh, fold.supports)
    for u in step.u_history:
        assert len(substrate_breaches(sub, fold.mesh.nodes + u)) == 0


def test_not_physical_finds_the_refusal_in_a_message():
    from simulator.mechanics.substrate import NOT_PHYSICAL, not_physical

    msg = f"gave up at t = 0.5: {NOT_PHYSICAL}crease node 3 2 um below substrate panel 1: " \
        "halving it; every shorter increment ..."
    assert not_physical(msg) == "crease node 3 2 um below substrate panel 1"
    assert not_physical("gave up at t = 0.5: no convergence in 30 iterations") == ""
