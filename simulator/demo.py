"""The main demo: a single crease with a residual fold, gravity and substrate contact.

Geometry, supports and mechanical parameters of the reference's Example01
(digest 8.1): a 21 um SU-8 panel hinged to a 500 um anchor by a 200 um wide,
0.5 um thick crease, 150 um above a substrate. The crease first takes its
residual (fabrication) fold, then gravity is applied; contact with the
substrate stops the panel.
"""

from __future__ import annotations

import numpy as np

from .geometry import fold_angles
from .simulation import simulate
from .state import equilibrium_system
from .steps import Gravity, SelfFold
from .model import ContactParameters, Model, Supports, make_model
from .example_patterns import single_fold_pattern
from .properties import BarHingeParameters

__all__ = ["single_fold_model", "single_fold_demo", "SINGLE_FOLD_SUPPORTS"]

#: Supports of the reference single fold (digest 8.1), 0-based nodes: anchor edge and substrate.
SINGLE_FOLD_SUPPORTS = Supports({0: "z", 1: "z", 2: "yz", 3: "xyz", 8: "xyz", 9: "xyz",
                                 10: "xyz", 11: "xyz"})


def single_fold_model(contact: bool = True, substrate: bool = True, **pattern_kwargs) -> Model:
    """Mechanical model of the reference single fold (Example01 parameters)."""
    pattern = single_fold_pattern(substrate=substrate, **pattern_kwargs)
    supports = SINGLE_FOLD_SUPPORTS if substrate else Supports({0: "z", 1: "z", 2: "yz", 3: "xyz"})
    return make_model(pattern, supports, BarHingeParameters(diagonal_rate=1000),
                      contact=ContactParameters(1e-4, 40e-6, 40e-6) if contact else None)


def single_fold_demo(residual_fold_deg: float = -10.0, gravity: bool = True) -> dict:
    """Self-fold to the residual angle, then apply gravity; returns a summary per step."""
    model = single_fold_model()
    steps = [SelfFold({2: np.radians(residual_fold_deg)}, increments=20)]
    if gravity:
        steps.append(Gravity(g=9.8, panels=[1], increments=20))
    result = simulate(model, steps)
    system = equilibrium_system(model)
    rows = []
    for step in result.steps:
        x = model.mesh.nodes + step.state.u
        ev = system.evaluate(step.state.u, step.state.spring_rest, hessian=False)
        rows.append({"step": step.name, "status": step.status, "increments": step.increments,
                     "iterations": step.iterations,
                     "fold_deg": float(np.degrees(fold_angles(model.mesh, x)[0])),
                     "tip_z_um": float(x[5, 2] * 1e6), "contacts": ev.n_contacts})
    return {"model": model, "result": result, "steps": rows}
