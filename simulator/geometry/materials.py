"""Material data (SI units) used by patterns and models.

Values are those used by the reference examples of Zhu & Filipov (2021) unless
stated otherwise; each constant documents its source.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from .._deprecation import warn_deprecated
from .._validate import finite, in_range, non_negative, positive
from ..errors import ParameterError

__all__ = ["Material", "Fluid", "SU8", "SPR", "SUBSTRATE", "GOLD", "GOLD_FILM_CONDUCTIVITY",
           "SILICON", "AIR", "WATER"]


#: Units of the non-negative material and fluid properties.
_UNITS = {"density": "kg/m^3", "thermal_conductivity": "W/(m K)", "specific_heat": "J/(kg K)"}


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
    specific_heat : float
        Specific heat capacity c [J/(kg K)], >= 0 (0 = not given; transient heat transfer needs
        it, together with ``density``).
    glass_transition : float or None
        Glass-transition temperature T_g [deg C], finite; None if unknown. Design problems
        bound crease temperatures by a multiple of the crease material's T_g.
    """

    name: str
    youngs_modulus: float
    poisson_ratio: float = 0.3
    density: float = 0.0
    thermal_conductivity: float = 0.0
    specific_heat: float = 0.0
    glass_transition: float | None = None

    def __post_init__(self):
        owner = f"Material {self.name!r}"
        positive(f"{owner}: youngs_modulus", self.youngs_modulus, "Pa")
        in_range(f"{owner}: poisson_ratio", self.poisson_ratio, -1, 0.5, open_low=True,
                 open_high=True)
        for field, unit in _UNITS.items():
            non_negative(f"{owner}: {field}", getattr(self, field), unit)
        finite(f"{owner}: glass_transition", self.glass_transition, "deg C",
               hint="give T_g, or None if unknown", allow_none=True)

    def to_dict(self) -> dict:
        """Plain-dict view for result metadata."""
        return asdict(self)


#: Volumetric heat capacity rho c of SU-8 in the reference transient example [J/(m^3 K)]
#: (04/Example01: ``creaseThermalCapacity = panelThermalCapacity = 2e6 / 1200``; theory 10.8).
_SU8_RHO_C = 2e6

#: SU-8 epoxy photoresist. E = 2 GPa, nu = 0.3, rho = 1200 kg/m^3 and k = 0.3 W/(m K) as in the
#: reference examples (Zhu & Filipov 2021, Example01-04 and the gripper); c = 2e6/1200 =
#: 1666.7 J/(kg K) from the reference transient example (theory 10.8). T_g = 210 deg C: the
#: paper bounds the gripper's crease temperature by 1.2 T_g of SU-8 (section 6.3) without printing
#: T_g; 210 deg C is the manufacturer's value for fully cross-linked SU-8 (MicroChem SU-8 2000
#: data sheet; "above 200 deg C" in the literature), giving the 252 deg C limit used throughout.
SU8 = Material("SU-8", youngs_modulus=2e9, poisson_ratio=0.3, density=1200.0,
               thermal_conductivity=0.3, specific_heat=_SU8_RHO_C / 1200.0,
               glass_transition=210.0)

#: SPR photoresist panels of the gripper; the reference models them with SU-8 properties
#: (including rho and c).
SPR = Material("SPR", youngs_modulus=2e9, poisson_ratio=0.3, density=1200.0,
               thermal_conductivity=0.3, specific_heat=_SU8_RHO_C / 1200.0)

#: Thick substrate / anchor panels (silicon wafer with oxide) as modelled by the reference examples:
#: mechanically the same modulus as the panels (they are fully supported), k = 1.3 W/(m K);
#: rho = 1200 kg/m^3 and c = 2e6/1200 J/(kg K) as the reference's transient example sets for
#: all panels (``panelThermalCapacity``; the reference then reads the conductivity instead by a
#: slip, theory 7.2; we use the specific heat).
SUBSTRATE = Material("substrate", youngs_modulus=2e9, poisson_ratio=0.3, density=1200.0,
                     thermal_conductivity=1.3, specific_heat=_SU8_RHO_C / 1200.0)

#: Gold (bimorph layer). E = 79 GPa (the reference scripts use fractions of it, theory 10.8);
#: nu = 0.44, rho = 19300 kg/m^3, c = 129 J/(kg K), k = 317 W/(m K) at 300 K (Incropera et al.,
#: Fundamentals of Heat and Mass Transfer, 6th ed., Table A.1; nu: CRC Handbook).
GOLD = Material("gold", youngs_modulus=79e9, poisson_ratio=0.44, density=19300.0,
                thermal_conductivity=317.0, specific_heat=129.0)

