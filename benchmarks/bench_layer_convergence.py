"""Does the crease metal layer's effect converge with the sheet refinement? (issue 30, theory
4.10, 4.11, 4.13).

The paper's two measured grippers (coordinate-descent cycle 4: W 240, La 900, L1 = L2 = 800
um; cycle 9: W 290, La 1150, L1 = L2 = 550 um), the default integral loss, in the paper
setting (``crease_conduction="paper"``) and with the crease's gold and SU-8 layers conducting
in parallel (``"layers"``, k_Au 150 W/(m K)), on the sheet refined uniformly r = 1, 2, 3, 4, 6,
8 (theory 4.11; r = 6 and 8 exceed the dense operator's limit ``MAX_SUB_TRIANGLES``, which
this benchmark lifts while it runs: 6336 and 11264 sub-triangles, about 0.5 and 1.8 GB):

1. *Fixed power* (flat, both base creases at 15 mW, nothing else heated): the base creases'
   actuation measure (the 7-node weighted mean of the mesh nodes, theory 5.3: what the
   mechanics reads), their area mean over the crease's fine triangles (the heat-weighted mean
   q.T / Q, which can only rise with a nested refinement), the layer effect on both, and the
   estimates ``2 T(2r) - T(r)`` (Richardson for an error of first order in the element size,
   from the nested pairs r = 2/4, 3/6, 4/8).
2. *Controls* (``--controls``, cycle 4, layers): the integral loss's levels raised at fixed r
   (m = 3, 8, 12: the operator converged on each sheet), T3 instead of the monotone
   conduction, and the central panel's held node released: none changes the trend.
3. *Where the error sits* (``--where``, cycle 4, layers): the r = 4 field interpolated onto the
   r = 8 sheet; the error's conduction energy e^T K e per fine triangle and loss energy
   e_i (L e)_i per node, within 50 / 100 / 200 um of the base creases' corners, and the
   largest nodal errors.
4. *Full-function power* (``--full-function``): ``evaluate_gripper`` (bisect) at r = 1-4 (and
   6 with ``--r6``, a few minutes per design), 2 x (assembly + grip) per heated crease, as
   ``studies/device_power_physics.py`` counts it, with the same estimates from r = 2/4 and
   3/6 of the powers, and the evaluations with the temperatures extrapolated,
   ``GripperHeatModel(sheet_extrapolation=True)`` at r = 2 (and 3 with ``--r6``), and from
   the sheets refined r and r + 1 (``"r+1"``), each with the evaluation's CPU time
   (``time.process_time``).

Run: ``python benchmarks/bench_layer_convergence.py`` (fixed power to r = 8, about 4 minutes;
``--quick`` stops at r = 4). Figures measured 8 Dec 2026: theory 4.13.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from contextlib import contextmanager
from unittest import mock

import numpy as np

from design import GripperDesign, GripperHeatModel, evaluate_gripper, make_gripper_model
from design.devices import BASE_CREASES
from simulator.thermal import ThermalModel, crease_temperatures
from simulator.model import heat_loss
from simulator.thermal.monotone import t3_matrices

#: The two measured grippers: cycle -> geometry [m].
DESIGNS = {4: dict(W=240e-6, La=900e-6, L1=800e-6, L2=800e-6),
           9: dict(W=290e-6, La=1150e-6, L1=550e-6, L2=550e-6)}
SETTINGS = ("paper", "layers")
POWER = 15e-3           # [W] per base crease


@contextmanager
def dense_limit(n: int = 12000):
    """Lift the dense operator's sub-triangle limit while the block runs (r = 6 and 8)."""
    with mock.patch.object(heat_loss, "MAX_SUB_TRIANGLES", max(n, heat_loss.MAX_SUB_TRIANGLES)):
        yield


def flat_solve(cycle: int, setting: str, r: int, thermal=None, **design):
    """``(tm, rise (n,) [K], base crease rows)`` of the flat gripper with its base creases at
    :data:`POWER`; ``thermal``: fields replaced in the model's thermal parameters."""
    model, _ = make_gripper_model(GripperDesign(**DESIGNS[cycle]),
                                  heat=GripperHeatModel(crease_conduction=setting,
                                                        sheet_refinement=r, **design))
    params = dataclasses.replace(model.thermal, **(thermal or {}))
    tm = ThermalModel(model.mesh, params, actuators=model.actuators)
    mesh = model.mesh
    base = [mesh.crease_row_of(c) for c in BASE_CREASES]
    p = np.zeros(mesh.n_creases)
    p[base] = POWER
    rise = tm.solve(mesh.nodes, tm.heat_vector(p)) - params.room_temperature
    return tm, rise, base


