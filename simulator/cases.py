"""Ready-made cases of the paper (Zhu & Filipov 2021), defaults from theory 10.

Every case is a function returning a :class:`Case` (model + loading steps) and accepts
keyword overrides; units are in the parameter names or listed in ``CASES[name].units``.
Node and crease ids below are 0-based (reference id - 1).

:func:`get_case` and :class:`Case` are at ``simulator``'s door; this namespace
(``simulator.cases``) also has the list of cases with their parameters (:func:`describe_cases`,
:func:`parameter_note`) and the model builders the cases share (:func:`miura_sheet_model`,
:func:`single_fold_model`).
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from dataclasses import dataclass, field

import numpy as np


from .case_notes import parameter_note
from .model.bimorph import Actuators, Bimorph
from ._validate import integer, non_negative, positive
from .errors import ParameterError
from .simulation import simulate
from .solvers.dynamics_options import DynamicsOptions
from .thermal.schedules import StepPower
from .steps import ArcLengthLoad, ElectroThermal, Gravity, Heat, SelfFold
from .geometry.materials import AIR, Material
from .model.mesh import make_mesh
from .model.model import REFERENCE_GRAVITY, ContactParameters, Model, Supports, make_model
from .geometry.example_patterns import (crane_pattern, double_fold_pattern, fold_directions, miura_sheet_pattern,
                       miura_vertices, roof_pattern, single_fold_pattern, strip_pattern,
                       with_substrate)
from .model.properties import BarHingeParameters
from .solvers.newton import NewtonOptions
from .model.heat_loss import ChainLoss, IntegralLoss
from .model.thermal_parameters import REFERENCE_BETA, ThermalParameters

__all__ = ["Case", "get_case", "describe_cases", "parameter_note", "CASES", "miura_sheet_model",
           "miura_fold_signs", "single_fold_model", "SINGLE_FOLD_SUPPORTS", "CRANE_POWER_MW"]

#: alpha_SU8 - alpha_Au [1/K] (52e-6 - 14e-6), the actuators of the paper's devices.
DELTA_ALPHA_AU_SU8 = 38e-6


@dataclass(frozen=True, eq=False)
class Case:
    """A model with its loading sequence and the parameters that made it."""

    name: str
    model: Model
    steps: tuple
    parameters: dict = field(default_factory=dict)
    description: str = ""

    def run(self, options: NewtonOptions = NewtonOptions(), progress=None):
        """Simulate all steps; returns a :class:`~simulator.results.SimulationResult`."""
        return simulate(self.model, self.steps, options=options, progress=progress)


CASES: dict = {}


def _case(**units):
    def register(fn):
        fn.units = units
        CASES[fn.__name__] = fn
        return fn
    return register


def get_case(name: str, **overrides) -> Case:
    """Build a case by name (``single_fold`` or ``single-fold``) with keyword overrides."""
    key = name.replace("-", "_")
    if key not in CASES:
        raise ParameterError(f"Unknown case {name!r}; available: "
                             f"{', '.join(n.replace('_', '-') for n in CASES)}.")
    fn = CASES[key]
    params = inspect.signature(fn).parameters
    unknown = [k for k in overrides if k not in params]
    if unknown:
        raise ParameterError(f"Case {name!r} has no parameter {unknown[0]!r}; parameters: "
                             f"{', '.join(params)}.")
    return fn(**overrides)


def describe_cases() -> list:
    """[(name, summary, [(parameter, default, unit), ...]), ...] for every case; the summary
    is the first paragraph of the case's docstring, on one line."""
    out = []
    for name, fn in CASES.items():
        doc = " ".join((fn.__doc__ or "").strip().split("\n\n")[0].split())
        params = [(p.name, p.default, fn.units.get(p.name, ""))
                  for p in inspect.signature(fn).parameters.values()]
        out.append((name, doc, params))
    return out


def _power(power_mW):
    non_negative("power_mW", power_mW, "mW")
    return power_mW * 1e-3


def _check(**kw):
    for k, v in kw.items():
        positive(k, v)


