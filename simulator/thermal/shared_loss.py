"""One integral loss operator for the two sheets of the extrapolation in r (theory 4.13).

``ThermalParameters(sheet_extrapolation="shared")`` solves the steady heat balance on the sheet
refined r and on the sheet refined 2r, as ``sheet_extrapolation=True`` does, but the two share
one single-layer operator: the r sheet's sub-triangles (the levels of
:func:`~simulator.thermal.integral_levels.sheet_levels` at r), whose ``S`` is assembled and
factorised once per build. The loss conductance of each sheet is ``M^T S^-1 M`` with its own
``M``, the sub-triangle means of its P1 temperature field (:func:`sub_triangle_means`): on the
r sheet the centroid values (the usual interpolation), on the 2r sheet the means of the finer
field, exact because every sub-triangle is split into pieces that each lie in one fine
triangle. A field of the r sheet interpolated onto the 2r sheet loses the same heat on both.

So the 2r solve costs its conduction matrix and a dense solve on its nodes, not a second
operator at four times the sub-triangles. The extrapolation then removes the conduction's
first-order error in r (the corner boundary layer of a conducting crease, theory 4.13) at a
fixed loss discretisation, whose own error is small on these sheets (its levels raised from
m = 3 to 12 move the gripper's actuation measure by at most 1.6 K at r = 2).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .integral import lump_couplings, plane_heights
from .integral_levels import integral_operator
from ._single_layer import subdivision

__all__ = ["SharedSheetLoss", "sub_triangle_means"]


def sub_triangle_means(coarse, triangles, level: int, fine, nodes) -> np.ndarray:
    """The means of the P1 field of the refined sheet ``fine`` over the sub-triangles of
    :func:`~simulator.thermal._single_layer.subdivision` at ``level`` of the fine triangles
    ``triangles`` (ids into ``coarse.mesh.triangles``) of the refined sheet ``coarse``, as a
    (n_sub, len(nodes)) matrix on the ``fine`` sheet's ``nodes`` (its rows in the order of
    :class:`~simulator.thermal.integral.IntegralOperator`: triangle-major, then sub-triangle).

    ``coarse`` and ``fine`` (:class:`~simulator.thermal.refined.RefinedSheet`) refine the same
    mesh, ``r`` and ``R``; each sub-triangle is split uniformly into pieces nested in both it
    and the ``R`` triangles (``lcm(level r, R) / (level r)`` per edge), whose centroid values
    are their exact means. With ``fine`` the ``coarse`` sheet itself, the centroid values of
    the sub-triangles (the interpolation ``M`` of the integral operator)."""
    r, R, m = coarse.r, fine.r, int(level)
    k = math.lcm(m * r, R) // (m * r)
    corners_r, corners_m, corners_R = (subdivision(v)[0] for v in (r, m, R))
    pieces = subdivision(k)[1]                                           # (k^2, 3)
    # the pieces' centroids in their mesh triangle: (s_r, s_m, k^2, 3)
    lam = np.einsum("ic,jcd,ade->ajie", pieces, corners_m, corners_r)
    mu = np.einsum("ajie,bef->ajibf", lam, np.linalg.inv(corners_R))    # in each R triangle
    inside = np.argmax(mu.min(axis=-1), axis=-1)                         # (s_r, s_m, k^2)
    mu = np.take_along_axis(mu, inside[..., None, None], axis=3)[..., 0, :]
    triangles = np.asarray(triangles, np.int64)
    parent, local = np.divmod(triangles, len(corners_r))
    child = parent[:, None, None] * len(corners_R) + inside[local]      # (t, s_m, k^2)
    cols = fine.mesh.triangles[child]                                    # (t, s_m, k^2, 3)
    rows = np.broadcast_to(np.arange(len(triangles) * len(corners_m)).reshape(
        len(triangles), len(corners_m), 1, 1), cols.shape)
    column = np.full(fine.n_fine, -1)
    column[nodes] = np.arange(len(nodes))
    out = np.zeros((len(triangles) * len(corners_m), len(nodes)))
    np.add.at(out, (rows.ravel(), column[cols].ravel()), (mu[local] / k ** 2).ravel())
    return out


class SharedSheetLoss:
    """The integral loss of the sheets refined r (``coarse``) and 2r (``fine``) on one operator
    (module notes): :meth:`operator` gives each sheet's thermal model its loss, a view of one
    block of the shared conductance.

    Parameters
    ----------
    coarse, fine : RefinedSheet
        The two refined sheets of one mesh.
    params : ThermalParameters
        The fine models' parameters (the integral loss, dense).
    """

    def __init__(self, coarse, fine, params):
        self.coarse, self.fine, self.params = coarse, fine, params
        #: the shared operator (built with the coarse sheet's model), its node count
        self.shared, self.k = None, 0
        self.plane = None

    def _build(self, model):
        """The shared operator on the coarse sheet's ``model``
        (:class:`~simulator.thermal.steady.ThermalModel`): its levels, plane and conducting
        triangles, with the fine sheet's means as further columns."""
        params = self.params
        loss = dataclasses.replace(params.loss, lumped=False)      # each view lumps its block
        keep = ~model.is_boundary
        triangles = np.flatnonzero(keep)
        fine_mesh = self.fine.mesh
        panel = fine_mesh.triangle_panel
        fine_boundary = (panel >= 0) & np.isin(panel, params.boundary_panels)
        fine_nodes = np.unique(fine_mesh.triangles[~fine_boundary])

        def extra(level):
            return sub_triangle_means(self.coarse, triangles, level, self.fine, fine_nodes)

        self.plane = model.plane
        self.shared = integral_operator(model.mesh.triangles[keep], model.mesh.n_nodes,
                                        dataclasses.replace(params, loss=loss), model.plane,
                                        self.coarse.r, extra)
        self.k = len(self.shared.nodes)
        self._fine_nodes = fine_nodes

    def operator(self, model):
        """The loss of ``model``, the thermal model of the coarse sheet (built first) or of
        the fine sheet: a :class:`_SheetLoss`."""
        if self.shared is None:
            self._build(model)
            return _SheetLoss(self, slice(0, self.k), self.shared.nodes, None)
        return _SheetLoss(self, slice(self.k, None), self._fine_nodes, self.coarse.P)


