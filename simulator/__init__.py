"""etorigami simulator: electro-thermo-mechanical bar-and-hinge simulation of active origami."""

from ._version import __version__
from .errors import ConvergenceError, EtorigamiError, ParameterError, PatternError
from .materials import Material
from .mesh import BarHingeMesh, build_mesh
from .pattern import Pattern

__all__ = ["__version__", "ConvergenceError", "EtorigamiError", "ParameterError", "PatternError",
           "Material", "BarHingeMesh", "build_mesh", "Pattern"]
