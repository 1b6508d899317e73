"""The parameters of :func:`~simulator.sensitivity.differentiate` and the derivatives of the
coupled residual in them (theory 12.3).

Kinds, in their order in a gradient: ``"power"`` (per crease, [W]), ``"rest_offset"`` (per
crease: an offset added to the crease rest angle at the start of the heating step, e.g. a
residual fold angle [rad]), ``"delta_alpha"`` (per crease, the bimorph's expansion mismatch
[1/K]), ``"bimorph"`` (the layers' moduli ``E1``, ``E2`` [Pa] and thicknesses ``t1``, ``t2``
[m]) and ``"medium_conductivity"`` [W/(m K)].
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import ParameterError
from ..thermal.steady import heat_weights

__all__ = ["PARAMETER_KINDS", "UNSUPPORTED_KINDS", "curvature_log_derivatives"]

#: The parameter kinds of :func:`~simulator.sensitivity.differentiate`, in gradient order.
PARAMETER_KINDS = ("power", "rest_offset", "delta_alpha", "bimorph", "medium_conductivity")
#: Kinds of issue 32 not supported yet, with the reason given when they are asked for.
UNSUPPORTED_KINDS = {
    "crease_width": "the crease width moves the mesh's reference nodes (and with them every "
                    "bar, hinge and conduction element): give it as a geometry parameter, "
                    "geometry=Geometry(build=p -> the model at that width, values={...})",
    "geometry": "geometry parameters are given as geometry=Geometry(build, values), not as "
                "a kind",
    "voltage": "heater circuits (powers that depend on the temperatures) are not supported",
}
_UNITS = {"power": "W", "rest_offset": "rad", "delta_alpha": "1/K", "E1": "Pa", "E2": "Pa",
          "t1": "m", "t2": "m", "medium_conductivity": "W/(m K)"}


def check_kinds(parameters) -> tuple:
    """The requested kinds, validated, in :data:`PARAMETER_KINDS` order."""
    from . import SensitivityNotSupported

    kinds = (parameters,) if isinstance(parameters, str) else tuple(parameters)
    for k in kinds:
        if k in UNSUPPORTED_KINDS:
            raise SensitivityNotSupported(
                f"parameters: {k!r} is not supported ({UNSUPPORTED_KINDS[k]}); supported: "
                f"{', '.join(PARAMETER_KINDS)}.")
        if k not in PARAMETER_KINDS:
            raise ParameterError(f"parameters: unknown kind {k!r}; give some of "
                                 f"{', '.join(PARAMETER_KINDS)}.")
    return tuple(k for k in PARAMETER_KINDS if k in kinds)


def curvature_log_derivatives(b) -> dict:
    """``d ln(kappa) / d q`` for q in E1, t1, E2, t2 of the Timoshenko curvature of the bimorph
    ``b`` (:func:`~simulator.model.bimorph.timoshenko_curvature`), [1/Pa] and [1/m].

    ``kappa ~ (1 + m)^2 / (h D)``, ``D = 3 (1 + m)^2 + (1 + m n)(m^2 + 1 / (m n))``,
    ``m = t1 / t2``, ``n = E1 / E2``, ``h = t1 + t2``."""
    E1, t1, E2, t2 = float(b.E1), float(b.t1), float(b.E2), float(b.t2)
    m, n, h = t1 / t2, E1 / E2, t1 + t2
    D = 3 * (1 + m) ** 2 + (1 + m * n) * (m * m + 1 / (m * n))
    dD_m = 6 * (1 + m) + n * (m * m + 1 / (m * n)) + (1 + m * n) * (2 * m - 1 / (m * m * n))
    dD_n = m * (m * m + 1 / (m * n)) - (1 + m * n) / (m * n * n)
    dm = 2 / (1 + m) - dD_m / D           # d ln kappa / d m
    dn = -dD_n / D
    return {"E1": dn / E2, "t1": dm / t2 - 1 / h, "E2": -dn * E1 / E2 ** 2,
            "t2": -dm * t1 / t2 ** 2 - 1 / h}


def parameter_columns(kinds, setting) -> tuple:
    """``(names, units, dR)``: the parameters of ``kinds`` and the derivatives of the coupled
    residual ``(R_mech on the free DOFs, R_th on the free nodes)`` in them, (n_u + n_T, k)
    dense; ``setting`` is the :class:`~simulator.sensitivity.adjoint._Setting` of the state.
    Built a kind's block at a time (no loop over creases: 341 parameters on the 8 x 8-cell
    Miura sheet)."""
    s = setting
    mesh, ids = s.model.mesh, [int(c) for c in s.model.mesh.crease_ids]
    n_u, C = s.n_u, mesh.n_creases
    names, units, blocks = [], [], []

    def add(kind, unit, du=None, dT=None, labels=None):
        """One block: ``du`` (n_u, k) and / or ``dT`` (n_T, k) [per unit of the parameter]."""
        k = len(labels) if labels is not None else 1
        block = np.zeros((n_u + s.n_T, k))
        if du is not None:
            block[:n_u] = np.reshape(du, (n_u, k))
        if dT is not None:
            block[n_u:] = np.reshape(dT, (s.n_T, k))
        names.extend([f"{kind}[{c}]" for c in labels] if labels is not None else [kind])
        units.extend([unit] * k)
        blocks.append(block)
    G = s.G.toarray()                        # dR_mech / d crease rest angle, (n_u, C)
    for kind in kinds:
        if kind == "power":                  # -(heat weights of crease c) on the free nodes
            H = sp.coo_matrix((np.tile(heat_weights(), C), (mesh.crease_nodes.ravel(),
                               np.repeat(np.arange(C), mesh.crease_nodes.shape[1]))),
                              shape=(mesh.n_nodes, C)).tocsr()
            add("power", "W", dT=-s.heat(H.toarray())[s.free_T], labels=ids)
        elif kind == "rest_offset":
            add("rest_offset", "rad", du=G, labels=ids)
        elif kind == "delta_alpha":
            add("delta_alpha", "1/K", du=G * (s.rot_per_delta_alpha * s.dTc), labels=ids)
        elif kind == "bimorph":
            _check_bimorph(s)
            for q, dlog in curvature_log_derivatives(s.model.actuators.bimorph).items():
                add(q, _UNITS[q], du=G @ (s.rot * dlog * s.dTc))
        elif kind == "medium_conductivity":
            add("medium_conductivity", "W/(m K)",
                dT=s.op.conductivity_derivative(s.rise)[s.free_T])
    return names, units, np.hstack(blocks) if blocks else np.zeros((n_u + s.n_T, 0))


def _check_bimorph(s) -> None:
    from . import SensitivityNotSupported

    if s.model.actuators is None:
        raise ParameterError("parameters: 'bimorph' needs a model with actuators.")
    if s.model.thermal.crease_conduction != "paper":
        raise SensitivityNotSupported(
            "parameters: 'bimorph' with crease_conduction = "
            f"{s.model.thermal.crease_conduction!r} (the layers also conduct) is not supported; "
            "supported: crease_conduction = 'paper'.")
