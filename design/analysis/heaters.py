"""Minimum-power heater allocation: which power on which heater folds the creases as asked.

For a fixed shape the steady temperatures are linear in the heater powers ``p`` [W]: the
actuation temperature rise of every crease (the 7-node weighted mean, theory 5.1) is ``G p``
and the rise of every crease node is ``H p``, with ``G`` and ``H`` from one factorisation of
the condensed conductivity (:meth:`~simulator.thermal.steady.ThermalModel.solve` with one column per heater). The
rest-angle change is ``r * (G p)`` (Timoshenko, linear in the rise), and near an equilibrium
the fold angles answer to the rest angles through the sensitivity ``S = d fold / d rest``
(one Newton solve per actuated crease: creases around a vertex move together). So, about the
current state (powers ``p_c``, folds ``f_c``), ``fold(p) ~ f_c + A (p - p_c)`` with
``A = S diag(r) G`` and

    minimise    sum_j n_j p_j                       total power (n_j creases on heater j)
    subject to  |f_c + A (p - p_c) - target| <= band   for the target creases
                T_0 + L H p <= T_limit              the limit measure of every crease
                0 <= p_j <= p_max

where ``L`` takes the measure the limit bounds (``temperature_measure``): by default the
documented measure of the 1.2 T_g limit (theory 5.4, the one every design problem and figure
checks), the mean of each crease's three centre-line nodes (A, B, Ctr), a linear functional of
the node temperatures, so the programme stays linear; ``"crease_max"`` bounds every crease node
instead (stricter: the hottest node is 5-20 degC above the centre-line mean).

is a linear programme (solved with cvxpy). With more heaters than targets (or heaters on
creases without a target, or a tolerance band) it chooses how to share the work; heat
conducted between neighbouring creases is used, not fought.

Folding changes the heat loss, which the linear model does not see, so
:func:`allocate_heaters` iterates: solve the LP, simulate heating with those powers from the
start state, rebuild ``G``, ``H`` and ``S`` at the folded shape, and repeat until every
target is met within ``fold_tol``. The targets are approached in stages, and each LP keeps
the powers within a trust region that grows while the linear model predicts the simulated
folds well and shrinks when it does not (the heat-loss feedback makes full steps overshoot).
Where the targets cannot be met, the LP finds the allocation closest to them (least total
excess over the band); the allocation is declared infeasible when that excess stays above
``fold_tol`` while the model predicts well. Each round is logged and kept in the result's
history.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from simulator import ConvergenceError, Heat, Model, NewtonOptions, ParameterError, simulate
from simulator.mechanics import fold_angles
from simulator.steps import SimulationState, initial_state
from simulator.thermal import TemperatureLimit, TemperatureVerdict
from simulator._result import ResultFiles
from simulator._validate import integer, non_negative, positive

from ..core.contract import check_outcome
from ._heater_lp import (TEMPERATURE_MEASURES, check_measure, check_targets, heater_table,
                         limit_rows, linear_model, solve_lp, crease_weights, fold_sensitivity,
                         influence_matrices, limit_temperatures, linear_allocation)
from ..devices.limits import SU8_TG

__all__ = ["HeaterAllocation", "ALLOCATION_STATUSES", "TEMPERATURE_MEASURES",
           "influence_matrices", "fold_sensitivity", "limit_temperatures", "linear_allocation",
           "allocate_heaters"]

logger = logging.getLogger(__name__)


def _total_power(power, heaters) -> float:
    """Sum over creases of their heater's power [W]."""
    return float(sum(p * len(c) for p, c in zip(power, heaters.values())))


#: Status words of :func:`allocate_heaters`: converged (success), and why it did not.
ALLOCATION_STATUSES = ("converged", "infeasible", "failed", "max_rounds")


