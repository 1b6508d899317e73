"""How the sheet loses heat to its medium: two implementations of one small interface, and the
substrate (theory 4.3, 4.7; issue 29).

* :class:`ChainLoss` -- the paper's model: a 1-D chain of medium layers under every node, of
  thickness t_env (capped by the distance to a thermal-boundary panel), spreading at the
  dissipation angle beta. Fitted: t_env is a calibration constant.
* :class:`IntegralLoss` -- calibration-free: the single-layer potential of the sheet in the
  medium, solved on sub-triangles of the mesh (theory 4.7), with an isothermal substrate plane
  if there is one. Nothing to fit.

Each carries only its own options; the medium (:class:`~simulator.geometry.materials.Fluid`:
:data:`~simulator.geometry.materials.AIR`, :data:`~simulator.geometry.materials.WATER`) and
the :class:`Substrate` are their own concepts, given to
:class:`~simulator.model.thermal_parameters.ThermalParameters` beside the loss::

    ThermalParameters(loss=IntegralLoss(), medium=WATER, substrate=Substrate.plane(p, n))
    ThermalParameters(loss=ChainLoss(thickness=1.5e-3))           # air, substrate from panels
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validate import in_range, integer, non_negative, one_of, positive
from ..errors import ParameterError

__all__ = ["HEAT_LOSS_MODELS", "ChainLoss", "IntegralLoss", "Substrate", "heat_loss_from_dict"]

#: The names of the heat-loss models (``loss.model``).
HEAT_LOSS_MODELS = ("chain", "integral")
#: How the integral loss's operator is solved (``IntegralLoss.operator``).
INTEGRAL_OPERATORS = ("auto", "dense", "fast")
#: Largest number of sub-triangles of the dense single-layer operator
#: (:class:`~simulator.thermal.integral.IntegralOperator`): 4000 x 4000 is 128 MB per matrix
#: and about 2 s of assembly and Cholesky on one core. Above it ``IntegralLoss(operator="auto")``
#: takes the fast path (theory 4.7). Read from here wherever it is used (the operator, the sheet
#: refinement in force), so that one patch of it moves them all.
MAX_SUB_TRIANGLES = 4000


@dataclass(frozen=True)
class ChainLoss:
    """The paper's chain heat loss (theory 4.3).

    Parameters
    ----------
    thickness : float
        Medium thickness t_env [m] between the sheet and room temperature, > 0 (the paper
        suggests 1.5 x the panel length); capped per node by the distance to a
        thermal-boundary panel (the substrate).
    layers : int
        Medium layers N per node, >= 1.
    dissipation_angle : float
        Heat-spreading angle beta [rad] in [0, pi/2)
        (:data:`~simulator.model.thermal_parameters.REFERENCE_BETA` matches the reference).
    """

    thickness: float
    layers: int = 10
    dissipation_angle: float = math.radians(20)

    model = "chain"

    def __post_init__(self):
        positive("ChainLoss.thickness", self.thickness, "m",
                 hint="the chains' medium thickness t_env, e.g. 1.5 x the panel length")
        integer("ChainLoss.layers", self.layers, 1)
        in_range("ChainLoss.dissipation_angle", self.dissipation_angle, 0, math.pi / 2, "rad",
                 hint="the range is [0, pi/2)", open_high=True)

    def to_dict(self) -> dict:
        """``{"model": "chain", ...}``, the fields in SI units (FOLD model files, metadata)."""
        return {"model": "chain", "thickness": float(self.thickness), "layers": int(self.layers),
                "dissipation_angle": float(self.dissipation_angle)}

    def describe(self) -> str:
        """``chain model (the paper's; t_env = 750 um, 10 layers, beta = 20 deg)``."""
        return (f"chain model (the paper's; t_env = {1e6 * self.thickness:.4g} um, "
                f"{self.layers} layers, beta = {math.degrees(self.dissipation_angle):.3g} deg)")


@dataclass(frozen=True)
class IntegralLoss:
    """The calibration-free integral heat loss (theory 4.7).

    Parameters
    ----------
    refinement : int
        Sub-triangles per mesh-triangle edge m (m^2 per triangle), 1..16. On a refined sheet
        (``ThermalParameters.sheet_refinement`` r > 1) at least m, nested in the fine
        triangles: ``ceil(m / r)`` per fine triangle edge, at least 2 where extrapolated
        (theory 4.11, ``integral_levels.sheet_levels``).
    extrapolation : bool or None
        Richardson extrapolation from the refinements ``max(m // 2, 2)`` and ``m`` (removes
        the first-order error of the flux's edge singularity); needs m >= 3. None: True from
        m = 3 on. On a refined sheet the partner is half the fine level, at least 1 per fine
        edge (2 per mesh edge at r = 2).
    shape_tol : float
        The operator is rebuilt when a node-to-node distance (or a height over the substrate)
        changed by more than this fraction since the last build, >= 0.
    correction_tol : float
        The accurate operator is rebuilt only when the cheap one (m = 1; on a refined sheet
        one per fine triangle, the Richardson partner) changed by more than this fraction; in
        between it follows the shape through the cheap operator's change, >= 0 (0: rebuilt at
        ``shape_tol``).
    lumped : bool
        Lump the positive couplings of the loss conductance onto its diagonal (theory 4.9,
        the analogue of mass lumping): every positive off-diagonal entry of the final
        conductance (after extrapolation and correction) moves onto the diagonal of both its
        rows, so that it stays symmetric and the loss of a uniform rise (its row sums) is
        unchanged; with the monotone conduction no node is then below room temperature under
        heating alone (the discrete maximum principle). Its negative couplings are kept: the
        conductance is not diagonal. False (default): the consistent (Galerkin) conductance
        ``M^T S^-1 M``, which couples neighbouring nodes positively (the gripper's lowest
        node -7.6 K at 15 mW) but agrees with the 3-D FE reference on the same P1 sheet; the
        lumped one lowers the crease T_max by up to 9 % on the strips and folded devices and
        14 % on the crane against it (theory 4.9).
    operator : {"auto", "dense", "fast"}
        How the single-layer operator is solved (theory 4.7). "dense" forms and factorises
        it (:mod:`simulator.thermal.integral`, up to ``MAX_SUB_TRIANGLES`` sub-triangles per
        level); "fast" never forms it: the far field by a direct compiled sum or the fast
        multipole method, the near field sparse, the coupled system by preconditioned MINRES
        (:mod:`simulator.thermal.integral_fast`: the same discrete model, kept within
        ``shape_tol``; ``correction_tol`` does not apply). "auto" (default): "fast"
        above the dense limit (more than ``MAX_SUB_TRIANGLES`` sub-triangles at
        ``refinement``), else "dense".
    """

    refinement: int = 3
    extrapolation: bool | None = None
    shape_tol: float = 0.02
    correction_tol: float = 0.1
    lumped: bool = False
    operator: str = "auto"

    model = "integral"

    def __post_init__(self):
        integer("IntegralLoss.refinement", self.refinement, 1, 16)
        non_negative("IntegralLoss.shape_tol", self.shape_tol)
        non_negative("IntegralLoss.correction_tol", self.correction_tol)
        one_of("IntegralLoss.operator", self.operator, INTEGRAL_OPERATORS)
        if self.extrapolation is not None and not isinstance(self.extrapolation,
                                                             (bool, np.bool_)):
            raise ParameterError(f"IntegralLoss.extrapolation = {self.extrapolation!r} must be "
                                 "True, False or None (True from refinement = 3 on).")
        if self.extrapolation is not None:
            object.__setattr__(self, "extrapolation", bool(self.extrapolation))
        if not isinstance(self.lumped, (bool, np.bool_)):
            raise ParameterError(f"IntegralLoss.lumped = {self.lumped!r} must be True (the "
                                 "positive couplings lumped onto the diagonal) or False (the "
                                 "consistent conductance).")
        object.__setattr__(self, "lumped", bool(self.lumped))
        if self.lumped and self.operator == "fast":
            raise ParameterError("IntegralLoss(lumped=True, operator='fast'): the fast path never "
                                 "forms the conductance it would lump; use operator='dense' or "
                                 "'auto', or lumped=False.")
        if self.extrapolation and self.refinement < 3:
            raise ParameterError(f"IntegralLoss.extrapolation = True needs refinement >= 3, got "
                                 f"{self.refinement}: the coarse level max(m // 2, 2) must be "
                                 "below m; use refinement=3 (or extrapolation=False).")

    def takes_fast_path(self, n_triangles: int) -> bool:
        """Whether a sheet of ``n_triangles`` triangles is solved on the fast path (theory 4.7):
        ``operator`` "fast", or "auto" above the dense limit (more than
        ``MAX_SUB_TRIANGLES`` sub-triangles at ``refinement``)."""
        if self.operator != "auto":
            return self.operator == "fast"
        return int(n_triangles) * self.refinement ** 2 > MAX_SUB_TRIANGLES

    @property
    def extrapolated(self) -> bool:
        """Whether the operator is extrapolated (``extrapolation``; None: from m = 3 on)."""
        return self.refinement >= 3 if self.extrapolation is None else self.extrapolation

    def to_dict(self) -> dict:
        """``{"model": "integral", ...}`` (FOLD model files, metadata); ``lumped`` only when
        True and ``operator`` only when not the default "auto", so that the dicts of the
        default, and those written before the fields existed, are as they were."""
        out = {"model": "integral", "refinement": int(self.refinement),
               "extrapolation": self.extrapolation, "shape_tol": float(self.shape_tol),
               "correction_tol": float(self.correction_tol)}
        if self.lumped:
            out["lumped"] = True
        if self.operator != "auto":
            out["operator"] = self.operator
        return out

    def describe(self) -> str:
        """``integral model (calibration-free; m = 3, extrapolated)`` (``, lumped`` with
        :attr:`lumped`)."""
        return (f"integral model (calibration-free; m = {self.refinement}"
                f"{', extrapolated' if self.extrapolated else ''}"
                f"{', lumped' if self.lumped else ''}"
                f"{'' if self.operator == 'auto' else f', {self.operator} operator'})")


def heat_loss_from_dict(value) -> ChainLoss | IntegralLoss:
    """A heat loss from its ``to_dict()`` form (:meth:`ChainLoss.to_dict`,
    :meth:`IntegralLoss.to_dict`), or the object itself."""
    if isinstance(value, (ChainLoss, IntegralLoss)):
        return value
    if not isinstance(value, dict) or value.get("model") not in HEAT_LOSS_MODELS:
        raise ParameterError(f"heat loss {value!r}: give ChainLoss(thickness=...) or "
                             "IntegralLoss(), or a dict with 'model': 'chain' or 'integral' "
                             "and their fields.")
    fields = {k: v for k, v in value.items() if k != "model"}
    cls = ChainLoss if value["model"] == "chain" else IntegralLoss
    try:
        return cls(**fields)
    except TypeError as error:
        raise ParameterError(f"heat loss {value!r}: {error}; the fields of {cls.__name__} are "
                             f"{', '.join(cls.__dataclass_fields__)}.") from None


@dataclass(frozen=True)
class Substrate:
    """An isothermal plane at room temperature under the sheet (the integral loss's image
    plane; the chains' t_env cap comes from the thermal-boundary panels).

    ``Substrate()`` (the default of :class:`~simulator.model.thermal_parameters.ThermalParameters`):
    the plane of the model's thermal-boundary panels, where it has some (else none).
    ``Substrate.plane(point, normal)``: an explicit plane, a point (3,) [m] and a normal (3,)
    pointing into the medium, in the global frame. No substrate (an unbounded medium):
    ``substrate=None``.
    """

    point: tuple | None = None
    normal: tuple | None = None

    def __post_init__(self):
        if (self.point is None) != (self.normal is None):
            raise ParameterError("Substrate: give both point and normal (Substrate.plane(point, "
                                 "normal)), or neither (the plane of the boundary panels).")
        if self.point is None:
            return
        try:
            p = tuple(float(c) for c in self.point)
            n = tuple(float(c) for c in self.normal)
        except (TypeError, ValueError):
            p = n = ()
        if len(p) != 3 or len(n) != 3 or not all(map(math.isfinite, p + n)) or not any(n):
            raise ParameterError(f"Substrate.plane({self.point!r}, {self.normal!r}) is invalid: "
                                 "give a point (x, y, z) [m] and a non-zero normal (nx, ny, nz) "
                                 "pointing into the medium.")
        object.__setattr__(self, "point", p)
        object.__setattr__(self, "normal", n)

    @classmethod
    def plane(cls, point, normal) -> Substrate:
        """An explicit plane: a point (3,) [m] and a normal (3,) pointing into the medium."""
        return cls(tuple(point), tuple(normal))

    @property
    def from_panels(self) -> bool:
        """Whether the plane is the model's boundary panels' (no explicit plane)."""
        return self.point is None

    def as_tuple(self) -> tuple:
        """The explicit plane as 6 floats (point, normal), or () for the panels' plane."""
        return () if self.point is None else self.point + self.normal

    def to_dict(self):
        """``"boundary_panels"`` or ``{"point": [...], "normal": [...]}`` (FOLD, metadata)."""
        if self.point is None:
            return "boundary_panels"
        return {"point": list(self.point), "normal": list(self.normal)}

    @classmethod
    def from_value(cls, value) -> Substrate | None:
        """A substrate from :meth:`to_dict`'s forms, a 6-tuple (point, normal), () / None (no
        substrate) or the object itself."""
        if value is None or isinstance(value, Substrate):
            return value
        if isinstance(value, str):
            if value in ("boundary_panels", "model"):
                return cls()
            raise ParameterError(f"substrate = {value!r}: use 'boundary_panels', a plane "
                                 "{'point': [x, y, z], 'normal': [nx, ny, nz]} or None.")
        if isinstance(value, dict):
            if set(value) != {"point", "normal"}:
                raise ParameterError(f"substrate = {value!r}: a plane is {{'point': [x, y, z], "
                                     "'normal': [nx, ny, nz]}.")
            return cls.plane(value["point"], value["normal"])
        try:
            v = tuple(value)
        except TypeError:
            v = None
        if v == ():
            return None
        if v is not None and len(v) == 2:
            return cls.plane(*v)
        if v is not None and len(v) == 6:
            return cls.plane(v[:3], v[3:])
        raise ParameterError(f"substrate = {value!r}: give Substrate() (the boundary panels' "
                             "plane), Substrate.plane(point, normal), or None (no substrate).")
