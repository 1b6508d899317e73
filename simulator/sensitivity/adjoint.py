"""Sensitivities of a steady coupled electro-thermal-mechanical state by the adjoint method
(theory 12.1).

At the end of a :class:`~simulator.steps.Heat` step with coupling "settled" or "iterated"
the displacements u (free DOFs) and the temperature rises dT (free nodes) solve

    R_mech(u, T, p) = f_int(u; s(theta0(T, p), p)) - f = 0,
    R_th(u, T, p)   = A(x(u), p) dT - q(p) = 0,

the rest angles ``theta0 = theta0_start + rot(p) (w . (T - T_start))`` of the Timoshenko
bimorph. :func:`differentiate` assembles the coupled Jacobian
``M = [[K, B], [C, A]]`` (``K`` the mechanics' exact tangent, ``B = dR_mech/dT`` through the
rest angles, ``C = dR_th/du`` through the shape dependence of the chain operator,
:class:`~simulator.sensitivity.chain.ChainOperator`, or of the integral loss,
:class:`~simulator.sensitivity.integral.IntegralShapeOperator`), factors it once, solves
``M^T lambda = (dJ/du, dJ/dT)`` per objective and returns ``dJ/dp = dJ/dp|_explicit -
lambda . dR/dp`` (the explicit term is that of geometry parameters, theory 12.5).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .._validate import one_of
from ..errors import ParameterError
from ..linalg.ladder import factorize
from ..mechanics.elements.springs import fold_angle_derivatives
from ..model.bimorph import crease_temperature_weights
from .geometry import Geometry, geometry_terms
from .integral import shape_operator
from .objectives import objective_terms
from .parameters import PARAMETER_KINDS, check_kinds, parameter_columns

__all__ = ["Sensitivity", "differentiate", "differentiate_state"]

logger = logging.getLogger(__name__)

#: A state counts as a steady coupled state where its heat balance holds to this fraction of
#: the heat input, ``|A dT - q| <= STEADY_RTOL |q|`` (a "staggered" Heat step's end lags by an
#: increment and fails it).
STEADY_RTOL = 1e-6


@dataclass(frozen=True)
class Sensitivity:
    """Total derivatives of one scalar of a steady coupled state.

    Attributes
    ----------
    value : float
        The objective at the state, in ``unit``.
    gradient : dict {name: float}
        ``dJ/dp`` per parameter, in ``units[name]``: e.g. ``"power[2]"`` in rad/W for a fold
        angle, K/W for a temperature, m/W for a coordinate; ``"rest_offset[2]"`` per rad,
        ``"delta_alpha[2]"`` per 1/K, ``"E1"``, ``"E2"`` per Pa, ``"t1"``, ``"t2"`` per m,
        ``"medium_conductivity"`` per W/(m K); ``"geometry[name]"`` per the unit of a
        :class:`~simulator.sensitivity.Geometry` parameter (m by default).
    units : dict {name: str}
        The unit of each entry of ``gradient``.
    unit : str
        The objective's unit (rad, m, K, or a callable's ``unit`` attribute, "-" without).
    success : bool
        The state is a steady coupled state, the operator is differentiable there and the
        coupled Jacobian was factored.
    status : str
        "converged", "nonsmooth" (the gradient is that of the active branch: see
        ``nonsmooth``), "not_steady" (the state does not solve the coupled equations: a
        "staggered" Heat step) or "singular" (the coupled Jacobian is singular: a limit
        point; ``gradient`` is empty).
    message : str
    nonsmooth : tuple of str
        The switches the state sits on (empty where it is differentiable).
    residual : dict
        ``"mechanics [N]"`` and ``"heat [W]"``: the norms of the two residuals at the state.
    parameters : tuple of str
        The parameter kinds asked for (:data:`~simulator.sensitivity.PARAMETER_KINDS` order).
    wall_time : float
        Seconds spent.
    """

    value: float
    gradient: dict
    units: dict
    unit: str
    success: bool
    status: str
    message: str
    nonsmooth: tuple = ()
    residual: dict = field(default_factory=dict)
    parameters: tuple = ()
    wall_time: float = 0.0

    def to_frame(self):
        """One row per parameter: ``parameter``, ``dJ/dp``, ``unit``."""
        import pandas as pd

        return pd.DataFrame({"parameter": list(self.gradient),
                             "dJ/dp": list(self.gradient.values()),
                             "unit": [self.units[k] for k in self.gradient]})


def differentiate(result, objective, parameters=PARAMETER_KINDS, step: int = -1,
                method: str = "adjoint", geometry: Geometry | None = None) -> Sensitivity:
    """Total derivative of a scalar of the state a :class:`~simulator.steps.Heat` step ended
    on, with respect to the model's parameters (theory 12.3).

    Parameters
    ----------
    result : SimulationResult
        A simulation whose step ``step`` is a successful :class:`~simulator.steps.Heat` step
        with ``coupling`` "settled" or "iterated" (its end is a steady coupled state).
    objective : FoldAngle, NodeCoordinate, CreaseTemperature, callable, or a list of them
        The scalar (:mod:`simulator.sensitivity.objectives`), or ``f(u, T) -> (value, dJ/du
        (n, 3), dJ/dT (n,))``. A list (or tuple) of objectives shares one factorisation (one
        solve with as many right-hand sides) and returns a tuple of :class:`Sensitivity`, in
        its order; their ``wall_time`` is the whole call's.
    parameters : str or sequence of str
        Kinds of :data:`~simulator.sensitivity.PARAMETER_KINDS` (default: all).
    step : int
        Index of the heating step in ``result.steps``.
    method : {"adjoint", "forward"}
        One transposed solve (the cost of one objective), or one solve per parameter.
    geometry : Geometry, optional
        Geometry parameters (:class:`~simulator.sensitivity.Geometry`: reference nodes or a
        model as a function of named parameters, at fixed topology), differentiated by the
        chain rule through the mesh at fixed displacements and temperatures (theory 12.5);
        their entries are ``"geometry[name]"``. ``parameters=()`` gives them alone.

    Notes
    -----
    The state at the start of the step (its temperatures and rest angles) is held fixed: the
    derivatives are those of the step's end for the parameters at that end. The dead loads of
    the :class:`~simulator.steps.Gravity` steps before the step follow the geometry (their
    panel areas); other loads are held. Supported: the chain heat loss (``ChainLoss``) and
    the dense integral loss (``IntegralLoss``, not lumped; plain or extrapolated, on the mesh
    or a refined sheet: :mod:`simulator.sensitivity.integral`, theory 12.6) with the T3 or
    monotone conduction, a linear heat balance, fixed crease powers (no circuits); others
    raise :class:`~simulator.sensitivity.SensitivityNotSupported`.
    """
    steps = list(getattr(result, "steps", ()))
    if not steps:
        raise ParameterError("differentiate: result must be a SimulationResult with steps.")
    try:
        rec = steps[step]
    except IndexError:
        raise ParameterError(f"differentiate: step = {step}; the result has {len(steps)} "
                             "steps.") from None
    i = steps.index(rec)
    if "coupling" not in rec.settings or "power_added [mW]" not in rec.settings:
        raise ParameterError(f"differentiate: step {i} ({rec.name!r}) is not a Heat step; "
                             "give the index of the heating step.")
    if not rec.success:
        raise ParameterError(f"differentiate: step {i} ended {rec.status!r} ({rec.message}); "
                             "differentiate a converged state.")
    start = steps[i - 1].state if i > 0 else result.initial_state
    out = differentiate_state(result.model, rec.state, start, objective, parameters, method,
                              geometry, loads=_gravity_loads(result.model, steps[:i], rec.state),
                              start_at=_reference_start(result.model, start) if i == 0 else None)
    if rec.settings["coupling"] != "staggered":
        return out
    lagging = [o if o.status != "converged" else _replace(
        o, status="not_steady", success=False, message="the step's coupling is 'staggered' "
        "(its end lags by one increment); use coupling='settled'")
        for o in (out if isinstance(out, tuple) else [out])]
    return tuple(lagging) if isinstance(out, tuple) else lagging[0]


def differentiate_state(model, state, start, objective, parameters=PARAMETER_KINDS,
                      method: str = "adjoint", geometry: Geometry | None = None,
                      loads=None, start_at=None) -> Sensitivity:
    """:func:`differentiate` of a steady coupled ``state`` (a
    :class:`~simulator.state.SimulationState`) of ``model`` reached by heating from ``start``
    (the state at the start of the heating step: its temperatures and crease rest angles are
    the bimorph's reference). ``loads(model) -> (n_nodes, 3)`` [N]: the dead loads on a model
    of other geometry (default: the state's, held fixed); ``start_at(model)``: the start
    state on a model of other geometry (default: ``start``, held fixed)."""
    t0 = time.perf_counter()
    one_of("method", method, ("adjoint", "forward"))
    kinds = check_kinds(parameters)
    many = isinstance(objective, (list, tuple))
    objectives = list(objective) if many else [objective]
    if not objectives:
        raise ParameterError("differentiate: objective = []; give at least one objective.")
    s = _Setting(model, state, start)
    terms = [objective_terms(o, model, state.u, state.temperature) for o in objectives]
    names, units, dR = parameter_columns(kinds, s)
    explicit = np.zeros((len(objectives), len(names)))
    if geometry is not None:
        loads = (lambda m: state.applied_load) if loads is None else loads
        s.start_at = start_at
        g_names, g_units, g_dR, g_explicit, rough = geometry_terms(geometry, s, objectives,
                                                                   s.residual_at, loads)
        s.nonsmooth = list(s.nonsmooth) + list(rough)
        names, units = names + g_names, units + g_units
        dR, explicit = np.column_stack([dR, g_dR]), np.hstack([explicit, g_explicit])
    rhs = np.column_stack([np.concatenate([gu.ravel()[s.free_u], s.on_thermal(gT)[s.free_T]])
                           for _, gu, gT, _, _ in terms])                     # (n, k)
    M, d = _equilibrated(s.jacobian())
    if method == "adjoint":
        M = M.T.tocsr()
    try:                # the ladder (simulator.linalg): M^T once for the adjoint, M forward
        lu = factorize(M, kind="general").solve
    except (RuntimeError, np.linalg.LinAlgError) as error:
        grads, failure = None, error
    else:
        failure = None
        if method == "adjoint":
            grads = explicit - (((d[:, None] * lu(d[:, None] * rhs)).reshape(rhs.shape)).T @ dR)
        else:
            grads = explicit - (rhs.T @ (d[:, None] * lu(d[:, None] * dR)).reshape(dR.shape)) \
                if dR.shape[1] else np.zeros((rhs.shape[1], 0))
    out = tuple(_sensitivity(s, term, None if grads is None else grads[j], failure, names,
                             units, kinds, t0) for j, term in enumerate(terms))
    return out if many else out[0]


def _sensitivity(s, term, grad, failure, names, units, kinds, t0) -> Sensitivity:
    """The :class:`Sensitivity` of one objective's ``term`` (:func:`objective_terms`) with its
    gradient ``grad`` (None where the factorisation failed with ``failure``)."""
    value, _, _, nonsmooth, unit = term
    nonsmooth = tuple(s.nonsmooth + nonsmooth)
    base = dict(value=value, unit=unit, nonsmooth=nonsmooth, residual=s.residual,
                parameters=kinds)
    if grad is None:
        return Sensitivity(gradient={}, units={}, success=False, status="singular",
                           message=f"the coupled Jacobian is singular ({failure}): a limit "
                           "point or an unconstrained mode", wall_time=time.perf_counter() - t0,
                           **base)
    status, success, message = "converged", True, "converged"
    if not s.steady:
        status, success = "not_steady", False
        message = (f"the state does not solve the heat balance on its shape (|A dT - q| = "
                   f"{s.residual['heat [W]']:.3g} W); heat with coupling='settled'")
    elif nonsmooth:
        status, success = "nonsmooth", False
        message = "not differentiable here (the gradient is the active branch's): " + \
            "; ".join(nonsmooth)
    return Sensitivity(gradient=dict(zip(names, map(float, grad))), units=dict(
        zip(names, (f"{unit}/{u}" for u in units))), success=success, status=status,
        message=message, wall_time=time.perf_counter() - t0, **base)


def _gravity_loads(model, before, state):
    """``loads(m)``: the state's dead loads with those of the Gravity steps in ``before`` (step
    records) recomputed on the mesh of model ``m`` (theory 12.5)."""
    from ..model.model import gravity_loads

    grav = [r.settings for r in before if {"g [m/s^2]", "scale", "direction"} <= set(r.settings)]
    if not grav:
        return None

    def weight(mesh):
        return sum(g["scale"] * gravity_loads(mesh, g["g [m/s^2]"], g["direction"], g["panels"])
                   for g in grav)
    held = state.applied_load - weight(model.mesh)
    return lambda m: held + weight(m.mesh)


def _reference_start(model, start):
    """``start_at(m)`` for a heating step that starts the simulation from the reference: its
    crease rest angles, those of the reference shape (:func:`~simulator.mechanics.rest_angles.
    initial_crease_rest`: pi where flat, the reference's fold where it starts folded), follow
    the geometry; None where the start's rest angles are not the reference's."""
    from ..mechanics.rest_angles import initial_crease_rest

    if not np.array_equal(start.crease_rest, initial_crease_rest(model.mesh)):
        return None
    return lambda m: _replace(start, crease_rest=initial_crease_rest(m.mesh))


def _equilibrated(M) -> tuple:
    """``(D M D, d)`` with ``D = diag(d)``, ``d = |diag M|^(-1/2)`` (1 where the diagonal is
    0): the mechanics' rows [N/m] and the heat balance's [W/K] brought to one scale, so that
    the factorisation's pivots do not depend on the units (``M^-1 = D (D M D)^-1 D``). The
    double fold's Jacobian has a condition number of 8e15, 6e10 equilibrated: the
    gradients carry round-off of about 1e-8 of themselves."""
    diag = np.abs(M.diagonal())
    d = np.where(diag > 0, 1 / np.sqrt(np.where(diag > 0, diag, 1.0)), 1.0)
    D = sp.diags(d)
    return (D @ M @ D).tocsr(), d


def _replace(out, **changes):
    from dataclasses import replace

    return replace(out, **changes)


class _Setting:
    """Everything of the coupled residual at one state: the free DOFs and nodes, the chain
    operator, the mechanics' tangent and the rest-angle coupling."""

    def __init__(self, model, state, start):
        from ..mechanics.equilibrium import equilibrium_system
        from ..thermal.steady import thermal_model

        _check_supported(model, state)
        self.model, self.state, self.start, self.start_at = model, state, start, None
        mesh = model.mesh
        self.tm_mesh = thermal_model(model)
        # the heat balance's nodes: the mesh's, or a refined sheet's fine nodes (mesh nodes
        # first, positions P x, heat spread by sheet.heat; theory 4.11)
        self.sheet = sheet = self.tm_mesh.sheet
        self.tm = tm = self.tm_mesh if sheet is None else self.tm_mesh.fine_model
        self.system = system = equilibrium_system(model)
        self.free_u, self.free_T = system.free, tm.free_nodes
        self.n_u, self.n_T = len(self.free_u), len(self.free_T)
        x = mesh.nodes + state.u
        room = float(state.room_temperature)
        self.op = shape_operator(tm, self._thermal_positions(x))
        self.nonsmooth = list(self.op.nonsmooth)
        self.A = self.op.matrix(self.free_T)
        q = self.heat(self.tm_mesh.heat_vector(state.crease_power))
        self.rise = np.zeros(tm.mesh.n_nodes)
        self.rise[:mesh.n_nodes] = state.temperature - room
        if sheet is not None:            # the fine rise on this operator, the mesh nodes' kept
            fine = np.zeros(tm.mesh.n_nodes)
            fine[self.free_T] = factorize(self.A.tocsc(), kind="spd").solve(q[self.free_T])
            self.rise[mesh.n_nodes:] = fine[mesh.n_nodes:]
        # the bimorph: target = rest_start + rot (w . (T - T_start)) on the crease nodes
        w = crease_temperature_weights()
        acts = model.actuators
        if acts is None:
            self.rot = np.zeros(mesh.n_creases)
            self.rot_per_delta_alpha = np.zeros(mesh.n_creases)
        else:
            self.rot = acts.rotation_per_kelvin(mesh)
            width = mesh.pattern.crease_width[mesh.crease_ids]
            unit = acts.bimorph.curvature(1.0, 1.0) * width
            self.rot_per_delta_alpha = unit if acts.scatter == 0 else \
                unit * acts.scatter_factors(mesh)
        self.dTc = (state.temperature - start.temperature)[mesh.crease_nodes] @ w
        self.W = sp.coo_matrix((np.tile(w, mesh.n_creases),
                                (np.repeat(np.arange(mesh.n_creases), 7),
                                 mesh.crease_nodes.ravel())),
                               shape=(mesh.n_creases, tm.mesh.n_nodes)).tocsr()
        self.ev = system.evaluate(state.u, state.spring_rest, hessian=True)
        self.G = self._rest_coupling(x)
        r_th = self.A @ self.rise[self.free_T] - q[self.free_T]
        r_m = self.ev.f_int[self.free_u] - state.applied_load.ravel()[self.free_u]
        self.residual = {"mechanics [N]": float(np.linalg.norm(r_m)),
                         "heat [W]": float(np.linalg.norm(r_th))}
        self.steady = self.residual["heat [W]"] <= STEADY_RTOL * max(
            float(np.linalg.norm(q[self.free_T])), 1e-300)

    def heat(self, q) -> np.ndarray:
        """The mesh nodal heat ``q`` (n,) or (n, k) [W] on the heat balance's nodes."""
        return q if self.sheet is None else self.sheet.heat(q)

    def _thermal_positions(self, x, sheet=None) -> np.ndarray:
        sheet = self.sheet if sheet is None else sheet
        return x if sheet is None else sheet.positions(x)

    def on_thermal(self, v) -> np.ndarray:
        """A nodal vector of the mesh (n,) on the heat balance's nodes (zero on fine nodes)."""
        out = np.zeros(self.n_thermal)
        out[:len(v)] = v
        return out

    @property
    def n_thermal(self) -> int:
        """Number of nodes of the heat balance (the fine nodes of a refined sheet)."""
        return self.tm.mesh.n_nodes

    def residual_at(self, model, loads) -> np.ndarray:
        """The coupled residual ``(R_mech on the free DOFs, R_th on the free nodes)`` of
        ``model`` (another geometry, same topology) with dead loads ``loads`` (n, 3) [N] at this
        state's displacements, temperatures and start (theory 12.5)."""
        from ..mechanics.equilibrium import equilibrium_system
        from ..steps.heating import thermal_actuation
        from ..thermal.steady import thermal_model

        state = self.state
        tm_mesh = thermal_model(model)
        sheet = tm_mesh.sheet
        tm = tm_mesh if sheet is None else tm_mesh.fine_model
        if not np.array_equal(tm.free_nodes, self.free_T):
            from . import SensitivityNotSupported
            raise SensitivityNotSupported("Geometry.build changed the thermal free nodes (the "
                                          "room-temperature nodes or boundary panels); keep "
                                          "the topology fixed.")
        start = self.start if self.start_at is None else self.start_at(model)
        _, spring = thermal_actuation(model, start)(state.temperature)
        f_int = equilibrium_system(model).evaluate(state.u, spring, hessian=False).f_int
        r_m = f_int[self.free_u] - np.asarray(loads).ravel()[self.free_u]
        op = shape_operator(tm, self._thermal_positions(model.mesh.nodes + state.u, sheet))
        q = tm_mesh.heat_vector(state.crease_power)
        q = q if sheet is None else sheet.heat(q)
        r_th = op.matrix(self.free_T) @ self.rise[self.free_T] - q[self.free_T]
        return np.concatenate([r_m, r_th])

    def _rest_coupling(self, x) -> np.ndarray:
        """``dR_mech / d(crease rest angle)`` on the free DOFs [N/rad], (n_u, C) sparse: each fold
        line's spring ``-k share grad(theta)`` (theory 3.4's shares of the rest-angle change)."""
        mesh, f = self.model.mesh, self.model.params.centre_line_share
        lines = mesh.crease_springs[:, [0, 1, 4, 5]]                       # (C, 4)
        share = np.array([(1 - f) / 2, (1 - f) / 2, f, f])
        springs = mesh.springs[lines.ravel()]                              # (4C, 4)
        _, grad, _ = fold_angle_derivatives(x[springs], hessian=False)     # (4C, 12)
        k = self.model.properties.spring_stiffness[lines.ravel()]
        vals = -(k * np.tile(share, mesh.n_creases))[:, None] * grad
        dofs = (3 * springs[:, :, None] + np.arange(3)).reshape(-1, 12)
        cols = np.repeat(np.arange(mesh.n_creases), 4)
        G = sp.coo_matrix((vals.ravel(), (dofs.ravel(), np.repeat(cols, 12))),
                          shape=(mesh.n_dof, mesh.n_creases)).tocsr()
        return G[self.free_u]

    def jacobian(self) -> sp.csr_matrix:
        """The coupled Jacobian ``[[K, B], [C, A]]`` on (free DOFs, free nodes)."""
        K = self.ev.K
        B = self.G @ sp.diags(self.rot) @ self.W[:, self.free_T]
        C = self.op.shape_jacobian(self.rise)[self.free_T]
        if self.sheet is not None:       # fine positions P x
            C = C @ sp.kron(self.sheet.P, sp.eye(3), format="csr")
        C = C.tocsr()[:, self.free_u]
        return sp.bmat([[K, B], [C, self.A]], format="csr")


def _check_supported(model, state) -> None:
    """Refuse, in one line, what :func:`differentiate` does not differentiate."""
    from . import SensitivityNotSupported

    p = model.thermal
    if p is None:
        raise ParameterError("differentiate: the model has no thermal parameters.")
    why = None
    if p.loss.model not in ("chain", "integral"):
        why = f"the {p.loss.model} heat loss"
    elif p.loss.model == "integral" and p.loss.lumped:
        why = "the lumped integral loss (IntegralLoss.lumped)"
    elif p.conduction_method not in ("t3", "monotone"):
        why = f"conduction {p.conduction_method!r}"
    elif p.sheet_extrapolation:
        why = f"sheet_extrapolation = {p.sheet_extrapolation!r}"
    elif state.circuits:
        why = "heater circuits"
    if why is None:
        from ..thermal.steady import thermal_model

        tm = thermal_model(model)
        if tm.nonlinear:
            why = "a nonlinear heat balance (a conductivity law or radiation)"
    if why is not None:
        raise SensitivityNotSupported(
            f"differentiate: {why} is not supported; supported: the chain heat loss (ChainLoss) "
            "or the dense integral loss (IntegralLoss, not lumped) with T3 or monotone "
            "conduction, a linear heat balance, no sheet extrapolation and fixed crease powers.")