def _fold_deg(name, value):
    """A fold angle given in degrees, checked to lie in (-180, 180]; returned in rad."""
    if not (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value) and -180.0 < value <= 180.0):
        raise ParameterError(f"{name} = {value!r} deg must be a fold angle in degrees in "
                             "(-180, 180] (0 flat, > 0 folded up).")
    return math.radians(value)


def _steps_int(name, value):
    return integer(name, value)


# ------------------------------------------------------------------------------ strip
@_case(W="-", L="-", L1="-", L2="-", tc="-", tp="-", beta_deg="deg", t_env="-")
def verification_strip(variant: str = "loss", W: float = 0.4, L: float = 1.0, L1: float = 1.0,
                       L2: float = 1.0, tc: float = 0.001, tp: float = 0.01,
                       beta_deg: float = 20.0, t_env: float = 3.0, layers: int = 10) -> Case:
    """Verification strip (theory 10.7): heat Q = 10 W L tc on one crease, non-dimensional.

    ``variant="within"``: conduction only (k = 1, no environment); ``"loss"``: k = 0.3 with
    heat loss to an environment (k_env = 0.026, beta converted with 3.14 as the reference).
    """
    if variant not in ("within", "loss"):
        raise ParameterError(f"variant = {variant!r}; use 'within' or 'loss'.")
    _check(W=W, L=L, L1=L1, L2=L2, tc=tc, tp=tp, t_env=t_env)
    k = 1.0 if variant == "within" else 0.3
    mat = Material("strip", youngs_modulus=2e9, poisson_ratio=0.3, thermal_conductivity=k)
    pattern = strip_pattern(W=W, L=L, L1=L1, L2=L2, crease_thickness=tc, panel_thickness=tp,
                            material=mat)
    if variant == "within":
        thermal = ThermalParameters(loss=ChainLoss(thickness=1.0, layers=1),
                                    medium=AIR.with_properties(thermal_conductivity=0.0),
                                    room_temperature=0.0, room_temperature_nodes=(0, 3, 5, 6))
    else:
        thermal = ThermalParameters(loss=ChainLoss(thickness=t_env,
                                                   layers=_steps_int("layers", layers),
                                                   dissipation_angle=beta_deg / 180 * 3.14),
                                    medium=AIR, room_temperature=0.0,
                                    room_temperature_nodes=(0, 3, 5, 6))
    model = make_model(pattern, Supports.nodes([0, 1, 2, 3, 8, 9, 10, 11]), thermal=thermal)
    return Case("verification_strip", model, (Heat({2: 10 * W * L * tc}, increments=1,
                                                    coupling="staggered"),),
                dict(variant=variant, W=W, L=L, L1=L1, L2=L2, tc=tc, tp=tp, beta_deg=beta_deg,
                     t_env=t_env, layers=layers), verification_strip.__doc__)


# ------------------------------------------------------------------------------ single fold
#: Supports of the reference single fold (theory 10.1), 0-based nodes: anchor edge and substrate.
SINGLE_FOLD_SUPPORTS = Supports({0: "z", 1: "z", 2: "yz", 3: "xyz", 8: "xyz", 9: "xyz",
                                 10: "xyz", 11: "xyz"})
#: The same without the substrate panel (nodes 8-11).
_SINGLE_FOLD_SUPPORTS_FREE = Supports({0: "z", 1: "z", 2: "yz", 3: "xyz"})


