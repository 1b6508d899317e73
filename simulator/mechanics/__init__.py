"""Mechanics: element families (bars, springs, contact, supports; the protocol in ``families``),
their kernels, contact search, generic assembly, the equilibrium system and fold-angle measures."""
