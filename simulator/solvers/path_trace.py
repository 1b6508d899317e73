"""Bookkeeping of a continuation run: accepted points, their stability, critical points.

:class:`PathTrace` collects the accepted points of :func:`~simulator.solvers.continuation.mgdcm` and
:func:`~simulator.solvers.displacement_control.displacement_control` with the inertia of their tangents
(:mod:`simulator.solvers.stability`), locates limit points and bifurcations between them
(:class:`CriticalPoint`) and builds the :class:`ContinuationResult`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._result import ResultFiles
from .stability import tangent_stability

__all__ = ["CriticalPoint", "ContinuationResult", "PathTrace", "BIFURCATION_ALIGNMENT",
           "CRITICAL_KINDS"]

#: Kinds of :class:`CriticalPoint`.
CRITICAL_KINDS = ("limit_point", "bifurcation", "stability_change")
#: A change of the negative-eigenvalue count is a bifurcation when |cos(mode, q)| is below this.
BIFURCATION_ALIGNMENT = 0.1


@dataclass(frozen=True)
class CriticalPoint:
    """A limit point or bifurcation located between two accepted increments.

    Attributes
    ----------
    kind : {"limit_point", "bifurcation", "stability_change"}
    load_factor : float
        Estimated load factor there (parabola through three points for a limit point).
    increment : int
        Index (0-based) of the first accepted increment past it.
    displacement : float or None
        Monitored displacement there [m] (interpolated), if the path has a monitor.
    maximum : bool
        True for a load-factor maximum, False for a minimum (and for bifurcations).
    """

    kind: str
    load_factor: float
    increment: int
    displacement: float | None = None
    maximum: bool = False

    def describe(self) -> str:
        """One line for a message, e.g. ``"limit point at load factor 0.42 (displacement
        31.2 um)"``."""
        return (f"{self.kind.replace('_', ' ')} at load factor {self.load_factor:.6g}"
                + ("" if self.displacement is None else
                   f" (displacement {self.displacement * 1e6:.4g} um)"))


@dataclass(frozen=True, eq=False)
class ContinuationResult(ResultFiles):
    """Outcome of :func:`mgdcm` or :func:`displacement_control`.

    Attributes
    ----------
    success : bool
    status : str
        "converged", "failed", "stopped" or (``mgdcm(locate_stability_loss="stop")``, with
        success) "stability_lost".
    message : str
    u : (n_nodes, 3) displacements at the last accepted point [m]
    load_factor : float at the last accepted point
    iterations, cuts : int
    history : list of (load_factor, u, iterations) per accepted point
    residual_norms : list of arrays per accepted point [N]
    stability : list of Stability per accepted point (empty if not computed)
    temperatures : list of (n_nodes,) arrays or None per accepted point
    critical_points : tuple of CriticalPoint
    evaluation : SystemValues at the last accepted point
    jumps : tuple of (before, after, kind)
        Branch switches (``mgdcm(switch_branches=True)``): history indices of the last stable
        point before a loss of stability and of the stable point the path jumped to at the
        load factor of the first unstable one, and the kind ("bifurcation").
    """

    success: bool
    status: str
    message: str
    u: np.ndarray
    load_factor: float
    iterations: int
    cuts: int
    history: list = field(default_factory=list)
    residual_norms: list = field(default_factory=list)
    stability: list = field(default_factory=list)
    temperatures: list = field(default_factory=list)
    critical_points: tuple = ()
    evaluation: object = None
    jumps: tuple = ()

    _csv_name = "path.csv"

    def to_frame(self):
        """One row per accepted point: ``point``, ``load_factor``, ``iterations``,
        ``max_displacement [m]`` (largest node displacement), and when computed ``stable``,
        ``negative_eigenvalues``, ``lowest_eigenvalue [N/m]``, ``max_temperature [degC]``."""
        import pandas as pd

        data = {"point": np.arange(1, len(self.history) + 1),
                "load_factor": [h[0] for h in self.history],
                "iterations": [h[2] for h in self.history],
                "max_displacement [m]": [float(np.linalg.norm(np.reshape(h[1], (-1, 3)),
                                                              axis=1).max(initial=0.0))
                                         for h in self.history]}
        if len(self.stability) == len(self.history) and self.stability:
            data.update({"stable": [s.stable for s in self.stability],
                         "negative_eigenvalues": [s.negative for s in self.stability],
                         "lowest_eigenvalue [N/m]": [s.lowest for s in self.stability]})
        if len(self.temperatures) == len(self.history) and any(
                t is not None for t in self.temperatures):
            data["max_temperature [degC]"] = [None if t is None else float(np.max(t))
                                              for t in self.temperatures]
        return pd.DataFrame(data)

    def _meta(self) -> dict:
        return {"load_factor": self.load_factor, "iterations": self.iterations,
                "cuts": self.cuts, "critical_points": list(self.critical_points)}


# ---------------------------------------------------------------------------- linear algebra

