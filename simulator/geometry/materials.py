"""Material data (SI units) used by patterns and models.

Values are those used by the reference examples of Zhu & Filipov (2021) unless
stated otherwise; each constant documents its source.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .._deprecation import warn_deprecated
from .._validate import finite, in_range, non_negative, positive
from ..errors import ParameterError

__all__ = ["Material", "Fluid", "SU8", "SPR", "SUBSTRATE", "GOLD", "GOLD_FILM_CONDUCTIVITY", "GOLD_FILM",
           "SILICON", "AIR", "WATER", "AIR_CONDUCTIVITY_TABLE", "WATER_CONDUCTIVITY_TABLE",
           "POLYMER_EMISSIVITY", "GOLD_FILM_EMISSIVITY", "KELVIN"]

#: 0 deg C in kelvin: absolute temperature ``T [K] = T [deg C] + KELVIN``.
KELVIN = 273.15


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
    emissivity : float
        Total hemispherical emissivity eps [-] of both faces, in [0, 1]: a sheet of this
        material radiates ``2 A eps sigma (T^4 - T_room^4)`` to surroundings at room
        temperature (theory 4.12). 0 (default, the paper setting): no radiation. Typical
        values: :data:`POLYMER_EMISSIVITY`, :data:`GOLD_FILM_EMISSIVITY`.
    """

    name: str
    youngs_modulus: float
    poisson_ratio: float = 0.3
    density: float = 0.0
    thermal_conductivity: float = 0.0
    specific_heat: float = 0.0
    glass_transition: float | None = None
    emissivity: float = 0.0

    def __post_init__(self):
        owner = f"Material {self.name!r}"
        positive(f"{owner}: youngs_modulus", self.youngs_modulus, "Pa")
        in_range(f"{owner}: poisson_ratio", self.poisson_ratio, -1, 0.5, open_low=True,
                 open_high=True)
        for field, unit in _UNITS.items():
            non_negative(f"{owner}: {field}", getattr(self, field), unit)
        finite(f"{owner}: glass_transition", self.glass_transition, "deg C",
               hint="give T_g, or None if unknown", allow_none=True)
        in_range(f"{owner}: emissivity", self.emissivity, 0, 1,
                 hint="a total hemispherical emissivity: 0 no radiation (the paper setting), "
                 f"about {POLYMER_EMISSIVITY} a polymer, {GOLD_FILM_EMISSIVITY} a gold film")

    def to_dict(self) -> dict:
        """Plain-dict view for result metadata (``emissivity`` only when not 0, so that the
        dicts written before it existed are as they were)."""
        out = asdict(self)
        if not self.emissivity:
            del out["emissivity"]
        return out


#: Total hemispherical emissivity of a polymer sheet (SU-8, SPR photoresist) [-]: organic
#: materials, paints and plastics emit about 0.85-0.95 of a black body in the thermal infrared
#: (the total-emissivity tables of infrared-thermometry manuals, e.g. FLIR's "Emissivity
#: tables", and the surveys they cite). A film of a few micrometres is partly transparent in
#: the infrared and emits less than the bulk, so 0.5-0.9 is the plausible range for the paper's
#: 1-5 um films (theory 4.12). A typical value, not a default: the materials below keep 0 (the
#: paper setting).
POLYMER_EMISSIVITY = 0.85

#: Total hemispherical emissivity of an evaporated gold film [-]: polished gold emits 0.02 at
#: 100 deg C and 0.02-0.03 at 200-600 deg C (the same tables); 0.02-0.05 for a film. A
#: typical value, not a default.
GOLD_FILM_EMISSIVITY = 0.03

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