@dataclass(frozen=True, eq=False)
class HeaterAllocation(ResultFiles):
    """Outcome of :func:`allocate_heaters`.

    Attributes
    ----------
    success : bool
        Every target fold is met within the tolerance, below the temperature limit.
    status : "converged", "infeasible" (the LP cannot meet the targets within the limits),
        "failed" (an LP or a simulation failed) or "max_rounds"
    message : str
    heaters : {name: crease ids}
    power : (k,) array or None
        Power of each heater [W] (each of its creases gets this value) in the last simulated
        round, i.e. the powers that gave ``achieved``; None if no round was simulated.
    rounds : number of LP + simulation rounds
    targets, achieved : {crease id: fold angle [rad]} asked for and reached
    max_temperature : float
        What the limit bounds, at the end of the last simulation [deg C]: the centre-line
        mean of the hottest crease (``temperature_measure`` "centre_line") or the hottest
        crease node ("crease_max")
    temperature_limit : [deg C]
    history : tuple of dicts, one per round (total power [mW], worst fold error [deg], ...)
    state : SimulationState after heating with ``power`` (None if no simulation ran)
    temperature_measure : "centre_line" or "crease_max", what ``temperature_limit`` bounds
    max_node_temperature : float
        Hottest crease node at the end of the last simulation [deg C] (equals
        ``max_temperature`` with "crease_max")
    """

    success: bool
    status: str
    message: str
    heaters: dict
    power: np.ndarray | None
    rounds: int
    targets: dict
    achieved: dict = field(default_factory=dict)
    max_temperature: float = math.nan
    temperature_limit: float = math.nan
    history: tuple = ()
    state: SimulationState | None = None
    temperature_measure: str = "centre_line"
    max_node_temperature: float = math.nan

    def __post_init__(self):
        check_outcome(self, ALLOCATION_STATUSES[:1], ALLOCATION_STATUSES[1:])

    @property
    def total_power(self) -> float | None:
        """Sum over creases of their power [W] (None if no round was simulated)."""
        return None if self.power is None else _total_power(self.power, self.heaters)

    def power_by_crease(self) -> dict:
        """{crease id: power [W]} (empty if no round was simulated)."""
        if self.power is None:
            return {}
        return {c: float(p) for p, cs in zip(self.power, self.heaters.values()) for c in cs}

    def to_frame(self):
        """One row per heated or target crease: heater, power (NaN if no round was
        simulated; 0 on a crease without heater), target and reached folds."""
        import pandas as pd

        by_crease = self.power_by_crease()
        unheated = 0.0 if self.power is not None else math.nan
        heater_of = {c: name for name, cs in self.heaters.items() for c in cs}
        rows = []
        for c in sorted(set(heater_of) | set(self.targets)):
            t, a = self.targets.get(c), self.achieved.get(c)
            rows.append({"crease": c, "heater": heater_of.get(c, ""),
                         "power [mW]": 1e3 * by_crease.get(c, unheated),
                         "target_fold [deg]": math.degrees(t) if t is not None else math.nan,
                         "fold_angle [deg]": math.degrees(a) if a is not None else math.nan})
        return pd.DataFrame(rows)

    def _tables(self) -> dict:
        import pandas as pd

        return {"heaters.csv": self.to_frame(),
                "rounds.csv": pd.DataFrame(list(self.history)) if self.history else None}

    def _meta(self) -> dict:
        return {"heaters": dict(self.heaters),
                "rounds": self.rounds, "total_power [W]": self.total_power,
                "max_temperature [degC]": self.max_temperature,
                "max_node_temperature [degC]": self.max_node_temperature,
                "temperature_limit [degC]": self.temperature_limit,
                "temperature_measure": self.temperature_measure,
                "targets [rad]": {str(k): v for k, v in self.targets.items()},
                "achieved [rad]": {str(k): v for k, v in self.achieved.items()}}