def single_fold_model(contact: bool = True, substrate: bool = True, thermal=None, actuators=None,
                      **pattern_kwargs) -> Model:
    """Model of the reference single fold (Example01, theory 10.1): the one builder of the
    single-fold cases, the demo and the tests.

    Parameters
    ----------
    contact : bool
        Substrate contact (``ContactParameters(1e-4, 40e-6, 40e-6)``: stiffness 1e-4, d0 and
        d1 40 um), only meaningful with the substrate.
    substrate : bool
        Include the substrate panel (supported) under the folding panel.
    thermal, actuators : optional
        :class:`~simulator.model.thermal_parameters.ThermalParameters` and :class:`~simulator.model.bimorph.Actuators`,
        needed for heating steps.
    **pattern_kwargs
        Geometry of :func:`~simulator.geometry.example_patterns.single_fold_pattern` (SI units).
    """
    pattern = single_fold_pattern(substrate=substrate, **pattern_kwargs)
    supports = SINGLE_FOLD_SUPPORTS if substrate else _SINGLE_FOLD_SUPPORTS_FREE
    return make_model(pattern, supports, BarHingeParameters(diagonal_rate=1000),
                      contact=ContactParameters(1e-4, 40e-6, 40e-6) if contact else None,
                      thermal=thermal, actuators=actuators)


def _single_fold_case(name, *, residual_fold_deg, gravity, thermal_steps, power_mW,
                      env_conductivity, crease_width, env_thickness, coupling, t_gold, t_su8,
                      panel_thickness, L, undercut, E_gold, delta_alpha, self_fold_steps,
                      room_nodes=(0, 3), loss_model="chain"):
    _check(crease_width=crease_width, env_thickness=env_thickness, t_gold=t_gold, t_su8=t_su8)
    if not (isinstance(env_conductivity, (int, float)) and env_conductivity >= 0):
        raise ParameterError(f"env_conductivity = {env_conductivity!r} must be >= 0 W/(m K).")
    thermal = ThermalParameters(
        loss=_case_loss(name, loss_model, ChainLoss(thickness=env_thickness,
                                                    dissipation_angle=REFERENCE_BETA)),
        medium=AIR.with_properties(thermal_conductivity=env_conductivity),
        boundary_panels=(2,), room_temperature_nodes=room_nodes)
    actuators = Actuators(Bimorph(E1=E_gold, t1=t_gold, E2=2e9, t2=t_su8), {2: delta_alpha})
    model = single_fold_model(thermal=thermal, actuators=actuators, L=L, W=crease_width,
                              undercut=undercut, panel_thickness=panel_thickness,
                              crease_thickness=t_gold + t_su8)
    steps = [SelfFold({2: _fold_deg("residual_fold_deg", residual_fold_deg)},
                      increments=self_fold_steps)]
    if gravity:
        steps.append(Gravity(g=REFERENCE_GRAVITY, panels=[1], increments=50))
    steps.append(Heat({2: _power(power_mW)}, increments=_steps_int("thermal_steps", thermal_steps),
                      coupling=coupling))
    return Case(name, model, tuple(steps))


@_case(residual_fold_deg="deg", thermal_steps="-", power_mW="mW", env_conductivity="W/(m K)",
       crease_width="m", env_thickness="m", loss_model="")
def single_fold(residual_fold_deg: float = 0.0, gravity: bool = False, thermal_steps: int = 500,
                power_mW: float = 100.0, env_conductivity: float = 0.6,
                crease_width: float = 200e-6, env_thickness: float = 750e-6,
                coupling: str = "staggered", loss_model: str = "chain") -> Case:
    """Single crease over a substrate heated to power_mW (reference Example01, theory 10.1).

    Defaults are exactly the reference's: residual fold 0, gravity off, k_env = 0.6 (water-like),
    500 increments to 100 mW. The paper's threshold study uses gravity=True and a negative
    residual fold. ``loss_model``: ``"chain"`` (the reference's chains, t_env =
    ``env_thickness``) or ``"integral"`` (nothing to fit; ``env_thickness`` unused; the
    substrate is the boundary panel's plane).
    """
    params = {k: v for k, v in locals().items()}
    case = _single_fold_case(
        "single_fold", residual_fold_deg=residual_fold_deg, gravity=gravity,
        thermal_steps=thermal_steps, power_mW=power_mW, env_conductivity=env_conductivity,
        crease_width=crease_width, env_thickness=env_thickness, coupling=coupling,
        t_gold=0.1e-6, t_su8=0.4e-6, panel_thickness=21e-6, L=0.5e-3, undercut=150e-6,
        E_gold=39.5e9, delta_alpha=DELTA_ALPHA_AU_SU8, self_fold_steps=80, loss_model=loss_model)
    return Case(case.name, case.model, case.steps, params, single_fold.__doc__)


