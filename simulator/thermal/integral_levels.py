"""Combinations of the integral heat-loss operator at several refinements (theory 4.7).

:class:`~simulator.thermal.integral.IntegralOperator` is the collocated single-layer operator at one
refinement ``m``; its error is of first order in ``1 / m`` (the flux density's edge
singularity). Two combinations make it accurate at a fraction of the cost of a fine ``m``:

* :class:`ExtrapolatedLoss`: Richardson extrapolation ``(m L_m - c L_c) / (m - c)`` of the
  operators at ``m`` and ``c`` (``IntegralLoss.extrapolation``), built together at
  the same shapes;
* :class:`CorrectedLoss`: the accurate operator (plain or extrapolated) rebuilt only when the
  cheap one (``m = 1``, rebuilt at the usual tolerance) has changed by a fraction of itself
  (``IntegralLoss.correction_tol``), and followed in between through the change
  of the cheap one, ``L(x) = L_acc(x0) + L_1(x) - L_1(x0)``. The correction ``L_acc - L_1`` is
  the discretisation error of ``L_1``: a near-field quantity that changes slowly with the
  shape, so it is refreshed rarely (theory 4.7 and docs/heat_fe.md measure how rarely, and
  what that costs in accuracy).

All operators share the interface the steady model uses: ``nodes``, ``builds``,
``loss_matrix(x)``, ``touching(x)``.
"""

from __future__ import annotations

import logging

import numpy as np

from .integral import IntegralOperator

__all__ = ["ExtrapolatedLoss", "CorrectedLoss", "coarse_refinement", "integral_operator",
           "uses_fast"]

logger = logging.getLogger(__name__)


