"""Exact sensitivities of steady coupled electro-thermal-mechanical states (theory 12.1).

:func:`differentiate` differentiates a scalar of the state a ``Heat`` step ended on (a fold
angle, a node coordinate, a crease temperature, or a function of your own) with respect to the
heater powers, rest-angle offsets, bimorph parameters, the medium's conductivity and geometry
parameters of the pattern (:class:`Geometry`: the chain rule through the mesh), by one
transposed solve of the coupled Jacobian (the adjoint method); the result is a
:class:`Sensitivity`.
"""

from ..errors import ParameterError


class SensitivityNotSupported(ParameterError, NotImplementedError):
    """A model or parameter :func:`differentiate` does not differentiate yet; the message
    names what is supported."""


from .adjoint import Sensitivity, differentiate, differentiate_state  # noqa: E402
from .geometry import Geometry  # noqa: E402
from .objectives import CreaseTemperature, FoldAngle, NodeCoordinate  # noqa: E402
from .parameters import PARAMETER_KINDS  # noqa: E402

__all__ = ["differentiate", "differentiate_state", "Sensitivity", "FoldAngle", "NodeCoordinate",
           "CreaseTemperature", "Geometry", "PARAMETER_KINDS", "SensitivityNotSupported"]
