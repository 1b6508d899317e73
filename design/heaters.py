"""Minimum-power heater allocation: which power on which heater folds the creases as asked.

For a fixed shape the steady temperatures are linear in the heater powers ``p`` [W]: the
actuation temperature rise of crease ``i`` (the 7-node weighted mean, digest 6.7) is
``(G p)_i`` and the rise of every crease node is ``H p``, with ``G`` and ``H`` from one
factorisation of the condensed conductivity (:meth:`ThermalModel.solve` with one column per
heater). The rest-angle change is ``r_i (G p)_i`` (Timoshenko, linear in the rise), so

    minimise    sum_j n_j p_j                      total power (n_j creases on heater j)
    subject to  (G p)_i = dT_i      for each target crease i (the rise its target fold needs)
                T_room + H p <= T_limit            every crease node below the limit
                0 <= p_j <= p_max

is a linear programme (solved with cvxpy). With more heaters than targets (or heaters on
creases without a target) it chooses how to share the work; heat conducted between
neighbouring creases is used, not fought.

Folding changes the heat loss (and gravity or contact keep the fold from following the rest
angle exactly), so :func:`allocate_heaters` iterates: solve the LP at the current shape,
simulate heating with those powers, measure how far the fold lags the rest-angle change,
rebuild ``G`` and ``H`` at the folded shape, and repeat until every target is met within
``fold_tol``. Where the limits make the LP infeasible at the current shape (the flat shape
loses more heat than the folded one), the round takes the largest reachable fraction of the
required rises instead; the allocation is declared infeasible only when that fraction stops
growing. Each round is logged and kept in the result's history.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from simulator.bimorph import crease_temperature_weights
from simulator.errors import ParameterError
from simulator.geometry import fold_angles
from simulator.heating import Heat, thermal_model
from simulator.loading import SimulationState, initial_state, simulate
from simulator.model import Model
from simulator.solvers import NewtonOptions

from .problem import SU8_TG

__all__ = ["HeaterAllocation", "influence_matrices", "allocate_heaters"]

logger = logging.getLogger(__name__)


def _heater_table(model: Model, heaters) -> dict:
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
    nodes = rise[mesh.crease_nodes]                               # (C, 7, k)
    G = np.einsum("cwk,w->ck", nodes, crease_temperature_weights())
    return G, nodes.reshape(-1, len(heaters))


@dataclass
class HeaterAllocation:
    """Outcome of :func:`allocate_heaters`.

    Attributes
    ----------
    heaters : {name: crease ids}
    power : (k,) power of each heater [W] (each of its creases gets this value)
    status : "converged", "infeasible", "failed" or "max_rounds"
    message : str
    rounds : number of LP + simulation rounds
    targets, achieved : {crease id: fold angle [rad]} asked for and reached
    max_temperature : hottest crease node at the end of the last simulation [deg C]
    temperature_limit : [deg C]
    history : one dict per round (total power [mW], worst fold error [deg], ...)
    state : SimulationState after heating with ``power`` (None if no simulation ran)
    """

    heaters: dict
    power: np.ndarray
    status: str
    message: str
    rounds: int
    targets: dict
    achieved: dict = field(default_factory=dict)
    max_temperature: float = math.nan
    temperature_limit: float = math.nan
    history: list = field(default_factory=list)
    state: SimulationState | None = None

    @property
    def converged(self) -> bool:
        return self.status == "converged"

    @property
    def total_power(self) -> float:
        """Sum over creases of their power [W]."""
        return float(sum(p * len(c) for p, c in zip(self.power, self.heaters.values())))

    def power_by_crease(self) -> dict:
        """{crease id: power [W]}."""
        return {c: float(p) for p, cs in zip(self.power, self.heaters.values()) for c in cs}

    def to_frame(self):
        """One row per heated or target crease: heater, power, target and reached folds."""
        import pandas as pd

        by_crease = self.power_by_crease()
        heater_of = {c: name for name, cs in self.heaters.items() for c in cs}
        rows = []
        for c in sorted(set(by_crease) | set(self.targets)):
            t, a = self.targets.get(c), self.achieved.get(c)
            rows.append({"crease": c, "heater": heater_of.get(c, ""),
                         "power [mW]": 1e3 * by_crease.get(c, 0.0),
                         "target_fold [deg]": math.degrees(t) if t is not None else math.nan,
                         "fold_angle [deg]": math.degrees(a) if a is not None else math.nan})
        return pd.DataFrame(rows)


def _solve_lp(G_t, d_rise, H, rise_limit, weights, p_max):
    """The allocation LP at one shape.

    Returns ``(p, reach, status)``: ``reach`` (<= 1) is the largest fraction of the required
    rises ``d_rise`` that the limits allow; ``p`` is the least-power allocation reaching that
    fraction (None if the LP could not be solved).
    """
    import cvxpy as cp

    p, lam = cp.Variable(G_t.shape[1], nonneg=True), cp.Variable()
    limits = [H @ p <= rise_limit] + ([p <= p_max] if p_max is not None else [])
    try:
        reach_lp = cp.Problem(cp.Maximize(lam), [G_t @ p == lam * d_rise, lam <= 1] + limits)
        reach_lp.solve()
        if reach_lp.status not in ("optimal", "optimal_inaccurate"):
            return None, math.nan, reach_lp.status
        reach = min(1.0, float(lam.value))
        power_lp = cp.Problem(cp.Minimize(weights @ p),
                              [G_t @ p == (reach - 1e-9) * d_rise] + limits)
        power_lp.solve()
    except cp.error.SolverError as exc:
        return None, math.nan, f"solver error: {exc}"
    if power_lp.status not in ("optimal", "optimal_inaccurate") or p.value is None:
        return None, reach, power_lp.status
    return np.maximum(np.asarray(p.value, float), 0.0), reach, power_lp.status


class _Rounds:
    """One LP at the current shape, then one heating simulation with its powers."""

    def __init__(self, model, state, table, rows, fold0, limit, max_power, increments, options,
                 out, relaxation):
        self.relaxation = relaxation
        self.model, self.state, self.table, self.rows, self.fold0 = model, state, table, rows, fold0
        self.limit, self.max_power, self.increments, self.options = (limit, max_power,
                                                                     increments, options)
        mesh = model.mesh
        self.rot = model.actuators.rotation_per_kelvin(mesh)[rows]
        self.rise_limit = limit - state.temperature[mesh.crease_nodes].ravel()
        self.weights = np.array([len(c) for c in table.values()], float)
        self.offset = np.zeros(len(rows))   # fold change minus rest-angle change (gravity...)
        self.x, self.out = mesh.nodes + state.u, out

    def round(self, goal, tol):
        """Returns (goal met, reachable fraction, shortfall per target [rad])."""
        t0, out, mesh, rows = time.perf_counter(), self.out, self.model.mesh, self.rows
        G, H = influence_matrices(self.model, self.x, self.table)
        d_rise = np.maximum((goal - self.fold0 - self.offset) / self.rot, 0.0)
        p, reach, lp_status = _solve_lp(G[rows], d_rise, H, self.rise_limit, self.weights,
                                        self.max_power)
        out.rounds += 1
        if p is None:
            out.status, out.message = "failed", f"round {out.rounds}: LP not solved ({lp_status})"
            logger.warning(out.message)
            return False, reach, None
        if out.rounds > 1:       # under-relaxed: the heat-loss feedback makes plain updates swing
            p = (1 - self.relaxation) * out.power + self.relaxation * p
        out.power = p
        res = simulate(self.model, [Heat({c: pj for pj, c in zip(p, self.table.values())},
                                         increments=self.increments)],
                       state=self.state, options=self.options)
        if not res.converged:
            out.status = "failed"
            out.message = f"round {out.rounds}: heating failed: {res.message}"
            logger.warning(out.message)
            return False, reach, None
        out.state, self.x = res.state, mesh.nodes + res.state.u
        reached = fold_angles(mesh, self.x)[rows]
        self.offset = (reached - self.fold0) - (res.state.crease_rest
                                                - self.state.crease_rest)[rows]
        out.achieved = dict(zip(out.targets, map(float, reached)))
        out.max_temperature = float(res.state.temperature[mesh.crease_nodes].max())
        short = (goal - reached) * np.sign(goal - self.fold0)     # > 0: not folded far enough
        out.history.append({"round": out.rounds, "total_power [mW]": 1e3 * out.total_power,
                            "reach": reach, "worst_fold_error [deg]": math.degrees(np.abs(short).max()),
                            "max_crease_temperature [degC]": out.max_temperature,
                            "wall_time [s]": time.perf_counter() - t0})
        logger.info("heater allocation round %d: %.4g mW, reach %.3f, worst fold error %.3g deg, "
                    "%.4g degC", out.rounds, 1e3 * out.total_power, reach,
                    math.degrees(np.abs(short).max()), out.max_temperature)
        met = (reach >= 1 - 1e-9 and np.abs(short).max() <= tol
               and out.max_temperature <= self.limit + 1e-6)
        return met, reach, short


def _check_targets(model, targets, rot):
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


def allocate_heaters(model: Model, targets: Mapping, *, heaters: Mapping | None = None,
                     state: SimulationState | None = None,
                     temperature_limit: float = 1.2 * SU8_TG, max_power: float | None = None,
                     fold_tol: float = math.radians(0.5), max_rounds: int = 20, stages: int = 3,
                     relaxation: float = 0.5,
                     increments: int = 50, options: NewtonOptions = NewtonOptions()
                     ) -> HeaterAllocation:
    """Least total power that folds every target crease to its target angle.

    Parameters
    ----------
    model : Model with thermal parameters and actuators
    targets : {crease id: fold angle [rad]}
        Fold angle from flat (sign as :func:`simulator.geometry.fold_angles`) each crease must
        reach within ``fold_tol``; a target that needs the crease to fold against its actuation direction is a
        ParameterError.
    heaters : {name: crease id or tuple of crease ids}, optional
        Independent circuits; every crease of a circuit gets the circuit's power. Default:
        one heater per actuated crease.
    state : SimulationState, optional
        Start state (after residual fold, gravity...); default the flat initial state.
    temperature_limit : float
        Upper bound on every crease node temperature [deg C] (default 1.2 T_g of SU-8).
    max_power : float, optional
        Upper bound per heater [W].
    fold_tol : float
        Accepted fold error [rad] (default 0.5 deg).
    max_rounds : int
        LP + simulation rounds before giving up (status "max_rounds").
    stages : int
        The targets are approached in this many equal fractions, each shape predicting the
        heat loss of the next (from the flat shape alone the powers overshoot badly); one
        round per intermediate stage, then rounds until the targets are met.
    relaxation : float
        Each round moves the powers this fraction of the way to the new LP solution (1: no
        relaxation); 0.5 damps the swing from the heat-loss feedback.
    increments : int
        Heating increments of each simulation.
    options : NewtonOptions

    Returns
    -------
    HeaterAllocation
        ``status`` is "converged", "infeasible" (the LP has no solution: limit or direction),
        "failed" (a simulation did not converge) or "max_rounds"; never raises for these.
    """
    if not (isinstance(max_rounds, int) and max_rounds >= 1):
        raise ParameterError(f"max_rounds = {max_rounds!r} must be a positive integer.")
    if not (0 < relaxation <= 1):
        raise ParameterError(f"relaxation = {relaxation!r} must be in (0, 1].")
    if not (isinstance(stages, int) and stages >= 1):
        raise ParameterError(f"stages = {stages!r} must be a positive integer.")
    if not (math.isfinite(fold_tol) and fold_tol > 0):
        raise ParameterError(f"fold_tol = {fold_tol!r} must be a positive angle in rad.")
    if max_power is not None and not (math.isfinite(max_power) and max_power > 0):
        raise ParameterError(f"max_power = {max_power!r} must be a positive power in W.")
    table = _heater_table(model, heaters)
    state = initial_state(model) if state is None else state
    mesh = model.mesh
    rot = (model.actuators.rotation_per_kelvin(mesh) if model.actuators is not None
           else np.zeros(mesh.n_creases))
    rows = _check_targets(model, targets, rot)
    target = np.array([float(v) for v in dict(targets).values()])
    fold0 = fold_angles(mesh, mesh.nodes + state.u)[rows]
    if np.any((target - fold0) * rot[rows] < 0):
        c = list(dict(targets))[int(np.argmax((target - fold0) * rot[rows] < 0))]
        raise ParameterError(f"targets[{c}]: folding crease {c} to {math.degrees(targets[c]):.4g}"
                             " deg needs folding against its actuation direction; heating "
                             "cannot do that.")
    out = HeaterAllocation(table, np.zeros(len(table)), "max_rounds", "", 0, dict(targets),
                           temperature_limit=float(temperature_limit))
    run = _Rounds(model, state, table, rows, fold0, temperature_limit, max_power, increments,
                  options, out, relaxation)
    for k in range(1, stages + 1):
        goal = fold0 + (k / stages) * (target - fold0)
        last_reach = -1.0
        while out.rounds < max_rounds:
            done, reach, short = run.round(goal, fold_tol)
            if out.status == "failed":
                return out
            if done or k < stages:       # one round per intermediate stage: a shape for G
                break
            if reach < 1 - 1e-9 and reach <= last_reach + 1e-3:
                out.status = "infeasible"
                out.message = (f"round {out.rounds}: the limits ({temperature_limit:.4g} degC" +
                               (f", {1e3 * max_power:.4g} mW per heater" if max_power else "") +
                               f") allow only {100 * reach:.1f}% of the temperature rise needed "
                               f"for {100 * k / stages:.0f}% of the target folds")
                logger.warning(out.message)
                return out
            last_reach = reach
        else:
            break
    else:
        out.status = "converged"
        out.message = (f"targets met within {math.degrees(fold_tol):.3g} deg in {out.rounds} "
                       f"rounds: {1e3 * out.total_power:.4g} mW")
        return out
    out.message = (f"targets not met within {math.degrees(fold_tol):.3g} deg after "
                   f"{max_rounds} rounds (worst fold error "
                   f"{out.history[-1]['worst_fold_error [deg]']:.3g} deg)")
    logger.warning(out.message)
    return out