class _SheetLoss:
    """One sheet's block of :class:`SharedSheetLoss`, with the interface of the integral
    operators the steady model reads (``nodes``, ``builds``, ``loss_matrix``, ``touching``,
    ``exact_at``); ``P`` maps the mesh nodes (the first of this sheet's) to the coarse sheet's
    positions (None: this is the coarse sheet)."""

    fast = False

    def __init__(self, owner: SharedSheetLoss, block: slice, nodes, P):
        self.owner, self.block, self.nodes, self.P = owner, block, nodes, P
        self.lumped = owner.params.loss.lumped
        self._last = (None, None)           # (shared conductance, this block of it)

    @property
    def builds(self) -> int:
        return self.owner.shared.builds

    def _coarse(self, x):
        x = np.asarray(x, float)
        return x if self.P is None else self.P @ x[:self.P.shape[1]]

    def touching(self, x) -> np.ndarray:
        """Nodes on (or below) the substrate plane at this sheet's positions ``x``, (n,)."""
        if self.P is None:
            return self.owner.shared.touching(x)
        x = np.asarray(x, float)
        h, tol = plane_heights(x, self.owner.plane, self.nodes)
        return np.zeros(len(x), bool) if h is None else h <= tol

    def loss_matrix(self, x) -> np.ndarray:
        """This sheet's loss conductance [W/K] on its ``nodes`` at its positions ``x``."""
        L = self.owner.shared.loss_matrix(self._coarse(x))
        if L is not self._last[0]:
            block = np.array(L[self.block, self.block])
            if self.lumped:
                block = lump_couplings(block)
            block.setflags(write=False)
            self._last = (L, block)
        return self._last[1]

    def exact_at(self, x) -> bool:
        """Rebuild the shared operator's accurate levels at ``x`` unless done there; whether
        this sheet's conductance changed since it last served it."""
        xc = self._coarse(x)
        done = self.owner.shared.exact_at(xc)
        return done or self.owner.shared.loss_matrix(xc) is not self._last[0]