@dataclass
class _Allocation:
    """The allocation while the rounds run (mutable); :meth:`result` freezes it."""

    heaters: dict
    targets: dict
    temperature_limit: float
    temperature_measure: str = "centre_line"
    status: str = "max_rounds"
    message: str = ""
    rounds: int = 0
    power: np.ndarray | None = None
    achieved: dict = field(default_factory=dict)
    max_temperature: float = math.nan
    max_node_temperature: float = math.nan
    history: list = field(default_factory=list)
    state: SimulationState | None = None
    verdict: TemperatureVerdict | None = None     # of the last simulated round

    def temperature_note(self) -> str:
        """``; last round: crease 3: centre-line mean 249.80 degC <= limit = 252 degC`` (the
        verdict of the last simulated round; empty if none)."""
        return "" if self.verdict is None else f"; last round: {self.verdict.message}"

    @property
    def total_power(self) -> float:
        return _total_power(self.power, self.heaters)

    def result(self) -> HeaterAllocation:
        return HeaterAllocation(
            self.status == "converged", self.status, self.message, self.heaters,
            None if self.state is None else self.power, self.rounds, self.targets,
            self.achieved, self.max_temperature, self.temperature_limit, tuple(self.history),
            self.state, self.temperature_measure, self.max_node_temperature)


class _Rounds:
    """One LP about the current state, then one heating simulation with its powers."""

    def __init__(self, model, state, table, rows, limit, max_power, increments, options,
                 out, band, coupling="settled"):
        self.band, self.coupling = band, coupling
        self.model, self.state, self.table, self.rows = model, state, table, rows
        self.limit, self.max_power, self.increments, self.options = (limit, max_power,
                                                                     increments, options)
        self.measure = out.temperature_measure
        self.verdict_limit = TemperatureLimit(limit, measure=self.measure)
        self.rise_limit = limit - limit_temperatures(model, state.temperature, self.measure)
        if np.any(self.rise_limit <= 0):
            raise ParameterError(f"temperature_limit = {limit!r} degC is not above the start "
                                 f"state's crease temperatures ({self.measure} measure).")
        self.weights = crease_weights(table)
        self.out, self.p_cur = out, np.zeros(len(table))
        self._linearise(state)
        # first trust radius: the power that takes each heater's hottest crease node a tenth
        # of the way to the limit (a step size, the same whatever the limit measure)
        node_rise = limit - state.temperature[model.mesh.crease_nodes].ravel()
        self.radius = 0.1 * node_rise.max() / np.maximum(self.H_nodes.max(axis=0), 1e-300)

    def _linearise(self, state, previous=None):
        """``A``, ``H`` and the folds at ``state`` (heated with ``p_cur``); the folds are kept
        continuous with ``previous`` through +-pi (atan2 wraps)."""
        self.A, self.H_nodes, folds = linear_model(self.model, state, self.table, self.rows)
        self.H = limit_rows(self.model, self.H_nodes, self.measure)  # the limit's measure per W
        if previous is not None:
            folds = previous + (folds - previous + np.pi) % (2 * np.pi) - np.pi
        self.folds = folds

    def round(self, goal, tol):
        """Returns (goal met, excess over the band that the LP could not remove [rad])."""
        t0, out, mesh, A = time.perf_counter(), self.out, self.model.mesh, self.A
        p, excess, lp_status = solve_lp(A, goal - self.folds, self.band, self.H,
                                         self.rise_limit, self.weights, self.p_cur,
                                         self.radius, self.max_power)
        out.rounds += 1
        if p is None:
            out.status, out.message = "failed", f"round {out.rounds}: LP not solved ({lp_status})"
            logger.warning(out.message)
            return False, excess
        planned = self.folds + A @ (p - self.p_cur)      # what the linear model expects
        res = simulate(self.model, [Heat({c: pj for pj, c in zip(p, self.table.values())},
                                         increments=self.increments, coupling=self.coupling)],
                       state=self.state, options=self.options)
        if not res.success:                            # too far: shrink the region, retry
            self.radius = self.radius / 4
            logger.info("heater allocation round %d: heating failed (%s); trust radius cut",
                        out.rounds, res.message)
            return False, excess
        previous = self.folds
        out.power = self.p_cur = p
        out.state = res.state
        try:
            self._linearise(res.state, previous)
        except (ParameterError, ConvergenceError) as exc:
            out.status, out.message = "failed", f"round {out.rounds}: {exc}"
            return False, excess
        reached = self.folds
        # trust region: grow when the linear model predicted the move well, shrink if not
        moved, miss = np.abs(planned - previous).max(), np.abs(reached - planned).max()
        self.radius = self.radius * (2.0 if miss <= 0.25 * moved + tol else
                                     0.5 if miss > 0.75 * moved else 1.0)
        out.achieved = dict(zip(out.targets, map(float, reached)))
        out.verdict = self.verdict_limit.judge(res.state.temperature, mesh)
        out.max_temperature = out.verdict.temperature
        out.max_node_temperature = out.verdict.hottest_node
        error = np.maximum(np.abs(reached - goal) - self.band, 0.0)
        out.history.append({"round": out.rounds, "total_power [mW]": 1e3 * out.total_power,
                            "worst_fold_error [deg]": math.degrees(error.max()),
                            "model_miss [deg]": math.degrees(miss),
                            "limit_temperature [degC]": out.max_temperature,
                            "max_crease_temperature [degC]": out.max_node_temperature,
                            "wall_time [s]": time.perf_counter() - t0})
        logger.info("heater allocation round %d: %.4g mW, fold error %.3g deg beyond the band, "
                    "model miss %.3g deg, %.4g degC", out.rounds, 1e3 * out.total_power,
                    math.degrees(error.max()), math.degrees(miss), out.max_temperature)
        # the LP puts the limit's measure on the limit; 1e-6 K of it is rounding, not a miss
        met = (error.max() <= tol and miss <= tol and out.max_temperature <= self.limit + 1e-6)
        return met, excess


