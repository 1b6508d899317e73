"""Materials of the sheet and media around it (SI units): :class:`Material` (modulus, Poisson
ratio, density, conductivity, specific heat, emissivity, glass transition) with the paper's
SU-8, SPR, substrate, gold and silicon, and :class:`Fluid` with air and water (the media of the
heat loss, optionally with a temperature-dependent conductivity)."""

from .geometry.materials import (AIR, AIR_CONDUCTIVITY_TABLE, GOLD, GOLD_FILM,
                                 GOLD_FILM_CONDUCTIVITY, GOLD_FILM_EMISSIVITY, KELVIN,
                                 POLYMER_EMISSIVITY, SILICON, SPR, SU8, SUBSTRATE, WATER,
                                 WATER_CONDUCTIVITY_TABLE, Fluid, Material)

__all__ = ["Material", "SU8", "SPR", "SUBSTRATE", "GOLD", "GOLD_FILM", "SILICON",
           "GOLD_FILM_CONDUCTIVITY", "POLYMER_EMISSIVITY", "GOLD_FILM_EMISSIVITY",
           "Fluid", "AIR", "WATER", "AIR_CONDUCTIVITY_TABLE", "WATER_CONDUCTIVITY_TABLE",
           "KELVIN"]