@_case(residual_fold_deg="deg", thermal_steps="-", power_mW="mW", env_conductivity="W/(m K)",
       crease_width="m", env_thickness="m")
def single_fold_prefolded(residual_fold_deg: float = 55.0, gravity: bool = False,
                          thermal_steps: int = 500, power_mW: float = 10.0,
                          env_conductivity: float = 0.026, crease_width: float = 300e-6,
                          env_thickness: float = 750e-6, coupling: str = "staggered") -> Case:
    """Pre-folded single crease that unfolds when heated (reference Example08, theory 10.5)."""
    params = {k: v for k, v in locals().items()}
    case = _single_fold_case(
        "single_fold_prefolded", residual_fold_deg=residual_fold_deg, gravity=gravity,
        thermal_steps=thermal_steps, power_mW=power_mW, env_conductivity=env_conductivity,
        crease_width=crease_width, env_thickness=env_thickness, coupling=coupling,
        t_gold=0.2e-6, t_su8=0.86e-6, panel_thickness=6e-6, L=0.5e-3, undercut=50e-6,
        E_gold=39.5e9, delta_alpha=-DELTA_ALPHA_AU_SU8, self_fold_steps=80)
    return Case(case.name, case.model, case.steps, params, single_fold_prefolded.__doc__)


#: Mesh nodes of the chip (anchor panel and substrate) of the single fold, held at room
#: temperature by :func:`single_fold_step_response` (a heat sink).
SINGLE_FOLD_CHIP_NODES = (0, 1, 2, 3, 8, 9, 10, 11, 15, 17)


@_case(power_mW="mW", t_on="s", t_off="s", dt="s", dt_min="s", dt_max="s",
       residual_fold_deg="deg", air_damping="N s/m^3", env_conductivity="W/(m K)",
       shape_tol="m")
def single_fold_step_response(power_mW: float = 3.0, t_on: float = 1.0, t_off: float = 1.0,
                              dt: float = 1e-3, dt_min: float = 1e-5, dt_max: float = 5e-3,
                              mechanics: str = "dynamic", residual_fold_deg: float = 0.0,
                              air_damping: float = 2.0, env_conductivity: float = 0.026,
                              shape_tol: float = 5e-6, record_every: int = 1) -> Case:
    """Single crease (gravity, substrate) in air under a power step: on for t_on, off for t_off.

    The geometry and actuator of ``single_fold``; the chip (anchor panel and substrate) is a
    heat sink at room temperature. Self-fold to the residual fold, gravity, then one
    :class:`~simulator.steps.ElectroThermal` step of ``t_on + t_off`` seconds with adaptive time
    steps in [dt_min, dt_max]. ``air_damping`` [N s/m^3] is a squeeze-film estimate for the
    panel 150 um above the substrate (damping ratio about 0.08 for the 40 Hz fold mode).
    ``shape_tol`` [m]: the heat matrices are re-assembled when a node has moved more than this
    (5 um: 88 instead of 499 assemblies on the default run, fold at the end of the on-phase
    within 1e-5 deg of re-assembling every step).
    """
    params = {k: v for k, v in locals().items()}
    _check(t_on=t_on, t_off=t_off)
    if not (isinstance(air_damping, (int, float)) and math.isfinite(air_damping)
            and air_damping >= 0):
        raise ParameterError(f"air_damping = {air_damping!r} must be >= 0 N s/m^3.")
    case = _single_fold_case(
        "single_fold_step_response", residual_fold_deg=residual_fold_deg, gravity=True,
        thermal_steps=1, power_mW=power_mW, env_conductivity=env_conductivity,
        crease_width=200e-6, env_thickness=750e-6, coupling="staggered",
        t_gold=0.1e-6, t_su8=0.4e-6, panel_thickness=21e-6, L=0.5e-3, undercut=150e-6,
        E_gold=39.5e9, delta_alpha=DELTA_ALPHA_AU_SU8, self_fold_steps=80,
        room_nodes=SINGLE_FOLD_CHIP_NODES)
    pulse = StepPower(_power(power_mW), 0.0, t_on)
    step = ElectroThermal({2: pulse}, duration=t_on + t_off, dt=dt, dt_min=dt_min,
                          dt_max=dt_max, mechanics=mechanics, shape_tol=shape_tol,
                          options=DynamicsOptions(method="generalized_alpha", rho_inf=0.5,
                                                  rtol=1e-6, air_damping=air_damping),
                          record_every=_steps_int("record_every", record_every))
    return Case("single_fold_step_response", case.model, (*case.steps[:-1], step), params,
                single_fold_step_response.__doc__)


