"""The linear model behind :mod:`design.analysis.heaters` (private; public names re-exported there):
heater circuits, temperature rise per heater watt (:func:`influence_matrices`), fold
sensitivity to the rest angles (:func:`fold_sensitivity`), the allocation LP about a state and
the one-LP baseline :func:`linear_allocation`."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

# The LP linearises the solver itself: the steady thermal operator and the crease temperature
# measures for the influence matrices, a Newton re-solve of the equilibrium system with moved
# crease rest angles for the fold sensitivities (all public in simulator's namespaces).
from simulator import ConvergenceError, Model, ParameterError, SolverError
from simulator.mechanics import equilibrium_system, fold_angles
from simulator.model import spring_rest_angles
from simulator.solvers import solve_equilibrium
from simulator.steps import SimulationState, initial_state
from simulator.thermal import (LIMIT_MEASURES, crease_limit_temperatures, crease_temperatures,
                               thermal_model)

from ..devices.limits import SU8_TG

__all__ = ["influence_matrices", "fold_sensitivity", "linear_allocation", "TEMPERATURE_MEASURES",
           "limit_temperatures"]

#: What the temperature limit bounds: ``"centre_line"``, the mean of each crease's three
#: centre-line nodes (A, B, Ctr; the documented measure of the 1.2 T_g limit, theory 5.4, as
#: in every design problem and figure), or ``"crease_max"``, every crease node (stricter);
#: :data:`simulator.thermal.LIMIT_MEASURES`.
TEMPERATURE_MEASURES = tuple(LIMIT_MEASURES)


def heater_table(model: Model, heaters) -> dict:
    """{name: tuple of crease ids}; default one heater per actuated crease."""
    mesh = model.mesh
    if heaters is None:
        if model.actuators is None:
            raise ParameterError("allocate_heaters: the model has no actuators (make_model("
                                 "..., actuators=Actuators(...))).")
        heaters = {f"crease {c}": (c,) for c in dict(model.actuators.delta_alpha)}
    table = {}
    for name, creases in dict(heaters).items():
        creases = tuple(creases) if isinstance(creases, (tuple, list)) else (creases,)
        if not creases:
            raise ParameterError(f"heaters[{name!r}] lists no crease; give crease ids.")
        for c in creases:
            mesh.crease_row_of(c)          # raises a ParameterError naming an unknown crease
        table[str(name)] = creases
    if not table:
        raise ParameterError("heaters is empty; give {name: (crease ids...)}.")
    return table


def influence_matrices(model: Model, x: np.ndarray, heaters: Mapping) -> tuple:
    """Temperature rise per watt of each heater at node positions ``x`` (n, 3) [m].

    Returns ``(G, H)``: ``G`` (C, k) [K/W] actuation-temperature rise of every crease row,
    ``H`` (C * 7, k) [K/W] rise of every crease node (rows of ``mesh.crease_nodes``).
    """
    mesh, tm = model.mesh, thermal_model(model)
    B = np.zeros((mesh.n_creases, len(heaters)))
    for j, creases in enumerate(heaters.values()):
        for c in creases:
            B[mesh.crease_row_of(c), j] = 1.0
    Q = np.column_stack([tm.heat_vector(b) for b in B.T])
    rise = tm.solve(x, Q, room_temperature=0.0)                  # (n, k), linear in Q
    G = crease_temperatures(rise, mesh)                           # (C, k)
    return G, rise[mesh.crease_nodes].reshape(-1, len(heaters))


def check_measure(measure) -> str:
    if measure not in TEMPERATURE_MEASURES:
        raise ParameterError(f"temperature_measure = {measure!r}; use 'centre_line' (the mean "
                             "of each crease's centre-line nodes, the documented measure of the "
                             "1.2 T_g limit) or 'crease_max' (every crease node).")
    return measure


def limit_temperatures(model: Model, node_values: np.ndarray,
                       measure: str = "centre_line") -> np.ndarray:
    """What the temperature limit bounds, from values at the mesh nodes.

    ``node_values`` (n,) or (n, k) (temperatures [deg C], or rises per heater watt [K/W]);
    returns (C,) or (C, k) for ``"centre_line"`` (the mean of each crease's centre-line nodes
    A, B, Ctr, :func:`simulator.thermal.crease_limit_temperatures`: a linear functional, so the LP
    stays linear) or (C * 7,) or (C * 7, k) for ``"crease_max"`` (every crease node, rows of
    ``mesh.crease_nodes``: their maximum is bounded by bounding each).
    """
    values = np.asarray(node_values)
    if check_measure(measure) == "centre_line":
        return crease_limit_temperatures(values, model.mesh)
    return values[model.mesh.crease_nodes].reshape(-1, *values.shape[1:])


def limit_rows(model: Model, H: np.ndarray, measure: str) -> np.ndarray:
    """Rows of the limit measure per heater watt from ``H`` (C * 7, k), the rise of every
    crease node (:func:`influence_matrices`)."""
    if measure == "crease_max":
        return H
    rise = np.zeros((model.mesh.n_nodes, H.shape[1]))
    rise[model.mesh.crease_nodes.ravel()] = H
    return limit_temperatures(model, rise, measure)


def solve_lp(A, step, band, H, rise_limit, weights, p_cur, radius, p_max):
    """The allocation LP about the current state, within a trust region.

    Asked: fold change ``A (p - p_cur)`` equal to ``step`` within ``band``, every power within
    ``radius`` of ``p_cur``. First the least total excess ``sum s`` over the band is found
    (0 if the step can be met), then the least power with that excess. Returns
    ``(p, excess [rad], status)``, ``p`` None if an LP was not solved.
    """
    import cvxpy as cp

    solver = "SCIPY" if "SCIPY" in cp.installed_solvers() else None   # HiGHS via scipy, quiet
    p, s = cp.Variable(A.shape[1], nonneg=True), cp.Variable(A.shape[0], nonneg=True)
    change = A @ p - A @ p_cur - step
    cons = [change <= band + s, change >= -band - s, H @ p <= rise_limit] + (
        [p <= p_max] if p_max is not None else [])
    try:
        region = [cp.abs(p - p_cur) <= radius] if np.all(np.isfinite(radius)) else []
        fit = cp.Problem(cp.Minimize(cp.sum(s)), cons + region)
        fit.solve(solver=solver)
        if fit.status == "infeasible":   # p_cur too hot for the limit: leave the region
            fit = cp.Problem(cp.Minimize(cp.sum(s)), cons)
            fit.solve(solver=solver)
        else:
            cons += region
        if fit.status not in ("optimal", "optimal_inaccurate"):
            return None, math.nan, fit.status
        excess = float(np.sum(s.value))
        power_lp = cp.Problem(cp.Minimize(weights @ p),
                              cons + [cp.sum(s) <= excess + 1e-9 + 1e-6 * excess])
        power_lp.solve(solver=solver)
    except (cp.error.SolverError, ValueError) as exc:
        return None, math.nan, f"solver error: {exc}"
    if power_lp.status not in ("optimal", "optimal_inaccurate") or p.value is None:
        return None, excess, power_lp.status
    return np.maximum(np.asarray(p.value, float), 0.0), excess, power_lp.status


def fold_sensitivity(model: Model, state: SimulationState, creases=None,
                     delta: float = 1e-4) -> np.ndarray:
    """``S[i, j] = d fold_i / d rest_j`` [rad/rad] at the equilibrium ``state``.

    Rows: every crease row; columns: the crease rows ``creases`` (default all). One Newton
    solve per column from ``state`` with crease ``j``'s rest angle moved by ``delta`` [rad].
    """
    mesh = model.mesh
    cols = np.arange(mesh.n_creases) if creases is None else np.asarray(creases, int)
    system = equilibrium_system(model)
    f = state.applied_load.ravel()

    def folds(rest):
        res = solve_equilibrium(system, state.u, f, spring_rest_angles(mesh, rest, model.params))
        if not res.success:
            raise ConvergenceError(f"fold_sensitivity: equilibrium not found ({res.message})",
                                       res)
        return fold_angles(mesh, mesh.nodes + res.u)

    base = folds(state.crease_rest)
    S = np.empty((mesh.n_creases, len(cols)))
    for k, j in enumerate(cols):
        rest = state.crease_rest.copy()
        rest[j] += delta
        S[:, k] = (folds(rest) - base) / delta
    return S


def crease_weights(table) -> np.ndarray:
    """Creases per heater: the weight of its power in the total."""
    return np.array([len(c) for c in table.values()], float)


def linear_model(model, state, table, rows) -> tuple:
    """``(A, H, folds)`` at ``state``: fold change of the target rows per heater watt
    (``S diag(r) G``), crease-node temperature rise per watt, current target folds."""
    mesh = model.mesh
    rot = model.actuators.rotation_per_kelvin(mesh)
    act = np.flatnonzero(rot)                            # actuated crease rows
    G, H = influence_matrices(model, mesh.nodes + state.u, table)
    A = fold_sensitivity(model, state, act)[rows] @ (rot[act, None] * G[act])
    return A, H, fold_angles(mesh, mesh.nodes + state.u)[rows]


def check_targets(model, targets, rot):
    mesh = model.mesh
    rows = {}
    for c, v in dict(targets).items():
        rows[c] = mesh.crease_row_of(c)
        if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v)):
            raise ParameterError(f"targets[{c}] = {v!r}; give a fold angle in rad.")
        if rot[rows[c]] == 0:
            raise ParameterError(f"targets: crease {c} is not an actuator (delta_alpha 0); "
                                 "heating cannot fold it.")
    if not rows:
        raise ParameterError("targets is empty; give {crease id: fold angle [rad]}.")
    return np.array(list(rows.values()))


def linear_allocation(model: Model, targets: Mapping, *, heaters: Mapping | None = None,
                      state: SimulationState | None = None,
                      temperature_limit: float = 1.2 * SU8_TG, band: float = 0.0,
                      temperature_measure: str = "centre_line") -> np.ndarray:
    """Powers [W] per heater from one LP at ``state`` (default flat), without simulating.

    The design one would make ignoring that folding changes the heat loss and the
    mechanics: the baseline that :func:`allocate_heaters` improves on. ``temperature_limit``
    [deg C] bounds ``temperature_measure`` as in :func:`allocate_heaters`. Raises
    :class:`ParameterError` if the LP has no solution.
    """
    check_measure(temperature_measure)
    table = heater_table(model, heaters)
    state = initial_state(model) if state is None else state
    rows = check_targets(model, targets, model.actuators.rotation_per_kelvin(model.mesh))
    A, H, folds = linear_model(model, state, table, rows)
    step = np.array([float(v) for v in dict(targets).values()]) - folds
    rise_limit = temperature_limit - limit_temperatures(model, state.temperature,
                                                        temperature_measure)
    p, _, status = solve_lp(A, step, band, limit_rows(model, H, temperature_measure), rise_limit,
                             crease_weights(table), np.zeros(len(table)), np.inf, None)
    if p is None:
        raise SolverError(f"linear_allocation: LP not solved ({status}).")
    return p