#: A thin evaporated gold film (heater or metal layer, 0.1-0.5 um): :data:`GOLD` with the
#: film's in-plane conductivity :data:`GOLD_FILM_CONDUCTIVITY`; density and specific heat are
#: the bulk's (19300 kg/m^3, 129 J/(kg K), Incropera Table A.1: the heat capacity of a film this
#: thick is the bulk's). For layer stacks (``Layer.of(GOLD_FILM, 0.1e-6)``, theory 4.10).
GOLD_FILM = Material("gold film", youngs_modulus=79e9, poisson_ratio=0.44, density=19300.0,
                     thermal_conductivity=GOLD_FILM_CONDUCTIVITY, specific_heat=129.0)

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
        k [W/(m K)], >= 0: the conductivity of the heat-loss operators (theory 4.3, 4.7);
        with a ``conductivity_table`` their reference conductivity k0, > 0 (the losses then
        follow the table whatever k0 is: theory 4.12).
    conductivity_table : tuple of (float, float)
        The conductivity as a function of temperature, ``((T [deg C], k [W/(m K)]), ...)``
        with T strictly increasing and k > 0, linear between the points and constant beyond
        the ends; () (default, the paper setting): the constant ``thermal_conductivity``.
        :meth:`with_temperature_dependence` gives the literature tables of :data:`AIR` and
        :data:`WATER` (:data:`AIR_CONDUCTIVITY_TABLE`, :data:`WATER_CONDUCTIVITY_TABLE`).
    """

    name: str
    density: float
    specific_heat: float
    thermal_conductivity: float
    conductivity_table: tuple = ()

    def __post_init__(self):
        for field in ("density", "specific_heat", "thermal_conductivity"):
            non_negative(f"Fluid {self.name!r}: {field}", getattr(self, field), _UNITS[field])
        object.__setattr__(self, "conductivity_table",
                           _checked_table(self.name, self.conductivity_table))
        if self.conductivity_table and not self.thermal_conductivity > 0:
            raise ParameterError(
                f"Fluid {self.name!r}: thermal_conductivity = {self.thermal_conductivity!r} "
                "W/(m K) with a conductivity_table: the table needs a reference conductivity "
                "> 0 (the heat-loss operators are built with it, theory 4.12); give e.g. the "
                "table's value at room temperature.")

    @property
    def temperature_dependent(self) -> bool:
        """Whether the conductivity follows :attr:`conductivity_table` (else constant)."""
        return bool(self.conductivity_table)

    def conductivity(self, T) -> np.ndarray:
        """The conductivity k [W/(m K)] at temperatures ``T`` [deg C] (any shape): the table
        interpolated linearly (constant beyond its ends), or the constant."""
        T = np.asarray(T, float)
        if not self.conductivity_table:
            return np.full(T.shape, float(self.thermal_conductivity))
        t, k = np.array(self.conductivity_table).T
        return np.interp(T, t, k)

    def kirchhoff(self, rise, room: float):
        """The Kirchhoff transformation of a temperature rise (theory 4.12): ``(Phi, dPhi)``,
        ``Phi = int_room^(room + rise) k(s) ds / k0`` [K] and its derivative ``k(room + rise)
        / k0`` [-], same shape as ``rise`` [K] (``room`` [deg C], k0 the
        ``thermal_conductivity``); ``(rise, 1)`` for a constant conductivity."""
        rise = np.asarray(rise, float)
        if not self.conductivity_table:
            return rise, np.ones(rise.shape)
        k0 = float(self.thermal_conductivity)
        T = room + rise
        phi = (_table_integral(T, self.conductivity_table)
               - _table_integral(np.array([room]), self.conductivity_table)[0]) / k0
        return phi, self.conductivity(T) / k0

    def with_temperature_dependence(self, table=None) -> Fluid:
        """This fluid with its conductivity following ``table`` ((T [deg C], k [W/(m K)]),
        ...) (None: the literature table of :data:`AIR` or :data:`WATER`, for those
        fluids), named ``"air, k(T)"``; e.g. ``ThermalParameters(medium=AIR.
        with_temperature_dependence())``. The constant ``thermal_conductivity`` stays the
        reference conductivity k0 of the loss operators (theory 4.12)."""
        if table is None:
            base = self.name.split(",")[0].split(" with ")[0]
            table = _LITERATURE_TABLES.get(base)
            if table is None:
                raise ParameterError(
                    f"Fluid {self.name!r}.with_temperature_dependence(): no literature table "
                    f"for this fluid (known: {', '.join(_LITERATURE_TABLES)}); give table="
                    "((T [deg C], k [W/(m K)]), ...).")
        name = self.name if self.conductivity_table else f"{self.name}, k(T)"
        return Fluid(name, self.density, self.specific_heat, self.thermal_conductivity,
                     tuple(table))

    def with_properties(self, **changes) -> Fluid:
        """This fluid with some of ``density`` [kg/m^3], ``specific_heat`` [J/(kg K)],
        ``thermal_conductivity`` [W/(m K)] changed: itself where none changes, else the known
        fluid (:data:`AIR`, :data:`WATER`) it then equals, else a fluid named after this one
        and what changed (``"air with k changed"``), its conductivity table kept;
        e.g. ``ThermalParameters(medium=AIR.with_properties(thermal_conductivity=0.6))``."""
        for field, value in changes.items():
            if field not in _UNITS:
                raise ParameterError(f"Fluid.with_properties: {field!r} is not a property of a "
                                     f"fluid; give {', '.join(_UNITS)}.")
            non_negative(f"Fluid.with_properties: {field}", value, _UNITS[field])
        if all(float(getattr(self, k)) == float(v) for k, v in changes.items()):
            return self
        values = {k: getattr(self, k) for k in _UNITS} | {k: float(v) for k, v in changes.items()}
        if not self.conductivity_table:
            known = next((f for f in (AIR, WATER) if all(getattr(f, k) == v
                                                          for k, v in values.items())), None)
            if known is not None:
                return known
        return Fluid(self._changed_name(values), **values,
                     conductivity_table=self.conductivity_table)

    def _changed_name(self, values: dict) -> str:
        """``"air with k changed"``: the name of this fluid with other ``values``."""
        symbols = {"density": "rho", "specific_heat": "c", "thermal_conductivity": "k"}
        base = self.name.split(" with ")[0]
        origin = next((f for f in (AIR, WATER) if f.name == base.split(",")[0]), self)
        changed = [s for k, s in symbols.items() if float(getattr(origin, k)) != values[k]]
        return f"{base} with {', '.join(changed)} changed"

    def environment(self) -> dict:
        """Deprecated: the old flat keywords of
        :class:`~simulator.model.thermal_parameters.ThermalParameters` for this fluid; give
        ``ThermalParameters(medium=fluid)``."""
        warn_deprecated("Fluid.environment() is deprecated (it gives the old flat keywords "
                        "env_conductivity, env_density, env_specific_heat); use "
                        "ThermalParameters(medium=fluid).")
        return {"env_conductivity": self.thermal_conductivity, "env_density": self.density,
                "env_specific_heat": self.specific_heat}

    def to_dict(self) -> dict:
        """Plain-dict view for result metadata (``conductivity_table`` as a list of pairs,
        only when given, so that the dicts written before it existed are as they were)."""
        out = asdict(self)
        if self.conductivity_table:
            out["conductivity_table"] = [list(p) for p in self.conductivity_table]
        else:
            del out["conductivity_table"]
        return out


def _checked_table(name: str, table) -> tuple:
    """``table`` as a tuple of ``(T [deg C], k [W/(m K)])`` float pairs, checked: at least two
    points, T finite and strictly increasing, k finite and > 0."""
    field = f"Fluid {name!r}: conductivity_table"
    if table is None or (not isinstance(table, np.ndarray) and len(table) == 0):
        return ()
    try:
        a = np.array(table, float)
    except (TypeError, ValueError):
        a = np.empty((0, 0))
    if a.ndim != 2 or a.shape[1] != 2 or len(a) < 2 or not np.isfinite(a).all():
        raise ParameterError(f"{field} = {table!r} must be at least two finite pairs "
                             "((T [deg C], k [W/(m K)]), ...), or () for a constant "
                             "conductivity.")
    if np.any(np.diff(a[:, 0]) <= 0):
        i = int(np.flatnonzero(np.diff(a[:, 0]) <= 0)[0])
        raise ParameterError(f"{field}: the temperatures must increase strictly; T = "
                             f"{a[i, 0]:g} deg C is followed by {a[i + 1, 0]:g} deg C; sort the "
                             "pairs by temperature and drop repeated ones.")
    if np.any(a[:, 1] <= 0):
        i = int(np.flatnonzero(a[:, 1] <= 0)[0])
        raise ParameterError(f"{field}: k = {a[i, 1]:g} W/(m K) at T = {a[i, 0]:g} deg C must be "
                             "> 0; give conductivities in W/(m K) (e.g. air 0.0263 at 26.85 "
                             "deg C).")
    return tuple((float(t), float(k)) for t, k in a)


def _table_integral(T, table) -> np.ndarray:
    """``int_{T_first}^{T} k(s) ds`` [W/m] of the piecewise-linear conductivity ``table``
    (constant beyond its ends) at temperatures ``T`` [deg C], exactly (trapezoids)."""
    t, k = np.array(table).T
    T = np.asarray(T, float)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (k[1:] + k[:-1]) * np.diff(t))])
    Tc = np.clip(T, t[0], t[-1])
    i = np.clip(np.searchsorted(t, Tc, side="right") - 1, 0, len(t) - 2)
    inside = cum[i] + 0.5 * (k[i] + np.interp(Tc, t, k)) * (Tc - t[i])
    return inside + k[0] * np.minimum(T - t[0], 0.0) + k[-1] * np.maximum(T - t[-1], 0.0)


#: Air as in the reference transient example (04/Example01: ``envDensity = 1.293``,
#: ``envThermalCapacity = 700``, ``envThermalConduct = 0.026``; theory 10.8). Note that
#: the textbook isobaric specific heat of air is 1007 J/(kg K) at 300 K (Incropera Table A.4).
AIR = Fluid("air", density=1.293, specific_heat=700.0, thermal_conductivity=0.026)

#: Water at 20 deg C: k = 0.6 W/(m K) as the reference's "water-like" environment (03/Example01);
#: rho = 998 kg/m^3, c = 4182 J/(kg K) (Incropera et al., 6th ed., Table A.6).
WATER = Fluid("water", density=998.0, specific_heat=4182.0, thermal_conductivity=0.6)

#: Conductivity of dry air at 1 atm [(deg C, W/(m K))], Incropera et al., Fundamentals of Heat
#: and Mass Transfer, 6th ed., Table A.4 (250-1000 K, every 50 K; converted from K by
#: :data:`KELVIN`): 0.0263 at 300 K, 0.0338 at 400 K, 0.0469 at 600 K. :meth:`Fluid.
#: with_temperature_dependence` of :data:`AIR` uses it (theory 4.12).
AIR_CONDUCTIVITY_TABLE = tuple(
    (T - KELVIN, 1e-3 * k) for T, k in (
        (250, 22.3), (300, 26.3), (350, 30.0), (400, 33.8), (450, 37.3), (500, 40.7),
        (550, 43.9), (600, 46.9), (650, 49.7), (700, 52.4), (750, 54.9), (800, 57.3),
        (850, 59.6), (900, 62.0), (950, 64.3), (1000, 66.7)))

#: Conductivity of saturated liquid water [(deg C, W/(m K))], Incropera et al., 6th ed., Table
#: A.6 (273.15-373.15 K): 0.569 at 0 deg C, 0.613 at 300 K, 0.680 at 100 deg C; constant beyond
#: (above 100 deg C at 1 atm the water boils, which no conduction model describes).
WATER_CONDUCTIVITY_TABLE = tuple(
    (T - KELVIN, 1e-3 * k) for T, k in (
        (273.15, 569), (280, 582), (290, 598), (300, 613), (310, 628), (320, 640), (330, 650),
        (340, 660), (350, 668), (360, 674), (370, 679), (373.15, 680)))

_LITERATURE_TABLES = {"air": AIR_CONDUCTIVITY_TABLE, "water": WATER_CONDUCTIVITY_TABLE}