# ------------------------------------------------------------------------------ double fold
@_case(residual_fold_deg="deg", thermal_steps="-", power_mW="mW per crease",
       env_conductivity="W/(m K)", gravity_scale="-", loss_model="")
def double_fold(residual_fold_deg: float = 0.0, gravity: bool = True, gravity_scale: float = 0.9,
                thermal_steps: int = 250, power_mW: float = 10.0,
                env_conductivity: float = 0.026, coupling: str = "staggered",
                loss_model: str = "chain") -> Case:
    """Anchor and two folding panels over a substrate, both creases heated (Example02, 8.2).

    Fold 2 (crease 5, farther from the substrate) gets hotter and folds more than fold 1.
    ``loss_model``: the heat loss, ``"chain"`` (the reference's chains, t_env = 600 um) or
    ``"integral"`` (nothing to fit; the substrate is the boundary panel's plane).
    """
    params = {k: v for k, v in locals().items()}
    pattern = double_fold_pattern()
    thermal = ThermalParameters(
        loss=_case_loss("double_fold", loss_model,
                        ChainLoss(thickness=600e-6, dissipation_angle=REFERENCE_BETA)),
        medium=AIR.with_properties(thermal_conductivity=env_conductivity),
        boundary_panels=(3,), room_temperature_nodes=(0, 3))
    actuators = Actuators(Bimorph(E1=0.7 * 79e9, t1=0.2e-6, E2=2e9, t2=0.9e-6),
                          {2: DELTA_ALPHA_AU_SU8, 5: DELTA_ALPHA_AU_SU8})
    supports = Supports({0: "z", 1: "z", 2: "yz", 3: "xyz", 12: "xyz", 13: "xyz", 14: "xyz",
                         15: "xyz"})
    model = make_model(pattern, supports, BarHingeParameters(diagonal_rate=1000),
                       contact=ContactParameters(1e-4, 20e-6, 20e-6), thermal=thermal,
                       actuators=actuators)
    rf = _fold_deg("residual_fold_deg", residual_fold_deg)
    steps = [SelfFold({2: rf, 5: rf}, increments=50)]
    if gravity:
        steps.append(Gravity(g=REFERENCE_GRAVITY, scale=gravity_scale, panels=[1, 2],
                             increments=80))
    steps.append(Heat({(2, 5): _power(power_mW)}, increments=_steps_int("thermal_steps",
                                                                         thermal_steps),
                      coupling=coupling))
    return Case("double_fold", model, tuple(steps), params, double_fold.__doc__)



def _case_loss(case: str, loss_model: str, chain: ChainLoss):
    """A case's heat loss by name: ``"chain"`` (the reference's ``chain``) or ``"integral"``
    (:class:`~simulator.model.heat_loss.IntegralLoss` at its defaults)."""
    if loss_model not in ("chain", "integral"):
        raise ParameterError(f"{case}: loss_model = {loss_model!r}; use 'chain' (the "
                             "reference's) or 'integral' (calibration-free).")
    return chain if loss_model == "chain" else IntegralLoss()


