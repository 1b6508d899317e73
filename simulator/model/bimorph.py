"""Timoshenko bi-material strip: curvature of a heated bimorph crease (theory 5.1-5.3).

A crease made of two bonded layers (moduli E1, E2, thicknesses t1, t2) whose thermal
expansion coefficients differ by ``delta_alpha`` bends with curvature (Timoshenko 1925)

    kappa = 6 delta_alpha dT (1 + m)^2 / (h [3 (1 + m)^2 + (1 + m n)(m^2 + 1/(m n))]),

with m = t1/t2, n = E1/E2, h = t1 + t2. The formula is invariant under swapping the
layers (m, n) -> (1/m, 1/n). Across a crease of width W the rotation is kappa W; its sign
follows ``delta_alpha`` (positive folds towards +z with the mesher's polarity).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .._validate import finite, non_negative, positive
from ..errors import ParameterError
from ..geometry.materials import GOLD, GOLD_FILM_CONDUCTIVITY, SU8
from .layers import Layer

__all__ = ["timoshenko_curvature", "Bimorph", "Actuators", "crease_temperature_weights"]


def timoshenko_curvature(delta_alpha, dT, E1, t1, E2, t2):
    """Curvature [1/m] of a bimorph for an expansion mismatch delta_alpha [1/K] and a
    temperature rise dT [K]; layer moduli E1, E2 [Pa] and thicknesses t1, t2 [m].
    All arguments broadcast."""
    m = np.asarray(t1, float) / t2
    n = np.asarray(E1, float) / E2
    h = np.asarray(t1, float) + t2
    return 6 * np.asarray(delta_alpha) * dT * (1 + m) ** 2 / (
        h * (3 * (1 + m) ** 2 + (1 + m * n) * (m**2 + 1 / (m * n))))


@dataclass(frozen=True)
class Bimorph:
    """The two actuator layers of a crease (e.g. gold on SU-8).

    Parameters
    ----------
    E1, t1 : float
        Modulus [Pa] and thickness [m] of layer 1 (gold in the paper's devices).
    E2, t2 : float
        Modulus [Pa] and thickness [m] of layer 2 (SU-8).
    k1, k2 : float
        In-plane thermal conductivity [W/(m K)] of layer 1 and layer 2, >= 0: the crease's
        sheet conductance ``k1 t1 + k2 t2`` [W/K] where the thermal parameters ask for
        ``crease_conduction="layers"`` (theory 4.10; unused with the default ``"paper"``).
        Defaults: a thin gold film,
        :data:`~simulator.geometry.materials.GOLD_FILM_CONDUCTIVITY` = 150 (bulk gold: 317),
        and SU-8, 0.3. The layer data live here, beside the layers' moduli and thicknesses,
        because the crease's conduction and its bending come from the same two layers.
    rho_c1, rho_c2 : float
        Volumetric heat capacity rho c [J/(m^3 K)] of layer 1 and layer 2, >= 0: the crease's
        areal heat capacity ``rho_c1 t1 + rho_c2 t2`` [J/(m^2 K)] in the transient model with
        ``crease_conduction="layers"`` (theory 7.2). Defaults: gold, 19300 kg/m^3 x 129
        J/(kg K) = 2.49e6 (Incropera et al., 6th ed., Table A.1; a film's specific heat is
        the bulk's), and the toolkit's SU-8, 1200 kg/m^3 x 1666.7 J/(kg K) = 2.0e6 (the
        reference's value, :data:`~simulator.geometry.materials.SU8`; "Determination of
        thermal and mechanical properties of SU-8" measured 1.6 J/(g K): theory 4.10).
    """

    E1: float
    t1: float
    E2: float
    t2: float
    k1: float = GOLD_FILM_CONDUCTIVITY
    k2: float = SU8.thermal_conductivity
    rho_c1: float = GOLD.density * GOLD.specific_heat
    rho_c2: float = SU8.density * SU8.specific_heat

    def __post_init__(self):
        for name in ("E1", "t1", "E2", "t2"):
            positive(f"Bimorph.{name}", getattr(self, name), "Pa" if name[0] == "E" else "m")
        for name, what in (("k1", "150 for a thin gold film"), ("k2", "0.3 for SU-8")):
            non_negative(f"Bimorph.{name}", getattr(self, name), "W/(m K)",
                         hint=f"give the layer's in-plane thermal conductivity, e.g. {what}")
        for name, what in (("rho_c1", "2.49e6 for gold"), ("rho_c2", "2.0e6 for SU-8")):
            non_negative(f"Bimorph.{name}", getattr(self, name), "J/(m^3 K)",
                         hint=f"give the layer's density times specific heat, e.g. {what}")

    @property
    def sheet_conductance(self) -> float:
        """In-plane sheet conductance ``k1 t1 + k2 t2`` of the two layers [W/K] (theory
        4.10)."""
        return float(self.k1) * float(self.t1) + float(self.k2) * float(self.t2)

    @property
    def layers(self) -> tuple:
        """The two layers as :class:`~simulator.model.layers.Layer` (conductivities ``k1``,
        ``k2``, heat capacities ``rho_c1``, ``rho_c2``): the stack of an actuated crease, and
        of a passive crease carrying the same heater film (``SheetLayers(creases={c:
        bimorph.layers})``; theory 4.10)."""
        return (Layer(self.t1, self.k1, self.rho_c1, "bimorph layer 1"),
                Layer(self.t2, self.k2, self.rho_c2, "bimorph layer 2"))

    @property
    def areal_capacity(self) -> float:
        """Areal heat capacity ``rho_c1 t1 + rho_c2 t2`` of the two layers [J/(m^2 K)]
        (theory 7.2)."""
        return float(self.rho_c1) * float(self.t1) + float(self.rho_c2) * float(self.t2)

    def curvature(self, delta_alpha, dT):
        """Curvature [1/m] for expansion mismatch [1/K] and temperature rise [K]."""
        return timoshenko_curvature(delta_alpha, dT, self.E1, self.t1, self.E2, self.t2)

    def to_dict(self) -> dict:
        return {"E1 [Pa]": self.E1, "t1 [m]": self.t1, "E2 [Pa]": self.E2, "t2 [m]": self.t2,
                "k1 [W/(m K)]": self.k1, "k2 [W/(m K)]": self.k2,
                "rho_c1 [J/(m^3 K)]": self.rho_c1, "rho_c2 [J/(m^3 K)]": self.rho_c2}


@dataclass(frozen=True)
class Actuators:
    """Which creases are bimorph actuators, and how they bend.

    Parameters
    ----------
    bimorph : Bimorph
        Layer data shared by all actuated creases (as in the reference).
    delta_alpha : mapping {crease id: delta_alpha [1/K]}
        Signed expansion mismatch of each actuated crease (alpha_SU8 - alpha_Au = 38e-6 /K in
        the paper; negative values fold the other way). Unlisted creases are passive.
    scatter : float
        Relative scatter of the actuation from crease to crease, >= 0 and < 0.5 (default 0,
        the reference's identical creases): each crease's rotation per kelvin is multiplied by
        ``1 + scatter z``, ``z`` a standard normal draw per crease id from ``seed``. It is the
        imperfection a fabricated sheet has. Without it, a symmetric pattern heated from a
        bifurcation takes the branch of its critical mode's sign, the same at any step count
        (theory 6.12); with a small one (1e-4 changes the folds by about 1e-4 of themselves) the
        branch taken can change with the seed, and with the step count.
    seed : int
        Seed of the scatter's draws.
    """

    bimorph: Bimorph
    delta_alpha: Mapping = field(default_factory=dict)
    scatter: float = 0.0
    seed: int = 0

    def __post_init__(self):
        if not isinstance(self.bimorph, Bimorph):
            raise ParameterError(f"Actuators.bimorph is a {type(self.bimorph).__name__}; give "
                                 "Bimorph(E1, t1, E2, t2) (delta_alpha is the second argument).")
        for c, v in dict(self.delta_alpha).items():
            finite(f"Actuators: delta_alpha of crease {c}", v, "1/K")
        finite("Actuators.scatter", self.scatter, "(a fraction)")
        if not 0.0 <= self.scatter < 0.5:
            raise ParameterError(
                f"Actuators.scatter = {self.scatter!r}: the relative scatter of the creases' "
                "actuation must be >= 0 and < 0.5 (1e-4 selects a branch, 0.05 is a fabricated "
                "sheet's scatter).")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) \
                or self.seed < 0:
            raise ParameterError(f"Actuators.seed = {self.seed!r}: give an integer >= 0.")

    def delta_alpha_array(self, mesh) -> np.ndarray:
        """(C,) expansion mismatch per crease row of a mesh (0 for passive creases)."""
        out = np.zeros(mesh.n_creases)
        for c, v in dict(self.delta_alpha).items():
            out[mesh.crease_row_of(c)] = float(v)
        return out

    def rotation_per_kelvin(self, mesh) -> np.ndarray:
        """(C,) rest-angle change per kelvin of crease temperature rise [rad/K]: kappa/dT x W."""
        width = mesh.pattern.crease_width[mesh.crease_ids]
        rot = self.bimorph.curvature(self.delta_alpha_array(mesh), 1.0) * width
        return rot if self.scatter == 0 else rot * self.scatter_factors(mesh)

    def scatter_factors(self, mesh) -> np.ndarray:
        """(C,) factor ``1 + scatter z`` of each crease row's actuation (:attr:`scatter`): the
        draws are made per crease id (the same crease gets the same factor in any mesh of the
        pattern)."""
        ids = np.asarray(mesh.crease_ids, int)
        z = np.random.default_rng(int(self.seed)).standard_normal(int(ids.max(initial=-1)) + 1)
        return 1.0 + self.scatter * z[ids]

    def to_dict(self) -> dict:
        out = {"bimorph": self.bimorph.to_dict(),
               "delta_alpha [1/K]": {str(k): float(v) for k, v in dict(self.delta_alpha).items()}}
        if self.scatter:
            out |= {"scatter": float(self.scatter), "seed": int(self.seed)}
        return out


def crease_temperature_weights() -> np.ndarray:
    """Weights of the 7 crease nodes (N11, N12, N21, N22, A, B, Ctr) in the crease temperature
    used for actuation (theory 5.1): half the mean of the 3 centre-line nodes plus half the
    mean of the 4 edge nodes."""
    return np.array([1 / 8, 1 / 8, 1 / 8, 1 / 8, 1 / 6, 1 / 6, 1 / 6])
