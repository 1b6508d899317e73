"""Wall time of the boundary-integral heat-loss model against the chain model (issue 19).

Acceptance: a gripper evaluation (bisect power search, start design) with
``loss_model="integral"`` takes at most 2x the chain model's time, and the crane case at most
3x. Each run is timed after a warm-up run (numba compilation), the median of ``--repeat``
runs. The acceptance is on wall time; the process (CPU) time is printed beside it, the
steadier measure on a shared, loaded machine. The two models predict different temperatures,
so the power searches and the Newton paths differ as well: the ratio is that of the whole
evaluation, as a user sees it.

The gripper rows use the same design and search settings for both models. The crane rows do
not use the same power: ``get_case("crane", loss_model=...)`` sets it per model
(``simulator.cases.CRANE_POWER_MW``): the reference's 4 mW with the chain model (chosen for
its chains, t_env = 1 mm) and 0.7 mW with the integral model, the power at which the crane
folds as far (mean |fold| 98.8 against 100.2 deg; the folds differ crease by crease, rms
18.6 deg). So the 3x is met on the crane folded as far, not at equal power. At the chain
model's 4 mW the integral model (and the 3-D FE) put the flat crane's crease temperature rises
at 3.4-10.2 times the chain model's: its crane folds flat by a quarter of the ramp and then
passes through itself (the case has no contact), a path of a different kind;
``--overdriven`` times that too (about 50 s more), for the record.

Each integral row also prints the operator builds of one run by level (the accurate m and its
Richardson partner, the cheap m = 1 of the correction between rebuilds; per edge of the
triangles the operator is built on: on the gripper's sheet, refined r = 2, its fine triangles,
where the default levels are 2 and 1, the partner being the cheap level, theory 4.11), and ``--accurate``
adds a row with the accurate operator rebuilt at every shape (``correction_tol=0,
shape_tol=0``): the answers the default must reproduce (theory 4.7).

``--before`` adds a row with the integral model's rebuild rules as they were before the
branch grip-fast (8 Dec 2026; theory 4.7, "Near the substrate plane"): the near-plane height
test against the last accurate build's heights instead of where the correction's secant puts
them, and the Richardson partner rebuilt with every accurate build even where it is the
correction's cheap operator, just built at the same shape. It prints that row's CPU time
against the chain model's beside the default's: the before/after ratio of one run, on the
same machine at the same load.

Run: ``python benchmarks/bench_loss_models.py`` (about a minute; ``--only gripper|crane``
runs one of the two rows, and ``--overdriven`` adds its row unless ``--only gripper``): the
integral model at its defaults (m = 3, Richardson-extrapolated, corrected between rebuilds);
``--refinement m``, ``--correction-tol``, ``--plain`` (the plain operator at m rebuilt at
``IntegralLoss.shape_tol``, the integral model before 6 Dec 2026).
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import dataclasses
import statistics
import time

from design.devices import gripper
from simulator import simulate
from simulator.cases import CRANE_POWER_MW, get_case
from simulator.thermal.integral import IntegralOperator
from simulator.thermal.integral_levels import CorrectedLoss, ExtrapolatedLoss


def _settings(args) -> dict:
    """The integral loss's fields (:class:`~simulator.IntegralLoss`) from the options (empty:
    its defaults, m = 3 Richardson-extrapolated from 2 and 3, corrected between rebuilds)."""
    out = {}
    if args.refinement is not None:
        out["refinement"] = args.refinement
    if args.plain:
        out.update(extrapolation=False, correction_tol=0.0)
    if args.correction_tol is not None:
        out["correction_tol"] = args.correction_tol
    return out


def _timed(fn, repeat):
    """Median wall time [s] and process (CPU) time [s] of ``repeat`` runs after a warm-up, and
    the last run's output."""
    fn()                                                   # warm-up (compilation, caches)
    walls, cpus = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return statistics.median(walls), statistics.median(cpus), out