# ------------------------------------------------------------------------------ Miura lifter
def miura_fold_signs(a, b, gamma, m, n) -> dict:
    """Fold direction (+1 / -1) of every crease of a Miura sheet, from a partly folded shape.

    Parameters
    ----------
    a, b : float
        Panel edge lengths [m] (as :func:`miura_sheet_model`).
    gamma : float
        Sector angle [rad], in (0, pi/2).
    m, n : int
        Cells along x and y.

    Returns
    -------
    dict
        Crease (edge) id of :func:`simulator.example_patterns.miura_sheet_pattern` -> +1
        (folds towards +z) or -1 (towards -z), in the sign convention of
        :func:`~simulator.mechanics.fold_angles`.
    """
    v, p = miura_vertices(a, b, gamma, m, n, ext=0.8)
    return fold_directions(v, p)


def miura_sheet_model(a: float = 1e-3, b: float = 1e-3, gamma: float = math.radians(60.0),
                      cells_x: int = 2, cells_y: int = 2, crease_width: float = 200e-6,
                      t_gold: float = 0.2e-6, t_su8: float = 0.8e-6,
                      panel_thickness: float = 10e-6, substrate: bool = False,
                      undercut: float = 100e-6) -> Model:
    """The Miura-ori lifter's model (paper 6.2, Example03, theory 10.3): the one builder behind
    the ``miura_lifter`` case and :func:`design.devices.miura.make_miura_model`.

    A Miura sheet of ``cells_x`` x ``cells_y`` cells, clamped along its first column of panels
    (x = 0 side); every crease an actuator (gold ``t_gold`` on SU-8 ``t_su8``, the crease
    ``t_gold + t_su8`` thick, ``|delta_alpha|`` = 50e-6 /K with the Miura fold directions);
    optionally over a clamped substrate ``undercut`` below that is a thermal boundary and a
    contact surface.

    Parameters
    ----------
    a, b : panel sides [m]
    gamma : sector angle [rad]
    cells_x, cells_y : cells along x and y
    crease_width : [m]
    t_gold, t_su8 : actuator layer thicknesses [m]
    panel_thickness : SU-8 panel thickness [m]
    substrate : bool
    undercut : gap between sheet and substrate [m]
    """
    m, n = cells_x, cells_y
    pattern = miura_sheet_pattern(a, b, gamma, m, n, W=crease_width,
                                  crease_thickness=t_gold + t_su8,
                                  panel_thickness=panel_thickness)
    boundary = ()
    if substrate:
        pattern = with_substrate(pattern, undercut=undercut, margin=0.5 * max(a, b))
        boundary = (pattern.n_panels - 1,)
    signs = miura_fold_signs(a, b, gamma, m, n)
    actuators = Actuators(Bimorph(E1=50e9, t1=t_gold, E2=2e9, t2=t_su8),
                          {c: -50e-6 * s for c, s in signs.items()})
    thermal = ThermalParameters(
        loss=ChainLoss(thickness=(a + b) / 2, dissipation_angle=REFERENCE_BETA), medium=AIR,
        boundary_panels=boundary)
    mesh = make_mesh(pattern)
    # clamp the left end: every node of the first column of panels (x = 0 side)
    fixed = {int(i): "xyz" for p in range(n) for i in mesh.panel_nodes(p)}
    if substrate:
        fixed.update({int(i): "xyz" for i in mesh.panel_nodes(pattern.n_panels - 1)})
    return make_model(mesh, Supports(fixed), BarHingeParameters(),
                      contact=ContactParameters() if substrate else None, thermal=thermal,
                      actuators=actuators)


@_case(a="m", b="m", gamma_deg="deg", crease_width="m", power_mW="mW per crease",
       thermal_steps="-", undercut="m", loss_model="")
