"""How the gripper's heat balance is modelled: the evaluation's choice, not the device's.

:class:`GripperHeatModel` holds the heat-loss model and its levels, the sheet's conduction and
refinement, the creases' in-plane conduction, the air's conductivity law and the radiation of
the surfaces (theory 4.3-4.12). It is given where an evaluation is configured:
``make_gripper_model(design, heat=...)``, ``evaluate_gripper(design, heat=...)``,
``GripperProblem(heat=...)``. :class:`~design.devices.gripper.GripperDesign` is the device
(geometry, layers, residual folds, the air's constant conductivity, the heaters' leads); its
former heat-model fields still work for one release, with a deprecation warning.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from simulator import ChainLoss, IntegralLoss, ParameterError, Substrate, ThermalParameters
from simulator.thermal import CONDUCTIONS, REFERENCE_BETA, SHEET_EXTRAPOLATIONS, sheet_levels
from simulator._validate import in_range, integer, one_of, positive

__all__ = ["GripperHeatModel", "HEAT_FIELDS", "LOSS_MODELS", "GRIPPER_TRIANGLES"]

#: Heat-loss models of :attr:`GripperHeatModel.loss_model` (theory 4.3 and 4.7).
LOSS_MODELS = ("chain", "integral")
#: How a crease conducts in-plane (:class:`~simulator.ThermalParameters` ``crease_conduction``).
_CREASE_CONDUCTIONS = ("paper", "layers")
#: Triangles of the gripper's mesh (every design: the dimensions move its nodes only).
GRIPPER_TRIANGLES = 48
#: The fields of :class:`GripperHeatModel`, which were :class:`GripperDesign`'s until issue 31.
HEAT_FIELDS = ("loss_model", "integral_refinement", "conduction", "sheet_refinement",
               "crease_conduction", "k_gold", "temperature_dependent_air", "emissivity_polymer",
               "emissivity_gold")


@dataclass(frozen=True)
class GripperHeatModel:
    """How the gripper's steady heat transfer is modelled (the defaults: the integral loss,
    the paper's crease conduction, constant air, no radiation).

    Parameters
    ----------
    loss_model : {"integral", "chain"}
        Heat loss: ``"integral"`` (default since 7 Dec 2026; theory 4.7: the single-layer
        potential of the sheet in the air over the isothermal substrate plane ``undercut``
        below the sheet, nothing fitted, within 3.2 % of the 3-D FE on the gripper) or
        ``"chain"`` (the paper's fitted chains, its optimisation's setting: 37-80 % too cool
        against the FE, about 2.7 times faster).
    integral_refinement : int
        Sub-triangles per triangle edge of the ``"integral"`` model
        (:class:`~simulator.ThermalParameters` ``integral_refinement``, 1-16, default 3:
        Richardson-extrapolated from 3 on, corrected between rebuilds; theory 4.7).
    conduction : {"t3", "monotone"} or None
        The sheet's conduction (default None: the loss model's, T3 with the chains and
        monotone with the integral loss; :class:`~simulator.ThermalParameters`
        ``conduction``, theory 4.9).
    sheet_refinement : int or None
        The sheet split into ``r^2`` per mesh triangle for the heat balance
        (:class:`~simulator.ThermalParameters` ``sheet_refinement``, theory 4.11; the integral
        model only), or None (default: the loss model's, 1 with the chains and 2 with the
        integral loss at ``integral_refinement`` up to 5).
    crease_conduction : {"paper", "layers"}
        How an actuated crease conducts in-plane (theory 4.10): ``"paper"`` (default: one
        polymer layer over the crease thickness, the reference's) or ``"layers"`` (the gold
        and SU-8 layers in parallel, ``k_gold t_gold + k2 t_su8``).
    k_gold : float or None
        In-plane thermal conductivity of the crease's gold film [W/(m K)] with
        ``crease_conduction="layers"``, or None (default: :class:`~simulator.Bimorph`'s
        thin-film value, 150; plausible 100-300, bulk 317; theory 4.10).
    temperature_dependent_air : bool
        The air's conductivity follows Incropera's Table A.4 (theory 4.12) instead of the
        design's constant ``env_conductivity`` (default False, the paper setting).
    emissivity_polymer, emissivity_gold : float
        Total hemispherical emissivities [-] of the polymer (the SPR panels, the creases'
        SU-8 face) and of the creases' gold face (theory 4.12); a crease radiates with the
        mean of its two faces'. Default 0 (no radiation, the paper setting); plausible
        0.5-0.9 for the thin polymer films, 0.02-0.05 for evaporated gold.
    sheet_extrapolation : bool or str
        The steady temperatures extrapolated from the sheet refined ``r`` and ``2 r``,
        ``2 T(2r) - T(r)`` (:class:`~simulator.ThermalParameters` ``sheet_extrapolation``,
        theory 4.13: the crease metal layer's effect converges so; True, each sheet its own
        loss operator, 5-14 times the evaluation's cost at r = 2; ``"r+1"``, from the sheets
        refined r and r + 1, about 3 times the cost).
        Default False; the integral loss on a sheet refined 2 to 8 only.
    """

    loss_model: str = "integral"
    integral_refinement: int = 3
    conduction: str | None = None
    sheet_refinement: int | None = None
    crease_conduction: str = "paper"
    k_gold: float | None = None
    temperature_dependent_air: bool = False
    emissivity_polymer: float = 0.0
    emissivity_gold: float = 0.0
    sheet_extrapolation: bool | str = False

    def __post_init__(self):
        one_of("GripperHeatModel.loss_model", self.loss_model, LOSS_MODELS)
        integer("GripperHeatModel.integral_refinement", self.integral_refinement, 1, 16)
        if self.conduction is not None:
            one_of("GripperHeatModel.conduction", self.conduction, CONDUCTIONS)
        if self.sheet_refinement is not None:
            integer("GripperHeatModel.sheet_refinement", self.sheet_refinement, 1, 16)
            if self.sheet_refinement > 1 and self.loss_model != "integral":
                raise ParameterError(f"GripperHeatModel.sheet_refinement = "
                                     f"{self.sheet_refinement} needs loss_model='integral' (the "
                                     "chains were fitted on the mesh triangles); use "
                                     "sheet_refinement=None or 1.")
        one_of("GripperHeatModel.crease_conduction", self.crease_conduction,
               _CREASE_CONDUCTIONS)
        positive("GripperHeatModel.k_gold", self.k_gold, "W/(m K)",
                 "100-300 for a thin gold film (bulk 317), or None for the default 150",
                 allow_none=True)
        if self.k_gold is not None and self.crease_conduction != "layers":
            raise ParameterError(f"GripperHeatModel.k_gold = {self.k_gold!r} W/(m K) acts only "
                                 "with crease_conduction='layers' (the paper setting conducts "
                                 "a crease as one polymer layer); set crease_conduction="
                                 "'layers' or leave k_gold None.")
        if not isinstance(self.temperature_dependent_air, (bool, np.bool_)):
            raise ParameterError(f"GripperHeatModel.temperature_dependent_air = "
                                 f"{self.temperature_dependent_air!r} must be True or False.")
        for name in ("emissivity_polymer", "emissivity_gold"):
            in_range(f"GripperHeatModel.{name}", getattr(self, name), 0.0, 1.0, "",
                     "0 without radiation (the paper setting), 0.5-0.9 a thin polymer film, "
                     "0.02-0.05 evaporated gold")
        self._check_extrapolation()

    def _check_extrapolation(self):
        """Check :attr:`sheet_extrapolation` (the integral loss, a sheet refined 2 to 8)."""
        if not (isinstance(self.sheet_extrapolation, (bool, np.bool_))
                or (isinstance(self.sheet_extrapolation, str)
                    and self.sheet_extrapolation in SHEET_EXTRAPOLATIONS)):
            raise ParameterError(f"GripperHeatModel.sheet_extrapolation = "
                                 f"{self.sheet_extrapolation!r} must be True or False, or "
                                 "'r+1' (the sheets r and r + 1).")
        if self.sheet_extrapolation and (self.loss_model != "integral"
                                         or not 2 <= self.sheet_refinement_in_force <= 8):
            raise ParameterError(
                f"GripperHeatModel.sheet_extrapolation = {self.sheet_extrapolation!r} "
                f"extrapolates from the sheet refined r and a finer one, r from 2 to 8 (theory "
                f"4.13); given loss_model = {self.loss_model!r} and sheet_refinement = {self.sheet_refinement!r}: use "
                "loss_model='integral' with sheet_refinement None or 2-8, or "
                "sheet_extrapolation=False.")

    def loss_parameters(self, design) -> dict:
        """The :class:`~simulator.ThermalParameters` fields of the heat-loss model on
        ``design``: the chains (t_env 1.5 x the mean of L1 and L2, the reference's beta; the
        substrate from the boundary panels), else the integral model over the substrate
        plane (the substrate panel's plane, ``design.undercut`` below the sheet, normal +z
        into the air)."""
        if self.loss_model == "chain":
            return {"loss": ChainLoss(thickness=1.5 * (design.L1 + design.L2) / 2,
                                      dissipation_angle=REFERENCE_BETA)}
        return {"loss": IntegralLoss(refinement=self.integral_refinement),
                "substrate": Substrate.plane((0.0, 0.0, -design.undercut), (0.0, 0.0, 1.0))}

    @property
    def sheet_refinement_in_force(self) -> int:
        """The sheet refinement of the heat balance (:attr:`sheet_refinement`, or the loss
        model's for the gripper mesh's :data:`GRIPPER_TRIANGLES` triangles)."""
        if self.sheet_refinement is not None:
            return self.sheet_refinement
        return self._thermal().sheet_refinement_for(GRIPPER_TRIANGLES)

    @property
    def integral_levels_in_force(self) -> str:
        """The integral loss's levels per mesh triangle edge in force on the gripper's sheet,
        ``"m/partner"`` (``"m"`` without extrapolation; theory 4.11: ``"4/2"`` at the default
        m = 3 on the sheet refined r = 2, ``"3/2"`` on the mesh triangles)."""
        r = self.sheet_refinement_in_force
        m, c = sheet_levels(self._thermal().loss, r)
        return f"{r * m}" + (f"/{r * c}" if c is not None else "")

    def _thermal(self) -> ThermalParameters:
        """The loss model alone (its levels and the sheet refinement in force do not depend
        on the design's dimensions: the start design's stand in)."""
        return ThermalParameters(**self.loss_parameters(_START))


#: The start design's dimensions [m] that the loss model reads (:meth:`loss_parameters`).
_START = SimpleNamespace(L1=1000e-6, L2=1000e-6, undercut=150e-6)