#: In-plane thermal conductivity of a thin (0.1-0.5 um) evaporated or sputtered gold film
#: [W/(m K)], about half the bulk 317: grain-boundary and surface scattering of the electrons
#: lower it. Thermal-lensing measurements find it falling from about 300 W/(m K) at 2 um to about
#: 100 W/(m K) at 100 nm (the abstract of "Thermal conduction in thin films measured by optical
#: surface thermal lensing"); scanning-thermal-microscopy and Wiedemann-Franz measurements of
#: 240 nm and 47 nm Au films agree with a kinetic thin-film model within 6.4 % (Zhang, Zhu and
#: Borca-Tasciuc, Nanoscale Adv. 2021, doi:10.1039/D0NA00657B). 150 W/(m K) is the value for
#: the paper's 0.1-0.2 um heater layers (theory 4.10), the default of
#: :attr:`simulator.model.bimorph.Bimorph.k1`; its plausible range is 100-300 W/(m K).
GOLD_FILM_CONDUCTIVITY = 150.0

#: Single-crystal silicon. E = 150 GPa and rho = 2300 kg/m^3 as in the reference micro-mirror
#: (02/Example04, theory 10.9); nu = 0.22 (polysilicon, Sharpe et al. 1997); c = 712 J/(kg K),
#: k = 148 W/(m K) at 300 K (Incropera et al., 6th ed., Table A.1).
SILICON = Material("silicon", youngs_modulus=150e9, poisson_ratio=0.22, density=2300.0,
                   thermal_conductivity=148.0, specific_heat=712.0)


@dataclass(frozen=True)
class Fluid:
    """Environment fluid around the structure (the heat-loss layers of the thermal model).

    Parameters
    ----------
    name : str
    density : float
        rho [kg/m^3], >= 0.
    specific_heat : float
        c [J/(kg K)], >= 0.
    thermal_conductivity : float
        k [W/(m K)], >= 0.
    """

    name: str
    density: float
    specific_heat: float
    thermal_conductivity: float

    def __post_init__(self):
        for field in ("density", "specific_heat", "thermal_conductivity"):
            non_negative(f"Fluid {self.name!r}: {field}", getattr(self, field), _UNITS[field])

    def with_properties(self, **changes) -> Fluid:
        """This fluid with some of ``density`` [kg/m^3], ``specific_heat`` [J/(kg K)],
        ``thermal_conductivity`` [W/(m K)] changed: itself where none changes, else the known
        fluid (:data:`AIR`, :data:`WATER`) it then equals, else a fluid named after this one
        and what changed (``"air with k changed"``);
        e.g. ``ThermalParameters(medium=AIR.with_properties(thermal_conductivity=0.6))``."""
        for field, value in changes.items():
            if field not in _UNITS:
                raise ParameterError(f"Fluid.with_properties: {field!r} is not a property of a "
                                     f"fluid; give {', '.join(_UNITS)}.")
            non_negative(f"Fluid.with_properties: {field}", value, _UNITS[field])
        if all(float(getattr(self, k)) == float(v) for k, v in changes.items()):
            return self
        values = {k: getattr(self, k) for k in _UNITS} | {k: float(v) for k, v in changes.items()}
        return next((f for f in (AIR, WATER) if all(getattr(f, k) == v
                                                   for k, v in values.items())),
                    None) or Fluid(self._changed_name(values), **values)

    def _changed_name(self, values: dict) -> str:
        """``"air with k changed"``: the name of this fluid with other ``values``."""
        symbols = {"density": "rho", "specific_heat": "c", "thermal_conductivity": "k"}
        base = self.name.split(" with ")[0]
        origin = next((f for f in (AIR, WATER) if f.name == base), self)
        changed = [s for k, s in symbols.items() if float(getattr(origin, k)) != values[k]]
        return f"{base} with {', '.join(changed)} changed"

    def environment(self) -> dict:
        """Deprecated: the old flat keywords of
        :class:`~simulator.thermal.parameters.ThermalParameters` for this fluid; give
        ``ThermalParameters(medium=fluid)``."""
        warn_deprecated("Fluid.environment() is deprecated (it gives the old flat keywords "
                        "env_conductivity, env_density, env_specific_heat); use "
                        "ThermalParameters(medium=fluid).")
        return {"env_conductivity": self.thermal_conductivity, "env_density": self.density,
                "env_specific_heat": self.specific_heat}

    def to_dict(self) -> dict:
        """Plain-dict view for result metadata."""
        return asdict(self)


#: Air as in the reference transient example (04/Example01: ``envDensity = 1.293``,
#: ``envThermalCapacity = 700``, ``envThermalConduct = 0.026``; theory 10.8). Note that
#: the textbook isobaric specific heat of air is 1007 J/(kg K) at 300 K (Incropera Table A.4).
AIR = Fluid("air", density=1.293, specific_heat=700.0, thermal_conductivity=0.026)

#: Water at 20 deg C: k = 0.6 W/(m K) as the reference's "water-like" environment (03/Example01);
#: rho = 998 kg/m^3, c = 4182 J/(kg K) (Incropera et al., 6th ed., Table A.6).
WATER = Fluid("water", density=998.0, specific_heat=4182.0, thermal_conductivity=0.6)