def allocate_heaters(model: Model, targets: Mapping, *, heaters: Mapping | None = None,
                     state: SimulationState | None = None,
                     temperature_limit: float = 1.2 * SU8_TG, max_power: float | None = None,
                     fold_tol: float = math.radians(0.5), max_rounds: int = 20, stages: int = 3,
                     band: float = 0.0, temperature_measure: str = "centre_line",
                     increments: int = 50, options: NewtonOptions = NewtonOptions(),
                     coupling: str = "settled") -> HeaterAllocation:
    """Least total power that folds every target crease to its target angle.

    Parameters
    ----------
    model : Model with thermal parameters and actuators
    targets : {crease id: fold angle [rad]}
        Fold angle from flat (sign as :func:`simulator.mechanics.fold_angles`) each crease must
        reach within ``fold_tol``; a target that needs the crease to fold against its actuation direction is a
        ParameterError.
    heaters : {name: crease id or tuple of crease ids}, optional
        Independent circuits; every crease of a circuit gets the circuit's power. Default:
        one heater per actuated crease.
    state : SimulationState, optional
        Start state (after residual fold, gravity...); default the flat initial state.
    temperature_limit : float
        Upper bound [deg C] on ``temperature_measure`` of every crease (default 1.2 T_g of
        SU-8).
    max_power : float, optional
        Upper bound per heater [W].
    fold_tol : float
        Accepted fold error [rad] (default 0.5 deg).
    band : float
        Freedom given to every target [rad]: a fold anywhere within ``band`` of its target is
        acceptable, and the LP uses it to save power (default 0: exact targets).
    max_rounds : int
        LP + simulation rounds before giving up (status "max_rounds").
    stages : int
        The targets are approached in this many equal fractions, each shape predicting the
        heat loss of the next (from the flat shape alone the powers overshoot badly); one
        round per intermediate stage, then rounds until the targets are met.
    temperature_measure : {"centre_line", "crease_max"}
        What ``temperature_limit`` bounds: the mean of each crease's three centre-line nodes
        (default; the documented measure of the 1.2 T_g limit, theory 5.4, checked by every
        design problem and figure) or every crease node (stricter).
    increments : int
        Heating increments of each simulation.
    options : NewtonOptions
    coupling : {"settled", "staggered", "iterated"}
        ``Heat.coupling`` of each simulation ("staggered": the reference's lagged loop).

    Returns
    -------
    HeaterAllocation
        ``success`` when converged; else ``status`` is "infeasible" (the LP has no solution:
        limit or direction), "failed" (an LP or a simulation failed) or "max_rounds"; never
        raises for these.
    """
    _check_settings(max_rounds=max_rounds, stages=stages, band=band, fold_tol=fold_tol,
                    max_power=max_power)
    check_measure(temperature_measure)
    table = heater_table(model, heaters)
    state = initial_state(model) if state is None else state
    mesh = model.mesh
    rot = (model.actuators.rotation_per_kelvin(mesh) if model.actuators is not None
           else np.zeros(mesh.n_creases))
    rows = check_targets(model, targets, rot)
    target = np.array([float(v) for v in dict(targets).values()])
    fold0 = fold_angles(mesh, mesh.nodes + state.u)[rows]
    if np.any((target - fold0) * rot[rows] < 0):
        c = list(dict(targets))[int(np.argmax((target - fold0) * rot[rows] < 0))]
        raise ParameterError(f"targets[{c}]: folding crease {c} to {math.degrees(targets[c]):.4g}"
                             " deg needs folding against its actuation direction; heating "
                             "cannot do that.")
    out = _Allocation(table, dict(targets), float(temperature_limit), temperature_measure)
    run = _Rounds(model, state, table, rows, temperature_limit, max_power, increments,
                  options, out, band, coupling)
    return _run_stages(run, fold0, target, stages, max_rounds, fold_tol).result()


