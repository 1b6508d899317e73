"""The steady heat balance of a mesh (theory 4): :class:`ThermalModel` puts together the
sheet's conduction (:mod:`simulator.thermal.conduction`: T3 elements or the monotone
conduction, layer stacks) and its heat loss to the medium (the paper's environment chains,
:mod:`simulator.thermal.chains`, or the calibration-free integral loss,
:mod:`simulator.thermal.integral_levels`, over the substrate plane of
:mod:`simulator.thermal.substrate`), holds the room-temperature nodes and solves for the
temperatures: linear, or by Newton's method where radiation or a temperature-dependent medium
makes the balance nonlinear (:mod:`simulator.thermal.nonlinear`), on the mesh or on its
refined sheet (:mod:`simulator.thermal.refined`). :func:`thermal_model` keeps one per model.

Unknowns of the full chain system are ordered by layer: index ``q * n + node`` (``q = 0`` is
the structure). Because every chain is a series of conductances ending at room temperature,
:meth:`ThermalModel.solve` eliminates the environment layers exactly (series sum, one diagonal
term per node) and solves the ``n x n`` structure system;
:meth:`ThermalModel.conductivity_matrix` gives the full ``(N + 1) n`` matrix of the reference
for inspection and checks.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import weakref
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from . import _thermal_jit

from ..mechanics.assembly import StiffnessPattern
from .._validate import array
from ..errors import ConvergenceError, ParameterError
from ..linalg import thresholds
from ..linalg.ladder import factorize
from ..model.mesh import BarHingeMesh
from ..model.model import Model
from ..model.sharp import check_not_sharp
from ..model.thermal_parameters import ThermalParameters
from .integral import IntegralOperator
from .integral_levels import integral_operator
from .chains import CAP_BOUNDARY, CAP_NONE, MIN_AIR_FRACTION, UNUSED_CHAINS, ChainEnvironment
from .conduction import SheetConduction
from .monotone import MonotoneConduction
from .nonlinear import NonlinearLoss, radiation, solve_heat_balance
from .refined import RefinedSheet
from .substrate import substrate_plane, warn_no_plane

__all__ = ["ThermalModel", "heat_weights", "thermal_model"]

logger = logging.getLogger(__name__)


def heat_weights() -> np.ndarray:
    """Share of a crease's power on its nodes N11, N12, N21, N22, A, B, Ctr (theory 4.6), (7,)."""
    return np.array([1 / 8, 1 / 8, 1 / 8, 1 / 8, 1 / 12, 1 / 12, 1 / 3])