@contextlib.contextmanager
def counted_builds():
    """Count the integral operator's builds by refinement m while the block runs: yields a
    ``Counter`` {m: builds}."""
    counts = collections.Counter()
    rebuild = IntegralOperator.rebuild

    def counting(self, x):
        counts[round(len(self._bary) ** 0.5)] += 1
        return rebuild(self, x)
    IntegralOperator.rebuild = counting
    try:
        yield counts
    finally:
        IntegralOperator.rebuild = rebuild


@contextlib.contextmanager
def rules_before_grip_fast():
    """The integral loss's rebuild rules before the branch grip-fast while the block runs:
    the near-plane height test without the secant's step (the heights of the last accurate
    build), and the Richardson partner rebuilt with every accurate build."""
    moved, rebuild = CorrectedLoss._moved_near_plane, ExtrapolatedLoss.rebuild
    CorrectedLoss._moved_near_plane = lambda self, x, Lb=None: moved(self, x)
    ExtrapolatedLoss.rebuild = lambda self, x: self._combine(self.fine.rebuild(x),
                                                             self.coarse.rebuild(x))
    try:
        yield
    finally:
        CorrectedLoss._moved_near_plane, ExtrapolatedLoss.rebuild = moved, rebuild


def _before(run):
    """``run`` under :func:`rules_before_grip_fast`."""
    def before():
        with rules_before_grip_fast():
            return run()
    return before


def _builds(counts) -> str:
    return "builds " + ", ".join(f"m = {m}: {n}" for m, n in sorted(counts.items(),
                                                                     reverse=True))


def gripper_run(loss_model: str, settings: dict):
    """A function evaluating the start-design gripper (bisect) with one loss model: the
    device's own option ``GripperHeatModel(loss_model=...)``, whose integral model includes
    the substrate plane under the gripper (z = -undercut), as the device has; ``settings``:
    other fields of its integral loss."""
    design = gripper.GripperDesign()
    heat = gripper.GripperHeatModel(loss_model=loss_model,
                                    **({"integral_refinement": settings["refinement"]}
                                       if "refinement" in settings else {}))
    extra = {k: v for k, v in settings.items() if k != "refinement"}
    if loss_model == "chain" or not extra:
        return lambda: gripper.evaluate_gripper(design, mode="bisect", heat=heat)
    return gripper_evaluation(design, lambda model: dataclasses.replace(
        model, thermal=model.thermal.with_loss(**extra)), heat)


def gripper_evaluation(design, transform, heat=None):
    """A function evaluating ``design`` (bisect, heat model ``heat``) with the model of
    ``gripper.make_gripper_model`` passed through ``transform(model) -> model`` while it
    runs."""
    original = gripper.make_gripper_model

    def model_with(design, *args, **kw):
        model, pre = original(design, *args, **kw)
        return transform(model), pre

    def run():
        gripper.make_gripper_model = model_with
        try:
            return gripper.evaluate_gripper(design, mode="bisect", heat=heat)
        finally:
            gripper.make_gripper_model = original
    return run


def crane_run(loss_model: str, settings: dict, power_mW=None):
    """A function running the crane case with one loss model, ``get_case("crane",
    loss_model=...)``: at its power for that model (``CRANE_POWER_MW``: 4 mW chain, 0.7 mW
    integral, where the crane folds as far) or at ``power_mW``."""
    case = get_case("crane", loss_model=loss_model, power_mW=power_mW)
    model = case.model
    if loss_model == "integral" and settings:
        model = dataclasses.replace(model, thermal=model.thermal.with_loss(**settings))
    return lambda: simulate(model, case.steps)