def area_mean(tm, base) -> float:
    """Mean rise [K] over the base creases' fine triangles (the last solve's fine field; NaN
    on the mesh triangles and with ``sheet_extrapolation``)."""
    if tm.sheet is None or tm.sheet_2r is not None:
        return float("nan")
    fine = tm.fine_model
    x = tm.sheet.positions(tm.mesh.nodes)
    t = fine.mesh.triangles
    rise = tm._last_fine[3] - tm._last_fine[2]
    area = 0.5 * np.linalg.norm(np.cross(x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]]), axis=1)
    on = np.isin(fine.mesh.triangle_crease, base)
    return float(np.sum(area[on] * rise[t[on]].mean(axis=1)) / area[on].sum())


def measures(cycle, setting, r, thermal=None, **design) -> tuple:
    """(actuation measure, area mean) [K] of the base creases at :data:`POWER`."""
    tm, rise, base = flat_solve(cycle, setting, r, thermal, **design)
    return float(crease_temperatures(rise, tm.mesh, "actuation")[base].mean()), area_mean(tm, base)


def _effect(a, b) -> str:
    return f"{100 * (b / a - 1):+6.1f} %"


def fixed_power(rs):
    print(f"1. fixed power: flat, base creases at {1e3 * POWER:g} mW; base creases' actuation "
          "measure / area mean rise [K]; layer effect")
    for cycle in DESIGNS:
        out = {}
        for r in rs:
            t0 = time.perf_counter()
            out[r] = {s: measures(cycle, s, r) for s in SETTINGS}
            (ap, mp), (al, ml) = out[r]["paper"], out[r]["layers"]
            print(f"  cycle {cycle} r = {r}: paper {ap:7.2f} / {mp:7.2f}   layers {al:7.2f} / "
                  f"{ml:7.2f}   effect {_effect(ap, al)} / {_effect(mp, ml)}   "
                  f"({time.perf_counter() - t0:.0f} s)", flush=True)
        for lo in (2, 3, 4):
            if lo in out and 2 * lo in out:
                est = {s: [2 * b - a for a, b in zip(out[lo][s], out[2 * lo][s])]
                       for s in SETTINGS}
                (ap, mp), (al, ml) = est["paper"], est["layers"]
                print(f"  cycle {cycle} 2 T({2 * lo}) - T({lo}): paper {ap:7.2f} / {mp:7.2f}   "
                      f"layers {al:7.2f} / {ml:7.2f}   effect {_effect(ap, al)} / "
                      f"{_effect(mp, ml)}")


def controls(rs):
    print("2. controls, cycle 4, layers: actuation measure [K] per r")
    cases = (("default (m = 3, monotone)", {}, {}),
             ("integral_refinement m = 8", {}, {"integral_refinement": 8}),
             ("integral_refinement m = 12", {}, {"integral_refinement": 12}),
             ("T3 conduction", {}, {"conduction": "t3"}),
             ("central node not held", {"room_temperature_nodes": ()}, {}))
    for name, thermal, design in cases:
        vals = [measures(4, "layers", r, thermal, **design)[0] for r in rs]
        print(f"  {name:28s} " + "  ".join(f"r{r} {v:7.2f}" for r, v in zip(rs, vals)),
              flush=True)


