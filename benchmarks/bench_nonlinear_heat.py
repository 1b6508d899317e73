"""What hot air and radiation do to the two measured grippers' full-function power, and what
they cost (issue 30 items 2-3, theory 4.12).

The paper's two measured grippers (coordinate-descent cycle 4: W 240, La 900, L1 = L2 = 800
um, measured 29.8 mW; cycle 9: W 290, La 1150, L1 = L2 = 550 um, measured 21.6 mW) are
evaluated (``evaluate_gripper``, bisect power search, the default integral loss with its sheet
refinement) with

* ``constant``: the paper setting (air at 0.026 W/(m K), no radiation);
* ``k(T)``: air's conductivity following Incropera's Table A.4
  (``AIR.with_temperature_dependence()``);
* ``eps 0.5``, ``eps 0.9``: radiation from both faces of the polymer panels and creases at
  emissivity 0.5 or 0.9 (the plausible range of the 1-5 um SU-8 and SPR films), the creases'
  gold face at 0.03 (``GOLD_FILM_EMISSIVITY``: the crease's two faces averaged, (eps +
  0.03) / 2);
* ``k(T) + eps 0.9``: both (all the new physics of this item).

The full-function power is that of the paper: twice the sum of the assembly and the grip
power per heated crease (two heated creases per stage). Each variant's evaluation is timed
(wall and CPU time after a warm-up; the median of ``--repeat`` runs for the paper setting and
for all the physics, whose ratio is the acceptance: at most 1.5). The device keeps its own
materials; a variant swaps the model's medium and materials in ``make_gripper_model`` while the
evaluation runs (``bench_loss_models.gripper_evaluation``, as that benchmark swaps its loss).

Run: ``python benchmarks/bench_nonlinear_heat.py`` (about a minute; ``--repeat 1`` quicker).
"""

from __future__ import annotations

import argparse
import dataclasses

from bench_loss_models import _timed as timed, gripper_evaluation
from design.devices import gripper
from simulator import AIR
from simulator.materials import GOLD_FILM_EMISSIVITY

#: The two measured grippers: (name, design, measured full-function power [mW]).
DESIGNS = (
    ("cycle 4", gripper.GripperDesign(W=240e-6, La=900e-6, L1=800e-6, L2=800e-6), 29.8),
    ("cycle 9", gripper.GripperDesign(W=290e-6, La=1150e-6, L1=550e-6, L2=550e-6), 21.6),
)
#: The variants: (name, temperature-dependent air, polymer emissivity).
VARIANTS = (("constant", False, 0.0), ("k(T)", True, 0.0), ("eps 0.5", False, 0.5),
            ("eps 0.9", False, 0.9), ("k(T) + eps 0.9", True, 0.9))


def with_physics(model, hot_air: bool, eps: float):
    """``model`` with air's conductivity law (``hot_air``) and its panels and creases at
    polymer emissivity ``eps`` (the creases' gold face at ``GOLD_FILM_EMISSIVITY``)."""
    thermal = model.thermal
    if hot_air:
        thermal = dataclasses.replace(thermal, medium=AIR.with_temperature_dependence())
    mesh = model.mesh
    if eps:
        pat = mesh.pattern
        panels = [dataclasses.replace(m, emissivity=eps) for m in pat.panel_material]
        crease = dataclasses.replace(pat.crease_material,
                                     emissivity=(eps + GOLD_FILM_EMISSIVITY) / 2)
        pat = dataclasses.replace(pat, panel_material=panels, crease_material=crease)
        mesh = dataclasses.replace(mesh, pattern=pat)
    return dataclasses.replace(model, mesh=mesh, thermal=thermal)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3,
                    help="timed runs of the paper setting and of all the physics")
    args = ap.parse_args(argv)
    print(f"{'design':<8} {'variant':<15} {'full function':>14} {'change':>8} "
          f"{'measured':>9} {'wall':>8} {'CPU':>8}")
    for name, design, measured in DESIGNS:
        base = times = None
        for variant, hot_air, eps in VARIANTS:
            repeat = args.repeat if variant in ("constant", "k(T) + eps 0.9") else 1
            run = gripper_evaluation(design, lambda m, h=hot_air, e=eps: with_physics(m, h, e))
            wall, cpu, out = timed(run, repeat)
            full = None if out.total_power is None else 2e3 * out.total_power
            base = full if base is None else base
            times = (wall, cpu) if times is None else times
            change = "-" if full is None or base is None else f"{100 * (full / base - 1):+.1f} %"
            shown = "not met" if full is None else f"{full:.2f} mW"
            print(f"{name:<8} {variant:<15} {shown:>14} {change:>8} {measured:>6.1f} mW "
                  f"{wall:7.2f} s {cpu:7.2f} s")
        print(f"{name:<8} all the physics / paper setting: wall {wall / times[0]:.2f}, CPU "
              f"{cpu / times[1]:.2f} (acceptance <= 1.5: "
              f"{'met' if wall / times[0] <= 1.5 else 'NOT met'} on wall time)")


if __name__ == "__main__":
    main()