class ThermalModel:
    """Conduction and environment-loss model of one mesh, with cached sparsity patterns.

    Parameters
    ----------
    mesh : BarHingeMesh
    params : ThermalParameters
    warn_no_plane : bool
        With the integral loss, boundary panels and ``substrate=None``, warn (once per
        process) at the first steady solve that the medium is unbounded below the sheet;
        False where the caller chose no plane.
    actuators : Actuators or None
        The model's actuators, for the sheet's layer stacks (see
        :class:`~simulator.thermal.conduction.SheetConduction`).

    Attributes
    ----------
    conduction : SheetConduction
        The sheet's conduction elements (:class:`~simulator.thermal.conduction.SheetConduction`:
        thicknesses, conductivities, layer stacks).
    environment : ChainEnvironment
        The environment chains (:class:`~simulator.thermal.chains.ChainEnvironment`; with the
        integral loss those of :data:`~simulator.thermal.chains.UNUSED_CHAINS`, which size the
        unused medium layers of the full system).
    """

    def __init__(self, mesh: BarHingeMesh, params: ThermalParameters,
                 warn_no_plane: bool = True, actuators=None):
        if not isinstance(params, ThermalParameters):
            raise ParameterError(f"params must be ThermalParameters, got {type(params).__name__}.")
        self.mesh, self.params = mesh, params
        n, pat = mesh.n_nodes, mesh.pattern
        for p in params.boundary_panels:
            if not 0 <= p < pat.n_panels:
                raise ParameterError(f"ThermalParameters.boundary_panels: panel {p} does not exist "
                                     f"(the pattern has panels 0..{pat.n_panels - 1}).")
        for v in params.room_temperature_nodes:
            if not 0 <= v < n:
                raise ParameterError(f"ThermalParameters.room_temperature_nodes: node {v} does not "
                                     f"exist (the mesh has nodes 0..{n - 1}).")
        tri = mesh.triangles
        self.conduction = conduction = SheetConduction(mesh, params, actuators)
        panel = mesh.triangle_panel
        self.is_boundary = (panel >= 0) & np.isin(panel, params.boundary_panels)
        fixed = np.zeros(n, bool)
        fixed[list(params.room_temperature_nodes)] = True
        #: room-temperature nodes of the chain model (and of the transient model)
        self.chain_fixed_nodes = np.flatnonzero(fixed)
        #: the chain loss (:class:`~simulator.model.heat_loss.ChainLoss`); with the integral loss
        #: the chains' defaults, which size the (unused) medium layers of the full system
        self.chains = params.loss if params.loss.model == "chain" else UNUSED_CHAINS
        self.environment = ChainEnvironment(mesh, self.chains, params.medium.thermal_conductivity,
                                            conduction.edge_lengths, self.is_boundary)
        #: the integral model's loss operator (:mod:`simulator.thermal.integral_levels`:
        #: an :class:`IntegralOperator` at refinement m, or its Richardson extrapolation, or either
        #: corrected through the m = 1 operator between rebuilds)
        self.integral = None
        #: the integral loss's substrate plane ``(point, unit normal)`` or None
        self.plane = None
        if params.loss.model == "integral":          # boundary panels lie on the substrate
            fixed[tri[self.is_boundary].ravel()] = True
            self.plane = substrate_plane(mesh, params)
            self.integral = self._integral_operator(params)
        #: warn at the first steady solve with the integral loss that boundary panels have no
        #: substrate plane (``substrate=None``; ``warn_no_plane=False``: the caller chose none)
        self._warn_plane = (warn_no_plane and self.integral is not None
                            and bool(params.boundary_panels) and self.plane is None)
        #: nodes held at room temperature by the steady model
        self.fixed_nodes = np.flatnonzero(fixed)
        self.free_nodes = np.flatnonzero(~fixed)
        self._check_solvable()
        self._factor_cache = None       # (compiled kernel?, positions, solver) of the last shape
        # the model's arguments of the compiled kernel (simulator.thermal._thermal_jit), in its
        # order (the integral loss: conduction only, no chains)
        chain = self.integral is None
        self._kernel_args = (
            np.array(tri, dtype=np.int64, order="C"), conduction.edge_lengths, conduction.kt,
            self.is_boundary, self.environment.cap_nodes.astype(np.int64),
            float(self.chains.thickness) if chain else 1.0,
            math.tan(self.chains.dissipation_angle),
            float(params.medium.thermal_conductivity) if chain else 0.0, int(self.chains.layers),
            MIN_AIR_FRACTION, CAP_BOUNDARY, CAP_NONE)
        #: the refined sheet (:class:`~simulator.thermal.refined.RefinedSheet`) where
        #: ``params.sheet_refinement_for`` the mesh is above 1, else None
        self.sheet = None
        #: the thermal model of the refined sheet (None without refinement)
        self.fine_model = None
        self._last_fine = None           # (x, q, fine temperatures) of the last solve
        #: the finer sheet (refined 2r, or r + 1 with ``"r+1"``) and its thermal model, with
        #: ``params.sheet_extrapolation`` (theory 4.13), else None
        self.sheet_2r = self.fine_model_2r = None
        #: the weights of the finer and the coarser sheet's temperatures in the extrapolation,
        #: ``R / (R - r)`` and ``-r / (R - r)`` (2 and -1 for R = 2r)
        self.extrapolation_weights = None
        r = params.sheet_refinement_for(len(tri))
        if r > 1:
            self._refine(r, warn_no_plane, actuators)
        elif params.sheet_extrapolation:
            raise ParameterError(
                f"ThermalParameters.sheet_extrapolation = True needs a refined sheet, but the "
                f"refinement in force on these {len(tri)} triangles is 1 (the dense operator's "
                "limit, theory 4.11); give sheet_refinement=2 or more, or "
                "sheet_extrapolation=False.")

    def _integral_operator(self, params):
        """The integral loss's operator on the sheet (the conducting triangles), at the levels
        of a refined sheet's fine triangles on a :class:`~simulator.thermal.refined.FineMesh`
        (theory 4.11)."""
        return integral_operator(self.mesh.triangles[~self.is_boundary], self.mesh.n_nodes,
                                 params, self.plane, getattr(self.mesh, "r", 1))

    def _refine(self, r: int, warn_no_plane: bool, actuators) -> None:
        """Solve on the mesh triangles split into ``r^2`` each (theory 4.11): the fine sheet's
        own model, whose integral operator, substrate plane and held nodes this one shows."""
        self.sheet = RefinedSheet(self.mesh, r)
        params = dataclasses.replace(self.params, sheet_refinement=1, sheet_extrapolation=False)
        mode = self.params.sheet_extrapolation
        if mode:
            R = self.params.finer_refinement(r)
            self.sheet_2r = RefinedSheet(self.mesh, R)
            self.extrapolation_weights = (R / (R - r), -r / (R - r))
        self.fine_model = ThermalModel(self.sheet.mesh, params, warn_no_plane, actuators)
        if mode:
            self.fine_model_2r = ThermalModel(self.sheet_2r.mesh, params, False, actuators)
        fine = self.fine_model
        self.integral, self.plane, self._warn_plane = fine.integral, fine.plane, False
        n = self.mesh.n_nodes
        self.fixed_nodes = fine.fixed_nodes[fine.fixed_nodes < n]
        self.free_nodes = np.setdiff1d(np.arange(n), self.fixed_nodes)

    def _check_solvable(self):
        """Without environment loss, every conducting component needs a room-temperature node."""
        if self.params.medium.thermal_conductivity > 0:
            return
        n, tri = self.mesh.n_nodes, self.mesh.triangles
        live = tri[self.conduction.kt > 0]
        adj = sp.coo_matrix((np.ones(3 * len(live)), (live.ravel(), np.roll(live, 1, 1).ravel())),
                            shape=(n, n))
        from scipy.sparse.csgraph import connected_components

        n_comp, label = connected_components(adj, directed=False)
        bad = np.setdiff1d(np.arange(n_comp), label[self.fixed_nodes])
        if len(bad):
            node = int(np.flatnonzero(label == bad[0])[0])
            raise ParameterError(
                f"node {node} has no heat path to room temperature (medium conductivity 0 and no "
                "room_temperature_nodes in its connected part): the temperatures are undefined.")

    @property
    def n_dof(self) -> int:
        """Size (N + 1) n of the full thermal system."""
        return (self.chains.layers + 1) * self.mesh.n_nodes

    # ------------------------------------------------------------------ element data
    def _positions(self, x) -> np.ndarray:
        """``x`` as a float array, checked to be finite and of the mesh's node shape [m]."""
        return array("positions x", x, self.mesh.nodes.shape, "m")

    def triangle_areas(self, x) -> np.ndarray:
        """Conduction areas A_t [m^2] of every triangle at positions ``x`` (n, 3) [m], (n_tri,)
        (reference edge lengths, current angle at the first node; theory 4.2)."""
        return self.conduction.t3(x)[1]

    # ------------------------------------------------------------------ matrices
    @property
    def monotone(self) -> MonotoneConduction | None:
        """The monotone conduction's triangulation where ``params.conduction_method`` is
        ``"monotone"``, else None (:attr:`SheetConduction.monotone
        <simulator.thermal.conduction.SheetConduction.monotone>`)."""
        return self.conduction.monotone

    @cached_property
    def _free_pattern(self) -> StiffnessPattern:
        n = self.mesh.n_nodes
        free_index = np.full(n, -1)
        free_index[self.free_nodes] = np.arange(len(self.free_nodes))
        return StiffnessPattern(self.conduction.families, free_index, diagonal=self.free_nodes)

    @cached_property
    def _full_pattern(self) -> StiffnessPattern:
        n, N = self.mesh.n_nodes, self.chains.layers
        q = np.arange(N)
        chain = np.stack([(q * n)[None, :] + np.arange(n)[:, None],
                          ((q + 1) * n)[None, :] + np.arange(n)[:, None]], axis=-1).reshape(-1, 2)
        return StiffnessPattern([*self.conduction.families, chain], np.arange(self.n_dof))

    def conductivity_matrix(self, x) -> sp.csr_matrix:
        """Full conductivity matrix [W/K], ((N + 1) n)^2, at node positions ``x`` (n, 3) [m].

        Index ``q * n + node`` is layer ``q`` (0 = structure) of a node; no boundary conditions.
        """
        K, area = self.conduction.t3(x)
        return self._full_pattern.matrix([*self.conduction.element_values(x, K),
                                          self.environment.pairs(x, area)])

    def chain_matrix(self, x) -> sp.csr_matrix:
        """The environment chains' part of :meth:`conductivity_matrix` [W/K] (the layer
        conductances alone, no sheet conduction), ((N + 1) n)^2, at positions ``x`` (n, 3)
        [m]."""
        K, area = self.conduction.t3(x)
        return self._full_pattern.matrix([*(np.zeros_like(v) for v in
                                            self.conduction.element_values(x, K)),
                                          self.environment.pairs(x, area)])

    def sheet_conduction(self, x) -> sp.csr_matrix:
        """The sheet's conduction matrix [W/K], (n, n), at node positions ``x`` (n, 3) [m]
        (:meth:`SheetConduction.matrix <simulator.thermal.conduction.SheetConduction.matrix>`:
        no loss, no boundary conditions)."""
        return self.conduction.matrix(x)

    def heat_vector(self, crease_power) -> np.ndarray:
        """Nodal heat input [W], (n,), from the power on each crease row, (C,) [W] (theory 4.6).

        Each crease gives 1/8 to N11, N12, N21, N22, 1/12 to A and B and 1/3 to Ctr.
        """
        mesh = self.mesh
        power = array("crease_power", crease_power, (mesh.n_creases,), "W",
                      hint="one entry per crease row")
        return np.bincount(mesh.crease_nodes.ravel(), (power[:, None] * heat_weights()).ravel(),
                           minlength=mesh.n_nodes).astype(float)

    def solve(self, x, q, room_temperature=None) -> np.ndarray:
        """Steady structure temperatures [deg C], (n,) (or (n, k) for k heat inputs).

        Parameters
        ----------
        x : (n, 3) array
            Current node positions [m] (the conductivity depends on the shape).
        q : (n,) or (n, k) array
            Nodal heat input [W], e.g. from :meth:`heat_vector`; k columns give k independent
            solutions from one factorisation (returned as (n, k)).
        room_temperature : float, optional
            Temperature [deg C] of the far layer and of the room-temperature nodes
            (default ``params.room_temperature``).

        Notes
        -----
        Equivalent to solving ``K_FF T_F = q_F - K_FD T_D`` on the full system (theory 4.5):
        every row of ``K`` sums to zero, so the temperature rise solves ``K_FF dT_F = q_F``, and
        the free environment layers of a node's chain condense exactly into one series
        conductance ``1 / sum_q (1 / g_q)`` to room temperature.
        """
        rt = self.params.room_temperature if room_temperature is None else float(room_temperature)
        q = np.asarray(q, float)
        n = self.mesh.n_nodes
        if q.shape[:1] != (n,) or q.ndim > 2 or not np.isfinite(q).all() \
                or not math.isfinite(rt):
            raise ParameterError(f"q must be a finite array of shape ({n},) or ({n}, k) [W] and "
                                 "the room temperature finite.")
        if self.sheet is not None:
            fine = self.fine_model.solve(self.sheet.positions(x), self.sheet.heat(q), rt)
            if self.sheet_2r is None:
                self._last_fine = (np.array(x, float), q.copy(), rt, fine)
                return fine[:n]
            fine_2r = self.fine_model_2r.solve(self.sheet_2r.positions(x), self.sheet_2r.heat(q),
                                               rt)
            wf, wc = self.extrapolation_weights       # Richardson in r (theory 4.13)
            return wf * fine_2r[:n] + wc * fine[:n]
        if self.nonlinear:
            return rt + self._nonlinear_rise(x, q, rt)
        rise = np.zeros(q.shape)
        if len(self.free_nodes):
            rise[self.free_nodes] = self.factorized(x)(q[self.free_nodes])
        return rt + rise

    @cached_property
    def _emissivity(self) -> np.ndarray:
        """Emissivity [-] of every triangle, (n_tri,): its panel's material's, or the crease
        material's; 0 on the boundary panels (they are the substrate)."""
        mesh, pat = self.mesh, self.mesh.pattern
        panel = mesh.triangle_panel
        eps_panel = np.array([getattr(m, "emissivity", 0.0) for m in pat.panel_material])
        eps = np.where(panel >= 0, eps_panel[np.maximum(panel, 0)],
                       getattr(pat.crease_material, "emissivity", 0.0))
        return np.where(self.is_boundary, 0.0, eps)

    @property
    def nonlinear(self) -> bool:
        """Whether the heat balance is nonlinear (theory 4.12): a medium conductivity law
        (``Fluid.conductivity_table``) or a material with an emissivity > 0."""
        return self.params.medium.temperature_dependent or bool(self._emissivity.any())

    def emissive_area(self, x) -> np.ndarray:
        """Emissivity times radiating area of every node, both faces [m^2], (n,), at positions
        ``x`` (n, 3) [m]: a third of ``2 eps A_t`` of each triangle at it (theory 4.12)."""
        area = self.conduction.t3(x)[1]
        tri = self.mesh.triangles
        return np.bincount(tri.ravel(), np.repeat(2 * self._emissivity * area / 3, 3),
                           minlength=self.mesh.n_nodes)

    def radiation_loss(self, x, temperature, room_temperature=None) -> np.ndarray:
        """Heat [W] each node radiates to surroundings at room temperature, (n,), at
        temperatures ``temperature`` (n,) [deg C] and positions ``x`` (n, 3) [m] (theory
        4.12; on a refined sheet that of the last solve's fine field, gathered)."""
        rt = self.params.room_temperature if room_temperature is None else float(room_temperature)
        if self.sheet is not None:
            return self._refined_loss(x, temperature, rt, "radiation_loss")
        return radiation(self.emissive_area(x), np.asarray(temperature, float) - rt, rt)

    def nonlinear_system(self, x, room_temperature=None):
        """The steady heat balance on its unknown nodes at positions ``x`` (n, 3) [m] (theory
        4.12): ``(A, loss, nodes)`` with the sheet's conduction ``A`` [W/K] (dense, or sparse
        for a large chain model), the :class:`~simulator.thermal.nonlinear.NonlinearLoss`
        (the chains condensed, or the integral model's loss conductance; radiation) and the
        mesh nodes solved for (the free nodes, without those touching the substrate): their
        rise solves ``A u + loss.flux(u) = q[nodes]``. Not on the fast path nor on a refined
        sheet (its fine model's system is the one solved)."""
        rt = self.params.room_temperature if room_temperature is None else float(room_temperature)
        if self.sheet is not None or getattr(self.integral, "fast", False):
            raise ParameterError(
                "the nonlinear heat balance (a medium conductivity law or radiation) is solved "
                "on the dense integral operator or the chains: "
                + ("a refined sheet's is its fine model's (tm.fine_model.nonlinear_system)."
                   if self.sheet is not None else
                   "the fast path of large sheets (IntegralLoss operator 'fast', or 'auto' "
                   "above the dense limit) does not take it; use IntegralLoss(operator="
                   "'dense') with a lower refinement, or the chains, or a constant "
                   "conductivity and emissivity 0."))
        K, g_eff = self._conductances(x, _thermal_jit.use_compiled())
        K = self.conduction.element_values(x, K)
        free = self.free_nodes
        e = self.emissive_area(x)[free]
        zero = np.zeros(len(free))
        medium = self.params.medium
        if self.integral is None:
            A = (self._dense_free(K, zero) if len(free) <= thresholds.CONDUCTION_DENSE_LIMIT
                 else self._free_pattern.matrix([*K, zero]))
            return A, NonlinearLoss(medium, rt, g=g_eff[free], emissive=e), free
        keep = ~self.integral.touching(x)[free]
        A, L = self._dense_free(K, zero), self._integral_loss(x)
        return (A[np.ix_(keep, keep)],
                NonlinearLoss(medium, rt, B=L[np.ix_(keep, keep)], emissive=e[keep]), free[keep])

    def _nonlinear_rise(self, x, q, rt) -> np.ndarray:
        """The steady rise [K], (n,), of the nonlinear heat balance for the nodal heat ``q``
        (n,) [W] by Newton's method (:func:`~simulator.thermal.nonlinear.solve_heat_balance`);
        :class:`ConvergenceError` carrying its result where it does not converge."""
        if q.ndim != 1:
            raise ParameterError(
                f"q of shape {q.shape}: the heat balance is nonlinear (a medium conductivity "
                "law or radiation, theory 4.12), so heat inputs do not superpose; solve one "
                "heat input (n,) at a time.")
        A, loss, nodes = self.nonlinear_system(x, rt)
        out = solve_heat_balance(A, loss, q[nodes])
        if not out.success:
            raise ConvergenceError(out.message, out)
        rise = np.zeros(self.mesh.n_nodes)
        rise[nodes] = out.rise
        return rise

    def factorized(self, x):
        """Solver ``q_free -> rise_free`` of the free-node system at positions ``x`` [m].

        The factorisation is kept for the last shape: solving again on the same positions
        (a fixed-shape coupling, several heat inputs) reuses it.
        """
        x = np.asarray(x, float)
        if self.nonlinear:
            raise ParameterError("factorized: the heat balance is nonlinear (a medium "
                                 "conductivity law or radiation, theory 4.12) and has no "
                                 "linear solver; use solve(x, q).")
        if self.sheet is not None:
            return self._refined_solver(x)
        compiled, last = _thermal_jit.use_compiled(), self._factor_cache
        if last is not None and last[0] == compiled and last[1].shape == x.shape \
                and np.array_equal(last[1], x):
            return last[2]
        K, g_eff = self._conductances(x, compiled)
        K = self.conduction.element_values(x, K)
        if self.integral is None:
            solver = self._factorize(K, g_eff[self.free_nodes])
        elif getattr(self.integral, "fast", False):      # the loss never formed
            solver = self._fast_solver(x, K)
        else:                            # nodes touching the substrate are held there
            solver = self._factorize(K, np.zeros(len(self.free_nodes)), self._integral_loss(x),
                                     self.integral.touching(x)[self.free_nodes])
        self._factor_cache = (compiled, x.copy(), solver)
        return solver

    @property
    def fine_temperatures(self):
        """Temperatures [deg C] of the refined sheet's fine nodes at the last solve, (n_fine,)
        or (n_fine, k) (theory 4.11; the mesh nodes first); None without refinement, before
        the first solve, or with ``sheet_extrapolation`` (two sheets)."""
        return None if self._last_fine is None else self._last_fine[3]

    def exact_loss_at(self, x) -> bool:
        """Rebuild the integral loss's accurate operator at positions ``x`` (n, 3) [m] unless
        its last build was there (``Heat``'s settled end, theory 6.6: the end state then does
        not depend on the shapes at which the operator was rebuilt on the way, hence not on
        the increment count); whether it rebuilt. The chains: nothing to rebuild."""
        if self.sheet is not None:
            done = self.fine_model.exact_loss_at(self.sheet.positions(x))
            if self.sheet_2r is not None:           # both rebuilt where due
                done = self.fine_model_2r.exact_loss_at(self.sheet_2r.positions(x)) or done
        else:
            exact = getattr(self.integral, "exact_at", None)
            done = bool(exact is not None and exact(np.asarray(x, float)))
        if done:
            self._factor_cache = None
        return done

    def _refined_solver(self, x):
        """:meth:`factorized` on the refined sheet: the mesh nodes' heat spread onto the fine
        nodes, the fine rise taken at the mesh nodes (with ``sheet_extrapolation`` ``2 T(2r) -
        T(r)``, or ``(r + 1) T(r + 1) - r T(r)``, theory 4.13)."""
        solve = self._sheet_solver(self.sheet, self.fine_model.free_nodes,
                                   self.fine_model.factorized(self.sheet.positions(x)))
        if self.sheet_2r is None:
            return solve
        solve_2r = self._sheet_solver(self.sheet_2r, self.fine_model_2r.free_nodes,
                                      self.fine_model_2r.factorized(self.sheet_2r.positions(x)))
        wf, wc = self.extrapolation_weights
        return lambda q_free: wf * solve_2r(q_free) + wc * solve(q_free)

    def _sheet_solver(self, sheet, ffree, solve):
        """The free mesh nodes' rise on one refined ``sheet``, whose model's free nodes are
        ``ffree`` and its solver ``solve`` (:meth:`factorized`)."""
        free = self.free_nodes

        def solver(q_free):
            q_free = np.asarray(q_free, float)
            q = np.zeros((self.mesh.n_nodes,) + q_free.shape[1:])
            q[free] = q_free
            rise = np.zeros((sheet.n_fine,) + q_free.shape[1:])
            rise[ffree] = solve(sheet.heat(q)[ffree])
            return rise[free]
        return solver

    def structure_conductances(self, x):
        """T3 matrices (n_tri, 3, 3) [W/K] and each node's environment chain condensed into
        one series conductance to room temperature, ``1 / sum_q (1 / g_q)`` (n,) [W/K] (0
        where a layer has no conductance), at positions ``x`` (n, 3) [m].

        Uses the compiled kernel of :mod:`simulator.thermal._thermal_jit` when the kernel backend is
        "numba" (:func:`simulator.mechanics.elements.springs.spring_kernel_backend`), else numpy.
        """
        return self._conductances(x, _thermal_jit.use_compiled())

    def _conductances(self, x, compiled: bool):
        """:meth:`structure_conductances` by the compiled kernel or by numpy."""
        if compiled:
            K, g_eff, floored = _thermal_jit.thermal_element_data(self._kernel_args,
                                                                  self._positions(x))
            if floored and self.integral is None:
                self.environment.warn_floored()
            return K, g_eff
        K, area = self.conduction.t3(x)
        if self.integral is not None:              # no chains: the integral loss instead
            return K, np.zeros(self.mesh.n_nodes)
        g = self.environment.conductance(x, area)
        with np.errstate(divide="ignore"):
            g_eff = np.where(np.all(g > 0, axis=1), 1 / np.sum(1 / g, axis=1), 0.0)
        return K, g_eff

    @cached_property
    def _dense_position(self):
        """Flat positions in the dense free-node matrix of the entries given to the free pattern
        (triangle matrices, then diagonal terms), and the mask of those kept (the others touch
        a fixed node)."""
        p = self._free_pattern
        keep = p.positions < p.nnz
        return p.dense_positions()[p.positions[keep]], keep

    def held_nodes(self, x) -> np.ndarray:
        """Nodes the steady model holds at room temperature at positions ``x`` (n, 3) [m]:
        :attr:`fixed_nodes` and, in the integral model, the nodes touching the substrate plane
        (:meth:`~simulator.thermal.integral.IntegralOperator.touching`)."""
        if self.sheet is not None:
            held = self.fine_model.held_nodes(self.sheet.positions(x))
            return held[held < self.mesh.n_nodes]
        if self.integral is None:
            return self.fixed_nodes
        return np.union1d(self.fixed_nodes, np.flatnonzero(self.integral.touching(x)))

    def _fast_solver(self, x, K):
        """Solver ``q_free -> rise_free`` of the integral model's fast path
        (:class:`~simulator.thermal.integral_fast.FastIntegralOperator`): the sparse conduction
        of the free nodes not touching the substrate, coupled to the loss by MINRES."""
        if self._warn_plane:
            self._warn_plane = False
            warn_no_plane(self.params)
        n_free = len(self.free_nodes)
        A = self._free_pattern.matrix([*K, np.zeros(n_free)])
        keep = ~self.integral.touching(x)[self.free_nodes]
        return _scattered(self.integral.solver(x, A[keep][:, keep], self.free_nodes[keep])
                          if keep.any() else None, keep)

    def integral_loss_matrix(self, x) -> np.ndarray:
        """The integral model's loss conductance [W/K] on ``integral.nodes`` at positions
        ``x`` (n, 3) [m]: ``L_m``, or extrapolated (``IntegralLoss.extrapolation``) the
        Richardson combination ``(m L_m - c L_c) / (m - c)``, ``c = max(m // 2, 2)``, and with
        ``IntegralLoss.correction_tol`` that operator corrected between rebuilds (theory 4.7);
        the result with its positive couplings lumped onto the diagonal with
        ``IntegralLoss.lumped`` (theory 4.9).
        Not on the fast path (``IntegralLoss.operator`` "fast"), which never forms it, nor on
        a refined sheet (``sheet_refinement`` > 1), whose loss couples the fine nodes."""
        if self.sheet is not None:
            raise ParameterError(
                f"the loss conductance of a refined sheet (sheet_refinement = {self.sheet.r}) "
                "lives on its fine nodes: use tm.fine_model.integral_loss_matrix("
                "tm.sheet.positions(x)), or tm.condensed_system(x) on the mesh nodes.")
        if getattr(self.integral, "fast", False):
            raise ParameterError("the integral model's fast path (IntegralLoss(operator='fast'), "
                                 "or 'auto' on a large sheet) never forms the loss conductance; "
                                 "use environment_loss, or IntegralLoss(operator='dense').")
        return self.integral.loss_matrix(x)

    def _integral_loss(self, x):
        """The integral model's loss conductance [W/K] on the free nodes, (n_free, n_free)."""
        if self._warn_plane:
            self._warn_plane = False
            warn_no_plane(self.params)
        rows, kept = self._integral_scatter
        L = np.zeros((len(self.free_nodes),) * 2)
        L[rows] = self.integral_loss_matrix(x)[kept]
        return L

    @cached_property
    def _integral_scatter(self):
        """Index pairs of :meth:`_integral_loss`: the free-node rows and columns of the integral
        model's sheet nodes, and the same entries of its loss conductance (``np.ix_``)."""
        idx = np.full(self.mesh.n_nodes, -1)
        idx[self.free_nodes] = np.arange(len(self.free_nodes))
        sheet = idx[self.integral.nodes]
        keep = sheet >= 0
        return np.ix_(sheet[keep], sheet[keep]), np.ix_(keep, keep)

    def environment_loss(self, x, temperature, room_temperature=None) -> np.ndarray:
        """Heat [W] each node loses to the medium at temperatures ``temperature`` (n,) [deg C]
        and positions ``x`` (n, 3) [m], (n,), by the parameters' loss model (the rest of the
        heat input leaves through the room-temperature nodes)."""
        rt = self.params.room_temperature if room_temperature is None else float(room_temperature)
        if self.sheet is not None:
            return self._refined_loss(x, temperature, rt, "environment_loss")
        rise = self.params.medium.kirchhoff(np.asarray(temperature, float) - rt, rt)[0]
        if self.integral is None:
            return self._conductances(x, False)[1] * rise
        if getattr(self.integral, "fast", False):
            return self.integral.loss(x, rise)
        out = np.zeros(self.mesh.n_nodes)
        nodes = self.integral.nodes
        if isinstance(self.integral, IntegralOperator) and not self.integral.lumped:
            out[nodes] = self.integral.M.T @ self.integral.sub_triangle_heat(x, rise)
        else:                            # the combined or lumped conductance the solve used
            out[nodes] = self.integral_loss_matrix(x) @ rise[nodes]
        return out

    def _refined_loss(self, x, temperature, rt, which: str) -> np.ndarray:
        """:meth:`environment_loss` or :meth:`radiation_loss` (``which``) on a refined sheet:
        the fine field of the last solve (the only one whose mesh-node temperatures determine
        it), its loss gathered onto the mesh nodes
        (:meth:`~simulator.thermal.refined.RefinedSheet.restrict`: the total kept)."""
        if self.sheet_2r is not None:
            raise ParameterError(
                f"{which} with ThermalParameters.sheet_extrapolation = True: the temperatures "
                "are extrapolated from two refined sheets, which have no one loss per node "
                "(theory 4.13); use sheet_extrapolation=False for the loss per node.")
        last, T = self._last_fine, np.asarray(temperature, float)
        if last is None or not (np.array_equal(last[0], np.asarray(x, float)) and last[2] == rt
                                and last[3].ndim == 1 and np.array_equal(last[3][:len(T)], T)):
            raise ParameterError(
                f"{which} on a refined sheet (sheet_refinement = {self.sheet.r}) "
                "needs the temperatures and positions of the last solve: the mesh nodes' "
                "temperatures do not determine the fine field; call solve(x, q) first.")
        fine = getattr(self.fine_model, which)(self.sheet.positions(x), last[3], rt)
        return self.sheet.restrict(fine)

    def condensed_system(self, x):
        """The refined sheet's steady system condensed onto the mesh nodes it does not hold,
        at positions ``x`` (n, 3) [m] (theory 4.11): ``(A, G)`` with the dense conductance
        ``A`` (n_free, n_free) [W/K] and the load map ``G`` (n_free, n) such that the rise of
        :attr:`free_nodes` solves ``A dT = G q`` for the mesh nodal heat ``q`` [W]: the fine
        nodes that are not mesh nodes eliminated exactly (a Schur complement), the heat put
        on them passed on through ``G``. Refined sheets with the dense loss only."""
        if self.sheet is None:
            raise ParameterError("condensed_system is the refined sheet's (sheet_refinement > "
                                 "1); without refinement the system is on the mesh nodes.")
        if self.sheet_2r is not None:
            raise ParameterError(
                "condensed_system with ThermalParameters.sheet_extrapolation = True: the "
                "temperatures are extrapolated from two refined sheets, steady only (theory "
                "4.13); use sheet_extrapolation=False in the time domain.")
        fine, sheet = self.fine_model, self.sheet
        X = sheet.positions(x)
        n = self.mesh.n_nodes
        K = fine.sheet_conduction(X).toarray()
        if getattr(fine.integral, "fast", False):
            raise ParameterError("condensed_system: the refined sheet's loss is on the fast path "
                                 "(too many sub-triangles for the dense operator); lower "
                                 "sheet_refinement or IntegralLoss.refinement.")
        K[np.ix_(fine.integral.nodes, fine.integral.nodes)] += fine.integral_loss_matrix(X)
        free = np.setdiff1d(np.arange(sheet.n_fine), fine.held_nodes(X))
        c, f = free[free < n], free[free >= n]
        Q = sheet.load
        if len(f) == 0:
            return K[np.ix_(c, c)], Q[c]
        solve = factorize(K[np.ix_(f, f)], kind="spd", dense_limit=len(f)).solve
        W = solve(np.hstack([K[np.ix_(f, c)], Q[f]]))
        A = K[np.ix_(c, c)] - K[np.ix_(c, f)] @ W[:, :len(c)]
        G = Q[c] - K[np.ix_(c, f)] @ W[:, len(c):]
        return 0.5 * (A + A.T), G

    def _factorize(self, K, g_free, loss=None, held=None):
        """Factorise the free-node system (conduction plus condensed chains, or plus the
        integral model's dense ``loss``); returns its solver ``q_free -> rise_free``
        (``K``: the list of element matrices of the conduction's families; ``held`` (n_free,) bool:
        free nodes eliminated with a zero rise, the integral model's nodes touching the
        substrate).

        By the factorisation ladder (:func:`~simulator.linalg.ladder.factorize`, kind
        "spd"): up to :data:`~simulator.linalg.thresholds.CONDUCTION_DENSE_LIMIT` free nodes
        dense Cholesky of the matrix scattered straight from the element terms (the sparse
        rungs if it is not positive definite); above, PARDISO if installed, else SuperLU (in
        nested-dissection order from :data:`~simulator.linalg.thresholds.ND_LIMIT` free nodes).
        """
        n_free = len(g_free)
        limit = thresholds.CONDUCTION_DENSE_LIMIT
        if loss is not None:             # the integral model: dense anyway
            A = self._dense_free(K, g_free) + loss
            if held is None or not held.any():
                return factorize(A, kind="spd", dense_limit=n_free).solve
            return _held_solver(A, ~held)
        if n_free <= limit:
            A = self._dense_free(K, g_free)
        else:
            A = self._free_pattern.matrix([*K, g_free])
        return factorize(A, kind="spd", dense_limit=limit).solve

    def _dense_free(self, K, diagonal) -> np.ndarray:
        """The dense free-node matrix [W/K], (n_free, n_free), scattered from the element
        matrices ``K`` (of the conduction's families) and the ``diagonal`` (n_free,) terms."""
        n_free = len(diagonal)
        pos, keep = self._dense_position
        flat = np.concatenate([*(v.ravel() for v in K), diagonal])[keep]
        return np.bincount(pos, flat, minlength=n_free * n_free).reshape(n_free, n_free)


