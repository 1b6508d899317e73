"""The sheet's in-plane heat conduction (theory 4.2, 4.9, 4.10).

Every mesh triangle (crease and panel fans) is a linear T3 conduction element built from its
REFERENCE edge lengths and the CURRENT angle at its first node, with the conductance ``k t``
of its material and thickness, or of its layer stack (``crease_conduction="layers"``: the
actuated creases' bimorph, the panels and passive creases of ``sheet_layers``); with
``conduction="monotone"`` the M-matrix conduction of :mod:`simulator.thermal.monotone` at the
current positions instead. No loss and no boundary conditions: the heat loss and the solve are
:class:`~simulator.thermal.steady.ThermalModel`'s.
"""

from __future__ import annotations

import logging
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .._validate import array, capped
from ..errors import ParameterError, PatternError
from ..model.bimorph import Actuators
from .monotone import MonotoneConduction, monotone_conduction

__all__ = ["SheetConduction", "bar_ids"]

logger = logging.getLogger(__name__)


def bar_ids(mesh, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Bars of ``mesh`` joining node pairs ``(a, b)`` (any shape), by a sorted-key search."""
    n = mesh.n_nodes
    bars = mesh.bars.astype(np.int64)
    keys = bars[:, 0] * n + bars[:, 1]
    order = np.argsort(keys)
    want = np.minimum(a, b).astype(np.int64) * n + np.maximum(a, b)
    pos = np.minimum(np.searchsorted(keys, want, sorter=order), len(keys) - 1)
    found = keys[order[pos]] == want
    if not found.all():
        raise PatternError("mesh triangle edge without a bar: the mesh is inconsistent.")
    return order[pos]


class SheetConduction:
    """The conduction elements of one mesh's sheet.

    Parameters
    ----------
    mesh : BarHingeMesh
    params : ThermalParameters
        Its ``crease_conduction``, ``sheet_layers`` and ``conduction_method`` are read.
    actuators : Actuators or None
        The model's :class:`~simulator.model.bimorph.Actuators`: with
        ``params.crease_conduction == "layers"`` their bimorph's layers give the actuated
        creases' sheet conductance ``k1 t1 + k2 t2`` (theory 4.10); unused with ``"paper"``.

    Attributes
    ----------
    edge_lengths : (n_tri, 3) float
        Reference lengths [m] of every triangle's edges (0-1, 0-2, 1-2).
    thickness, conductivity : (n_tri,) float
        Thickness t [m] and conductivity k [W/(m K)] of every triangle (a layer stack's
        effective ``sum k t / t``).
    kt : (n_tri,) float
        Sheet conductance ``k t`` [W/K] of every triangle.
    layered : (n_tri,) bool
        Triangles that conduct and store heat as a layer stack (``crease_conduction="layers"``:
        the actuated creases' and the ``params.sheet_layers``' panels and creases).
    layer_capacity : (n_tri,) float
        Areal heat capacity ``sum rho c t`` [J/(m^2 K)] of the layered triangles' stacks (0
        elsewhere; the transient model takes the others' from their material, theory 7.2).
    """

    def __init__(self, mesh, params, actuators=None):
        self.mesh, self.params = mesh, params
        pat, tri = mesh.pattern, mesh.triangles
        self.edge_lengths = mesh.bar_length[bar_ids(mesh, tri[:, [0, 0, 1]], tri[:, [1, 2, 2]])]
        panel, crease = mesh.triangle_panel, mesh.triangle_crease
        is_panel = panel >= 0
        k_panel = np.array([m.thermal_conductivity for m in pat.panel_material])
        self.thickness = np.where(is_panel, pat.panel_thickness[panel],
                                  pat.crease_thickness[np.append(mesh.crease_ids, 0)[crease]])
        self.conductivity = np.where(is_panel, k_panel[panel],
                                     pat.crease_material.thermal_conductivity)
        self.kt = self.conductivity * self.thickness
        self.layered = np.zeros(len(tri), bool)
        self.layer_capacity = np.zeros(len(tri))
        if params.crease_conduction == "layers":
            self._layers(actuators)

    def _layers(self, actuators) -> None:
        """Give the layered triangles (``crease_conduction="layers"``, theory 4.10) their
        stack's sheet conductance and areal heat capacity: the actuated creases their bimorph's
        ``k1 t1 + k2 t2`` and ``rho_c1 t1 + rho_c2 t2``, the panels and passive creases of
        ``params.sheet_layers`` their stack's sums. Their :attr:`conductivity` becomes the
        effective ``sum k t / t`` over the pattern's thickness ``t``."""
        stacks = self.params.sheet_layers
        kt, cap = self.kt.copy(), self.layer_capacity.copy()
        if stacks is not None:
            listed, skt, scap = stacks.per_triangle(self.mesh, self.mesh.pattern)
            kt, cap, self.layered = np.where(listed, skt, kt), scap, listed
        if actuators is not None or stacks is None:
            actuated = self._actuated_triangles(actuators, stacks)
            b = actuators.bimorph
            kt = np.where(actuated, b.sheet_conductance, kt)
            cap = np.where(actuated, b.areal_capacity, cap)
            self.layered = self.layered | actuated
        self.kt, self.layer_capacity = kt, cap
        with np.errstate(divide="ignore", invalid="ignore"):
            self.conductivity = np.where(self.layered & (self.thickness > 0),
                                         self.kt / self.thickness, self.conductivity)
        logger.debug("conduction 'layers': %d of %d triangles as layer stacks",
                     int(self.layered.sum()), len(self.layered))

    def _actuated_triangles(self, actuators, stacks) -> np.ndarray:
        """(n_tri,) bool: the triangles of the creases ``actuators`` actuate; an error without
        actuators, or where ``stacks`` (:class:`~simulator.model.layers.SheetLayers`) lists
        an actuated crease (its layers are its bimorph's)."""
        if not isinstance(actuators, Actuators):
            raise ParameterError(
                f"ThermalParameters.crease_conduction = 'layers' needs the model's actuators "
                f"(their bimorph layers conduct), got actuators = {actuators!r}; give "
                "make_model(..., actuators=Actuators(Bimorph(...), ...)), or "
                "ThermalParameters(sheet_layers=SheetLayers(...)) for the stacks of panels and "
                "passive creases, or crease_conduction='paper'.")
        ids = [int(c) for c in dict(actuators.delta_alpha)]
        both = sorted(set(ids) & set(stacks.creases)) if stacks is not None else []
        if both:
            raise ParameterError(
                f"SheetLayers.creases lists the actuated crease(s) {capped(both)}: an actuated "
                "crease conducts as its bimorph's layers (Actuators.bimorph); list only passive "
                "creases (a heater film without actuation), or change the Bimorph.")
        actuated = np.isin(self.mesh.crease_ids, ids)
        crease = np.asarray(self.mesh.triangle_crease)
        return (crease >= 0) & np.append(actuated, False)[crease]

    def t3(self, x):
        """T3 matrices (n_tri, 3, 3) [W/K] and areas A_t (n_tri,) [m^2] at positions ``x``
        (n, 3) [m] (reference edge lengths, current angle at the first node)."""
        x = array("positions x", x, self.mesh.nodes.shape, "m")
        tri = self.mesh.triangles
        u, v = x[tri[:, 1]] - x[tri[:, 0]], x[tri[:, 2]] - x[tri[:, 0]]
        alpha = np.arctan2(np.linalg.norm(np.cross(u, v), axis=1), np.einsum("ij,ij->i", u, v))
        l1, l2 = self.edge_lengths[:, 0], self.edge_lengths[:, 1]
        x3, y3 = l2 * np.cos(alpha), l2 * np.sin(alpha)
        area = 0.5 * l1 * y3
        zero = np.zeros_like(l1)
        b = np.stack([-y3, y3, zero], axis=1)
        c = np.stack([x3 - l1, -x3, l1], axis=1)
        scale = self.kt / (4 * area)
        K = scale[:, None, None] * (b[:, :, None] * b[:, None, :] + c[:, :, None] * c[:, None, :])
        return K, area

    @cached_property
    def monotone(self) -> MonotoneConduction | None:
        """The monotone conduction's triangulation (:mod:`simulator.thermal.monotone`), chosen
        at the mesh's positions, where ``params.conduction_method`` is ``"monotone"``; else
        None."""
        if self.params.conduction_method != "monotone":
            return None
        mesh = self.mesh
        region = np.where(mesh.triangle_panel >= 0, mesh.triangle_panel,
                          -1 - mesh.triangle_crease)
        out = monotone_conduction(mesh.nodes, mesh.triangles, region, self.kt)
        logger.debug("monotone conduction: %d flips, %d Steiner points", out.flips,
                     out.n_steiner)
        return out

    @cached_property
    def families(self) -> list:
        """Mesh nodes of the conduction's element families: the triangles (T3), or the
        monotone conduction's :attr:`~simulator.thermal.monotone.MonotoneConduction.families`."""
        return [self.mesh.triangles] if self.monotone is None else self.monotone.families

    def element_values(self, x, K) -> list:
        """Element matrices [W/K] of :attr:`families` at positions ``x``, given the T3 matrices
        ``K`` (n_tri, 3, 3) of the mesh triangles there."""
        return [K] if self.monotone is None else self.monotone.element_values(x)

    def matrix(self, x) -> sp.csr_matrix:
        """The sheet's conduction matrix [W/K], (n, n), at node positions ``x`` (n, 3) [m]:
        the T3 elements or the monotone conduction (``params.conduction_method``, theory 4.2,
        4.9); no loss, no boundary conditions (every row sums to zero)."""
        x = array("positions x", x, self.mesh.nodes.shape, "m")
        n = self.mesh.n_nodes
        rows, cols, vals = [], [], []
        for nodes, v in zip(self.families, self.element_values(x, self.t3(x)[0])):
            k = nodes.shape[1]
            rows.append(np.repeat(nodes, k, axis=1).ravel())
            cols.append(np.tile(nodes, (1, k)).ravel())
            vals.append(np.ravel(v))
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows),
                                                     np.concatenate(cols))), shape=(n, n))
