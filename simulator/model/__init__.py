"""The bar-and-hinge model: mesh, element properties, bimorph actuators, lumped masses, the
thermal parameters (heat loss, layers) and the Model that ties them together.

The public names (``from simulator.model import stack_model``): everything of the model
family, the names at ``simulator``'s door (:class:`Model`, :func:`make_model`, the mesh and
the parameters) and the rest: concentrated hinges (sharp creases), plain crease patterns with
a layer stack (:func:`stack_model` and its panel and contact helpers), lumped masses and the
gravity constants.
"""

from .._lazy import attach as _attach

__getattr__, __dir__ = _attach(__name__, {
    ".model": ("Model", "make_model", "Supports", "ContactParameters", "STANDARD_GRAVITY",
               "REFERENCE_GRAVITY"),
    ".mesh": ("BarHingeMesh", "make_mesh"),
    ".properties": ("BarHingeParameters",),
    "..mechanics.rest_angles": ("spring_rest_angles",),
    ".bimorph": ("Actuators", "Bimorph"),
    ".sharp": ("SharpHingeParameters", "sharp_model"),
    ".sharp_mesh": ("SharpHingeMesh", "build_sharp_mesh"),
    ".mass": ("lumped_masses",),
    "..stacks": ("LayerStack", "STACKS", "get_stack", "stack_model", "central_panel",
               "unsupported_panels", "check_supported", "plain_contact"),
    "..geometry.orientation": ("start_fold_angles",),
}, renamed="simulator._moved")

__all__ = [
    # the model, its mesh and parameters (also at simulator's door)
    "Model", "make_model", "BarHingeMesh", "make_mesh", "BarHingeParameters", "Supports",
    "ContactParameters", "Actuators", "Bimorph", "spring_rest_angles",
    # concentrated hinges (make_model(crease_model="sharp"))
    "sharp_model", "SharpHingeParameters", "SharpHingeMesh", "build_sharp_mesh",
    # plain crease patterns: layer stacks, fixed panel, contact, fold signs of a start shape
    "stack_model", "LayerStack", "STACKS", "get_stack", "central_panel", "unsupported_panels",
    "check_supported", "plain_contact", "start_fold_angles",
    # masses and gravity
    "lumped_masses", "STANDARD_GRAVITY", "REFERENCE_GRAVITY",
]