def crane_overdriven(loss_model: str, settings: dict):
    """The crane with either loss model at the chain model's 4 mW (with the integral model
    it folds flat by a quarter of the ramp and passes through itself: a warning)."""
    return crane_run(loss_model, settings, power_mW=CRANE_POWER_MW["chain"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--refinement", type=int, default=None,
                    help="the integral loss's refinement m (default: the model's, 3)")
    ap.add_argument("--plain", action="store_true",
                    help="the plain operator at m, rebuilt at its shape_tol (no "
                         "extrapolation, no correction: the integral model before 6 Dec 2026)")
    ap.add_argument("--correction-tol", type=float, default=None,
                    help="the integral loss's correction_tol (default: the model's, 0.1)")
    ap.add_argument("--accurate", action="store_true",
                    help="also the integral model with the accurate operator rebuilt at every "
                         "shape (correction_tol=0, shape_tol=0): the answers to reproduce")
    ap.add_argument("--before", action="store_true",
                    help="also the integral model with the rebuild rules before the branch "
                         "grip-fast (8 Dec 2026), and its CPU ratio against the chains")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--only", choices=("gripper", "crane"), help="run one of the two rows")
    ap.add_argument("--overdriven", action="store_true",
                    help="also the crane at 4 mW with both models (the integral model's crane "
                         "passes through itself there: not a comparison of the same task)")
    args = ap.parse_args(argv)
    rows = [("gripper evaluation (bisect)", gripper_run, 2.0), ("crane case", crane_run, 3.0)]
    if args.overdriven:
        rows.append(("crane at 4 mW (overdriven)", crane_overdriven, None))
    for name, make, limit in rows:
        if args.only and not name.startswith(args.only):
            continue
        walls, cpus = {}, {}
        for loss in ("chain", "integral"):
            walls[loss], cpus[loss], out = _timed(make(loss, _settings(args)), args.repeat)
            print(f"{name:<28} {loss:<9}: {walls[loss]:7.3f} s (CPU {cpus[loss]:7.3f} s)   "
                  f"{_summary(out)}")
        with counted_builds() as counts:
            make("integral", _settings(args))()
        print(f"{name:<28} integral operator per run: {_builds(counts)}")
        if args.accurate:
            run = make("integral", {**_settings(args), "correction_tol": 0.0, "shape_tol": 0.0})
            wall, cpu, out = _timed(run, 1)
            with counted_builds() as counts:
                run()
            print(f"{name:<28} {'accurate':<9}: {wall:7.3f} s (CPU {cpu:7.3f} s)   "
                  f"{_summary(out)}; at every shape: {_builds(counts)}")
        if args.before:
            run = _before(make("integral", _settings(args)))
            wall, cpu, out = _timed(run, args.repeat)
            with counted_builds() as counts:
                run()
            print(f"{name:<28} {'before':<9}: {wall:7.3f} s (CPU {cpu:7.3f} s)   "
                  f"{_summary(out)}; {_builds(counts)}")
            print(f"{name:<28} CPU ratio integral / chain: before {cpu / cpus['chain']:.2f}, "
                  f"now {cpus['integral'] / cpus['chain']:.2f} (integral now / before "
                  f"{cpus['integral'] / cpu:.2f})")
        ratio = walls["integral"] / walls["chain"]
        verdict = ("no acceptance" if limit is None else
                   f"acceptance <= {limit:g}: {'met' if ratio <= limit else 'NOT met'}")
        print(f"{name:<28} ratio integral / chain = {ratio:.2f} ({verdict}; CPU time ratio "
              f"{cpus['integral'] / cpus['chain']:.2f})")


def _summary(out) -> str:
    if hasattr(out, "assembly"):
        a, g = out.assembly.power_per_crease, out.grip.power_per_crease
        fmt = lambda p: "-" if p is None else f"{1e3 * p:.3f}"  # noqa: E731
        hot = lambda r: "-" if r.max_crease_temperature is None else \
            f"{r.max_crease_temperature:.2f}"                      # noqa: E731
        return (f"assembly {fmt(a)} mW, grip {fmt(g)} mW per crease ({out.status}); hottest "
                f"crease {hot(out.assembly)} / {hot(out.grip)} degC")
    import numpy as np

    n = sum(s.increments for s in out.steps)
    fold = np.degrees(np.abs(out.fold_angle[-1]))
    return (f"{out.status}, {n} increments, {1e3 * out.wall_time / max(n, 1):.1f} ms per "
            f"increment; |fold| mean {fold.mean():.1f}, max {fold.max():.1f} deg; hottest "
            f"crease {out.crease_temperature[-1].max():.1f} degC")


if __name__ == "__main__":
    main()
