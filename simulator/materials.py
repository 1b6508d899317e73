"""Material data (SI units) used by patterns and models.

Values are those used by the reference examples of Zhu & Filipov (2021) unless
stated otherwise; each constant documents its source.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from .errors import ParameterError

__all__ = ["Material", "SU8", "SPR", "SUBSTRATE"]


@dataclass(frozen=True)
class Material:
    """Isotropic material.

    Parameters
    ----------
    name : str
        Label used in reports.
    youngs_modulus : float
        Young's modulus E [Pa], > 0.
    poisson_ratio : float
        Poisson's ratio nu [-], in (-1, 0.5).
    density : float
        Mass density rho [kg/m^3], >= 0 (used by gravity).
    thermal_conductivity : float
        Thermal conductivity k [W/(m K)], >= 0.
    glass_transition : float or None
        Glass-transition temperature T_g [deg C], finite; None if unknown. Design problems
        bound crease temperatures by a multiple of the crease material's T_g.
    """

    name: str
    youngs_modulus: float
    poisson_ratio: float = 0.3
    density: float = 0.0
    thermal_conductivity: float = 0.0
    glass_transition: float | None = None

    def __post_init__(self):
        checks = {
            "youngs_modulus": (self.youngs_modulus, lambda v: v > 0, "> 0 Pa"),
            "poisson_ratio": (self.poisson_ratio, lambda v: -1 < v < 0.5, "in (-1, 0.5)"),
            "density": (self.density, lambda v: v >= 0, ">= 0 kg/m^3"),
            "thermal_conductivity": (self.thermal_conductivity, lambda v: v >= 0, ">= 0 W/(m K)"),
        }
        for field, (value, ok, allowed) in checks.items():
            if not (isinstance(value, (int, float)) and math.isfinite(value) and ok(value)):
                raise ParameterError(
                    f"Material {self.name!r}: {field} = {value!r} is invalid; it must be {allowed}.")
        tg = self.glass_transition
        if tg is not None and not (isinstance(tg, (int, float)) and math.isfinite(tg)):
            raise ParameterError(f"Material {self.name!r}: glass_transition = {tg!r} is invalid; "
                                 "give T_g in deg C as a finite number, or None if unknown.")

    def to_dict(self) -> dict:
        """Plain-dict view for result metadata."""
        return asdict(self)


#: SU-8 epoxy photoresist. E = 2 GPa, nu = 0.3, rho = 1200 kg/m^3 and k = 0.3 W/(m K) as in the
#: reference examples (Zhu & Filipov 2021, Example01-04 and the gripper). T_g = 210 deg C: the
#: paper bounds the gripper's crease temperature by 1.2 T_g of SU-8 (section 6.3) without printing
#: T_g; 210 deg C is the manufacturer's value for fully cross-linked SU-8 (MicroChem SU-8 2000
#: data sheet; "above 200 deg C" in the literature), giving the 252 deg C limit used throughout.
SU8 = Material("SU-8", youngs_modulus=2e9, poisson_ratio=0.3, density=1200.0,
               thermal_conductivity=0.3, glass_transition=210.0)

#: SPR photoresist panels of the gripper; the reference models them with SU-8 properties.
SPR = Material("SPR", youngs_modulus=2e9, poisson_ratio=0.3, density=1200.0, thermal_conductivity=0.3)

#: Thick substrate / anchor panels (silicon wafer with oxide) as modelled by the reference examples:
#: mechanically the same modulus as the panels (they are fully supported), k = 1.3 W/(m K).
SUBSTRATE = Material("substrate", youngs_modulus=2e9, poisson_ratio=0.3, density=1200.0,
                     thermal_conductivity=1.3)