def miura_lifter(cells_x: int = 2, cells_y: int = 2, a: float = 1e-3, b: float = 1e-3,
                 gamma_deg: float = 60.0, crease_width: float = 200e-6, power_mW: float = 9.0,
                 thermal_steps: int = 250, substrate: bool = False, undercut: float = 100e-6,
                 coupling: str = "staggered", on_limit_point: str = "stop",
                 loss_model: str = "chain") -> Case:
    """Miura-ori lifter (paper 6.2): left end clamped (first column of panels), right end lifts
    when all creases are heated; optionally over a substrate that cools the creases near it.

    Geometry and actuators of Example03 (theory 10.3): 10 um panels, 1 um creases, gold 0.2 um
    on SU-8 0.8 um, |delta_alpha| = 50e-6 /K with the Miura fold directions
    (:func:`miura_sheet_model`).
    ``on_limit_point="continue"`` follows a snap of the sheet by arc length in the power.
    ``loss_model``: the heat loss, ``"chain"`` (the reference's chains, t_env = the mean panel
    edge) or ``"integral"`` (nothing to fit; over the substrate panel's plane when there is
    one).
    """
    params = {k: v for k, v in locals().items()}
    _check(a=a, b=b, gamma_deg=gamma_deg, crease_width=crease_width, undercut=undercut)
    m, n = _steps_int("cells_x", cells_x), _steps_int("cells_y", cells_y)
    gamma = math.radians(gamma_deg)
    model = miura_sheet_model(a, b, gamma, m, n, crease_width, substrate=substrate,
                              undercut=undercut)
    loss = _case_loss("miura_lifter", loss_model, model.thermal.loss)
    if loss is not model.thermal.loss:
        model = dataclasses.replace(model, thermal=dataclasses.replace(model.thermal, loss=loss))
    steps = (Heat({tuple(miura_fold_signs(a, b, gamma, m, n)): _power(power_mW)},
                  increments=_steps_int("thermal_steps", thermal_steps), coupling=coupling,
                  on_limit_point=on_limit_point),)
    return Case("miura_lifter", model, steps, params, miura_lifter.__doc__)


# ------------------------------------------------------------------------------ crane
_CRANE_SIGN = {1: -1, 7: -1, 8: -1, 10: -1, 12: -1, 17: -1, 18: -1, 19: -1,
               3: 1, 5: 1, 6: 1, 9: 1, 11: 1, 13: 1, 14: 1, 15: 1, 21: 1}     # reference ids


#: Base power q [mW] of the crane case by heat-loss model: the reference's 4 mW with the chain
#: model; with the integral model the power at which the crane folds as far (all creases
#: active, 500 increments: mean |fold| 98.8 against 100.2 deg, rms difference of the 17 folds
#: 18.6 deg, the smallest of 0.6-0.8 mW), its hottest crease then at 115.6 against 146.2 deg C
#: (the heat is shared between creases). On the flat crane the integral model's and the 3-D FE's
#: crease temperature rises are 3.4-10.2 times the chain model's: at 4 mW the integral model's
#: crane folds flat by a quarter of the ramp and then passes through itself (no contact).
CRANE_POWER_MW = {"chain": 4.0, "integral": 0.7}


