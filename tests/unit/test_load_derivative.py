"""The load derivative q of :class:`LoadPath` near the kink of the spring law (theory 3.3, 6.11).

The spring law wraps the deviation at +-pi from the rest angle, so the internal force is linear
in the rest angles only between those kinks; a difference over a rest probe that crosses one
gives a wrong q."""

import logging

import numpy as np

from simulator.cases import get_case
from simulator.mechanics.elements.springs import fold_angle
from simulator.mechanics.equilibrium import equilibrium_system
from simulator.solvers import LoadPath
from simulator.solvers import load_path

GAP = 0.03          # [rad] distance of a spring's deviation from its kink
CREASE = [2, 3, 6, 7]   # the single fold's springs whose rest angles heating turns (kind 3)


def fold_path(deviation, R):
    """The single fold, flat (u = 0), with the springs' deviations from their rest angles and
    rest-angle changes R [rad] given; its LoadPath without dead loads."""
    model = get_case("single_fold").model
    mesh = model.mesh
    theta = fold_angle(mesh.nodes[mesh.springs])
    system = equilibrium_system(model)
    n = mesh.n_dof if hasattr(mesh, "n_dof") else mesh.nodes.size
    return LoadPath(system, np.zeros(n), np.zeros(n), theta - deviation, R), mesh


def difference_q(path, u, h):
    """q by the plain difference over a rest change h R."""
    f = path.system.evaluate(u, path.rest0).f_int
    f1 = path.system.evaluate(u, path.rest0 + h * path.R, hessian=False).f_int
    return path.P[path.free] - (f1 - f)[path.free] / h


def relative(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def test_q_near_a_kink_matches_a_tiny_difference_where_the_old_probe_did_not(caplog):
    """Spring 2 is GAP from its kink and R moves its rest angle towards it: the probe of
    REST_PROBE = 0.1 rad crosses the kink (its q is far off); LoadPath.at flips the probe's
    sign and agrees with a difference over 1e-7 rad."""
    n_springs = 20
    dev = np.full(n_springs, 0.4)
    dev[2] = np.pi - GAP
    R = np.zeros(n_springs)
    R[CREASE] = [-1.0, -0.5, -0.5, -0.5]
    path, mesh = fold_path(dev, R)
    assert len(mesh.springs) == n_springs and set(mesh.spring_kind[CREASE]) == {3}
    u = np.zeros_like(mesh.nodes)
    ref = difference_q(path, u, 1e-7)
    old = difference_q(path, u, load_path.REST_PROBE)
    with caplog.at_level(logging.DEBUG, logger="simulator.solvers.load_path"):
        q = path.at(u, 0.0).q
    assert relative(q, ref) < 1e-6
    assert relative(old, ref) > 0.1
    assert "probe shrunk from 0.1 to -0.1 rad" in caplog.text


def test_springs_near_both_kinks_halve_the_probe(caplog):
    """Spring 2 crosses its kink for a positive probe, spring 6 for a negative one: the probe
    is halved to below GAP."""
    dev = np.full(20, 0.4)
    dev[2], dev[6] = np.pi - GAP, -(np.pi - GAP)
    R = np.zeros(20)
    R[CREASE] = -1.0
    path, mesh = fold_path(dev, R)
    u = np.zeros_like(mesh.nodes)
    ref = difference_q(path, u, 1e-7)
    with caplog.at_level(logging.DEBUG, logger="simulator.solvers.load_path"):
        q = path.at(u, 0.0).q
    assert relative(q, ref) < 1e-6
    assert relative(difference_q(path, u, 0.1), ref) > 0.1
    assert relative(difference_q(path, u, -0.1), ref) > 0.1
    assert "probe shrunk from 0.1 to 0.025 rad" in caplog.text


def test_q_away_from_kinks_is_the_plain_difference(caplog):
    """No spring within the probe of its kink: q is bit-identical to the difference over
    REST_PROBE, and nothing is logged."""
    dev = np.linspace(-2.5, 2.5, 20)
    R = np.linspace(-1.0, 2.0, 20)
    path, mesh = fold_path(dev, R)
    u = np.zeros_like(mesh.nodes)
    with caplog.at_level(logging.DEBUG, logger="simulator.solvers.load_path"):
        q = path.at(u, 0.0).q
    assert np.array_equal(q, difference_q(path, u, load_path.REST_PROBE / 2.0))
    assert "probe" not in caplog.text


class NeverLinear:
    """f_int = sqrt|rest - rest0| on one DOF: not linear over any probe."""

    free = np.array([0])

    def __init__(self, rest0):
        self.rest0, self.calls = rest0, 0

    def evaluate(self, u, rest, hessian=True):
        self.calls += 1

        class Values:
            f_int = np.array([np.sqrt(abs(rest[0] - self.rest0[0]))])
            K = np.eye(1)
            tangent = None
        return Values()


def test_no_linear_probe_ends_at_the_smallest_and_says_so(caplog):
    rest0 = np.array([0.3])
    system = NeverLinear(rest0)
    path = LoadPath(system, np.zeros(1), np.zeros(1), rest0, np.array([1.0]))
    with caplog.at_level(logging.DEBUG, logger="simulator.solvers.load_path"):
        d = load_path._rest_difference(system, np.zeros((1, 3)), rest0, path.R,
                                       np.zeros(1))
    assert system.calls == 2 * (2 * load_path.PROBE_HALVINGS + 2)
    h = load_path.REST_PROBE * 0.5 ** load_path.PROBE_HALVINGS
    assert np.allclose(d, np.sqrt(h) / -h)
    assert "not linear over any rest-angle probe" in caplog.text
