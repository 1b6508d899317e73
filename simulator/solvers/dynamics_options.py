"""Settings of the time integrator (:class:`DynamicsOptions`): the generalized-alpha method and its
coefficients, Rayleigh and air damping, Newton tolerances and step cutting."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import ParameterError

__all__ = ["DynamicsOptions"]

#: Names of the time-stepping methods (:attr:`DynamicsOptions.method`).
METHODS = ("newmark", "hht", "generalized_alpha")


@dataclass(frozen=True)
class DynamicsOptions:
    """Settings of the time integrator.

    Parameters
    ----------
    method : {"newmark", "hht", "generalized_alpha"}
        "newmark": constant average acceleration (beta = 1/4, gamma = 1/2), no numerical damping.
        "hht": Hilber-Hughes-Taylor alpha, ``rho_inf`` in [0.5, 1]. "generalized_alpha":
        Chung-Hulbert, ``rho_inf`` in [0, 1]. Both damp high frequencies (contact chatter,
        stiff bar modes) and stay second-order accurate.
    rho_inf : float
        Spectral radius at infinite frequency of the dissipative methods (1 = none, smaller =
        more); ignored by "newmark".
    rayleigh_alpha : float
        Mass-proportional damping alpha [1/s] (damping ratio alpha / (2 omega)). Default 0.
    rayleigh_beta : float
        Stiffness-proportional damping beta [s] (damping ratio beta omega / 2) on the material
        stiffness at the current configuration. Default 0. (The reference's defaults are
        alpha = beta = 1e-4, which over-damps modes above a few kHz, theory 8.3.) A small beta,
        or a dissipative method, calms the stiff crease-node modes that a sudden rest-angle
        change excites (the crease's centre line takes half of it, its edge lines a quarter
        each, so about 1/9 of the released energy goes into an S-shaped crease mode).
    air_damping : float
        Linear air damping c_air [N s/m^3]: a force ``-c_air A_i v_i`` on every node with the
        sheet area ``A_i`` lumped to it like the mass (:func:`~simulator.model.mass.lumped_areas`).
        Default 0.
    rtol : float
        Newton stops when the effective residual [N] is at most ``rtol`` times the largest of
        the inertia, damping, internal and external force norms of the step.
    atol : float
        Absolute residual tolerance [N] (0: relative only).
    max_iter : int
        Newton iterations per time step.
    max_cuts : int
        How many times a time step may be halved (recursively) before the integration fails.
    """

    method: str = "newmark"
    rho_inf: float = 0.8
    rayleigh_alpha: float = 0.0
    rayleigh_beta: float = 0.0
    air_damping: float = 0.0
    rtol: float = 1e-10
    atol: float = 0.0
    max_iter: int = 25
    max_cuts: int = 8

    def __post_init__(self):
        if self.method not in METHODS:
            raise ParameterError(f"DynamicsOptions.method = {self.method!r}; use one of "
                                 f"{', '.join(METHODS)}.")
        lo = 0.5 if self.method == "hht" else 0.0
        if not (_real(self.rho_inf) and lo <= self.rho_inf <= 1):
            raise ParameterError(f"DynamicsOptions.rho_inf = {self.rho_inf!r} must lie in "
                                 f"[{lo:g}, 1] for method {self.method!r}.")
        for name in ("rayleigh_alpha", "rayleigh_beta", "air_damping", "rtol", "atol"):
            v = getattr(self, name)
            if not (_real(v) and v >= 0):
                raise ParameterError(f"DynamicsOptions.{name} = {v!r} must be finite and >= 0.")
        if self.rtol == 0 and self.atol == 0:
            raise ParameterError("DynamicsOptions: rtol and atol cannot both be 0.")
        for name, least in (("max_iter", 1), ("max_cuts", 0)):
            v = getattr(self, name)
            if not (isinstance(v, int) and not isinstance(v, bool) and v >= least):
                raise ParameterError(f"DynamicsOptions.{name} = {v!r} must be an integer >= "
                                     f"{least}.")

    @property
    def coefficients(self) -> tuple[float, float, float, float]:
        """(alpha_m, alpha_f, beta, gamma) of the generalized-alpha form."""
        if self.method == "newmark":
            return 0.0, 0.0, 0.25, 0.5
        r = self.rho_inf
        if self.method == "hht":
            am, af = 0.0, (1 - r) / (1 + r)
        else:
            am, af = (2 * r - 1) / (r + 1), r / (r + 1)
        gamma = 0.5 - am + af
        return am, af, 0.25 * (1 - am + af) ** 2, gamma

    def to_dict(self) -> dict:
        return asdict(self)


def _real(v) -> bool:
    """True if ``v`` is a finite real number (not a bool)."""
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) \
        and math.isfinite(v)