@_case(power_mW="mW", thermal_steps="-", loss_model="")
def crane(deactivated: bool = False, power_mW: float | None = None, thermal_steps: int = 500,
          coupling: str = "staggered", loss_model: str = "chain") -> Case:
    """Origami crane (paper 6.1, Example04): 17 active creases, or creases 8 and 17
    (reference ids) left unheated with half power on 9 and 11 (``deactivated=True``).

    ``loss_model``: the heat loss, ``"chain"`` (the reference's chains, t_env = 1 mm) or
    ``"integral"`` (nothing to fit, :class:`~simulator.model.thermal_parameters.ThermalParameters`).
    ``power_mW``: the base power q, by default :data:`CRANE_POWER_MW` of the loss model (4 mW,
    the reference's, with the chain model; 0.7 mW with the integral model, at which the crane
    folds as far: at 4 mW it folds flat early and passes through itself).
    """
    params = {k: v for k, v in locals().items()}
    loss = _case_loss("crane", loss_model, ChainLoss(thickness=1e-3,
                                                     dissipation_angle=REFERENCE_BETA))
    if power_mW is None:
        power_mW = params["power_mW"] = CRANE_POWER_MW[loss_model]
    q = _power(power_mW)
    heat = {6: q, 13: q, 21: q, 9: q, 11: q, 1: 4 * q, 18: 4 * q, 3: 1.5 * q, 5: 1.5 * q,
            14: 1.5 * q, 15: 1.5 * q, 7: 2 * q, 8: 2 * q, 10: 2 * q, 12: 2 * q, 17: q / 2,
            19: q / 2}
    if deactivated:
        del heat[8], heat[17]
        heat[9] = heat[11] = q / 2
    pattern = crane_pattern()
    thermal = ThermalParameters(loss=loss, medium=AIR)
    actuators = Actuators(Bimorph(E1=50e9, t1=0.2e-6, E2=2e9, t2=0.8e-6),
                          {c - 1: 200e-6 * s for c, s in _CRANE_SIGN.items()})
    model = make_model(pattern, Supports({12: "xyz", 13: "yz", 15: "z", 17: "z"}),
                       BarHingeParameters(), thermal=thermal, actuators=actuators)
    steps = (Heat({c - 1: v for c, v in heat.items()},
                  increments=_steps_int("thermal_steps", thermal_steps), coupling=coupling),)
    return Case("crane", model, steps, params, crane.__doc__)


# ------------------------------------------------------------------------------ snap-through
@_case(span="m", rise="m", depth="m", load_mN="mN", arc_length="-", power_mW="mW per crease")
def snap_through(variant: str = "force", span: float = 1e-3, rise: float = 40e-6,
                 depth: float = 500e-6, load_mN: float = 1.0, arc_length: float = 0.1,
                 max_increments: int = 300, power_mW: float = 12.0,
                 thermal_steps: int = 60) -> Case:
    """Snap-through followed past its limit points by arc length.

    ``variant="force"``: a shallow two-panel roof (``roof_pattern``: span, rise, 20 um SU-8
    panels, a 20 um x 5 um ridge crease), pinned along both eaves and pushed down at its ridge
    by ``load_mN`` times the load factor until the ridge centre has moved down 2.5 rises
    (through the inverted shape); ``path.csv`` records that displacement. ``variant="heated"``: the Miura lifter with a = 0.5 mm, b = 1 mm, gamma = 45
    deg, W = 300 um, 4 x 2 cells over a substrate heated on all creases to ``power_mW``; it
    snaps at ~9.2 mW per crease, which load control cannot pass (``on_limit_point="continue"``).
    """
    params = {k: v for k, v in locals().items()}
    if variant == "heated":
        case = miura_lifter(cells_x=4, cells_y=2, a=0.5e-3, b=1e-3, gamma_deg=45.0,
                            crease_width=300e-6, power_mW=power_mW, thermal_steps=thermal_steps,
                            substrate=True, on_limit_point="continue")
        return Case("snap_through", case.model, case.steps, params, snap_through.__doc__)
    if variant != "force":
        raise ParameterError(f"variant = {variant!r}; use 'force' or 'heated'.")
    _check(span=span, rise=rise, depth=depth, load_mN=load_mN, arc_length=arc_length)
    pattern = roof_pattern(span=span, rise=rise, depth=depth)
    model = make_model(pattern)
    x = model.mesh.nodes[:, 0]
    eaves = np.flatnonzero(np.isclose(x, 0) | np.isclose(x, span))
    model = make_model(model.mesh, Supports({int(i): "xyz" for i in eaves}))
    ridge = np.unique(model.mesh.crease_nodes[0])
    force = -1e-3 * load_mN / len(ridge)
    centre = int(model.mesh.crease_nodes[0][6])
    step = ArcLengthLoad({int(i): (0.0, 0.0, force) for i in ridge}, arc_length=arc_length,
                         max_increments=_steps_int("max_increments", max_increments),
                         target_displacement=2.5 * rise, monitor=(centre, "-z"))
    return Case("snap_through", model, (step,), params, snap_through.__doc__)
