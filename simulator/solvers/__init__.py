"""Solvers: one Newton iteration and one cut-and-retry driver (:mod:`.nonlinear`) behind Newton
load control, arc-length continuation and displacement control, dynamics (generalized-alpha);
stability and natural modes.

The public names (``from simulator.solvers import solve_equilibrium``) work on an
:class:`~simulator.mechanics.EquilibriumSystem` or a model's state: Newton at a fixed load
(:func:`solve_equilibrium`), path following through limit points on a :class:`LoadPath`
(:func:`mgdcm`, the modified generalized displacement control method, and
:func:`control_displacement`), time integration (:func:`integrate`, :class:`TimeIntegrator`),
stability, equilibrium checks and natural modes. The loading steps of ``simulator`` call them
for you.
"""

from .._lazy import attach as _attach

__getattr__, __dir__ = _attach(__name__, {
    ".newton": ("NewtonOptions", "NewtonResult", "newton as solve_equilibrium"),
    ".load_path": ("LoadPath",),
    ".path_trace": ("ContinuationResult", "CriticalPoint"),
    ".continuation": ("mgdcm",),
    ".displacement_control": ("displacement_control as control_displacement",),
    ".dynamics_options": ("DynamicsOptions",),
    ".dynamics": ("DynamicsResult", "integrate"),
    ".generalized_alpha": ("MotionState", "TimeIntegrator"),
    ".stability": ("Stability", "tangent_stability", "state_stability"),
    ".equilibrium_check": ("EQUILIBRIUM_RTOL", "EquilibriumCheck", "check_equilibrium"),
    ".modes": ("ModesResult", "natural_modes"),
})

__all__ = [
    # Newton at a fixed load
    "solve_equilibrium", "NewtonOptions", "NewtonResult",
    # path following through limit points
    "LoadPath", "mgdcm", "control_displacement", "ContinuationResult", "CriticalPoint",
    # dynamics
    "integrate", "DynamicsOptions", "DynamicsResult", "TimeIntegrator", "MotionState",
    # stability, equilibrium checks, natural modes
    "Stability", "tangent_stability", "state_stability", "check_equilibrium",
    "EquilibriumCheck", "EQUILIBRIUM_RTOL", "natural_modes", "ModesResult",
]