def _run_stages(run: _Rounds, fold0, target, stages, max_rounds, fold_tol) -> _Allocation:
    """Approach the targets in ``stages`` fractions; rounds until met at the last one."""
    out, band = run.out, run.band
    limits = f"{out.temperature_limit:.4g} degC ({out.temperature_measure})" + (f", {1e3 * run.max_power:.4g} mW per heater"
                                                    if run.max_power else "")
    stuck = 0
    for k in range(1, stages + 1):
        goal = fold0 + (k / stages) * (target - fold0)
        while out.rounds < max_rounds:
            done, excess = run.round(goal, fold_tol)
            if out.status == "failed":
                return out
            if done or (k < stages and out.achieved):   # one round per intermediate stage
                break
            # the LP cannot remove the excess although its region is not the limit
            stuck = stuck + 1 if excess > fold_tol and out.history and \
                out.history[-1]["model_miss [deg]"] <= math.degrees(fold_tol) else 0
            if stuck >= 2:
                out.status = "infeasible"
                out.message = (f"round {out.rounds}: the heaters ({len(out.heaters)} circuits) "
                               f"and limits ({limits}) leave the folds "
                               f"{math.degrees(excess):.3g} deg (sum over targets) from "
                               f"{100 * k / stages:.0f}% of the targets"
                               + out.temperature_note())
                logger.warning(out.message)
                return out
        else:
            break
    else:
        out.status = "converged"
        out.message = (f"targets met within {math.degrees(band + fold_tol):.3g} deg in "
                       f"{out.rounds} rounds: {1e3 * out.total_power:.4g} mW"
                       + out.temperature_note())
        return out
    out.message = (f"targets not met within {math.degrees(band + fold_tol):.3g} deg after "
                   f"{max_rounds} rounds" + (f" (worst fold error "
                                             f"{out.history[-1]['worst_fold_error [deg]']:.3g} "
                                             "deg)" if out.history else "")
                   + out.temperature_note())
    logger.warning(out.message)
    return out


def _check_settings(*, max_rounds, stages, band, fold_tol, max_power):
    integer("max_rounds", max_rounds)
    integer("stages", stages)
    non_negative("band", band, "rad")
    positive("fold_tol", fold_tol, "rad")
    positive("max_power", max_power, "W", allow_none=True)
