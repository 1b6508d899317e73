"""Mechanics: element families (bars, springs, contact, supports; the protocol in ``families``),
their kernels, contact search, generic assembly, the equilibrium system and fold-angle measures.

The public names (``from simulator.mechanics import equilibrium_system``): a model's
:class:`EquilibriumSystem` (:func:`equilibrium_system`), the protocol of an element family for a
new element type (:class:`ElementFamily`, :class:`FamilyValues`, :class:`Configuration`), fold
angles and panels crossing each other between two states.
"""

from .._lazy import attach as _attach

__getattr__, __dir__ = _attach(__name__, {
    ".equilibrium": ("EquilibriumSystem", "equilibrium_system"),
    ".families": ("Configuration", "ElementFamily", "FamilyValues"),
    ".kinematics": ("fold_angles",),
    ".crossing": ("crease_crossings", "node_crossings"),
})

__all__ = ["equilibrium_system", "EquilibriumSystem", "ElementFamily", "FamilyValues",
           "Configuration", "fold_angles", "crease_crossings", "node_crossings"]
