"""The chain heat-loss model's steady operator and its exact derivative in the shape (theory
12.2).

The structure rise dT solves ``A(x) dT = q`` on the free nodes with
``A(x) = sum_e K_e(alpha_e) + k_env diag(g1(x))``: the T3 matrices of the triangles, each a
function of the current angle ``alpha_e`` at its first node (reference edge lengths), and every
node's condensed chain ``g1_i = 1 / sum_q 1 / g1_iq`` per unit medium conductivity, whose layer
conductances ``g1_iq = sum_{e at i} N (2/3) (A_e / t_air,e + L_e tan(beta) s_q)`` depend on the
triangle areas ``A_e(alpha_e)`` and on ``t_air,e = min(t_env, tcap_e)``, ``tcap_e`` the mean
distance of the triangle's vertices to the nearest thermal-boundary triangle (theory 4.3-4.4).
:class:`ChainOperator` recomputes these numbers with numpy at given positions (the same
formulas as :class:`~simulator.thermal.steady.ThermalModel`), the matrix ``A``, the Jacobian
``d(A(x) dT)/dx`` of its product with a fixed rise, exactly (the closest-point gradients of
:func:`~simulator.mechanics.elements.contact.distance_derivatives`), and the places where the
operator is not differentiable: ``min(t_env, tcap)`` switching, two boundary triangles equally
near a node with different closest points, a node on a boundary panel it is not part of, a
floored ``t_air``.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..mechanics.elements.contact import distance_derivatives, point_triangle_distance

__all__ = ["ChainOperator", "SWITCH_RTOL"]

#: A switch of the operator counts as reached (reported as a non-smooth point) within this
#: relative distance: ``|tcap - t_env| <= SWITCH_RTOL t_env``, two nearest boundary distances
#: within ``SWITCH_RTOL`` of each other.
SWITCH_RTOL = 1e-6


class ChainOperator:
    """The steady chain operator of a :class:`~simulator.thermal.steady.ThermalModel` ``tm``
    at positions ``x`` (n, 3) [m], with its shape derivative.

    Attributes
    ----------
    K : (m, 3, 3) T3 matrices [W/K]; dK : (m, 3, 3) their derivative in alpha [W/(K rad)]
    dalpha : (m, 9) gradient of each triangle's angle at its first node [rad/m]
    area, darea : (m,) areas [m^2] and their derivative in alpha [m^2/rad]
    t_air : (m,) environment thickness [m]; capped : (m,) bool where it is ``tcap`` (< t_env)
    g1 : (n,) condensed chain per unit medium conductivity [m]; rho : (n,)
        ``sum_q (g1_i / g1_iq)^2`` [-]
    nonsmooth : list of str, the switches the operator sits on (empty: differentiable)
    """

    def __init__(self, tm, x):
        self.tm, self.x = tm, np.asarray(x, float)
        self.nonsmooth = []
        self._conduction()
        self._distances()
        self._chains()

    # ------------------------------------------------------------------ conduction
    def _conduction(self):
        tm, x, tri = self.tm, self.x, self.tm.mesh.triangles
        u, v = x[tri[:, 1]] - x[tri[:, 0]], x[tri[:, 2]] - x[tri[:, 0]]
        nu, nv = np.linalg.norm(u, axis=1), np.linalg.norm(v, axis=1)
        alpha = np.arctan2(np.linalg.norm(np.cross(u, v), axis=1), np.einsum("ij,ij->i", u, v))
        cos, sin = np.cos(alpha), np.sin(alpha)
        uh, vh = u / nu[:, None], v / nv[:, None]
        da_u = (cos[:, None] * uh - vh) / (nu * sin)[:, None]
        da_v = (cos[:, None] * vh - uh) / (nv * sin)[:, None]
        self.dalpha = np.concatenate([-(da_u + da_v), da_u, da_v], axis=1)
        l1, l2 = tm.environment.edge_lengths[:, 0], tm.environment.edge_lengths[:, 1]
        x3, y3 = l2 * cos, l2 * sin
        self.area, self.darea = 0.5 * l1 * y3, 0.5 * l1 * x3
        z = np.zeros_like(l1)
        b, c = np.stack([-y3, y3, z], 1), np.stack([x3 - l1, -x3, l1], 1)
        db, dc = np.stack([-x3, x3, z], 1), np.stack([-y3, y3, z], 1)
        s = tm.conduction.kt / (4 * self.area)

        def outer(p, q):
            return p[:, :, None] * q[:, None, :]
        self.K = s[:, None, None] * (outer(b, b) + outer(c, c))
        self.dK = s[:, None, None] * (outer(db, b) + outer(b, db) + outer(dc, c) + outer(c, dc)) \
            - self.K * (self.darea / self.area)[:, None, None]

    # ------------------------------------------------------------------ tcap
    def _distances(self):
        """Nearest boundary triangle of every cap node, its distance and gradient."""
        tm, x = self.tm, self.x
        n, tri = tm.mesh.n_nodes, tm.mesh.triangles
        self.dmin = np.zeros(n)
        self.dgrad = np.zeros((n, 12))            # d dmin / d (P, T1, T2, T3)
        self.dnodes = np.zeros((n, 4), dtype=int)
        if not tm.is_boundary.any():
            return
        bt = tri[tm.is_boundary]
        on_panel = np.zeros(n, bool)
        on_panel[bt.ravel()] = True
        p = tm.environment.cap_nodes
        d = point_triangle_distance(np.repeat(x[p], len(bt), axis=0),
                                    np.tile(x[bt], (len(p), 1, 1)))[0].reshape(len(p), len(bt))
        order = np.argsort(d, axis=1)
        near = order[:, 0]
        self.dmin[p] = d[np.arange(len(p)), near]
        moving = ~on_panel[p]
        q = p[moving]
        if not len(q):
            return
        dist, grad, _, _ = distance_derivatives(x[q], x[bt[near[moving]]])
        self.dgrad[q] = grad
        self.dnodes[q] = np.column_stack([q, bt[near[moving]]])
        touching = q[dist <= SWITCH_RTOL * max(tm.chains.thickness, 1e-300)]
        if len(touching):
            self.nonsmooth.append(f"node(s) {touching.tolist()} touch a thermal-boundary panel "
                                  "(tcap is not differentiable at distance 0)")
        if bt.shape[0] > 1:
            self._ties(q, d[moving], order[moving], grad, x[bt])

    def _ties(self, q, d, order, grad, xb):
        """Report nodes whose two nearest boundary triangles are equally near with different
        closest points (the min over triangles switches)."""
        rows = np.arange(len(q))
        d1, d2 = d[rows, order[:, 0]], d[rows, order[:, 1]]
        close = np.flatnonzero(d2 - d1 <= SWITCH_RTOL * np.maximum(d1, 1e-300))
        if not len(close):
            return
        _, g2, _, _ = distance_derivatives(self.x[q[close]], xb[order[close, 1]])
        differ = np.linalg.norm(g2[:, :3] - grad[close, :3], axis=1) > 1e-8
        if differ.any():
            self.nonsmooth.append(f"node(s) {q[close[differ]].tolist()} are equally near two "
                                  "thermal-boundary triangles (tcap switches between them)")

    # ------------------------------------------------------------------ chains
    def _chains(self):
        tm = self.tm
        tri, chains = tm.mesh.triangles, tm.chains
        t_env = chains.thickness
        cap = np.where(tm.is_boundary, 1e10, self.dmin[tri].mean(axis=1)) \
            if tm.is_boundary.any() else np.full(len(tri), 1e5)
        self.capped = ~(t_env < cap)
        self.t_air = np.where(self.capped, cap, t_env)
        near = np.flatnonzero(~tm.is_boundary & (np.abs(cap - t_env) <= SWITCH_RTOL * t_env))
        if len(near):
            self.nonsmooth.append(f"triangle(s) {near.tolist()}: tcap = t_env (t_air = "
                                  "min(t_env, tcap) switches)")
        floor = 1e-9 * t_env
        if np.any(self.t_air < floor):
            self.nonsmooth.append("t_air floored at 1e-9 t_env on a triangle touching a "
                                  "thermal-boundary panel")
            self.t_air = np.maximum(self.t_air, floor)
        N = chains.layers
        s = (np.arange(1, N + 1) - 0.5) / N
        spread = tm.environment.edge_lengths.sum(axis=1) * math.tan(chains.dissipation_angle)
        h = N * (2 / 3) * ((self.area / self.t_air)[:, None] + spread[:, None] * s)   # (m, N)
        g = tm.environment.node_layer_sum(h)                                                       # (n, N)
        with np.errstate(divide="ignore", invalid="ignore"):
            ok = np.all(g > 0, axis=1)
            self.g1 = np.where(ok, 1 / np.sum(1 / g, axis=1), 0.0)
            self.rho = np.where(ok, np.sum((self.g1[:, None] / g) ** 2, axis=1), 0.0)

    # ------------------------------------------------------------------ products
    @property
    def k_env(self) -> float:
        return float(self.tm.params.medium.thermal_conductivity)

    def conduction_matrix(self) -> sp.csr_matrix:
        """The sheet's conduction [W/K], (n, n), sparse: ``A`` without the loss (the T3
        elements, or the monotone conduction)."""
        if self.tm.conduction.monotone is not None:
            return self.tm.conduction.matrix(self.x)
        tri, n = self.tm.mesh.triangles, self.tm.mesh.n_nodes
        rows, cols = np.repeat(tri, 3, axis=1).ravel(), np.tile(tri, (1, 3)).ravel()
        return sp.coo_matrix((self.K.ravel(), (rows, cols)), shape=(n, n)).tocsr()

    def matrix(self, nodes) -> sp.csr_matrix:
        """``A`` [W/K] on ``nodes`` (rows and columns), sparse."""
        A = self.conduction_matrix() + sp.diags(self.k_env * self.g1)
        return A[nodes][:, nodes].tocsr()

    def conductivity_derivative(self, rise) -> np.ndarray:
        """``d (A dT) / d k_env`` [W/(K W/(m K))] for the rise ``dT`` = ``rise`` (n,) [K],
        (n,): the loss is proportional to the medium's conductivity."""
        return self.g1 * rise

    def conduction_parts(self, rise) -> list:
        """The conduction's part of :meth:`shape_jacobian`, as ``[(rows, cols, values)]``:
        ``(dK/dalpha dT_e) x dalpha/dx`` per T3 triangle, or the monotone conduction's
        (:func:`~simulator.sensitivity.conduction.monotone_jacobian`)."""
        mono = self.tm.conduction.monotone
        if mono is not None:
            from .conduction import monotone_jacobian

            J = monotone_jacobian(mono, self.x, rise).tocoo()
            return [(J.row, J.col, J.data)]
        tri = self.tm.mesh.triangles
        m = len(tri)
        cols9 = (3 * tri[:, :, None] + np.arange(3)).reshape(m, 9)
        r = np.einsum("eij,ej->ei", self.dK, rise[tri])
        return [(np.repeat(tri, 9, axis=1).ravel(), np.tile(cols9, (1, 3)).ravel(),
                 (r[:, :, None] * self.dalpha[:, None, :]).ravel())]

    def shape_jacobian(self, rise) -> sp.csr_matrix:
        """``d (A(x) dT) / dx`` [W/(K m)] for the fixed rise ``dT`` = ``rise`` (n,) [K], (n, 3n)
        (rows: nodes, columns: node-major coordinates)."""
        tm, n = self.tm, self.tm.mesh.n_nodes
        tri = tm.mesh.triangles
        m = len(tri)
        cols9 = (3 * tri[:, :, None] + np.arange(3)).reshape(m, 9)
        parts = self.conduction_parts(rise)
        # chains through the areas: k dT_i rho_i N (2/3) / t_air dA/dalpha x dalpha/dx
        N, k = tm.chains.layers, self.k_env
        w = k * (rise * self.rho)[tri] * (N * 2 / 3 / self.t_air * self.darea)[:, None]  # (m, 3)
        parts.append((np.repeat(tri, 9, axis=1).ravel(), np.tile(cols9, (1, 3)).ravel(),
                      (w[:, :, None] * self.dalpha[:, None, :]).ravel()))
        # chains through t_air = tcap: -k dT_i rho_i N (2/3) A / t_air^2 x (1/3) sum_v dd_v/dx
        e = np.flatnonzero(self.capped & ~tm.is_boundary)
        if len(e):
            c = -k * (rise * self.rho)[tri[e]] * (N * 2 / 3 * self.area[e]
                                                  / self.t_air[e] ** 2 / 3)[:, None]  # (k, 3)
            v = tri[e]                                                     # the vertices
            dn = self.dnodes[v]                                            # (k, 3, 4)
            dcols = (3 * dn[..., None] + np.arange(3)).reshape(len(e), 36)  # 3 vertices x 12
            dg = self.dgrad[v].reshape(len(e), 36)
            parts.append((np.repeat(v, 36, axis=1).ravel(), np.tile(dcols, (1, 3)).ravel(),
                          (c[:, :, None] * dg[:, None, :]).ravel()))
        rows, cols, vals = (np.concatenate(a) for a in zip(*parts))
        return sp.coo_matrix((vals, (rows, cols)), shape=(n, 3 * n)).tocsr()

