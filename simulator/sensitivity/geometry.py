"""Geometry parameters of :func:`~simulator.sensitivity.differentiate`: the chain rule through
the mesh (theory 12.5).

A :class:`Geometry` maps named parameters (a panel length, a Miura cell's ``a``, ``b``,
``gamma``, a crease width) to a model of the SAME topology: either to the mesh's reference
node positions ``nodes(p) -> (n_nodes, 3)`` (the model is rebuilt on them, bar lengths and
every property that reads them recomputed) or to a whole :class:`~simulator.model.Model`
(needed where a parameter is also data of the pattern, e.g. the crease width, which sets the
hinge stiffness and the bimorph's rotation). The state is held at fixed displacements ``u``
and temperatures (the current positions ``x = X(p) + u`` move with the reference), and the
derivative of the coupled residual in each parameter is a central difference of its assembly
(no solve) at that state, with the step ``h = eps^(1/2) max(|p|, scale)``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ParameterError

__all__ = ["Geometry", "GEOMETRY_STEP", "ROUGH_RTOL", "with_reference_nodes"]

#: The relative step of the central differences of the residual assembly,
#: ``h = GEOMETRY_STEP max(|p|, scale)``, ``eps^(1/2)`` = 1.5e-8 (theory 12.5): the residual at
#: fixed displacements is strongly curved in the geometry (the stiff bars of a folded panel
#: strain when its reference moves under fixed displacements; on the single fold the central
#: difference's truncation error is 3e-4 of the mechanical term at ``eps^(1/3) p``, 7e-6 at
#: ``1e-6 p``), while its round-off, ``eps / h`` of the element forces, stays below 1e-7.
GEOMETRY_STEP = float(np.finfo(float).eps ** 0.5)
#: A geometry parameter's residual columns at ``h`` and ``4 h`` may differ by this fraction of
#: their largest entry (per block: mechanics, heat, the objective's own term); more is reported
#: as a non-smooth point (a builder not smooth at the step's scale). Measured: 4e-8 at most on
#: the single fold and the 2 x 2 Miura lifter, 0.1 to 4 for the Miura builder's round-off wiggle.
ROUGH_RTOL = 1e-5


@dataclass(frozen=True)
class Geometry:
    """Geometry parameters of a model, for :func:`~simulator.sensitivity.differentiate`.

    Parameters
    ----------
    build : callable
        ``build(p) -> nodes or Model``, ``p`` a dict {name: value}: the mesh's reference node
        positions (n_nodes, 3) [m] at fixed topology, or a :class:`~simulator.model.Model`
        with the same mesh topology, supports and thermal boundary (e.g. rebuilt from a
        pattern with other dimensions). Reference nodes alone leave the pattern's data (crease
        widths, thicknesses) unchanged: give a model for a crease width.
    values : mapping {name: float}
        The parameters at the differentiated state; ``build(values)`` must give the state's
        model (checked on the reference nodes, to 1e-9 of the model's size).
    units : mapping {name: str}, optional
        Each parameter's unit (default "m").
    scale : mapping {name: float}, optional
        Typical size of each parameter, in its unit, for the step of the central differences
        ``h = eps^(1/2) max(|p|, scale)`` (default: the model's size for "m", 1 otherwise).
    """

    build: Callable
    values: Mapping
    units: Mapping = field(default_factory=dict)
    scale: Mapping = field(default_factory=dict)

    def __post_init__(self):
        if not callable(self.build):
            raise ParameterError(f"Geometry.build = {self.build!r:.60} is not callable; give "
                                 "a function p -> reference nodes (n_nodes, 3) or a Model.")
        if not isinstance(self.values, Mapping) or not self.values:
            raise ParameterError(f"Geometry.values = {self.values!r:.60}; give a non-empty "
                                 "mapping {name: value}.")
        for k, v in self.values.items():
            if not isinstance(k, str) or not np.isfinite(float(v)):
                raise ParameterError(f"Geometry.values[{k!r}] = {v!r}; give finite values "
                                     "under string names.")
        for what in ("units", "scale"):
            extra = set(getattr(self, what)) - set(self.values)
            if extra:
                raise ParameterError(f"Geometry.{what} names {sorted(extra)}, which are not "
                                     f"in values ({sorted(self.values)}).")
        for k, v in self.scale.items():
            if not float(v) > 0:
                raise ParameterError(f"Geometry.scale[{k!r}] = {v!r}; give a positive size.")

    def unit(self, name) -> str:
        return self.units.get(name, "m")

    def step(self, name, size: float) -> float:
        """The central-difference step of parameter ``name`` [its unit]; ``size`` the model's
        size [m] (the default scale of a length)."""
        default = size if self.unit(name) == "m" else 1.0
        return GEOMETRY_STEP * max(abs(float(self.values[name])), float(
            self.scale.get(name, default)))

    def model_at(self, model, p):
        """The model at parameters ``p`` (of the same topology as ``model``)."""
        from ..model.model import Model

        out = self.build(dict(p))
        if isinstance(out, Model):
            _check_topology(model, out)
            return out
        return with_reference_nodes(model, out)


def with_reference_nodes(model, nodes):
    """``model`` rebuilt on reference node positions ``nodes`` (n_nodes, 3) [m]: the bar
    lengths from them, the properties (stiffnesses, areas) from those; the pattern's data,
    supports, thermal parameters and actuators unchanged."""
    from ..model.model import make_model

    mesh = model.mesh
    nodes = np.asarray(nodes, dtype=float)
    if nodes.shape != mesh.nodes.shape or not np.all(np.isfinite(nodes)):
        raise ParameterError(f"Geometry.build returned nodes of shape {nodes.shape}; give a "
                             f"finite array of shape {mesh.nodes.shape} (or a Model).")
    length = np.linalg.norm(nodes[mesh.bars[:, 1]] - nodes[mesh.bars[:, 0]], axis=1)
    moved = replace(mesh.with_nodes(nodes), bar_length=length)
    return make_model(moved, model.supports, model.params, model.contact, model.thermal,
                      model.actuators)


def _check_topology(model, other) -> None:
    from . import SensitivityNotSupported

    a, b = model.mesh, other.mesh
    same = all(np.array_equal(getattr(a, k), getattr(b, k)) for k in (
        "bars", "springs", "triangles", "crease_ids", "crease_nodes")) and \
        np.array_equal(model.fixed_mask, other.fixed_mask)
    if not same:
        raise SensitivityNotSupported(
            "Geometry.build gave a model of another topology (its bars, springs, triangles, "
            "creases or supports differ); geometry parameters are differentiated at fixed "
            "topology only: keep the pattern's panels and creases and the supports.")


def geometry_terms(geometry: Geometry, setting, objectives, residual, loads) -> tuple:
    """``(names, units, dR (n_u + n_T, k), dJ_explicit (n_objectives, k), rough)``: central
    differences of the coupled residual ``residual(model, loads)`` and of each of the
    ``objectives`` (a list) at the fixed state, in
    each parameter of ``geometry`` (theory 12.5); ``rough`` lists the parameters whose
    differences at ``h`` and ``4 h`` disagree (:data:`ROUGH_RTOL`)."""
    if not isinstance(geometry, Geometry):
        raise ParameterError(f"geometry = {geometry!r:.60}; give a "
                             "simulator.sensitivity.Geometry or None.")
    s = setting
    size = float(np.ptp(s.model.mesh.nodes, axis=0).max())
    base = geometry.model_at(s.model, geometry.values)
    gap = np.abs(base.mesh.nodes - s.model.mesh.nodes).max()
    if gap > 1e-9 * size:
        raise ParameterError(f"Geometry: build(values) moves the reference nodes by up to "
                             f"{gap:.3g} m from the model's; give the values the state's "
                             "model was built with.")
    names, units, cols, explicit, rough = [], [], [], [], []

    def difference(name, h):
        ends = [geometry.model_at(s.model, {**geometry.values, name: geometry.values[name]
                                            + d * h}) for d in (1, -1)]
        r = [residual(m, loads(m)) for m in ends]
        j = [np.array([_objective_value(o, m, s.state) for o in objectives]) for m in ends]
        return (r[0] - r[1]) / (2 * h), (j[0] - j[1]) / (2 * h)
    for name in geometry.values:
        h = geometry.step(name, size)
        (col, ex), (col4, ex4) = difference(name, h), difference(name, 4 * h)
        worst = max(_gap(col[:s.n_u], col4[:s.n_u]), _gap(col[s.n_u:], col4[s.n_u:]),
                    *(_gap(ex[o:o + 1], ex4[o:o + 1]) for o in range(len(ex))))
        if worst > ROUGH_RTOL:
            rough.append(f"geometry[{name}]: the residual's central differences at h = {h:.3g} "
                         f"and 4 h differ by {worst:.2g} of themselves (Geometry.build is not "
                         "smooth at the step's scale)")
        cols.append(col)
        explicit.append(ex)
        names.append(f"geometry[{name}]")
        units.append(geometry.unit(name))
    return names, units, np.column_stack(cols), np.column_stack(explicit), rough


def _gap(a, b) -> float:
    """``max|a - b| / max|a|`` (0 where both vanish)."""
    scale = np.abs(a).max() if a.size else 0.0
    return float(np.abs(a - b).max() / scale) if scale > 0 else (
        0.0 if not b.size or np.abs(b).max() == 0 else np.inf)


def _objective_value(objective, model, state) -> float:
    """The objective on ``model`` at the state's displacements and temperatures; a callable
    ``f(u, T)`` does not see the model (its explicit derivative is 0)."""
    if hasattr(objective, "terms"):
        return float(objective.terms(model, state.u, state.temperature)[0])
    return 0.0