class PathTrace:
    """Accepted points of a continuation, with their stability and the critical points.

    The start point seeds the limit-point search (a restart exactly at a limit point turns
    there) but is not recorded.
    """

    def __init__(self, path, monitor, stability, u0, lam0, prior=None):
        self.path, self.monitor, self.check = path, monitor, stability
        self.history, self.residuals, self.stab, self.temps = [], [], [], []
        self.iterations, self.cuts, self.critical, self.align = 0, 0, [], []
        self.points, self.arc, self.jumps = [], [], []
        for u, lam in ([] if prior is None else [prior]) + [(u0, lam0)]:
            self._add(np.asarray(u, float), float(lam))
        self.offset = len(self.points)           # point k is history entry k - offset
        self.last = None

    def _add(self, u, lam):
        du = 0.0 if not self.points else np.linalg.norm(
            (u - self.points[-1][1]).ravel()[self.path.free])
        self.arc.append((self.arc[-1] if self.arc else 0.0) + float(du))
        self.points.append((lam, u))

    def accept(self, u, lam, pt, its, res):
        self._add(u, lam)
        self.history.append((lam, u, its))
        self.residuals.append(np.asarray(res, float))
        self.temps.append(pt.temperature)
        self.last = pt
        if self.check:
            self.stab.append(tangent_stability(pt.K))
            self.align.append(self.stab[-1].load_alignment(pt.q))

    def pop(self):
        """Forget the last accepted point (its Newton iterations stay counted)."""
        for seq in (self.history, self.residuals, self.temps, self.points, self.arc):
            seq.pop()
        if self.check:
            self.stab.pop()
            self.align.pop()

    def measure(self, u) -> float | None:
        return None if self.monitor is None else float(self.monitor @ u.ravel())

    def _locate(self) -> list:
        """Critical points between accepted points: a limit point where the load factor passes
        an extremum (located by a parabola through three points in arc length); where the count
        of negative eigenvalues changes without one, a bifurcation if the critical mode is
        orthogonal to the load derivative q (|cos| below :data:`BIFURCATION_ALIGNMENT`), else a
        "stability_change" (e.g. heating paths, whose load-factor extremum includes the
        thermal feedback that the mechanical tangent leaves out)."""
        pts, out, o = self.points, [], self.offset
        lam = np.array([p[0] for p in pts])
        turns = [k for k in range(1, len(pts) - 1)
                 if (lam[k] - lam[k - 1]) * (lam[k + 1] - lam[k]) < 0]
        for k in turns:
            s = np.array(self.arc[k - 1:k + 2]) - self.arc[k]
            c = np.polyfit(s, lam[k - 1:k + 2], 2)
            s_star = float(np.clip(-c[1] / (2 * c[0]), s[0], s[2])) if c[0] != 0 else 0.0
            m = [self.measure(pts[j][1]) for j in (k - 1, k, k + 1)]
            disp = None if m[0] is None else float(np.polyval(np.polyfit(s, m, 2), s_star))
            out.append(CriticalPoint("limit_point", float(np.polyval(c, s_star)),
                                     max(0, k + 1 - o if s_star > 0 else k - o), disp,
                                     bool(lam[k] > lam[k - 1])))
        neg = [st.negative for st in self.stab]
        switched = {b + 1: kind for b, _, kind in self.jumps}   # first unstable point
        landed = {a for _, a, _ in self.jumps}
        for j in range(len(neg)):                 # history j is point j + o
            if j in landed:
                continue                          # the jump back onto a stable branch
            if j in switched:
                out.append(CriticalPoint(switched[j], 0.5 * (lam[j + o - 1] + lam[j + o]), j,
                                         self.measure(pts[j + o - 1][1])))
            elif j > 0 and neg[j] != neg[j - 1] and not any(k - o in (j - 2, j - 1, j)
                                                            for k in turns):
                a = min(self.align[j - 1], self.align[j])
                kind = "bifurcation" if a < BIFURCATION_ALIGNMENT else "stability_change"
                out.append(CriticalPoint(kind, 0.5 * (lam[j + o - 1] + lam[j + o]), j,
                                         self.measure(pts[j + o][1])))
        return sorted(out, key=lambda c: c.increment)

    def result(self, success, status, message, u, lam):
        self.critical = self._locate()
        crit = "; ".join(c.describe() for c in self.critical)
        if crit:
            message = f"{message}; {crit}"
        return ContinuationResult(success, status, message, u, float(lam), self.iterations,
                                  self.cuts, self.history, self.residuals, self.stab,
                                  self.temps, tuple(self.critical),
                                  None if self.last is None else self.last.evaluation,
                                  tuple(self.jumps))


def lost_peak(res, lam0):
    """Index of the highest accepted point of a failed arc-length run that passed a
    load-factor maximum above ``lam0``, or None."""
    if res.status != "failed" or not any(p.kind == "limit_point" and p.maximum
                                         for p in res.critical_points):
        return None
    lam = np.array([h[0] for h in res.history])
    k = int(np.argmax(lam))
    return k if lam[k] > lam0 else None
