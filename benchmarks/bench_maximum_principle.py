"""Discrete maximum principle of the steady heat model (issue 29 item 5; theory 4.2).

Prints the numbers behind theory 4.2's "Monotone conduction":

1. *Heating alone, flat shapes* (the crane at 5 mW, the gripper at 15 mW on its base creases,
   the double fold at 10 mW per crease): the lowest node temperature rise [K] with the T3 and
   with the monotone conduction, chains and integral loss, the mean centre-line rise of the
   heated creases and the monotone conduction's flips and Steiner points.
2. *The cause*: positive couplings of the assembled T3 conduction by kind of edge, and the
   lowest rise with the positive couplings of the conduction, or of the integral loss operator
   L, moved onto the diagonal (:func:`~simulator.thermal.integral.lump_couplings`; for L the
   option ``IntegralLoss(lumped=True)``).
3. *Mesh refinement* (a converged reference for the same model): every mesh triangle split
   uniformly into r^2 (T3 from positions), the crease heat spread evenly over each crease (the
   T3 nodal split is exactly that, at r = 1), the chain loss as the loss density
   g_p / A_p of each node (A_p a third of its triangles' area) interpolated linearly and
   lumped on the fine nodes (r = 1: exactly the chains), and the integral loss on the fine
   triangles (one collocation point each, beside the coarse model at m = r: the same
   sub-triangles, only the temperature's resolution differs). Mean centre-line rise of the
   heated creases and the lowest rise, at r = 1 (the T3 model, but for the even spread of the
   heat: the gripper's hand-edited crease nodes make its nodal split uneven), 2, 4, 8; beside
   it the coarse T3 model with the plain operator at m = r, consistent and lumped.
4. *Lumped or consistent* (the default integral model, m = 3 extrapolated, monotone
   conduction): the heated creases' mean centre-line and centre-node rise and the lowest
   rise.

Run: ``python benchmarks/bench_maximum_principle.py`` (about two minutes; ``--quick`` stops
the refinement at r = 4).
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from design import GripperDesign, GripperHeatModel, make_gripper_model
from design.devices import BASE_CREASES
from simulator import IntegralLoss
from simulator.thermal import ThermalModel, crease_temperatures
from simulator.cases import get_case
from simulator.thermal._single_layer import subdivision
from simulator.model.heat_loss import MAX_SUB_TRIANGLES
from simulator.thermal.integral import IntegralOperator, lump_couplings
from simulator.thermal.monotone import t3_matrices


def _with(model, **fields):
    return dataclasses.replace(model, thermal=dataclasses.replace(model.thermal, **fields))


def devices(loss):
    """``{name: (model, crease power (C,) [W])}`` of the three devices with the loss model."""
    out = {}
    crane = get_case("crane", loss_model=loss, power_mW=5.0)
    out["crane"] = (crane.model, crane.steps[0].power_array(crane.model.mesh))
    grip, _ = make_gripper_model(GripperDesign(), heat=GripperHeatModel(loss_model=loss))
    p = np.zeros(grip.mesh.n_creases)
    p[[grip.mesh.crease_row_of(c) for c in BASE_CREASES]] = 15e-3
    out["gripper"] = (grip, p)
    double = get_case("double_fold").model
    if loss == "integral":
        double = _with(double, loss=IntegralLoss())
    out["double_fold"] = (double, np.full(double.mesh.n_creases, 10e-3))
    return out


def centre_line(rise, mesh, power) -> float:
    """Mean centre-line rise [K] of the heated creases."""
    return float(crease_temperatures(rise, mesh, "centre_line")[power > 0].mean())


def flat_table():
    print("1. heating alone, flat: lowest rise [K] T3 -> monotone; heated creases' mean "
          "centre-line rise [K] T3 -> monotone")
    for loss in ("chain", "integral"):
        for name, (model, p) in devices(loss).items():
            out = {}
            for cond in ("t3", "monotone"):
                tm = ThermalModel(model.mesh, dataclasses.replace(model.thermal, conduction=cond))
                rise = (tm.solve(model.mesh.nodes, tm.heat_vector(p))
                        - model.thermal.room_temperature)
                out[cond] = (rise.min(), centre_line(rise, model.mesh, p), tm.monotone)
            mc = out["monotone"][2]
            (a, ca, _), (b, cb, _) = out["t3"], out["monotone"]
            print(f"  {name:11s} {loss:8s} min {a:+8.4f} -> {b:+8.4f}   centre line {ca:7.2f} -> "
                  f"{cb:7.2f} ({100 * (cb / ca - 1):+.2f} %)   flips {mc.flips}, Steiner points "
                  f"{mc.n_steiner}")


def _coarse(tm, x, p, clip_k=False, clip_l=False, refinement=None):
    """Rise [K] of the T3 model solved densely, optionally with lumped couplings
    (:func:`lump_couplings`) or with the plain integral operator at ``refinement``."""
    n = tm.mesh.n_nodes
    K = tm.sheet_conduction(x).toarray()
    held = np.zeros(n, bool)
    if tm.integral is None:
        held[list(tm.params.room_temperature_nodes)] = True
        L = np.diag(tm.structure_conductances(x)[1])
    else:
        held[tm.held_nodes(x)] = True
        L = np.zeros((n, n))
        if refinement is None:
            L[np.ix_(tm.integral.nodes, tm.integral.nodes)] = tm.integral_loss_matrix(x)
        else:
            op = IntegralOperator(tm.mesh.triangles[~tm.is_boundary], n,
                                  tm.params.medium.thermal_conductivity, refinement, tm.plane)
            L[np.ix_(op.nodes, op.nodes)] = op.loss_matrix(x)
    K, L = (lump_couplings(K) if clip_k else K), (lump_couplings(L) if clip_l else L)
    free = ~held
    rise = np.zeros(n)
    q = tm.heat_vector(p)
    rise[free] = np.linalg.solve((K + L)[np.ix_(free, free)], q[free])
    return rise


def cause_table():
    print("2. the cause: positive T3 couplings by edge kind; lowest rise [K] with the conduction's"
          " (K) or the loss operator's (L) positive couplings moved onto the diagonal")
    for loss in ("chain", "integral"):
        for name, (model, p) in devices(loss).items():
            tm = ThermalModel(model.mesh, dataclasses.replace(model.thermal, conduction="t3"))
            x = model.mesh.nodes
            kinds = _kinds(tm, x) if loss == "chain" else ""
            row = [f"{_coarse(tm, x, p).min():+.4f}",
                   f"K {_coarse(tm, x, p, clip_k=True).min():+.4f}"]
            if loss == "integral":
                row.append(f"L {_coarse(tm, x, p, clip_l=True).min():+.4f}")
                n = tm.mesh.n_nodes
                L = np.zeros((n, n))
                L[np.ix_(tm.integral.nodes, tm.integral.nodes)] = tm.integral_loss_matrix(x)
                adj = (tm.sheet_conduction(x).toarray() != 0) & ~np.eye(n, dtype=bool)
                row.append(f"L > 0 on {int((L[adj] > 0).sum()) // 2} of {int(adj.sum()) // 2} "
                           "mesh edges")
            print(f"  {name:11s} {loss:8s} {kinds} min: " + ", ".join(row))


def _kinds(tm, x):
    mesh = tm.mesh
    region = np.where(mesh.triangle_panel >= 0, mesh.triangle_panel, -1 - mesh.triangle_crease)
    A = tm.sheet_conduction(x).toarray()
    sides = {}
    for t, (a, b, c) in enumerate(mesh.triangles):
        for i, j in ((a, b), (b, c), (a, c)):
            sides.setdefault((min(i, j), max(i, j)), []).append(region[t])
    count = {"inside a region": 0, "between regions": 0, "outline": 0}
    for (i, j), regs in sides.items():
        if A[i, j] > 1e-12 * np.abs(A).max():
            kind = ("outline" if len(regs) == 1 else "inside a region" if regs[0] == regs[1]
                    else "between regions")
            count[kind] += 1
    return "positive couplings " + ", ".join(f"{v} {k}" for k, v in count.items()) + ";"


def refine(mesh, r):
    """Uniform refinement: fine triangles (f, 3), their parents (f,), and the interpolation
    ``P`` (n_fine, n) of the fine nodes from the mesh nodes."""
    bary, _ = subdivision(r)
    keys, ftri, parent = {}, [], []
    for t, corners in enumerate(mesh.triangles):
        for s in range(len(bary)):
            ids = []
            for v in range(3):
                w = np.rint(bary[s, v] * r).astype(int)
                key = tuple(sorted((int(c), int(k)) for c, k in zip(corners, w) if k))
                ids.append(keys.setdefault(key, len(keys)))
            ftri.append(ids)
            parent.append(t)
    P = np.zeros((len(keys), mesh.n_nodes))
    for key, i in keys.items():
        for c, k in key:
            P[i, c] = k / r
    return np.array(ftri), np.array(parent), P


def fine_rise(model, p, r):
    """Rise [K] at the mesh nodes of the uniformly refined model (item 3 of the docstring),
    and the lowest rise of all fine nodes."""
    tm = ThermalModel(model.mesh, dataclasses.replace(model.thermal, conduction="t3"))
    mesh, x = tm.mesh, tm.mesh.nodes
    ftri, parent, P = refine(mesh, r)
    X, nf = P @ x, len(P)
    Ke = t3_matrices(X[ftri], tm.conduction.kt[parent])
    area = 0.5 * np.linalg.norm(np.cross(X[ftri[:, 1]] - X[ftri[:, 0]],
                                         X[ftri[:, 2]] - X[ftri[:, 0]]), axis=1)
    A = np.zeros((nf, nf))
    np.add.at(A, (np.repeat(ftri, 3, axis=1).ravel(), np.tile(ftri, (1, 3)).ravel()), Ke.ravel())
    q = np.zeros(nf)
    for row in np.flatnonzero(p):
        on = mesh.triangle_crease[parent] == row
        np.add.at(q, ftri[on].ravel(), np.repeat(p[row] * area[on] / area[on].sum() / 3, 3))
    node = np.where(P.max(axis=1) == 1, P.argmax(axis=1), -1)
    held = np.isin(node, list(tm.params.room_temperature_nodes)) & (node >= 0)
    if tm.integral is None:
        g = tm.structure_conductances(x)[1]
        a_c = np.bincount(mesh.triangles.ravel(), np.repeat(tm.triangle_areas(x) / 3, 3),
                          minlength=mesh.n_nodes)
        a_f = np.bincount(ftri.ravel(), np.repeat(area / 3, 3), minlength=nf)
        A += np.diag((P @ (g / a_c)) * a_f)
    else:
        boundary = tm.is_boundary[parent]
        held[np.unique(ftri[boundary])] = True
        op = IntegralOperator(ftri[~boundary], nf, tm.params.medium.thermal_conductivity, 1,
                              tm.plane)
        A[np.ix_(op.nodes, op.nodes)] += op.loss_matrix(X)
    free = ~held
    rise = np.zeros(nf)
    rise[free] = np.linalg.solve(A[np.ix_(free, free)], q[free])
    out = np.zeros(mesh.n_nodes)
    out[node[node >= 0]] = rise[node >= 0]
    return out, rise.min()


def refinement_table(levels):
    print("3. mesh refinement: heated creases' mean centre-line rise [K] (lowest rise [K] of "
          "all fine nodes)")
    for loss in ("chain", "integral"):
        for name, (model, p) in devices(loss).items():
            cells = []
            for r in levels:
                if loss == "integral" and r * r * len(model.mesh.triangles) > MAX_SUB_TRIANGLES:
                    cells.append(f"r={r}: too many sub-triangles")
                    continue
                out, low = fine_rise(model, p, r)
                cells.append(f"r={r}: {centre_line(out, model.mesh, p):7.2f} ({low:+.3f})")
                if loss == "integral":
                    tm = ThermalModel(model.mesh, dataclasses.replace(model.thermal,
                                                                      conduction="t3"))
                    c, d = (_coarse(tm, model.mesh.nodes, p, clip_l=clip, refinement=r)
                            for clip in (False, True))
                    cells[-1] += (f" [T3 at m={r}: {centre_line(c, model.mesh, p):7.2f}, "
                                  f"lumped {centre_line(d, model.mesh, p):7.2f}]")
            mono = ThermalModel(model.mesh, dataclasses.replace(model.thermal,
                                                                conduction="monotone"))
            m = mono.solve(model.mesh.nodes, mono.heat_vector(p)) - model.thermal.room_temperature
            print(f"  {name:11s} {loss:8s} " + "; ".join(cells)
                  + f"; monotone: {centre_line(m, model.mesh, p):7.2f}")


def lumped_table():
    print("4. the default integral model, consistent -> lumped: heated creases' mean "
          "centre-line rise [K], mean centre-node rise [K], lowest rise [K]")
    for name, (model, p) in devices("integral").items():
        cells = []
        for lumped in (False, True):
            tm = ThermalModel(model.mesh, model.thermal.with_loss(lumped=lumped))
            rise = tm.solve(model.mesh.nodes, tm.heat_vector(p)) - model.thermal.room_temperature
            ctr = crease_temperatures(rise, model.mesh, "centre")[p > 0].mean()
            cells.append((centre_line(rise, model.mesh, p), ctr, rise.min()))
        print(f"  {name:11s} " + "   ".join(f"{a} {b:7.2f} -> {c:7.2f}" for a, b, c in zip(
            ("centre line", "centre", "lowest"), *cells)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="refinement up to r = 4")
    args = parser.parse_args(argv)
    flat_table()
    cause_table()
    refinement_table((1, 2, 4) if args.quick else (1, 2, 4, 8))
    lumped_table()


if __name__ == "__main__":
    main()