def _held_solver(A, keep):
    """Solver ``q -> rise`` of the dense system ``A`` with the rows and columns not in ``keep``
    eliminated (their rise 0: held at room temperature; their heat goes to the holder)."""
    solve = factorize(A[np.ix_(keep, keep)], kind="spd", dense_limit=int(keep.sum())).solve \
        if keep.any() else None
    return _scattered(solve, keep)


def _scattered(solve, keep):
    """Solver ``q -> rise`` of all free nodes from ``solve`` (None: nothing to solve) of those
    in ``keep``; the others' rise is 0."""

    def solver(q):
        q = np.asarray(q, float)
        rise = np.zeros(q.shape)
        if solve is not None:
            rise[keep] = solve(q[keep])
        return rise
    return solver


_THERMAL: "weakref.WeakKeyDictionary[Model, ThermalModel]" = weakref.WeakKeyDictionary()


def thermal_model(model: Model) -> ThermalModel:
    """The cached :class:`~simulator.thermal.steady.ThermalModel` of a model (built on first use)."""
    if getattr(model.mesh, "sharp", False):
        check_not_sharp(model, "A heating step")
    if model.thermal is None:
        raise ParameterError("This model has no thermal parameters: pass thermal="
                             "ThermalParameters(...) to make_model to use heating steps.")
    tm = _THERMAL.get(model)
    if tm is None:
        tm = _THERMAL[model] = ThermalModel(model.mesh, model.thermal,
                                            actuators=model.actuators)
    return tm
