"""One implicit time step of the bar-and-hinge mechanics: generalized-alpha and Newton (theory 8.2).

Equation of motion on the free DOFs (supports eliminated as in statics)::

    M a + C v + f_int(u; theta0) = f_ext(t)

with the lumped mass ``M`` of :mod:`simulator.model.mass`, the internal force of bars, springs, contact
and elastic supports, and a damping matrix ``C = alpha M + beta K_mat(u) + diag(c_air A_node)``
(Rayleigh damping plus linear air damping per unit sheet area). ``K_mat`` is the material part
of the stiffness at the current configuration
(:meth:`~simulator.mechanics.equilibrium.EquilibriumSystem.material_stiffness`: no stress or contact terms),
so it is positive semi-definite and never damps rigid-body rotations. The reference uses the full
tangent at the start of each step instead (theory 8.3); with the stiff crease bars that lagged
matrix damps a rotating panel spuriously (0.7 % of its energy per period at 1e-3 rad and 100
steps per period, against 2e-6 here). One time step is the generalized-alpha family (Chung & Hulbert 1993)::

    M a_{n+1-am} + C v_{n+1-af} + f_int_{n+1-af} - f_ext_{n+1-af} = 0,  x_{n+1-a} = (1-a) x_{n+1} + a x_n

with Newmark's update of u and v. ``method="newmark"`` is the constant average acceleration rule
(am = af = 0, beta = 1/4, gamma = 1/2: the reference's scheme, non-dissipative, energy-conserving
for linear systems); ``"hht"`` and ``"generalized_alpha"`` damp the high-frequency (stiff bar,
contact chatter) modes with spectral radius ``rho_inf`` at infinite frequency while staying
second-order accurate. Unlike the reference (one linear solve per step, theory 8.4), every step
is solved by Newton's method on the effective residual; a step that does not converge is cut in
halves (bounded), with loads and rest angles interpolated linearly in time.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace

import numpy as np

from .dynamics_options import DynamicsOptions
from .._validate import positive
from ..mechanics.equilibrium import EquilibriumSystem, SystemValues
from ..errors import ParameterError
from ..model.mass import check_masses, lumped_areas, lumped_masses
from ..mechanics.equilibrium import assembled_tangent as _tangent
from ..linalg import thresholds
from ..linalg.ladder import solve
from ..linalg.small_solve import as_dense
from .nonlinear import bisect, iterate

__all__ = ["MotionState", "StepReport", "TimeIntegrator"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class MotionState:
    """Kinematic state at one time.

    Attributes
    ----------
    time : float [s]
    u, v, a : (n_nodes, 3) displacements [m], velocities [m/s], accelerations [m/s^2]
        (zero velocity and acceleration on fixed DOFs)
    f_ext : (n_dof,) external load at this time [N]
    spring_rest : (n_springs,) spring rest angles at this time [rad]
    evaluation : SystemValues at (u, spring_rest), with the tangent
    """

    time: float
    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    f_ext: np.ndarray
    spring_rest: np.ndarray
    evaluation: SystemValues = field(repr=False)

    @property
    def strain_energy(self) -> float:
        """Internal (bars, springs, contact, elastic supports) energy [J]."""
        return float(sum(self.evaluation.energies.values()))


@dataclass(frozen=True, eq=False)
class StepReport:
    """Outcome of one time step (``success``, ``message``; the new state if it succeeded).

    ``dissipated`` and ``external_work`` are the damping energy [J] and the work of the external
    loads [J] over the step (trapezoidal rule in the displacement increment).
    """

    success: bool
    message: str
    state: MotionState
    iterations: int = 0
    cuts: int = 0
    residual_norms: tuple = ()
    dissipated: float = 0.0
    external_work: float = 0.0


class TimeIntegrator:
    """Time stepping of one model: masses, damping and the scheme, cached.

    Parameters
    ----------
    system : EquilibriumSystem
    options : DynamicsOptions
    masses : (n_nodes,) nodal masses [kg], optional
        Default :func:`~simulator.model.mass.lumped_masses` of the mesh; every node with a free DOF
        needs a positive mass (:class:`ParameterError` names the massless materials).
    """

    def __init__(self, system: EquilibriumSystem, options: DynamicsOptions = DynamicsOptions(),
                 masses: np.ndarray | None = None):
        if not isinstance(options, DynamicsOptions):
            raise ParameterError(f"options is a {type(options).__name__}; give "
                                 "DynamicsOptions(...).")
        model = system.model
        self.system, self.options = system, options
        self.masses = lumped_masses(model.mesh) if masses is None else np.asarray(masses, float)
        if self.masses.shape != (model.mesh.n_nodes,):
            raise ParameterError(f"masses must have shape ({model.mesh.n_nodes},), got "
                                 f"{self.masses.shape}.")
        check_masses(model, self.masses)
        free = system.free
        self.m = np.repeat(self.masses, 3)[free]
        self.c_air = options.air_damping * np.repeat(lumped_areas(model.mesh), 3)[free]
        self.size = float(np.max(np.ptp(model.mesh.nodes, axis=0)))

    # ------------------------------------------------------------------ states
    def initial_state(self, u, v, f_ext, spring_rest, time: float = 0.0) -> MotionState:
        """State at ``time`` with the acceleration from dynamic equilibrium,
        ``a = M^-1 (f_ext - C v - f_int)`` on the free DOFs."""
        sys, free = self.system, self.system.free
        n = sys.n_dof
        u = self._vector(u, n, "initial displacements").reshape(-1, 3)
        v = self._vector(v, n, "initial velocities").reshape(-1, 3)
        f_ext = self._vector(f_ext, n, "external load")
        spring_rest = self._vector(spring_rest, len(sys.spr_k), "spring rest angles")
        v.ravel()[sys.free_index < 0] = 0.0
        ev = sys.evaluate(u, spring_rest, hessian=True)
        vf = v.ravel()[free]
        a = np.zeros(sys.n_dof)
        a[free] = (f_ext[free] - self._damping(u.ravel())[0](vf) - ev.f_int[free]) / self.m
        return MotionState(float(time), u, v, a.reshape(-1, 3), f_ext, spring_rest, ev)

    @staticmethod
    def _vector(value, size: int, what: str) -> np.ndarray:
        """A finite float copy of ``value`` with ``size`` entries (any shape), else an error."""
        arr = np.array(value, float).ravel()
        if arr.size != size or not np.isfinite(arr).all():
            raise ParameterError(f"{what} must be {size} finite numbers (got shape "
                                 f"{np.shape(value)}{'' if arr.size != size else ' with NaN/inf'}).")
        return arr

    def _damping(self, u):
        """Damping at displacements ``u`` (n_dof,): (``v -> C v`` on the free DOFs, its diagonal
        part [N s/m], its stiffness part ``beta K_mat`` [N s/m] or None)."""
        o = self.options
        diag = o.rayleigh_alpha * self.m + self.c_air
        Kb = None
        if o.rayleigh_beta > 0:
            Kb = o.rayleigh_beta * self.system.material_stiffness(u.reshape(-1, 3))

        def apply(v):
            return diag * v if Kb is None else diag * v + Kb @ v
        return apply, diag, Kb

    # ------------------------------------------------------------------ stepping
    def step(self, state: MotionState, dt: float, f_ext, spring_rest=None) -> StepReport:
        """Advance ``state`` by ``dt`` [s] to the load ``f_ext`` (n_dof,) [N] and rest angles
        ``spring_rest`` (default: unchanged) at the end of the step.

        A step whose Newton solve fails is split into two halves (loads and rest angles
        interpolated linearly), recursively up to ``options.max_cuts`` levels (the cut driver
        :func:`~simulator.solvers.nonlinear.bisect`).
        """
        positive("time step dt", dt, "s")
        f_ext = self._vector(f_ext, self.system.n_dof, "external load")
        rest = state.spring_rest if spring_rest is None else \
            self._vector(spring_rest, len(state.spring_rest), "spring rest angles")
        return bisect(self._attempt, _halves, _join, state, (dt, f_ext, rest),
                      self.options.max_cuts)

    def _attempt(self, state, span) -> StepReport:
        report = self._solve(state, *span)
        if not report.success:
            logger.info("time step %.3g s at t = %.6g s failed (%s); halving", span[0],
                         state.time, report.message)
        return report

    def _solve(self, s: MotionState, dt, f_ext, rest) -> StepReport:
        """One Newton solve of the step; unknown u_{n+1}."""
        sys, o, m = self.system, self.options, self.m
        free = sys.free
        am, af, beta, gamma = o.coefficients
        un, vn, an = s.u.ravel()[free], s.v.ravel()[free], s.a.ravel()[free]
        C0 = self._damping(s.u.ravel())[0]                        # damping at t_n
        # generalized-alpha terms known at t_n
        known = am * m * an + af * (C0(vn) + s.evaluation.f_int[free] - s.f_ext[free]) \
            - (1 - af) * f_ext[free]
        c_a, c_v = 1 / (beta * dt**2), gamma / (beta * dt)
        u = s.u.ravel().copy()
        step = dt * vn                    # predictor: constant velocity; with contact, no node
        if sys.max_step is not None and np.max(np.abs(step)) > sys.max_step:   # may jump
            step *= sys.max_step / np.max(np.abs(step))                         # through a panel
        u[free] = un + step
        problem = _DynamicStep(self, u, rest, (known, f_ext[free]), (un, vn, an),
                               (am, af, beta, gamma, dt), (c_a, c_v))

        def tolerance(point, first):
            return max(o.atol, o.rtol * point.scale)
        out = iterate(problem, max_iter=o.max_iter, atol=o.atol, rtol=o.rtol, size=self.size,
                      max_step=sys.max_step, tolerance=tolerance, record_final=True)
        norms = (np.array(out.residual_norms),)
        if not out.success:
            return StepReport(False, out.message, s, out.iterations, 0, norms)
        p = out.point
        power = 0.5 * (C0(vn) + p.C(p.v))        # damping force, trapezoidal mean
        return self._accept(s, dt, f_ext, rest, p.ev, u, p.v, p.a, power, out.iterations,
                            out.residual_norms)

    def _jacobian(self, K, Kb, af, am, c_a, c_v, c_diag):
        """Effective stiffness ``(1 - af) (K + c_v Kb) + (1 - am) c_a M + (1 - af) c_v C_diag``
        on the free DOFs: dense for small systems (the same numbers as the sparse form, which
        the ladder, :func:`~simulator.linalg.ladder.solve`, would densify anyway), else CSR."""
        dense = K.shape[0] <= thresholds.DENSE_LIMIT and self.options.linear_solver in (
            "auto", "dense")
        J = (1 - af) * (as_dense(K) if dense else K)
        if Kb is not None:                   # d(Kb(u) v)/du ~ c_v Kb
            J = J + ((1 - af) * c_v) * (as_dense(Kb) if dense else Kb)
        diagonal = J.diagonal() + (1 - am) * c_a * self.m + (1 - af) * c_v * c_diag
        if dense:
            J[np.diag_indices_from(J)] = diagonal
            return J
        J = J.tocsr()
        J.setdiag(diagonal)
        return J

    def _accept(self, s, dt, f_ext, rest, ev, u, v, a, damping, it, norms) -> StepReport:
        free, n = self.system.free, self.system.n_dof
        vv, aa = np.zeros(n), np.zeros(n)
        vv[free], aa[free] = v, a
        new = MotionState(s.time + dt, u.reshape(-1, 3), vv.reshape(-1, 3), aa.reshape(-1, 3),
                          f_ext, np.asarray(rest, float), ev)
        du = u[free] - s.u.ravel()[free]
        work = float(du @ (0.5 * (s.f_ext[free] + f_ext[free])))
        return StepReport(True, "converged", new, it, 0, (np.array(norms),),
                          dissipated=float(du @ damping), external_work=work)


@dataclass(frozen=True, eq=False)
class _StepPoint:
    """One evaluation of the dynamic step: the evaluation, the Newmark velocity and
    acceleration, the damping at the iterate and the force scale of the convergence test."""

    ev: SystemValues
    v: np.ndarray
    a: np.ndarray
    C: object
    c_diag: np.ndarray
    Kb: object
    scale: float


class _DynamicStep:
    """Newton's problem of one time step for :func:`~simulator.solvers.nonlinear.iterate`:
    the generalized-alpha residual on the free DOFs with ``u_{n+1}`` unknown, corrected with
    the effective stiffness."""

    def __init__(self, integrator, u, rest, loads, start, coefficients, rates):
        self.it, self.u, self.rest = integrator, u, rest
        self.known, self.f_free = loads                # terms known at t_n, f_ext on the free DOFs
        self.un, self.vn, self.an = start
        self.am, self.af, self.beta, self.gamma, self.dt = coefficients
        self.c_a, self.c_v = rates

    def evaluate(self):
        it, free, m = self.it, self.it.system.free, self.it.m
        am, af, beta, gamma, dt = self.am, self.af, self.beta, self.gamma, self.dt
        ev = it.system.evaluate(self.u.reshape(-1, 3), self.rest, hessian=True)
        uf = self.u[free]
        a = self.c_a * (uf - self.un - dt * self.vn) - (0.5 / beta - 1) * self.an
        v = self.vn + dt * ((1 - gamma) * self.an + gamma * a)
        C, c_diag, Kb = it._damping(self.u)        # stiffness part at the current iterate
        inertia, damping = (1 - am) * m * a, (1 - af) * C(v)
        r = inertia + damping + (1 - af) * ev.f_int[free] + self.known
        scale = max(np.linalg.norm(inertia), np.linalg.norm(damping),
                    np.linalg.norm(ev.f_int[free]), np.linalg.norm(self.f_free))
        return r, _StepPoint(ev, v, a, C, c_diag, Kb, scale)

    def correct(self, p, r):
        J = self.it._jacobian(_tangent(p.ev), p.Kb, self.af, self.am, self.c_a, self.c_v,
                              p.c_diag)
        du = solve(J, -r, backend=self.it.options.linear_solver)
        return "effective stiffness is singular" if du is None else du

    def apply(self, du, scale):
        self.u[self.it.system.free] += du


def _halves(state: MotionState, span) -> tuple:
    """The two halves of a time step ``(dt, f_ext, rest)`` from ``state``: loads and rest
    angles at the middle by linear interpolation."""
    dt, f_ext, rest = span
    middle = (dt / 2, 0.5 * (state.f_ext + f_ext), 0.5 * (state.spring_rest + rest))
    return middle, (dt / 2, f_ext, rest)


def _join(first: StepReport, second: StepReport | None) -> StepReport:
    """The report of a halved time step from its halves' (``second`` None: the first failed)."""
    if second is None:
        return replace(first, cuts=first.cuts + 1)
    return replace(second, iterations=first.iterations + second.iterations,
                   cuts=first.cuts + second.cuts + 1,
                   residual_norms=first.residual_norms + second.residual_norms,
                   dissipated=first.dissipated + second.dissipated,
                   external_work=first.external_work + second.external_work)