def coarse_refinement(m: int) -> int:
    """Coarse refinement ``c`` of the Richardson pair of ``m`` (m >= 3): ``m // 2``, at least 2
    (from ``c = 1``, one collocation point per triangle, the error is not yet of first order)."""
    return max(m // 2, 2)


class ExtrapolatedLoss:
    """Richardson extrapolation ``(m L_m - c L_c) / (m - c)`` of two :class:`IntegralOperator`.

    Both are built at the same shapes: the fine one's criterion (``shape_tol``) decides, and a
    rebuild of the fine operator rebuilds the coarse one at the same positions.
    """

    def __init__(self, fine: IntegralOperator, coarse: IntegralOperator, m: int, c: int):
        if not int(m) > int(c) >= 1:
            raise ValueError(f"ExtrapolatedLoss needs m > c >= 1, got m = {m}, c = {c}")
        self.fine, self.coarse, self.m, self.c = fine, coarse, int(m), int(c)
        self.nodes = fine.nodes
        self._L, self._built = None, -1

    @property
    def builds(self) -> int:
        """Number of builds so far (of the fine operator; each also builds the coarse one)."""
        return self.fine.builds

    def touching(self, x) -> np.ndarray:
        return self.fine.touching(x)

    def _combine(self, Lf, Lc) -> np.ndarray:
        L = (self.m * Lf - self.c * Lc) / (self.m - self.c)
        L.setflags(write=False)
        self._L, self._built = L, self.fine.builds
        return L

    def loss_matrix(self, x) -> np.ndarray:
        """``(m L_m - c L_c) / (m - c)`` [W/K] on :attr:`nodes` at positions ``x`` (n, 3) [m]."""
        Lf = self.fine.loss_matrix(x)
        if self.fine.builds != self._built:
            return self._combine(Lf, self.coarse.rebuild(self.fine.last_positions))
        return self._L

    def rebuild(self, x) -> np.ndarray:
        """Build both operators at positions ``x`` (n, 3) [m] whatever the last build; returns
        the extrapolated loss conductance."""
        return self._combine(self.fine.rebuild(x), self.coarse.rebuild(x))


class CorrectedLoss:
    """An accurate operator rebuilt only where the shape has changed enough, following the
    shape in between through a cheap one: ``L(x) = L_acc(x0) + L_base(x) - L_base(x0)``.

    The accurate operator is rebuilt (at ``x0 = x``) when the cheap one, itself rebuilt at its
    ``shape_tol``, has changed since the last accurate build by more than ``tol`` of itself:
    ``||L_base(x) - L_base(x0)|| > tol ||L_base(x0)||`` (largest absolute row sum). The
    correction ``L_acc - L_base`` is the cheap operator's discretisation error, a function of
    the near-field geometry that ``L_base`` sees (parts of the sheet approaching each other or
    the substrate plane change it most), so its change is measured through ``L_base``; a
    rigid motion changes neither.

    Parameters
    ----------
    accurate : IntegralOperator or ExtrapolatedLoss
        The accurate operator (has ``rebuild(x)``).
    base : IntegralOperator
        The cheap operator (m = 1), rebuilt at its ``shape_tol``; rebuilt at ``x0`` whenever
        the accurate one is, so that ``L(x0) = L_acc(x0)``.
    tol : float
        Relative change of ``L_base`` that triggers an accurate rebuild, > 0.
    """

    def __init__(self, accurate, base: IntegralOperator, tol: float):
        self.accurate, self.base, self.tol = accurate, base, float(tol)
        self.nodes = base.nodes
        self._accurate0 = self._base0 = None
        self._near = None       # (node ids, their heights) under the cheap operator's scale

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

    def change(self, L_base) -> float:
        """Relative change of the cheap operator ``L_base`` since the last accurate build
        (largest absolute row sum of the difference over that of ``L_base(x0)``)."""
        norm = np.abs(self._base0).sum(axis=1).max()
        return float(np.abs(L_base - self._base0).sum(axis=1).max() / norm) if norm > 0 \
            else float(np.abs(L_base).max() > 0)

    def loss_matrix(self, x) -> np.ndarray:
        """``L_acc(x0) + L_base(x) - L_base(x0)`` [W/K] on :attr:`nodes` at positions ``x``."""
        x = np.asarray(x, float)
        Lb = None
        if self._accurate0 is not None:
            Lb = self.base.loss_matrix(x)
            # not refreshed where the m = 1 operator is not positive definite: the sheet passes
            # through itself and the model is not reliable there (IntegralOperator warns once)
            if (self.change(Lb) <= self.tol and not self._moved_near_plane(x)) or \
                    not self.base.last_definite:
                return self._accurate0 + (Lb - self._base0)
        self._accurate0 = self.accurate.rebuild(x)
        self._near = self._near_plane(x)
        last = self.base.last_positions
        self._base0 = Lb if Lb is not None and np.array_equal(last, x) else self.base.rebuild(x)
        logger.debug("integral loss: accurate operator rebuilt (%d so far)", self.builds)
        return self._accurate0


    def _near_plane(self, x):
        """``(nodes, heights, floor)`` of the nodes closer to the substrate plane than the
        cheap operator's mean sub-triangle diameter d at positions ``x`` (None without a
        plane), with the height floor 1e-3 d."""
        h, _ = self.base._heights(x)
        if h is None:
            return None
        sub = self.base.sub_triangles(x)
        d = float(np.linalg.norm(sub - np.roll(sub, 1, axis=1), axis=2).max(axis=1).mean())
        near = np.flatnonzero(h < d)
        return near, h[near], 1e-3 * d

    def _moved_near_plane(self, x) -> bool:
        """Whether a node that was closer to the substrate plane than the cheap operator's
        sub-triangles at the last accurate build has changed its height by more than
        :data:`NEAR_PLANE_RTOL` x ``tol`` of it (at least of 1e-3 sub-triangle diameters).

        The cheap operator does not resolve a gap thinner than its sub-triangles, so the
        correction's change is not seen through it there: on the double fold over its boundary
        panels' plane the corrected temperatures drifted 1.7 % of the largest rise (0.31 %
        with this test, 39 accurate builds over 93 shapes instead of 13)."""
        if self._near is None or not len(self._near[0]):
            return False
        nodes, h0, floor = self._near
        h, _ = self.base._heights(x)
        return bool(np.any(np.abs(h[nodes] - h0) > NEAR_PLANE_RTOL * self.tol
                           * np.maximum(h0, floor)))


#: A height over the substrate plane under the cheap operator's sub-triangles may change by
#: this fraction of ``integral_correction_tol`` before the accurate operator is rebuilt
#: (:meth:`CorrectedLoss._moved_near_plane`; 2 % of the height at the default 0.1).
NEAR_PLANE_RTOL = 0.2


def uses_fast(n_triangles: int, loss) -> bool:
    """Whether the :class:`~simulator.thermal.loss.IntegralLoss` ``loss`` on ``n_triangles``
    sheet triangles takes the fast path (:mod:`simulator.thermal.integral_fast`): its
    ``operator`` "fast", or "auto" above the dense limit (more than ``MAX_SUB_TRIANGLES``
    sub-triangles at its ``refinement``)."""
    from .integral import MAX_SUB_TRIANGLES

    if loss.operator != "auto":
        return loss.operator == "fast"
    return n_triangles * loss.refinement ** 2 > MAX_SUB_TRIANGLES


def integral_operator(triangles, n_nodes, params, plane=None):
    """The integral loss operator of :class:`~simulator.thermal.parameters.ThermalParameters`
    ``params`` on the sheet ``triangles`` over the substrate ``plane`` ((point, unit normal) or
    None), whose ``loss`` is an :class:`~simulator.thermal.loss.IntegralLoss`: an
    :class:`IntegralOperator` at its ``refinement`` built at its ``shape_tol``, an
    :class:`ExtrapolatedLoss` or a :class:`CorrectedLoss`; on the fast path
    (:func:`uses_fast`) a :class:`~simulator.thermal.integral_fast.FastIntegralOperator` of
    the same levels (plain or extrapolated, rebuilt at every shape)."""
    loss = params.loss
    m, k = loss.refinement, params.medium.thermal_conductivity
    if uses_fast(len(np.asarray(triangles).reshape(-1, 3)), loss):
        from .integral_fast import FastIntegralOperator

        levels = [(1.0, m)]
        if loss.extrapolated:
            c = coarse_refinement(m)
            levels = [(m / (m - c), m), (-c / (m - c), c)]
        return FastIntegralOperator(triangles, n_nodes, k, levels, plane)
    correct = loss.correction_tol > 0 and (m > 1 or loss.extrapolated)
    memo = [None, None]                      # the levels share the sheet's distances

    def level(r):
        out = IntegralOperator(triangles, n_nodes, k, r, plane, loss.shape_tol)
        out.distance_memo = memo
        return out

    fine = level(m)
    accurate = fine
    if loss.extrapolated:
        c = coarse_refinement(m)
        accurate = ExtrapolatedLoss(fine, level(c), m, c)
    if not correct:
        return accurate
    return CorrectedLoss(accurate, level(1), loss.correction_tol)
