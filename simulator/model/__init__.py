"""The bar-and-hinge model: mesh, element properties, bimorph actuators, lumped masses
and the Model that ties them together."""