def _nested(xc, tc, triangles_c, xf) -> np.ndarray:
    """The P1 field ``tc`` on the sheet refined r (nodes ``xc``, fine ``triangles_c``) at the
    nodes ``xf`` of the sheet refined 2r: each is a node or the midpoint of an edge there."""
    def key(x):
        return tuple(np.round(np.asarray(x) * 1e8).astype(int))

    at = {key(x): tc[i] for i, x in enumerate(xc)}
    edges = np.unique(np.sort(triangles_c[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0)
    at.update({key(0.5 * (xc[a] + xc[b])): 0.5 * (tc[a] + tc[b]) for a, b in edges})
    return np.array([at[key(x)] for x in xf])


def where(rc: int = 4):
    """Print where the r = ``rc`` field's error against r = 2 ``rc`` sits (docstring item 3)."""
    sol = {r: flat_solve(4, "layers", r, conduction="t3") for r in (rc, 2 * rc)}
    (tmc, _, _), (tmf, _, base) = sol[rc], sol[2 * rc]
    xc, xf = (tm.sheet.positions(tm.mesh.nodes) for tm in (tmc, tmf))
    tc, tf = (tm._last_fine[3] - tm._last_fine[2] for tm in (tmc, tmf))
    e = tf - _nested(xc, tc, tmc.sheet.mesh.triangles, xf)
    fine = tmf.fine_model
    t = fine.mesh.triangles
    cond = np.einsum("ti,tij,tj->t", e[t], t3_matrices(xf[t], fine._kt), e[t])
    loss = np.zeros(len(xf))
    nodes = fine.integral.nodes
    loss[nodes] = e[nodes] * (fine.integral_loss_matrix(xf) @ e[nodes])
    mesh = tmf.mesh
    corners = mesh.nodes[np.unique(mesh.crease_nodes[base][:, :4])][:, :2]
    d_tri = np.linalg.norm(xf[t].mean(axis=1)[:, None, :2] - corners[None], axis=2).min(axis=1)
    d_node = np.linalg.norm(xf[:, None, :2] - corners[None], axis=2).min(axis=1)
    print(f"3. where the error sits: cycle 4, layers, T3, r = {rc} against r = {2 * rc}: energy "
          f"conduction {cond.sum():.4f} + loss {loss.sum():.4f} W K")
    area = 0.5 * np.linalg.norm(np.cross(xf[t[:, 1]] - xf[t[:, 0]], xf[t[:, 2]] - xf[t[:, 0]]),
                                axis=1) * ~fine.is_boundary
    for lim in (50e-6, 100e-6, 200e-6):
        print(f"  within {1e6 * lim:3.0f} um of a base crease corner ({area[d_tri < lim].sum() / area.sum():.2f} "
              f"of the sheet): conduction {cond[d_tri < lim].sum() / cond.sum():.2f}, loss "
              f"{loss[d_node < lim].sum() / loss.sum():.2f} of the error energy")
    i = np.argsort(-np.abs(e))[:4]
    print("  largest errors [K] at (x, y) [um]: " + ", ".join(
        f"{e[k]:+.1f} ({1e6 * xf[k, 0]:.0f}, {1e6 * xf[k, 1]:.0f})" for k in i))


def _full(geometry, setting, r, extrapolate=False):
    """(full-function power, assembly, grip per crease) [mW] of one evaluation, and its CPU
    time [s]."""
    t0 = time.process_time()
    res = evaluate_gripper(GripperDesign(**geometry),
                           heat=GripperHeatModel(crease_conduction=setting, sheet_refinement=r,
                                                 sheet_extrapolation=extrapolate))
    a = res.assembly.power_per_crease if res.assembly.success else float("nan")
    g = res.grip.power_per_crease if res.grip.success else float("nan")
    return 2e3 * (a + g), 1e3 * a, 1e3 * g, time.process_time() - t0


def full_function(rs, extrapolated):
    print("4. full-function power 2 x (assembly + grip) [mW] (assembly, grip per crease)")
    for cycle, geometry in DESIGNS.items():
        out = {}
        rows = [(r, False) for r in rs] + [(r, e) for r in extrapolated
                                           for e in (True, "r+1")]
        for r, ext in rows:
            res = {s: _full(geometry, s, r, ext) for s in SETTINGS}
            out[r, ext] = {s: v[0] for s, v in res.items()}
            finer = r + 1 if ext == "r+1" else 2 * r
            label = f"r = {r}, {finer} extrapolated" if ext else f"r = {r}"
            print(f"  cycle {cycle} {label}: " + "   ".join(
                f"{s} {p:7.3f} ({a:6.3f}, {g:5.3f}; {t:5.2f} s)"
                for s, (p, a, g, t) in res.items())
                + f"   effect {_effect(out[r, ext]['paper'], out[r, ext]['layers'])}",
                flush=True)
        for lo in (2, 3):
            if (lo, False) in out and (2 * lo, False) in out:
                est = {s: 2 * out[2 * lo, False][s] - out[lo, False][s] for s in SETTINGS}
                print(f"  cycle {cycle} 2 P({2 * lo}) - P({lo}): paper {est['paper']:7.3f}   "
                      f"layers {est['layers']:7.3f}   effect "
                      f"{_effect(est['paper'], est['layers'])}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fixed power to r = 4 only")
    ap.add_argument("--controls", action="store_true", help="item 2 of the docstring")
    ap.add_argument("--where", action="store_true", help="item 3 of the docstring")
    ap.add_argument("--full-function", action="store_true", help="item 4 of the docstring")
    ap.add_argument("--r6", action="store_true", help="item 4 also at r = 6")
    args = ap.parse_args(argv)
    with dense_limit():
        fixed_power((1, 2, 3, 4) if args.quick else (1, 2, 3, 4, 6, 8))
        if args.controls:
            controls((2, 3, 4))
        if args.where:
            where()
        if args.full_function:
            full_function((1, 2, 3, 4, 6) if args.r6 else (1, 2, 3, 4),
                          (2, 3) if args.r6 else (2,))


if __name__ == "__main__":
    main()
