"""Mechanics: element families (bars, springs, contact), contact search, assembly,
the equilibrium system and the fold-angle measures of a deformed mesh."""
