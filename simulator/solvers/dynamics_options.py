"""Settings of the time integrator (:class:`DynamicsOptions`): the generalized-alpha method and its
coefficients, Rayleigh and air damping, Newton tolerances and step cutting."""

from __future__ import annotations

from dataclasses import asdict, dataclass

from .._validate import in_range, integer, non_negative, one_of
from ..errors import ParameterError
from ..linalg.ladder import check_backend

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
    linear_solver : {"auto", "dense", "pardiso", "superlu"}
        Backend of the effective-stiffness solves (as ``NewtonOptions.linear_solver``; see
        :mod:`simulator.linalg.ladder`).
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
    linear_solver: str = "auto"

    def __post_init__(self):
        check_backend(self.linear_solver, "DynamicsOptions.linear_solver")
        one_of("DynamicsOptions.method", self.method, METHODS)
        lo = 0.5 if self.method == "hht" else 0.0
        in_range("DynamicsOptions.rho_inf", self.rho_inf, lo, 1,
                 hint=f"the range for method {self.method!r}")
        for name, unit in _UNITS.items():
            non_negative(f"DynamicsOptions.{name}", getattr(self, name), unit)
        if self.rtol == 0 and self.atol == 0:
            raise ParameterError("DynamicsOptions: rtol and atol cannot both be 0.")
        integer("DynamicsOptions.max_iter", self.max_iter)
        integer("DynamicsOptions.max_cuts", self.max_cuts, 0)

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


#: Units of the non-negative settings (rtol is relative; atol is a force [N]).
_UNITS = {"rayleigh_alpha": "1/s", "rayleigh_beta": "s", "air_damping": "N s/m^3", "rtol": "",
          "atol": "N"}

