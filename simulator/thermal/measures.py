"""Each crease's temperature measures, from node values: the one place that knows which crease
nodes carry which measure (theory 5.3, 5.4).

A crease of the bar-and-hinge mesh has seven nodes (``BarHingeMesh.crease_nodes``: N11, N12,
N21, N22 on its two panel edges, then A, B, Ctr on its centre line); a concentrated hinge two.

==================  ======================================================================
measure             per crease
==================  ======================================================================
``"actuation"``     the 7-node weighted mean that drives the bimorph (theory 5.3,
                    :func:`~simulator.model.bimorph.crease_temperature_weights`)
``"centre_line"``   the mean of A, B, Ctr: the measure of the 1.2 T_g limit (theory 5.4)
``"centre"``        the centre node Ctr
``"crease_max"``    the hottest of its nodes
==================  ======================================================================

On a concentrated hinge every measure but ``"crease_max"`` is the mean of its two nodes.
"""

from __future__ import annotations

import numpy as np

from .._validate import one_of

__all__ = ["CREASE_MEASURES", "crease_temperatures"]

#: The measures of :func:`crease_temperatures`.
CREASE_MEASURES = ("actuation", "centre_line", "centre", "crease_max")
#: Columns of ``BarHingeMesh.crease_nodes`` (N11, N12, N21, N22, A, B, Ctr) on the centre line,
#: and of its centre node.
_CENTRE_LINE, _CENTRE = slice(4, 7), 6


def crease_temperatures(node_values, mesh, measure: str = "actuation") -> np.ndarray:
    """Per crease one temperature measure of node values.

    Parameters
    ----------
    node_values : array (n,) or (n, ...)
        Values at the mesh nodes, node axis first: temperatures [deg C], or rises [K] or rises
        per heater watt [K/W] (every measure but ``"crease_max"`` is linear, so it maps rises
        to rises). Records (m, n) go in transposed: ``crease_temperatures(T.T, mesh).T``.
    mesh : BarHingeMesh or SharpHingeMesh
    measure : {"actuation", "centre_line", "centre", "crease_max"}
        See the module docstring.

    Returns
    -------
    ndarray (C,) or (C, ...), in ``mesh.crease_ids`` order
    """
    one_of("crease temperature measure", measure, CREASE_MEASURES,
           hint="'actuation' drives the bimorph, 'centre_line' is the measure of the 1.2 T_g "
                "limit, 'centre' the centre node, 'crease_max' the hottest node")
    nodes = np.asarray(node_values, dtype=float)[np.asarray(mesh.crease_nodes)]  # (C, w, ...)
    if measure == "crease_max":
        return nodes.max(axis=1)
    if nodes.shape[1] != 7:                      # concentrated hinges: the two hinge nodes
        return nodes.mean(axis=1)
    if measure == "actuation":
        from ..model.bimorph import crease_temperature_weights

        return np.tensordot(crease_temperature_weights(), nodes, axes=(0, 1))
    if measure == "centre":
        return nodes[:, _CENTRE]
    return nodes[:, _CENTRE_LINE].mean(axis=1)
