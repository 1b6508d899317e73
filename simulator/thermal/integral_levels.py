"""Combinations of the integral heat-loss operator at several refinements (theory 4.7).

:class:`~simulator.thermal.integral.IntegralLoss` is the collocated single-layer operator at one
refinement ``m``; its error is of first order in ``1 / m`` (the flux density's edge
singularity). Two combinations make it accurate at a fraction of the cost of a fine ``m``:

* :class:`ExtrapolatedLoss`: Richardson extrapolation ``(m L_m - c L_c) / (m - c)`` of the
  operators at ``m`` and ``c`` (``ThermalParameters.integral_extrapolation``), built together at
  the same shapes;
* :class:`CorrectedLoss`: the accurate operator (plain or extrapolated) rebuilt only when the
  shape has moved by a loose tolerance, and followed in between through the change of a cheap
  one (``m = 1``) rebuilt at the usual tolerance,
  ``L(x) = L_acc(x0) + L_1(x) - L_1(x0)`` (``ThermalParameters.integral_correction_tol``). The
  correction ``L_acc - L_1`` is the discretisation error of ``L_1``: a near-field quantity that
  changes slowly with the shape, so it is refreshed rarely (docs/heat_fe.md measures how
  rarely, and what that costs in accuracy).

All operators share the interface the steady model uses: ``nodes``, ``builds``,
``loss_matrix(x)``, ``touching(x)``.
"""

from __future__ import annotations

import logging

import numpy as np

from .integral import IntegralLoss

__all__ = ["ExtrapolatedLoss", "CorrectedLoss", "coarse_refinement", "integral_operator"]

logger = logging.getLogger(__name__)


def coarse_refinement(m: int) -> int:
    """Coarse refinement ``c`` of the Richardson pair of ``m`` (m >= 3): ``m // 2``, at least 2
    (from ``c = 1``, one collocation point per triangle, the error is not yet of first order)."""
    return max(m // 2, 2)


class ExtrapolatedLoss:
    """Richardson extrapolation ``(m L_m - c L_c) / (m - c)`` of two :class:`IntegralLoss`.

    Both are built at the same shapes: the fine one's criterion (``shape_tol``) decides, and a
    rebuild of the fine operator rebuilds the coarse one at the same positions.
    """

    def __init__(self, fine: IntegralLoss, coarse: IntegralLoss, m: int, c: int):
        self.fine, self.coarse, self.m, self.c = fine, coarse, int(m), int(c)
        self.nodes = fine.nodes
        self._L, self._built = None, -1

    @property
    def builds(self) -> int:
        """Number of builds so far (of the fine operator; each also builds the coarse one)."""
        return self.fine.builds

    @property
    def last_positions(self) -> np.ndarray:
        """Positions [m] of the last build."""
        return self.fine.last_positions

    def touching(self, x) -> np.ndarray:
        return self.fine.touching(x)

    def loss_matrix(self, x) -> np.ndarray:
        """``(m L_m - c L_c) / (m - c)`` [W/K] on :attr:`nodes` at positions ``x`` (n, 3) [m]."""
        Lf = self.fine.loss_matrix(x)
        if self.fine.builds != self._built:
            Lc = self.coarse.rebuild(self.fine.last_positions)
            self._L = (self.m * Lf - self.c * Lc) / (self.m - self.c)
            self._built = self.fine.builds
        return self._L


class CorrectedLoss:
    """An accurate operator refreshed at a loose tolerance, following the shape in between
    through a cheap one: ``L(x) = L_acc(x0) + L_base(x) - L_base(x0)``.

    Parameters
    ----------
    accurate : IntegralLoss or ExtrapolatedLoss
        The accurate operator; its own ``shape_tol`` (the loose one) decides when it is rebuilt
        (at ``x0``).
    base : IntegralLoss
        The cheap operator, rebuilt at its (tight) ``shape_tol``; rebuilt at ``x0`` whenever the
        accurate one is, so that ``L(x0) = L_acc(x0)``.
    """

    def __init__(self, accurate, base: IntegralLoss):
        self.accurate, self.base = accurate, base
        self.nodes = base.nodes
        self._offset, self._built = None, -1

    @property
    def builds(self) -> int:
        """Number of builds of the accurate operator so far (a diagnostic;
        :attr:`base_builds` counts the cheap one's)."""
        return self.accurate.builds

    @property
    def base_builds(self) -> int:
        return self.base.builds

    def touching(self, x) -> np.ndarray:
        return self.base.touching(x)

    def loss_matrix(self, x) -> np.ndarray:
        """``L_acc(x0) + L_base(x) - L_base(x0)`` [W/K] on :attr:`nodes` at positions ``x``."""
        La = self.accurate.loss_matrix(x)
        if self.accurate.builds != self._built:
            x0 = self.accurate.last_positions
            self._offset = La - self.base.rebuild(x0)
            self._built = self.accurate.builds
            logger.debug("integral loss: accurate operator rebuilt (%d so far)", self._built)
        return self._offset + self.base.loss_matrix(x)


def integral_operator(triangles, n_nodes, params):
    """The integral loss operator of :class:`~simulator.thermal.parameters.ThermalParameters`
    ``params`` on the sheet ``triangles``: ``(operator, plain)`` where ``plain`` is the
    :class:`IntegralLoss` at ``integral_refinement`` built at ``integral_shape_tol`` if the
    operator is that one alone (None otherwise)."""
    m, k, plane = params.integral_refinement, params.env_conductivity, params.plane
    correct = params.integral_correction_tol > 0 and (m > 1 or params.extrapolated)
    tol = params.integral_correction_tol if correct else params.integral_shape_tol

    memo = [None, None]                      # the levels share the sheet's distances

    def level(r, shape_tol=tol):
        out = IntegralLoss(triangles, n_nodes, k, r, plane, shape_tol)
        out.distance_memo = memo
        return out

    fine = level(m)
    if correct:          # the correction is the error of the m = 1 operator: its length scale
        fine.floor_factor, fine.height_floor = float(m), 1.0
    accurate = fine
    if params.extrapolated:
        c = coarse_refinement(m)
        accurate = ExtrapolatedLoss(fine, level(c), m, c)
    if not correct:
        return accurate, (fine if accurate is fine else None)
    return CorrectedLoss(accurate, level(1, params.integral_shape_tol)), None
