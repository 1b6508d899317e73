"""The paper's environment chains (theory 4.3-4.4): the heat loss of
:class:`~simulator.model.heat_loss.ChainLoss`.

Each node owns a chain of ``N`` layers of the medium ending at room temperature; layer ``q`` of
a triangle's three nodes receives the conductance ``k_env A_q N / t_air`` with
``A_q = (2/3) A_t + (2/3) L_sum t_air tan(beta) (q - 1/2) / N`` (the paper's heat-loss area),
where ``t_air = min(t_env, tcap)`` and ``tcap`` is the mean distance of the triangle's vertices
to the thermal-boundary (substrate) panels. Boundary triangles keep their chains (as in the
reference); t_air is floored at :data:`MIN_AIR_FRACTION` t_env where the reference would divide
by zero. :class:`~simulator.thermal.steady.ThermalModel` condenses the chains into one series
conductance per node.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from ..mechanics.elements.contact import point_triangle_distance
from ..model.heat_loss import ChainLoss

__all__ = ["ChainEnvironment", "CAP_BOUNDARY", "CAP_NONE", "MIN_AIR_FRACTION", "UNUSED_CHAINS"]

logger = logging.getLogger(__name__)

#: Cap value of boundary triangles themselves and of all triangles without boundary panels [m].
CAP_BOUNDARY, CAP_NONE = 1e10, 1e5
#: Floor of t_air relative to t_env: a triangle lying on a boundary panel would otherwise get an
#: infinite conductance (the reference divides by zero there).
MIN_AIR_FRACTION = 1e-9
#: The chains' defaults, which size the medium layers of the full system (unused) with the
#: integral loss.
UNUSED_CHAINS = ChainLoss(thickness=1.0)


class ChainEnvironment:
    """The environment chains of one mesh.

    Parameters
    ----------
    mesh : BarHingeMesh
    chains : ChainLoss
        Thickness t_env [m], dissipation angle beta [rad] and layer count N of the chains.
    k_env : float
        Conductivity of the medium [W/(m K)].
    edge_lengths : (n_tri, 3) array
        Reference lengths [m] of every triangle's edges (0-1, 0-2, 1-2).
    is_boundary : (n_tri,) bool array
        Triangles of the thermal-boundary panels.
    """

    def __init__(self, mesh, chains: ChainLoss, k_env: float, edge_lengths, is_boundary):
        self.mesh, self.chains, self.k_env = mesh, chains, float(k_env)
        self.edge_lengths, self.is_boundary = edge_lengths, is_boundary
        #: nodes of the triangles off the boundary panels, whose distance to them caps t_env
        self.cap_nodes = np.unique(mesh.triangles[~is_boundary])

    def warn_floored(self) -> None:
        logger.warning("a triangle touches a thermal boundary panel; t_air floored at %g m",
                       MIN_AIR_FRACTION * self.chains.thickness)

    def tcap(self, x) -> np.ndarray:
        """Cap of t_env per triangle [m], (n_tri,) (theory 4.4).

        Mean over the triangle's vertices of the distance to the nearest boundary-panel triangle
        at positions ``x`` (n, 3) [m]; 1e10 for boundary triangles, 1e5 without boundary panels.
        """
        x = np.asarray(x, float)
        tri = self.mesh.triangles
        if not self.is_boundary.any():
            return np.full(len(tri), CAP_NONE)
        bc = x[tri[self.is_boundary]]                                      # (m, 3, 3)
        p = self.cap_nodes
        d, _, _ = point_triangle_distance(np.repeat(x[p], len(bc), axis=0),
                                          np.tile(bc, (len(p), 1, 1)))
        dmin = np.zeros(self.mesh.n_nodes)
        dmin[p] = d.reshape(len(p), len(bc)).min(axis=1)
        return np.where(self.is_boundary, CAP_BOUNDARY, dmin[tri].mean(axis=1))

    def geometry(self, x, area):
        """Environment layer areas and thickness of every triangle (theory 4.3-4.4) at
        positions ``x`` (n, 3) [m], given the triangles' conduction areas ``area`` (n_tri,)
        [m^2].

        Returns
        -------
        a_q : (n_tri, N) array
            Heat-loss area A_q [m^2] of layer q seen by EACH of the triangle's three nodes,
            ``(2/3) A_t + (2/3) L_sum t_air tan(beta) (q - 1/2) / N``.
        t_air : (n_tri,) array
            Environment thickness [m], ``min(t_env, tcap)`` (floored, see the module notes).
        """
        chains = self.chains
        t_env = chains.thickness
        t_air = np.where(t_env < (cap := self.tcap(x)), t_env, cap)
        if np.any(t_air < MIN_AIR_FRACTION * t_env):
            self.warn_floored()
            t_air = np.maximum(t_air, MIN_AIR_FRACTION * t_env)
        N = chains.layers
        s = (np.arange(1, N + 1) - 0.5) / N
        l_sum = self.edge_lengths.sum(axis=1)
        spread = l_sum * t_air * math.tan(chains.dissipation_angle)
        return (2 / 3) * area[:, None] + (2 / 3) * spread[:, None] * s, t_air

    def node_layer_sum(self, per_triangle) -> np.ndarray:
        """Sum a per-triangle, per-layer quantity (n_tri, N) onto every node's chain, (n, N)."""
        N, tri = self.chains.layers, self.mesh.triangles
        nodes = np.repeat(tri, N, axis=1).ravel()
        layer = np.tile(np.arange(N), 3 * len(tri))
        flat = np.bincount(nodes * N + layer, np.repeat(per_triangle, 3, axis=0).ravel(),
                           minlength=self.mesh.n_nodes * N)
        return flat.reshape(-1, N)

    def conductance(self, x, area) -> np.ndarray:
        """Environment conductance of every node and layer [W/K], (n, N) (theory 4.3), at
        positions ``x`` (n, 3) [m] and conduction areas ``area`` (n_tri,) [m^2]."""
        a_q, t_air = self.geometry(x, area)
        return self.node_layer_sum(self.k_env * a_q * self.chains.layers / t_air[:, None])

    def pairs(self, x, area) -> np.ndarray:
        """The 2 x 2 matrices [W/K] of every node's chain layers, node-major, (n N, 2, 2)."""
        g = self.conductance(x, area).ravel()                              # node-major (n, N)
        return g[:, None, None] * np.array([[1.0, -1.0], [-1.0, 1.0]])
