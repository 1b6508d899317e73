"""Scalar objectives of a steady state for :func:`~simulator.sensitivity.differentiate`: each
gives its value and its exact partial derivatives in the displacements and temperatures.

An objective is one of the classes here or a callable ``f(u, T) -> (value, dJ/du, dJ/dT)``
with ``u`` (n, 3) [m] the displacements from the mesh nodes, ``T`` (n,) [deg C] the node
temperatures, ``dJ/du`` (n, 3) and ``dJ/dT`` (n,) in the objective's unit per m and per K.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import one_of
from ..errors import ParameterError
from ..geometry.polygons import rings
from ..mechanics.elements.springs import fold_angle_derivatives
from ..mechanics.kinematics import fold_angles, panel_normals
from ..thermal.measures import CREASE_MEASURES, crease_temperatures

__all__ = ["FoldAngle", "NodeCoordinate", "CreaseTemperature", "objective_terms"]

_AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class FoldAngle:
    """Fold angle of crease ``crease`` (an id of the pattern) [rad].

    ``measure="fold"``: the panel-to-panel fold angle of
    :func:`~simulator.mechanics.kinematics.fold_angles` (``SimulationResult.fold_angle``);
    ``"rotation"``: the crease rotation of
    :func:`~simulator.mechanics.kinematics.crease_rotations` (the sum over its fold lines).
    """

    crease: int
    measure: str = "fold"
    unit = "rad"

    def __post_init__(self):
        one_of("FoldAngle.measure", self.measure, ("fold", "rotation"))

    def terms(self, model, u, T):
        mesh = model.mesh
        row, x = mesh.crease_row_of(self.crease), mesh.nodes + u
        g = np.zeros_like(x)
        if self.measure == "rotation":
            springs = mesh.springs[mesh.crease_springs[row, [0, 1, 4, 5]]]
            theta, grad, _ = fold_angle_derivatives(x[springs], hessian=False)
            share = np.array([1.0, 1.0, 0.5, 0.5])
            np.add.at(g, springs.ravel(), (share[:, None] * grad).reshape(-1, 3))
            value = float(share @ (theta - np.pi))
        else:
            value = float(fold_angles(mesh, x)[row])
            g = _fold_angle_gradient(mesh, x, row)
        return value, g, np.zeros(len(x)), []


@dataclass(frozen=True)
class NodeCoordinate:
    """Coordinate ``axis`` ("x", "y" or "z") of node ``node`` in the current shape [m]."""

    node: int
    axis: str = "z"
    unit = "m"

    def __post_init__(self):
        one_of("NodeCoordinate.axis", self.axis, tuple(_AXES))

    def terms(self, model, u, T):
        n = model.mesh.n_nodes
        if not 0 <= int(self.node) < n:
            raise ParameterError(f"NodeCoordinate.node = {self.node}: the mesh has nodes "
                                 f"0..{n - 1}.")
        a = _AXES[self.axis]
        g = np.zeros((n, 3))
        g[self.node, a] = 1.0
        return float(model.mesh.nodes[self.node, a] + u[self.node, a]), g, np.zeros(n), []


@dataclass(frozen=True)
class CreaseTemperature:
    """A temperature measure of crease ``crease`` [deg C]: "actuation", "centre_line",
    "centre" or "crease_max" of :func:`~simulator.thermal.crease_temperatures` (the maximum is
    not differentiable where two nodes are equally hot: reported as a non-smooth point)."""

    crease: int
    measure: str = "centre_line"
    unit = "K"

    def __post_init__(self):
        one_of("CreaseTemperature.measure", self.measure, CREASE_MEASURES)

    def terms(self, model, u, T):
        mesh = model.mesh
        row, n = mesh.crease_row_of(self.crease), mesh.n_nodes
        value = float(crease_temperatures(T, mesh, self.measure)[row])
        nodes = mesh.crease_nodes[row]
        gT, nonsmooth = np.zeros(n), []
        if self.measure == "crease_max":
            t = T[nodes]
            hot = np.flatnonzero(t >= t.max() - 1e-9 * max(abs(t.max()), 1.0))
            if len(np.unique(nodes[hot])) > 1:
                nonsmooth.append(f"crease {self.crease}: nodes {nodes[hot].tolist()} are equally "
                                 "hot (the maximum switches)")
            gT[nodes[int(np.argmax(t))]] = 1.0
        else:                            # a linear measure: its weights on the crease nodes
            basis = np.zeros((n, len(nodes)))
            basis[nodes, np.arange(len(nodes))] = 1.0
            np.add.at(gT, nodes, crease_temperatures(basis, mesh, self.measure)[row])
        return value, np.zeros((n, 3)), gT, nonsmooth


def objective_terms(objective, model, u, T):
    """``(value, dJ/du (n, 3), dJ/dT (n,), nonsmooth messages, unit)`` of an objective."""
    if hasattr(objective, "terms"):
        value, gu, gT, nonsmooth = objective.terms(model, u, T)
        return value, gu, gT, nonsmooth, objective.unit
    if not callable(objective):
        raise ParameterError(f"objective = {objective!r}: give FoldAngle, NodeCoordinate, "
                             "CreaseTemperature or a callable f(u, T) -> (value, dJ/du (n, 3), "
                             "dJ/dT (n,)).")
    out = objective(u, T)
    try:
        value, gu, gT = out
        value, gu, gT = float(value), np.asarray(gu, float), np.asarray(gT, float)
    except (TypeError, ValueError):
        raise ParameterError("the objective callable must return (value, dJ/du, dJ/dT), got "
                             f"{type(out).__name__}.") from None
    if gu.shape != u.shape or gT.shape != T.shape:
        raise ParameterError(f"the objective callable returned dJ/du of shape {gu.shape} and "
                             f"dJ/dT of shape {gT.shape}; give {u.shape} and {T.shape}.")
    return value, gu, gT, [], getattr(objective, "unit", "-")


def _fold_angle_gradient(mesh, x, row) -> np.ndarray:
    """Gradient (n, 3) [rad/m] of :func:`~simulator.mechanics.kinematics.fold_angles` of crease
    row ``row`` at positions ``x``: the Newell normals' derivative (``dA/dc_j = [ (c_{j-1} -
    c_{j+1}) / 2 ]_x``, none in the centre), through their normalisation, the axis and the
    atan2."""
    s = mesh.panel_corner_start
    top = mesh.pattern.panel_orientation
    p1, p2 = mesh.crease_panels[row]
    normals = panel_normals(mesh, x)
    n1, n2 = normals[p1] * top[p1], normals[p2] * top[p2]
    ring = rings(np.diff(s))
    q1 = mesh.crease_edge_bars[row, 0]
    prev = ring.prev[q1]
    r = (x[prev] - x[q1]) * top[p1]
    a = r / np.linalg.norm(r)
    y, z = np.cross(n1, n2) @ a, n1 @ n2
    den = y * y + z * z
    g_n1 = (z * np.cross(n2, a) - y * n2) / den
    g_n2 = (z * np.cross(a, n1) - y * n1) / den
    g_a = z * np.cross(n1, n2) / den
    g = np.zeros_like(x)
    g_r = (g_a - a * (a @ g_a)) / np.linalg.norm(r) * top[p1]
    g[prev] += g_r
    g[q1] -= g_r
    for p, g_n in ((p1, g_n1), (p2, g_n2)):
        corners = np.arange(s[p], s[p + 1])
        c = x[corners]
        area = 0.5 * np.cross(c, np.roll(c, -1, axis=0)).sum(axis=0)     # Newell's vector area
        n = area / np.linalg.norm(area)
        g_area = top[p] * (g_n - n * (n @ g_n)) / np.linalg.norm(area)
        v = 0.5 * (np.roll(c, 1, axis=0) - np.roll(c, -1, axis=0))       # (c_{j-1} - c_{j+1})/2
        g[corners] += np.cross(g_area, v)
    return g
