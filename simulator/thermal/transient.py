"""Transient heat transfer: lumped heat capacity and a theta-method in time (theory 8.1).

The unknowns are those of the steady model (:mod:`simulator.thermal.steady`): the structure nodes and
the ``N`` environment layers of every node, index ``q * n + node``. The capacity matrix is
diagonal (lumped, theory 7.2) and uses the same volumes as the conductivity:

* solid: ``rho c t A_t / 3`` to each vertex of a triangle (material of its panel, or the crease
  material; unlike the reference, panels use their specific heat, not their conductivity,
  theory 7.2); a triangle that conducts as a layer stack (``crease_conduction="layers"``,
  theory 4.10) holds ``sum rho c t`` over the same layers instead;
* environment: layer segment ``q`` of a vertex holds ``rho_env c_env A_q t_air / N``, half on
  each of its two end copies (``A_q``, ``t_air`` as in the conductance, theory 4.3-4.4).

Room-temperature nodes and the far layer ``N`` are Dirichlet nodes at room temperature; the
free unknowns are integrated as temperature rises ``dT`` with the theta-method

    (C / dt + theta K) dT_{k+1} = (C / dt - (1 - theta) K) dT_k
                                  + theta q_{k+1} + (1 - theta) q_k,

theta in [1/2, 1] (1/2 Crank-Nicolson, second order; 1 backward Euler, first order, L-stable;
the reference uses :data:`REFERENCE_THETA` = 2/3). The default is :data:`DEFAULT_THETA` = 1,
backward Euler: L-stable, so under a steady or switched power the temperature never overshoots
or dips below room temperature, whatever dt (theta < 1 damps the fast modes of a stiff
environment only partly: with theta = 2/3 a power step at dt = 1 ms makes the single fold dip
below room temperature and oscillate). Comparisons with the reference pass
``theta=REFERENCE_THETA``. The conductivity and capacity are assembled
on the shape at the start of each time step and re-assembled only when the shape changes, so
``C / dt + theta K`` is factorised once while dt and shape are fixed. Powers given as schedules
enter each step as their exact mean over the step (``q_k = q_{k+1}`` = mean), so the heat put
in equals the integral of the power even for pulses shorter than dt.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .._result import ResultFiles
from .._validate import in_range, integer, positive
from ..errors import ParameterError
from ..linalg import thresholds
from ..linalg.ladder import check_backend, factorize
from ..model.model import Model
from .nonlinear import NonlinearLoss
from .schedules import crease_power_function
from .steady import ThermalModel, thermal_model

__all__ = ["REFERENCE_THETA", "DEFAULT_THETA", "capacity_vector", "areal_capacity", "HeatSystem", "heat_system", "ThetaStepper",
           "theta_step", "stepper_for", "heat_out_rate", "TransientHeatResult", "integrate_heat", "environment_profile",
           "free_heat_input", "initial_rise", "check_time_step", "check_theta",
           "medium_diffusion_time", "check_quasi_static_medium"]

logger = logging.getLogger(__name__)

#: Weight of the new time level used by the reference (``Solver_DynamicsThermal``, theory 8.5).
REFERENCE_THETA = 2 / 3
#: The default weight: 1, backward Euler (L-stable: no undershoot below room temperature, no
#: oscillation under a power step, whatever the time step).
DEFAULT_THETA = 1.0


def check_time_step(dt, name: str = "dt") -> float:
    """``dt`` [s] as a float, or :class:`ParameterError` unless finite and > 0 (the message
    calls ``name`` a time step: use :func:`~simulator._validate.positive` for durations)."""
    return positive(name, dt, "s", hint="give the time step in seconds")


def check_theta(theta) -> float:
    """``theta`` as a float, or :class:`ParameterError` unless in [1/2, 1]."""
    return in_range("theta", theta, 0.5, 1, hint=f"0.5 Crank-Nicolson, 1 backward Euler, "
                    f"{REFERENCE_THETA:.4g} the reference's")


# ------------------------------------------------------------------ capacity
def _volumetric_capacity(tm: ThermalModel) -> np.ndarray:
    """rho c [J/(m^3 K)] of every triangle's material, (n_tri,); error for missing density /
    heat where a triangle that is not a layer stack (:attr:`SheetConduction.layered
    <simulator.thermal.conduction.SheetConduction.layered>`) needs it."""
    mesh, pat = tm.mesh, tm.mesh.pattern
    panel = mesh.triangle_panel
    mats = list(pat.panel_material) + [pat.crease_material]
    which = np.where(panel >= 0, panel, len(mats) - 1)
    c = tm.conduction
    for k in np.unique(which[(c.thickness > 0) & ~c.layered]):
        m = mats[k]
        where = f"panel {k}" if k < len(mats) - 1 else "the creases"
        for field, unit in (("density", "kg/m^3"), ("specific_heat", "J/(kg K)")):
            if not getattr(m, field, 0.0) > 0:
                raise ParameterError(
                    f"Material {m.name!r} ({where}) has {field} = {getattr(m, field, None)!r} "
                    f"{unit}: transient heat transfer needs density > 0 and specific_heat > 0; "
                    f"give Material(..., density=..., specific_heat=...).")
    rho_c = np.array([m.density * m.specific_heat for m in mats])
    return rho_c[which]


def areal_capacity(tm: ThermalModel) -> np.ndarray:
    """Areal heat capacity [J/(m^2 K)] of every triangle, (n_tri,) (theory 7.2): ``rho c t``
    of its material and thickness, or ``sum rho c t`` over its layers where it conducts as a
    layer stack (:attr:`SheetConduction.layered
    <simulator.thermal.conduction.SheetConduction.layered>`, theory 4.10): the same layers in the steady
    conduction and in the capacity."""
    c = tm.conduction
    return np.where(c.layered, c.layer_capacity, _volumetric_capacity(tm) * c.thickness)


def capacity_vector(tm: ThermalModel, x) -> np.ndarray:
    """Lumped heat capacity [J/K] of every unknown, ((N + 1) n,), at positions ``x`` (n, 3) [m].

    Index ``q * n + node`` as :meth:`ThermalModel.conductivity_matrix` (theory 7.2). With
    a medium conductivity 0 the environment is not in thermal contact and holds no heat.
    """
    medium, mesh = tm.params.medium, tm.mesh
    n, N = mesh.n_nodes, tm.chains.layers
    area = tm.triangle_areas(x)
    solid = areal_capacity(tm) * area / 3
    C = np.zeros((N + 1, n))
    C[0] = np.bincount(mesh.triangles.ravel(), np.repeat(solid, 3), minlength=n)
    if medium.thermal_conductivity > 0:            # k_env = 0: no environment in contact
        a_q, t_air = tm.environment.geometry(x, area)
        rho_c = medium.density * medium.specific_heat
        seg = tm.environment.node_layer_sum(rho_c * a_q * t_air[:, None] / N)
        C[:-1] += 0.5 * seg.T
        C[1:] += 0.5 * seg.T
    return C.ravel()


# ------------------------------------------------------------------ reduced system
@dataclass(frozen=True, eq=False)
class HeatSystem:
    """Conductivity and capacity on the free unknowns at one shape.

    Attributes
    ----------
    K : (m, m) sparse CSC conductivity among the free unknowns [W/K]
    C : (m,) lumped capacity of the free unknowns [J/K]
    free : (m,) indices of the free unknowns in the full ((N + 1) n) numbering
    outflow : (m,) heat flow into the Dirichlet nodes per kelvin of rise of each free unknown
        [W/K]; ``outflow @ dT`` is the heat leaving the free unknowns.
    load : (m, n) array or None
        The heat of the free unknowns from the mesh nodal heat (a refined sheet's condensed
        system, theory 4.11: part of a node's heat leaves through the eliminated fine nodes);
        None: the free unknowns' own entries.
    nonlinear : NonlinearLoss or None
        The nonlinear losses (a medium conductivity law, radiation; theory 4.12): ``K`` is
        then the linear part only (the sheet's conduction), the medium's conductance and the
        radiation are here, and ``outflow`` is that of ``K`` plus the medium at its reference
        conductivity (the steppers book the exact heat out: :func:`heat_out_rate`). None: a
        linear system.
    """

    K: sp.csc_matrix
    C: np.ndarray
    free: np.ndarray
    outflow: np.ndarray
    load: np.ndarray | None = None
    nonlinear: NonlinearLoss | None = None


def _dirichlet_mask(tm: ThermalModel) -> np.ndarray:
    """Full-size mask of the unknowns held at room temperature."""
    n, N = tm.mesh.n_nodes, tm.chains.layers
    fixed = np.zeros((N + 1, n), bool)
    fixed[0, tm.chain_fixed_nodes] = True
    fixed[N] = True
    if tm.params.medium.thermal_conductivity == 0:
        fixed[1:] = True                   # layers decoupled from the structure: room temperature
    return fixed.ravel()


def heat_system(tm: ThermalModel, x) -> HeatSystem:
    """Assemble :class:`HeatSystem` at positions ``x`` (n, 3) [m]."""
    medium = tm.params.medium
    if medium.thermal_conductivity > 0 and not medium.density * medium.specific_heat > 0:
        raise ParameterError(
            f"ThermalParameters: the medium's density {medium.density!r} kg/m^3 and specific "
            f"heat {medium.specific_heat!r} J/(kg K): transient heat transfer with an "
            "environment needs both > 0 (e.g. medium=AIR or medium=WATER).")
    if tm.integral is not None:
        return _integral_heat_system(tm, x)
    fixed = _dirichlet_mask(tm)
    free = np.flatnonzero(~fixed)
    K = tm.conductivity_matrix(x).tocsc()
    C = capacity_vector(tm, x)[free]
    if np.any(C <= 0):
        raise ParameterError(f"unknown {int(free[np.argmin(C)])} has no heat capacity: every "
                             "node needs a triangle with thickness, density and specific heat.")
    outflow = -np.asarray(K[np.flatnonzero(fixed)][:, free].sum(axis=0)).ravel()
    if tm.nonlinear:                   # the chains' layers apart: they conduct by the law
        B = tm.chain_matrix(x).tocsc()[free][:, free]
        return HeatSystem((K[free][:, free] - B).tocsc(), C, free, outflow, None,
                          _nonlinear_loss(tm, x, free, B))
    return HeatSystem(K[free][:, free].tocsc(), C, free, outflow)


def _nonlinear_loss(tm: ThermalModel, x, free, B) -> NonlinearLoss:
    """The :class:`~simulator.thermal.nonlinear.NonlinearLoss` of the free unknowns ``free``
    (structure nodes first in the full numbering, ``q * n + node``) with the medium's
    conductance ``B`` among them: radiation from the structure nodes."""
    n = tm.mesh.n_nodes
    e = np.zeros(len(free))
    sheet = free < n
    e[sheet] = tm.emissive_area(x)[free[sheet]]
    return NonlinearLoss(tm.params.medium, tm.params.room_temperature, B=B, emissive=e)


def _integral_heat_system(tm: ThermalModel, x) -> HeatSystem:
    """:class:`HeatSystem` of the integral loss model (theory 8.1): the structure nodes only
    (the chain layers are not unknowns), the sheet's T3 conduction plus the loss conductance
    ``L`` of the medium taken as quasi-static (its heat capacity neglected:
    :func:`medium_diffusion_time` says when that holds), the nodes held by the steady model
    (:meth:`~simulator.thermal.steady.ThermalModel.held_nodes`) at room temperature."""
    mesh, n = tm.mesh, tm.mesh.n_nodes
    x = np.asarray(x, float)
    area = tm.triangle_areas(x)
    tri = mesh.triangles
    free = np.setdiff1d(np.arange(n), tm.held_nodes(x))
    load = nonlinear = None
    if tm.sheet is not None:           # the fine nodes eliminated: they hold no heat
        if tm.nonlinear:
            raise ParameterError(
                f"the time domain on a refined sheet (sheet_refinement = {tm.sheet.r}) with a "
                "medium conductivity law or radiation (theory 4.12): the fine nodes are "
                "eliminated linearly; use ThermalParameters(sheet_refinement=1) for the "
                "transient, or a constant conductivity and emissivity 0.")
        Kff, load = tm.condensed_system(x)
    else:
        K = tm.sheet_conduction(x).toarray()
        sheet = tm.integral.nodes
        loss = tm.integral_loss_matrix(x)
        K[np.ix_(sheet, sheet)] += loss
        Kff = K[np.ix_(free, free)]
        if tm.nonlinear:
            B = np.zeros((n, n))
            B[np.ix_(sheet, sheet)] = loss
            nonlinear = _nonlinear_loss(tm, x, free, B[np.ix_(free, free)])
    solid = areal_capacity(tm) * area / 3
    C = np.bincount(tri.ravel(), np.repeat(solid, 3), minlength=n)[free]
    if np.any(C <= 0):
        raise ParameterError(f"node {int(free[np.argmin(C)])} has no heat capacity: every "
                             "node needs a triangle with thickness, density and specific heat.")
    # heat leaving the free nodes per kelvin of each one's rise: into the held nodes and the
    # medium (the column sums: the rows of the conduction alone sum to zero)
    if nonlinear is not None:
        return HeatSystem(sp.csc_matrix(Kff - nonlinear.B), C, free, Kff.sum(axis=0), load,
                          nonlinear)
    return HeatSystem(sp.csc_matrix(Kff), C, free, Kff.sum(axis=0), load)


def medium_diffusion_time(tm: ThermalModel, x) -> float:
    """Diffusion time [s] of the medium over the device, ``D^2 rho_env c_env / k_env`` (D the
    largest extent of the sheet at positions ``x`` (n, 3) [m]): the integral loss model in time
    takes the medium as quasi-static, exact for changes slower than this (theory 8.1); inf
    without a medium heat capacity."""
    medium = tm.params.medium
    D = float(np.ptp(np.asarray(x, float), axis=0).max())
    rho_c = medium.density * medium.specific_heat
    k_env = medium.thermal_conductivity
    return D * D * rho_c / k_env if k_env > 0 else 0.0


def check_quasi_static_medium(tm: ThermalModel, x, dt: float, owner: str) -> None:
    """WARNING (once per call) where the integral loss model is integrated in time with a time
    step ``dt`` [s] shorter than :func:`medium_diffusion_time`: the medium then lags the sheet,
    which the quasi-static loss neglects (it loses less heat early on than the medium would
    take, so the sheet heats faster at first; the steady state is exact)."""
    if tm.integral is None:
        return
    tau = medium_diffusion_time(tm, x)
    if dt < tau:
        logger.warning(
            "%s with the integral heat loss: the medium is taken as quasi-static; its diffusion "
            "time over the device, %.3g ms, exceeds the time step %.3g ms, so during the first "
            "~%.3g ms the sheet heats faster than it would (the medium's heat capacity is "
            "neglected); the steady state is exact (theory 8.1)", owner, 1e3 * tau, 1e3 * dt,
            1e3 * tau)


def free_heat_input(tm: ThermalModel, free: np.ndarray, power, load=None) -> np.ndarray:
    """Heat input [W] of the free unknowns ``free`` for the (C,) crease powers [W] (``load``:
    a :class:`HeatSystem`'s map from the mesh nodal heat, where it has one)."""
    if load is not None:
        return load @ tm.heat_vector(power)
    q = np.zeros(tm.n_dof)
    q[:tm.mesh.n_nodes] = tm.heat_vector(power)
    return q[free]


def environment_profile(tm: ThermalModel, x, rise) -> np.ndarray:
    """Steady temperature rise [K] of every unknown, ((N + 1) n,), given the structure rise.

    Each chain is a series of conductances to room temperature, so layer ``q`` carries the
    fraction ``sum_{s >= q} 1/g_s / sum_s 1/g_s`` of its node's rise (quasi-steady environment,
    used to start from a structure-only temperature such as a steady :class:`Heat` result).
    """
    n, N = tm.mesh.n_nodes, tm.chains.layers
    full = np.zeros((N + 1, n))
    full[0] = rise
    if tm.integral is not None:            # no chains: the structure nodes are the unknowns
        return full.ravel()
    g = tm.environment.conductance(x, tm.triangle_areas(x))
    if tm.params.medium.thermal_conductivity > 0:
        with np.errstate(divide="ignore"):
            r = np.where(g > 0, 1 / g, np.inf)
        tail = np.cumsum(r[:, ::-1], axis=1)[:, ::-1]           # sum_{s >= q}, q = 0..N-1
        with np.errstate(invalid="ignore"):
            frac = np.where(np.isfinite(tail[:, :1]), tail / tail[:, :1], 0.0)
        full[1:N] = (frac[:, 1:] * rise[:, None]).T
    full[_dirichlet_mask(tm).reshape(N + 1, n)] = 0.0
    return full.ravel()


# ------------------------------------------------------------------ theta-method
class ThetaStepper:
    """The theta-method operator for fixed ``K``, ``C``, ``dt``, ``theta``, factorised once.

    Parameters
    ----------
    K : (m, m) sparse conductivity [W/K]
    C : (m,) lumped capacity [J/K], > 0
    dt : float
        Time step [s], > 0.
    theta : float
        Weight of the new time level, in [1/2, 1].
    linear_solver : {"auto", "dense", "pardiso", "superlu"}
        Backend of the factorisation (:func:`~simulator.linalg.ladder.factorize`).
    """

    def __init__(self, K, C, dt, theta=DEFAULT_THETA, linear_solver="auto", nonlinear=None):
        self.dt, self.theta = check_time_step(dt), check_theta(theta)
        C = np.asarray(C, float)
        if C.ndim != 1 or K.shape != (len(C), len(C)) or not np.all(C > 0):
            raise ParameterError(f"ThetaStepper: need K of shape (m, m) and C of shape (m,) with "
                                 f"C > 0 J/K; got K {K.shape}, C {C.shape}.")
        self.K, self.C = sp.csc_matrix(K), C
        #: the nonlinear losses (:class:`~simulator.thermal.nonlinear.NonlinearLoss`) or None
        self.nonlinear = nonlinear
        #: the mean heat flow [W] out of the unknowns over the last step (nonlinear steps)
        self.out_rate = None
        if nonlinear is not None:      # linearised at the start of every step: no factors kept
            self._lu = None
            return
        mass = sp.diags(C / self.dt)
        A = (mass + self.theta * self.K).tocsc()
        # the ladder, never dense (kept for many steps); PARDISO if installed, else SuperLU
        self._lu = factorize(A, kind="spd", backend=check_backend(
            linear_solver, "ThetaStepper: linear_solver"),
            dense_limit=thresholds.TRANSIENT_DENSE_LIMIT) if len(C) else None
        self._rhs = (mass - (1 - self.theta) * self.K).tocsr()

    def step(self, T, q_old, q_new) -> np.ndarray:
        """Rise at the new time level [K], (m,), from the rise ``T`` and heat inputs [W] at the
        old and new time levels, (m,) each."""
        if self.nonlinear is not None:
            return self._linearised_step(np.asarray(T, float), q_old, q_new)
        if self._lu is None:
            return np.asarray(T, float)
        b = self._rhs @ T + self.theta * np.asarray(q_new) + (1 - self.theta) * np.asarray(q_old)
        return self._lu.solve(b)

    def _linearised_step(self, T, q_old, q_new) -> np.ndarray:
        """One step of the theta method linearised at its start (theory 4.12): with the heat
        flow ``F(T) = K T + loss(T)`` and its Jacobian ``J`` at ``T``, ``(C / dt + theta J)
        dT = theta q_new + (1 - theta) q_old - F(T)``; the same as the linear step where
        ``F`` is linear, and its fixed point is the steady ``F(T) = q``. Sets
        :attr:`out_rate`, the step's exact mean heat flow out, ``1^T (F(T) + theta J dT)``."""
        if not len(T):
            self.out_rate = 0.0
            return T
        loss, th = self.nonlinear, self.theta
        full, d = loss.jacobian(T)
        d = d + self.C / self.dt
        if full is None or sp.issparse(full):
            J = self.K + (0 if full is None else full)
            A = (sp.diags(d) + th * J).tocsc()
            kind = "spd" if full is None else "general"
        else:
            J = self.K.toarray() + full
            A = th * J
            A[np.diag_indices_from(A)] += d
            kind = "general"
        A_diag = d - self.C / self.dt            # the Jacobian's own diagonal terms
        F = self.K @ T + loss.flux(T)
        dT = factorize(A, kind=kind, dense_limit=thresholds.TRANSIENT_DENSE_LIMIT).solve(
            th * np.asarray(q_new) + (1 - th) * np.asarray(q_old) - F)
        self.out_rate = float(np.sum(F + th * (J @ dT + A_diag * dT)))
        return T + dT


def heat_out_rate(system: HeatSystem, stepper: ThetaStepper, T, T_new) -> float:
    """The mean heat flow [W] out of the free unknowns over the step from rises ``T`` to
    ``T_new`` [K] that ``stepper`` took on ``system``: ``outflow @ (theta T_new + (1 - theta)
    T)``, or the nonlinear step's own (:attr:`ThetaStepper.out_rate`)."""
    if system.nonlinear is not None:
        return stepper.out_rate
    th = stepper.theta
    return system.outflow @ (th * T_new + (1 - th) * T)


def stepper_for(system: HeatSystem, dt: float, theta: float = DEFAULT_THETA,
                room: float | None = None) -> ThetaStepper:
    """The :class:`ThetaStepper` of ``system`` (its nonlinear losses included, at room
    temperature ``room`` [deg C] where given) with time step ``dt`` [s] and weight
    ``theta``."""
    loss = system.nonlinear
    if loss is not None and room is not None:
        loss = dataclasses.replace(loss, room=float(room))
    return ThetaStepper(system.K, system.C, dt, theta, nonlinear=loss)


_LAST: dict = {}


def theta_step(K, C, T, q_old, q_new, dt, theta=DEFAULT_THETA) -> np.ndarray:
    """One theta-method step: solve ``(C/dt + theta K) T_new = (C/dt - (1 - theta) K) T +
    theta q_new + (1 - theta) q_old`` (rises [K], capacities [J/K], heat [W], dt [s]).

    The factorisation is reused while the SAME ``K`` and ``C`` objects and the same ``dt`` and
    ``theta`` are passed (do not modify them in place between calls); a new shape means new
    matrices and a new factorisation. :class:`ThetaStepper` holds the operator explicitly.
    """
    key = (dt, theta)
    if not (_LAST.get("K") is K and _LAST.get("C") is C and _LAST.get("key") == key):
        _LAST.update(K=K, C=C, key=key, stepper=ThetaStepper(K, C, dt, theta))
    return _LAST["stepper"].step(T, q_old, q_new)


# ------------------------------------------------------------------ integration
@dataclass(frozen=True, eq=False)
class TransientHeatResult(ResultFiles):
    """Temperature history of :func:`integrate_heat` (``m`` records, record 0 = start).

    Attributes
    ----------
    success : bool
    status : str
        "converged" (reached ``t_end``), "stopped" (callback), "failed" (non-finite values) or
        "thermal_runaway" (heater circuits without an operating point).
    message : str
    time : (m,) [s]
    temperature : (m, n) structure node temperatures [deg C]
    power : (m, C) crease powers at the record's time [W]
    mean_power : (m, C) crease powers averaged over the time step ending at the record [W]
        (what the heat equation integrated: the exact mean of a schedule, else the
        theta-weighted end values; at record 0 the powers at t = 0)
    heat_in : (m,) heat put into the free unknowns since the start [J]
    heat_out : (m,) heat that left to room-temperature nodes and the far layer [J]
    heat_stored : (m,) sum of C (T - room) over the free unknowns [J]; with a fixed shape
        ``heat_stored - heat_stored[0] = heat_in - heat_out`` to round-off.
    final_temperature : ((N + 1) n,) temperatures of all unknowns at the end [deg C]
    dt : float
        Time step used [s] (``t_end / ceil(t_end / dt)``, so the last step ends at ``t_end``).
    theta : float
    steps : int
        Time steps taken.
    assemblies : int
        How often K and C were assembled (once per distinct shape).
    """

    success: bool
    status: str
    message: str
    time: np.ndarray
    temperature: np.ndarray
    power: np.ndarray
    heat_in: np.ndarray
    heat_out: np.ndarray
    heat_stored: np.ndarray
    final_temperature: np.ndarray
    dt: float
    theta: float
    steps: int
    assemblies: int
    mean_power: np.ndarray | None = None

    def to_frame(self):
        """Long table, one row per record and structure node: ``time [s]``, ``node``,
        ``temperature [degC]``, ``heat_in [J]``, ``heat_out [J]``, ``heat_stored [J]``."""
        import pandas as pd

        m, n = self.temperature.shape
        rep = lambda a: np.repeat(a, n)  # noqa: E731
        return pd.DataFrame({"time [s]": rep(self.time), "node": np.tile(np.arange(n), m),
                             "temperature [degC]": self.temperature.ravel(),
                             "heat_in [J]": rep(self.heat_in), "heat_out [J]": rep(self.heat_out),
                             "heat_stored [J]": rep(self.heat_stored)})

    _csv_name = "transient_heat.csv"

    def _meta(self) -> dict:
        return {"dt [s]": self.dt, "theta": self.theta, "steps": self.steps,
                "assemblies": self.assemblies}


def initial_rise(tm, x, T0, room) -> np.ndarray:
    """Start rise [K] of every unknown, ((N + 1) n,), from temperatures ``T0`` [deg C] of the
    structure nodes (n,) (quasi-steady environment) or of all unknowns; None: zero."""
    n, size = tm.mesh.n_nodes, tm.n_dof
    if T0 is None:
        return np.zeros(size)
    T0 = np.asarray(T0, float)
    if T0.shape not in ((n,), (size,)) or not np.all(np.isfinite(T0)):
        raise ParameterError(f"T0 must be finite temperatures [deg C] of shape ({n},) (structure "
                             f"nodes) or ({size},) (all unknowns); got shape {T0.shape}.")
    if T0.shape == (size,):
        return np.where(_dirichlet_mask(tm), 0.0, T0 - room)
    return environment_profile(tm, x, T0 - room)


def integrate_heat(tm: ThermalModel, x, powers, t_end, dt, theta=DEFAULT_THETA, room=None,
                   T0=None, record_every: int = 1, callback=None) -> TransientHeatResult:
    """Integrate the transient heat equation from ``t = 0`` to ``t_end`` by the theta-method.

    Parameters
    ----------
    tm : ThermalModel or Model
        The heat-transfer model (a :class:`~simulator.model.model.Model` gives its cached one).
    x : (n, 3) array or callable
        Node positions [m], or ``x(t)`` giving them at time t [s]; K and C are assembled on the
        positions at the start of each time step and re-assembled when they change.
    powers : mapping or callable
        ``{crease id or tuple of ids: PowerSchedule or watts}`` (see
        :mod:`simulator.thermal.schedules`), or ``powers(t)`` giving the (C,) crease powers [W].
        If ``powers`` has a ``mean(t0, t1)`` method (schedules given as a mapping do), each
        step uses the exact mean power over the step (so pulses shorter than dt keep their
        energy); otherwise the theta-weighted powers at the two ends of the step. If it has an
        ``observe(temperature)`` method (heater circuits,
        :class:`~simulator.thermal.electrical.CircuitPowers`), it is given the structure
        temperatures (n,) [deg C] at the start and after every step, and a non-empty answer
        (no operating point) ends the run with status "thermal_runaway".
    t_end, dt : float
        End time and (largest) time step [s], > 0.
    theta : float
        In [1/2, 1]; default :data:`DEFAULT_THETA` = 1 (backward Euler, L-stable); the
        reference's is :data:`REFERENCE_THETA` = 2/3.
    room : float, optional
        Room temperature [deg C] (default ``tm.params.room_temperature``).
    T0 : (n,) or ((N + 1) n,) array, optional
        Start temperatures [deg C]; structure-only values get a quasi-steady environment
        (:func:`environment_profile`). Default: room temperature everywhere.
    record_every : int
        Record every k-th step (the last step is always recorded).
    callback : callable, optional
        ``callback(k, n_steps, t, temperature)`` after step k; returning True stops the run.
    """
    tm = _as_thermal_model(tm)
    t_end, dt = positive("t_end", t_end, "s"), check_time_step(dt)
    theta = check_theta(theta)
    integer("record_every", record_every)
    room = tm.params.room_temperature if room is None else float(room)
    powers = _power_function(tm, powers)
    shape = x if callable(x) else (lambda t, _x=np.asarray(x, float): _x)
    n_steps = max(1, math.ceil(t_end / dt * (1 - 1e-12)))
    run = _HeatRun(tm, shape, powers, t_end / n_steps, theta, room, T0)
    check_quasi_static_medium(tm, shape(0.0), run.h, "integrate_heat")
    status, message, k = run.steps(t_end, n_steps, record_every, callback)
    logger.info("integrate_heat: %s (%d steps of %g s, theta %g, %d assemblies)", status, k,
                run.h, theta, run.assemblies)
    return run.result(status, message, k)


def _as_thermal_model(tm) -> ThermalModel:
    """The :class:`ThermalModel` of ``tm`` (a Model gives its cached one), else an error."""
    if isinstance(tm, Model):
        return thermal_model(tm)
    if not isinstance(tm, ThermalModel):
        raise ParameterError(f"integrate_heat: give a Model with thermal parameters or a "
                             f"ThermalModel, not {type(tm).__name__}.")
    return tm


def _power_function(tm: ThermalModel, powers):
    """``powers`` as a function ``t -> (C,)`` crease powers [W] (a mapping of schedules gives one
    with a ``mean(t0, t1)`` method), else an error."""
    if isinstance(powers, Mapping):
        return crease_power_function(tm.mesh, powers)
    if not callable(powers):
        raise ParameterError("powers must be a mapping {crease: schedule or W} or a function "
                             "t -> (C,) crease powers [W].")
    return powers


class _HeatRun:
    """State of one :func:`integrate_heat` run with time step ``h`` [s]: the operator on the
    current shape, the rise [K] of the free unknowns, the heat sums [J] and the records."""

    def __init__(self, tm: ThermalModel, shape, powers, h: float, theta: float, room, T0):
        self.tm, self.shape, self.powers, self.h, self.theta, self.room = (tm, shape, powers, h,
                                                                           theta, room)
        self.x = np.asarray(shape(0.0), float)
        self.system = heat_system(tm, self.x)
        self.stepper, self.assemblies = stepper_for(self.system, h, theta, room), 1
        self.rise = initial_rise(tm, self.x, T0, room)
        self.T = self.rise[self.system.free]
        self.free = self.system.free                          # the free set never changes
        self.averaged = hasattr(powers, "mean")
        self.observing = hasattr(powers, "observe")   # powers that depend on the temperature
        self.why = self._observe()
        p_new = np.asarray(powers(0.0), float)
        self.q_new = self.heat(p_new)
        self.p_new = self.p_mean = p_new
        self.log = {"time": [0.0], "temperature": [self.temperature()], "power": [p_new],
                    "mean_power": [p_new], "heat_in": [0.0], "heat_out": [0.0],
                    "heat_stored": [self.system.C @ self.T]}
        self.e_in = self.e_out = 0.0

    def heat(self, p) -> np.ndarray:
        """Heat input [W] of the free unknowns for the (C,) crease powers ``p`` [W]."""
        return free_heat_input(self.tm, self.free, p, self.system.load)

    def temperature(self) -> np.ndarray:
        """Structure node temperatures [deg C], (n,)."""
        return self.room + self.rise[:self.tm.mesh.n_nodes]

    def _observe(self) -> str:
        """Give temperature-dependent powers (heater circuits) the current temperatures; ""
        or why they are no operating point (a run-away)."""
        return self.powers.observe(self.temperature()) if self.observing else ""

    def steps(self, t_end, n_steps, record_every, callback) -> tuple[str, str, int]:
        """Take the ``n_steps`` steps up to ``t_end`` [s] unless the temperature becomes
        non-finite or the callback stops; (status, message, steps taken)."""
        status, message = "converged", f"reached t = {t_end:g} s in {n_steps} steps"
        for k in range(1, n_steps + 1):
            record = k % record_every == 0 or k == n_steps
            t1, p_new = self.advance(k, record)
            if not np.all(np.isfinite(self.T)):
                status, message = "failed", f"non-finite temperature at t = {t1:g} s (step {k})"
            elif self.why:
                status = "thermal_runaway"
                message = f"at t = {t1:g} s (step {k}): {self.powers.runaway_message(self.why)}"
                logger.warning("integrate_heat: %s", message)
            elif callback is not None and callback(k, n_steps, t1, self.temperature()):
                status, message = "stopped", f"stopped by the callback at t = {t1:g} s (step {k})"
            if record or status != "converged":
                self.record(t1, p_new)
            if status != "converged":
                break
        return status, message, k

    def reassemble(self, k: int, t0: float) -> None:
        """Re-assemble K and C (and re-factorise) if the shape at ``t0`` [s] changed (k > 1)."""
        x_new = np.asarray(self.shape(t0), float)
        if k > 1 and not np.array_equal(x_new, self.x):
            self.x, self.system = x_new, heat_system(self.tm, x_new)
            self.stepper = stepper_for(self.system, self.h, self.theta, self.room)
            self.assemblies += 1

    def advance(self, k: int, record: bool):
        """Time step ``k``, from (k - 1) h to k h: the heat input over the step, the theta
        step, the heat sums. Returns (k h [s], the (C,) powers at k h [W] or None if unused)."""
        h, theta, powers = self.h, self.theta, self.powers
        t0, t1 = (k - 1) * h, k * h
        self.reassemble(k, t0)
        p_new = None if self.averaged else np.asarray(powers(t1), float)
        if self.averaged:                     # exact heat input per step (PWM, steps, ramps)
            self.p_mean = np.asarray(powers.mean(t0, t1), float)
            q_old = q_new = self.heat(self.p_mean)
        else:
            q_old, q_new = self.q_new, self.heat(p_new)
            self.p_mean = theta * p_new + (1 - theta) * self.p_new
            self.p_new = p_new
        self.q_new = q_new
        T = self.T
        T_new = self.stepper.step(T, q_old, q_new)
        self.e_in += h * np.sum(theta * q_new + (1 - theta) * q_old)
        self.e_out += h * heat_out_rate(self.system, self.stepper, T, T_new)
        self.T = T_new
        self.rise[self.free] = T_new
        self.why = self._observe()
        if record and p_new is None:          # the powers at t1 (at the new temperatures)
            p_new = np.asarray(powers(t1), float)
        return t1, p_new

    def record(self, t1: float, p_new) -> None:
        """Append the state at ``t1`` [s] to the records (``p_new``: the powers there, or None)."""
        p_new = np.asarray(self.powers(t1), float) if p_new is None else p_new
        for key, val in (("time", t1), ("temperature", self.temperature()), ("power", p_new),
                         ("mean_power", self.p_mean), ("heat_in", self.e_in), ("heat_out", self.e_out),
                         ("heat_stored", self.system.C @ self.T)):
            self.log[key].append(val)

    def result(self, status: str, message: str, k: int) -> TransientHeatResult:
        """The :class:`TransientHeatResult` after ``k`` steps."""
        return TransientHeatResult(
            success=status == "converged", status=status, message=message,
            **{key: np.array(val, float) for key, val in self.log.items()},
            final_temperature=self.room + self.rise, dt=self.h, theta=self.theta, steps=k,
            assemblies=self.assemblies)
