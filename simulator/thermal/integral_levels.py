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
  of the cheap one, ``L(x) = L_acc(x0) + L_1(x) - L_1(x0)``, plus the correction's change
  along the secant of the last two accurate builds. The correction ``L_acc - L_1`` is
  the discretisation error of ``L_1``: a near-field quantity that changes slowly with the
  shape, so it is refreshed rarely (theory 4.7 and docs/heat_fe.md measure how rarely, and
  what that costs in accuracy).

All operators share the interface the steady model uses: ``nodes``, ``builds``,
``loss_matrix(x)``, ``touching(x)``.
"""

from __future__ import annotations

import logging

import numpy as np

from ..errors import ParameterError

from .integral import IntegralOperator, lump_couplings

__all__ = ["ExtrapolatedLoss", "CorrectedLoss", "coarse_refinement", "integral_operator",
           "fast_levels", "describe_levels"]

logger = logging.getLogger(__name__)


def coarse_refinement(m: int) -> int:
    """Coarse refinement ``c`` of the Richardson pair of ``m`` (m >= 3): ``m // 2``, at least 2
    (from ``c = 1``, one collocation point per triangle, the error is not yet of first order)."""
    return max(m // 2, 2)


class ExtrapolatedLoss:
    """Richardson extrapolation ``(m L_m - c L_c) / (m - c)`` of two :class:`IntegralOperator`.

    Both are built at the same shapes: the fine one's criterion (``shape_tol``) decides, and a
    rebuild of the fine operator rebuilds the coarse one at the same positions. With
    ``lumped`` the combination of the two consistent operators is lumped
    (:func:`~simulator.thermal.integral.lump_couplings`): lumping either before combining
    would not do, ``- c L_c`` turns its negative couplings positive.
    """

    def __init__(self, fine: IntegralOperator, coarse: IntegralOperator, m: int, c: int,
                 lumped: bool = False):
        if not int(m) > int(c) >= 1:
            raise ValueError(f"ExtrapolatedLoss needs m > c >= 1, got m = {m}, c = {c}")
        self.fine, self.coarse, self.m, self.c = fine, coarse, int(m), int(c)
        self.lumped = bool(lumped)
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
        if self.lumped:
            L = lump_couplings(L)
        L.setflags(write=False)
        self._L, self._built = L, self.fine.builds
        return L

    def loss_matrix(self, x) -> np.ndarray:
        """``(m L_m - c L_c) / (m - c)`` [W/K] on :attr:`nodes` at positions ``x`` (n, 3) [m]
        (lumped if :attr:`lumped`)."""
        Lf = self.fine.loss_matrix(x)
        if self.fine.builds != self._built:
            return self._combine(Lf, self.coarse.rebuild(self.fine.last_positions))
        return self._L

    def rebuild(self, x) -> np.ndarray:
        """Build both operators at positions ``x`` (n, 3) [m] whatever the last build (the
        coarse one kept if its last build was at ``x``: where it is also the cheap operator of
        a :class:`CorrectedLoss`, which has just built it there); returns the extrapolated
        loss conductance."""
        x = np.asarray(x, float)
        self.coarse.exact_at(x)
        return self._combine(self.fine.rebuild(x), self.coarse.loss_matrix(x))

    @property
    def last_positions(self):
        """Positions (n, 3) [m] of the last build (None before the first)."""
        return self.fine.last_positions

    def exact_at(self, x) -> bool:
        """Rebuild both at positions ``x`` unless the last build was there; whether it
        rebuilt (:meth:`IntegralOperator.exact_at`)."""
        x = np.asarray(x, float)
        last = self.fine.last_positions
        if last is not None and np.array_equal(last, x) and self.fine.builds == self._built:
            return False
        self.rebuild(x)
        return True


class CorrectedLoss:
    """An accurate operator rebuilt only where the shape has changed enough, following the
    shape in between through a cheap one: ``L(x) = L_acc(x0) + L_base(x) - L_base(x0) + s dC``.

    The accurate operator is rebuilt (at ``x0 = x``) when the cheap one, itself rebuilt at its
    ``shape_tol``, has changed since the last accurate build by more than ``tol`` of itself:
    ``||L_base(x) - L_base(x0)|| > tol ||L_base(x0)||`` (largest absolute row sum). The
    correction ``L_acc - L_base`` is the cheap operator's discretisation error, a function of
    the near-field geometry that ``L_base`` sees (parts of the sheet approaching each other or
    the substrate plane change it most), so its change is measured through ``L_base``; a
    rigid motion changes neither.

    The cheap operator follows the accurate one's change only in part (on the gripper over its
    substrate, 0.2-0.3 of the change is left), so from the second accurate build on the
    correction also moves along the secant of the last two builds ``x_prev -> x0``: by ``s
    dC``, ``dC`` the correction's change between them and ``s`` where ``L_base(x) -
    L_base(x0)`` lies along ``L_base(x0) - L_base(x_prev)`` (:meth:`secant_step`, clipped to
    [-1, 1]): exact at both builds, first order along a path through them. Near the
    substrate plane, where the cheap operator is blind, the heights are watched against
    where the same secant step puts them (:meth:`_moved_near_plane`).

    Parameters
    ----------
    accurate : IntegralOperator or ExtrapolatedLoss
        The accurate operator (has ``rebuild(x)``).
    base : IntegralOperator
        The cheap operator (m = 1), rebuilt at its ``shape_tol``; rebuilt at ``x0`` whenever
        the accurate one is, so that ``L(x0) = L_acc(x0)``.
    tol : float
        Relative change of ``L_base`` that triggers an accurate rebuild, > 0.
    lumped : bool
        Lump the corrected conductance (:func:`~simulator.thermal.integral.lump_couplings`);
        ``accurate`` and ``base`` are the consistent ones. The sum is lumped, not its
        terms: the difference ``L_base(x) - L_base(x0)`` has couplings of either sign, and
        lumping the sum keeps ``L(x0)`` the lumped ``L_acc(x0)``.
    """

    def __init__(self, accurate, base: IntegralOperator, tol: float, lumped: bool = False):
        self.accurate, self.base, self.tol = accurate, base, float(tol)
        self.lumped = bool(lumped)
        self.nodes = base.nodes
        self._accurate0 = self._base0 = self._base0_norm = None
        self._last = (None, None, None)     # (L_base, L_acc(x0), their sum) of the last call
        self._heights0 = None   # the nodes' heights over the substrate plane at x0 (or None)
        self._near = None       # (node ids, their heights) under the cheap operator's scale
        #: (dL_base, dC, ||dL_base||^2, dh) between the last two accurate builds (dh: of the
        #: nodes' heights over the substrate plane, None without one; None before two builds)
        self._secant = None

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
        norm = self._base0_norm
        return float(np.abs(L_base - self._base0).sum(axis=1).max() / norm) if norm > 0 \
            else float(np.abs(L_base).max() > 0)

    def loss_matrix(self, x) -> np.ndarray:
        """``L_acc(x0) + L_base(x) - L_base(x0) + s dC`` [W/K] on :attr:`nodes` at positions
        ``x`` (:meth:`secant_step`; lumped if :attr:`lumped`)."""
        x = np.asarray(x, float)
        Lb = None
        if self._accurate0 is not None:
            Lb = self.base.loss_matrix(x)
            # not refreshed where the m = 1 operator is not positive definite: the sheet passes
            # through itself and the model is not reliable there (IntegralOperator warns once)
            if (self.change(Lb) <= self.tol and not self._moved_near_plane(x, Lb)) or \
                    not self.base.last_definite:
                return self._corrected(Lb)
        return self._rebuild(x, Lb)

    def exact_at(self, x) -> bool:
        """Rebuild the accurate operator at positions ``x`` unless its last build was there,
        so that the conductance there is the accurate one, whatever the path of shapes before
        (the end of a settled coupling, theory 6.6); whether it rebuilt."""
        x = np.asarray(x, float)
        last = self.accurate.last_positions
        if self._accurate0 is not None and last is not None and np.array_equal(last, x):
            return False
        self._rebuild(x, None)
        return True

    def _rebuild(self, x, Lb) -> np.ndarray:
        """The accurate operator rebuilt at ``x`` (``Lb``: the cheap one there, if known),
        the secant updated; returns the conductance there."""
        accurate = self.accurate.rebuild(x)
        # the cheap operator may be the accurate one's Richardson partner, just rebuilt here
        base = (self.base.loss_matrix(x) if np.array_equal(self.base.last_positions, x)
                else self.base.rebuild(x))
        heights = self.base._heights(x)[0]
        if self._accurate0 is not None:
            d_base = base - self._base0
            norm = float(np.sum(d_base * d_base))
            self._secant = (d_base, (accurate - base) - (self._accurate0 - self._base0),
                            norm, None if heights is None else heights - self._heights0) \
                if norm > 0 else None
        self._accurate0, self._base0, self._heights0 = accurate, base, heights
        self._base0_norm = np.abs(base).sum(axis=1).max()       # of change()
        self._near = self._near_plane(x)
        logger.debug("integral loss: accurate operator rebuilt (%d so far)", self.builds)
        return self._corrected(self._base0)

    def _corrected(self, Lb) -> np.ndarray:
        """``L_acc(x0) + Lb - L_base(x0) + s dC``, lumped if :attr:`lumped` (kept while ``Lb``
        and ``L_acc(x0)`` are the same arrays; ``s = 0`` at ``x0``)."""
        if Lb is self._base0 and not self.lumped:
            return self._accurate0
        last_base, last_accurate, L = self._last
        if Lb is last_base and self._accurate0 is last_accurate:
            return L
        step = Lb - self._base0
        L = self._accurate0 + step
        if self._secant is not None:
            L = L + self.secant_step(step) * self._secant[1]
        if self.lumped:
            L = lump_couplings(L)
        L.setflags(write=False)
        self._last = (Lb, self._accurate0, L)
        return L

    def secant_step(self, step) -> float:
        """Where the cheap operator's change ``step = L_base(x) - L_base(x0)`` lies along the
        last two accurate builds' ``x_prev -> x0``: ``s = <step, dL_base> / ||dL_base||^2``
        (Frobenius), clipped to [-1, 1] (0 at ``x0``, -1 at ``x_prev``, up to one such step
        beyond ``x0``); the correction moves by ``s dC``, ``dC`` the change of ``L_acc -
        L_base`` between the two builds."""
        d_base, _, norm, _ = self._secant
        return float(np.clip(np.sum(step * d_base) / norm, -1.0, 1.0))

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

    def _moved_near_plane(self, x, Lb=None) -> bool:
        """Whether a node that was closer to the substrate plane than the cheap operator's
        sub-triangles at the last accurate build is off the height the correction assumes by
        more than :data:`NEAR_PLANE_RTOL` x ``tol`` of it (heights at least 1e-3 sub-triangle
        diameters): its height ``h0`` there; or, with the cheap operator ``Lb`` at ``x`` and
        a secant, the height at which its inverse has moved along the secant as the
        correction has, ``1/h0 + s (1/h0 - 1/h_prev)`` (:meth:`secant_step`; ``h_prev`` its
        height at the build before): through a gap ``h`` thin against the sheet the loss is
        about ``k A / h``, so it is ``1/h`` that the cheap operator, and with it ``s``, follows.
        The difference is measured as ``h0 |1/h - (1/h0 + s (1/h0 - 1/h_prev))|``, for a small
        change the relative change of the height, as without a secant.

        The cheap operator does not resolve a gap thinner than its sub-triangles, so the
        correction's change is not seen through it there: on the double fold over its boundary
        panels' plane the corrected temperatures drifted 1.7 % of the largest rise (0.31 %
        with this test at 0.2 correction_tol, 39 accurate builds over 93 shapes instead of 13;
        with the secant 0.28 % at correction_tol, 22 builds; with the inverse heights moved
        along the secant too, 0.33 % with 13 builds, and the default gripper's bisect
        evaluation 8 accurate builds instead of 18, the same powers; the heights themselves
        moved along it: 0.28 %, 15 and 11)."""
        if self._near is None or not len(self._near[0]):
            return False
        nodes, h0, floor = self._near
        h = self.base._heights(x)[0][nodes]
        scale = np.maximum(h0, floor)
        if Lb is None or self._secant is None or self._secant[3] is None:
            off = np.abs(h - h0) / scale
        else:                            # h0 |1/h - 1/h0 - s (1/h0 - 1/h_prev)|
            s = self.secant_step(Lb - self._base0)
            previous = np.maximum(h0 - self._secant[3][nodes], floor)
            off = np.abs(scale / np.maximum(h, floor) - 1.0 - s + s * scale / previous)
        return bool(np.any(off > NEAR_PLANE_RTOL * self.tol))


#: A height over the substrate plane under the cheap operator's sub-triangles may change by
#: this fraction of ``integral_correction_tol`` before the accurate operator is rebuilt
#: (:meth:`CorrectedLoss._moved_near_plane`; 10 % of the height at the default 0.1). Measured
#: with the secant correction: the double fold over its boundary panels' plane 0.28 % of the
#: largest rise from a rebuild at every shape (0.2 without the secant: 0.31 %, 1.0: 1.0 %), the
#: default gripper's powers those of a rebuild at every shape with 20 accurate builds (0.2:
#: 41; 3.0: 8 builds, the grip power 1.544 against 1.531 mW per crease). With the heights
#: moved along the secant (:meth:`CorrectedLoss._moved_near_plane`, their inverses): the
#: double fold 0.33 % with 13 accurate builds, the gripper's powers those of a rebuild at every
#: shape with 8.
NEAR_PLANE_RTOL = 1.0


def fast_levels(loss, n_triangles: int):
    """``[(weight, refinement)]`` of the fast path for the
    :class:`~simulator.thermal.IntegralLoss` ``loss`` (``n_triangles`` is not used: the
    levels are the loss's own, plain or extrapolated from ``coarse_refinement``, at any size;
    Richardson from m = 2 and 1 is 2.4-3.9 % off the default on bent Miura sheets and 7.8-8.5 %
    over a plane, theory 4.7)."""
    m = loss.refinement
    if loss.extrapolated:
        c = coarse_refinement(m)
        return [(m / (m - c), m), (-c / (m - c), c)]
    return [(1.0, m)]


def describe_levels(levels) -> str:
    """``"m = 2 extrapolated from 1 (2 L_2 - L_1)"`` or ``"m = 2"`` of fast-path levels."""
    if len(levels) == 1:
        return f"m = {levels[0][1]}"
    (w1, m1), (w2, m2) = levels
    return f"m = {m1} extrapolated from {m2} ({w1:g} L_{m1} - {-w2:g} L_{m2})"


def sheet_levels(loss, r: int = 1) -> tuple[int, int | None]:
    """The :class:`~simulator.thermal.IntegralLoss` ``loss``'s levels on a sheet refined
    ``r`` (theory 4.11), per edge of the triangles the operator is built on: the refinement
    and its Richardson partner (None: not extrapolated). On the mesh triangles (``r = 1``) the
    loss's own, ``m`` and :func:`coarse_refinement`; on the fine triangles of a refined sheet
    ``ceil(m / r)``, at least 2 where extrapolated, with the partner ``max(m_f // 2, 1)``, so
    that per mesh triangle edge the sub-triangles number at least ``m`` and the partner's at
    least 2, nested in the fine triangles (a sub-triangle straddling two fine ones would
    sample the fine field's kink at one point: measured 15 % hot on the gripper at m = 3 per
    mesh edge on r = 2). The gripper at r = 2, m = 3: 2 and 1, i.e. 4 and 2 per mesh edge."""
    m = loss.refinement
    if r == 1:
        return m, (coarse_refinement(m) if loss.extrapolated else None)
    m_f = max(-(-m // r), 2 if loss.extrapolated else 1)
    return m_f, (max(m_f // 2, 1) if loss.extrapolated else None)


def integral_operator(triangles, n_nodes, params, plane=None, sheet_refinement: int = 1):
    """The integral loss operator of :class:`~simulator.thermal.ThermalParameters`
    ``params`` on the sheet ``triangles`` over the substrate ``plane`` ((point, unit normal) or
    None), whose ``loss`` is an :class:`~simulator.thermal.IntegralLoss`: an
    :class:`IntegralOperator` at its ``refinement`` built at its ``shape_tol``, an
    :class:`ExtrapolatedLoss` or a :class:`CorrectedLoss`; on the fast path
    (``IntegralLoss.takes_fast_path``) a
    :class:`~simulator.thermal.integral_fast.FastIntegralOperator` of the same levels (plain or extrapolated, kept within ``shape_tol``). On the fine triangles
    of a sheet refined ``sheet_refinement`` the levels of :func:`sheet_levels` (dense only),
    the cheap level of the correction the partner where that is 1 (one operator)."""
    loss = params.loss
    m, c = sheet_levels(loss, sheet_refinement)
    k = params.medium.thermal_conductivity
    n_triangles = len(np.asarray(triangles).reshape(-1, 3))
    if sheet_refinement > 1 and loss.operator == "fast":
        raise ParameterError(
            f"a refined sheet (sheet_refinement = {sheet_refinement}) needs the integral loss's "
            "dense operator, not IntegralLoss(operator='fast'); use sheet_refinement=1 (the "
            "default where the fast path is taken).")
    if sheet_refinement == 1 and loss.takes_fast_path(n_triangles):
        from .integral_fast import FastIntegralOperator

        if loss.lumped:
            raise ParameterError(
                f"IntegralLoss(lumped=True) needs the dense operator, but this sheet's "
                f"{n_triangles} triangles at refinement {m} take "
                "the fast path, which never forms the conductance it would lump; use "
                "lumped=False.")
        levels = fast_levels(loss, n_triangles)
        return FastIntegralOperator(triangles, n_nodes, k, levels, plane,
                                    shape_tol=loss.shape_tol)
    correct = loss.correction_tol > 0 and (m > 1 or c is not None)
    memo, heights = [None, None], [None, None, None]   # the levels share the sheet's distances

    def level(r, lumped=False):
        out = IntegralOperator(triangles, n_nodes, k, r, plane, loss.shape_tol, lumped)
        out.distance_memo, out.height_memo = memo, heights    # and heights
        return out

    # lumped (IntegralLoss.lumped) is the outermost operator only, whose conductance the
    # solve uses: the combinations are of the consistent operators
    fine = level(m, loss.lumped and not (c is not None or correct))
    accurate, coarse = fine, None
    if c is not None:
        coarse = level(c)
        accurate = ExtrapolatedLoss(fine, coarse, m, c, loss.lumped and not correct)
    if not correct:
        return accurate
    return CorrectedLoss(accurate, coarse if c == 1 else level(1), loss.correction_tol,
                         loss.lumped)
