"""Simulation subcommands: ``demo``, ``cases``, ``run``.

``etorigami demo`` shows the paper's headline result (section 5.1): a single electro-thermal
crease (gold on SU-8) with a residual fold rests on the substrate under gravity; heated by a
power ramp it stays down until the power passes a threshold, then lifts off and folds up.
"""

from __future__ import annotations

import sys
import time

from simulator import __version__

from ._common import fold_deg, progress_bar
from ._terms import cli_terms

__all__ = ["add_simulate_commands", "demo_run", "heating_table",
           "threshold_power", "circuit_table"]

#: The demo's heating ramp: power at its end [mW] and thermal increments (2.5 mW each).
DEMO_POWER_MW = 100.0
DEMO_INCREMENTS = 40
#: Rows of the printed table (about; the threshold row is added).
DEMO_ROWS = 10
#: Without substrate contact the threshold is the power where the fold has risen this much [deg].
FOLD_RISE_DEG = 1.0

POWER, FOLD, TEMP, CONTACT = ("power [mW]", "fold_angle [deg]", "temperature [degC]",
                              "substrate_contact")


# ------------------------------------------------------------------------------ demo
def demo_run(residual_fold_deg: float = -10.0, gravity: bool = True, progress=None):
    """Run the demo case: ``single_fold`` with gravity, heated to 100 mW in 40 increments."""
    from simulator import get_case

    case = get_case("single_fold", residual_fold_deg=residual_fold_deg, gravity=gravity,
                    thermal_steps=DEMO_INCREMENTS, power_mW=DEMO_POWER_MW)
    return case, case.run(progress=progress)


def heating_table(result):
    """One row per record of the heating ramp (from the last state before it).

    Columns ``power [mW]``, ``fold_angle [deg]``, ``temperature [degC]`` (crease) and
    ``substrate_contact`` (any contact pair of the folding panel with the substrate active).
    """
    import numpy as np
    import pandas as pd

    # behind the doors on purpose: the contact count of the equilibrium system at a record
    # (the system's element-family interface is not public; tests/unit/test_architecture.py)
    from simulator.mechanics import equilibrium_system

    h = result.history
    heat = np.flatnonzero(h["stage_name"] == "heat")
    recs = np.concatenate(([heat[0] - 1], heat)) if len(heat) else np.array([len(h["stage"]) - 1])
    system = equilibrium_system(result.model)
    rest = result.steps[-1].state.spring_rest        # contact does not depend on it
    contact = [system.evaluate(h["u"][r], rest, hessian=False).n_contacts > 0 for r in recs]
    return pd.DataFrame({POWER: h["power"][recs, 0] * 1e3,
                         FOLD: np.degrees(result.fold_angle[recs, 0]),
                         TEMP: result.crease_temperature[recs, 0], CONTACT: contact})


def threshold_power(table) -> tuple:
    """(power [mW] or None, what it marks) from a :func:`heating_table`.

    On the substrate: the first power at which the panel has left it (no contact). Otherwise
    (no gravity): the first power at which the fold is ``FOLD_RISE_DEG`` above its start.
    """
    import numpy as np

    if table[CONTACT].iloc[0]:
        above, what = ~table[CONTACT].to_numpy(), "the panel leaves the substrate"
    else:
        fold = table[FOLD].to_numpy()
        above, what = fold - fold[0] >= FOLD_RISE_DEG, f"the fold rises by {FOLD_RISE_DEG:g} deg"
    hits = np.flatnonzero(above)
    return (float(table[POWER].iloc[hits[0]]) if len(hits) else None), what


def _print_demo(case, result, table, threshold, what, wall):
    rf, grav = case.parameters["residual_fold_deg"], case.parameters["gravity"]
    print(f"etorigami {__version__} demo: one electro-thermal crease (gold on SU-8), residual "
          f"fold {rf:g} deg, {'on the substrate under gravity' if grav else 'no gravity'}, "
          f"heated to {DEMO_POWER_MW:g} mW")
    print(f"  {case.model.thermal.describe(len(case.model.mesh.triangles))}")
    print("  steps: " + ", ".join(f"{s.name} {s.status} ({s.increments} increments)"
                                  for s in result.steps))
    every = max(1, round((len(table) - 1) / DEMO_ROWS))
    rows = set(range(0, len(table), every)) | {len(table) - 1}
    if threshold is not None:
        rows.add(int((table[POWER].to_numpy() == threshold).nonzero()[0][0]))
    print(f"  {'power [mW]':>10}  {'fold angle [deg]':>16}  {'temperature [degC]':>18}"
          f"  {'on substrate':>12}")
    for i in sorted(rows):
        r = table.iloc[i]
        mark = "  <- threshold" if threshold is not None and r[POWER] == threshold else ""
        print(f"  {r[POWER]:10.1f}  {r[FOLD]:16.2f}  {r[TEMP]:18.1f}"
              f"  {'yes' if r[CONTACT] else 'no':>12}{mark}")
    if threshold is None:
        print(f"  threshold: not reached below {DEMO_POWER_MW:g} mW ({what} never)")
    else:
        print(f"  threshold: {threshold:.1f} mW ({what}; to within the "
              f"{DEMO_POWER_MW / DEMO_INCREMENTS:g} mW ramp increment)")
    print(f"  wall time {wall:.2f} s")


def _demo(args) -> int:
    fold_deg("--residual-fold", args.residual_fold)
    t0 = time.perf_counter()
    case, result = demo_run(args.residual_fold, gravity=not args.no_gravity)
    table = heating_table(result)
    threshold, what = threshold_power(table)
    _print_demo(case, result, table, threshold, what, time.perf_counter() - t0)
    if args.out:
        from ._plots import demo_figure

        out = result.save(args.out, {"case": case.name, "parameters": case.parameters,
                                     "threshold_power [mW]": threshold})
        footer = case.model.thermal.describe(len(case.model.mesh.triangles))
        demo_figure(table, threshold, what, footer).savefig(out / "demo.png", dpi=120)
        print(f"  results in {out}: creases.csv, nodes.npz, meta.json, demo.png")
    return 0 if result.success else 1


# ------------------------------------------------------------------------------ cases, run
def _cases(args) -> int:
    import textwrap

    from simulator.cases import describe_cases, parameter_note

    from .case_params import cli_unit, to_cli

    for name, doc, params in describe_cases():
        print(textwrap.fill(f"{name.replace('_', '-')}: {doc}", 92, subsequent_indent="  ",
                            break_on_hyphens=False))
        for pname, default, si_unit in params:
            unit = cli_unit(si_unit).name
            unit = f" [{unit}]" if unit else ""
            note = parameter_note(name, pname)
            shown = "(chosen by the case)" if default is None else repr(to_cli(default, si_unit))
            print(f"    {pname} = {shown}{unit}" + (f"  ({note})" if note else ""))
    return 0


def _run(args) -> int:
    from simulator import NewtonOptions, get_case, simulate

    from ._summary import summary_lines
    from .case_params import case_overrides
    from .files import fold_case, is_fold_file, reader_options
    from .plain import heat_failure_hint
    from .precheck import check_heating

    if is_fold_file(args.case):
        name, model, steps, params = fold_case(args.case, args.set, reader_options(args))
        meta = {"model_file": str(args.case), "overrides": params}
    else:
        from .plain import refuse_electrical_without_heat

        refuse_electrical_without_heat(args, f"{args.case} is a built-in case with its own "
                                       "heating")
        case = get_case(args.case, **case_overrides(args.set, args.case))
        name, model, steps = case.name, case.model, case.steps
        meta = {"case": case.name, "parameters": case.parameters}
    warning = check_heating(model, steps, name)
    if warning:
        print(warning, file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    where = {}
    with progress_bar(desc=name, unit="inc", disable=args.quiet) as bar:
        def progress(done, total):
            where.update(done=done, total=total)
            if bar.total != total:
                bar.reset(total=total)
            bar.update(done - bar.n)

        result = simulate(model, steps, progress=progress, interruptible=True,
                          options=NewtonOptions(stability=args.stability, branch=args.branch))
    if result.status == "interrupted":
        return _save_interrupted(result, args.out, meta, where)
    out = result.save(args.out, meta)
    hint = heat_failure_hint(meta.get("overrides", {}), model, result, args.unit_scale)
    print(f"{name}: {result.status} ({cli_terms(result.message)}) in "
          f"{time.perf_counter() - t0:.1f} s; "
          f"results in {out}" + (f"; {hint}" if hint else ""))
    print(_last_record_table(result, model))
    circuits = circuit_table(result)
    if circuits:
        print(circuits)
    for line in summary_lines(result):
        print(line)
    return 0 if result.success else 1


def _last_record_table(result, model) -> str:
    """The creases at the last record (crease, power, fold angle, temperatures), printed as
    pandas would print those rows of ``creases.csv`` (without importing pandas), with the
    centre-line mean ``temperature_centre [degC]``, what the 1.2 T_g limit is judged on,
    before the hottest node ``temperature_max [degC]``."""
    from ._text_table import format_table

    columns = result.to_columns()
    last = columns["step"] == columns["step"].max()
    if model.thermal is None and getattr(model.mesh, "sharp", False):
        names = ["crease", "fold_angle [deg]"]            # concentrated hinges: not heated
        return format_table({n: columns[n][last] for n in names})
    table = {n: columns[n][last] for n in ("crease", "power [mW]", "fold_angle [deg]",
                                           "temperature [degC]")}
    table["temperature_centre [degC]"] = result.crease_temperature_centre_line[-1]
    table["temperature_max [degC]"] = columns["temperature_max [degC]"][last]
    return format_table(table)


def circuit_table(result) -> str:
    """The heater circuits at the last record that has them, in CLI units: ``circuit``,
    ``voltage [V]``, ``current [mA]``, ``power [mW]`` (delivered), ``lead_loss [mW]``; ""
    without circuits."""
    import numpy as np

    from ._text_table import format_table

    cols = result.history["columns"]
    labels = [n[len("circuit_"):-len("_voltage [V]")] for n in cols
              if n.startswith("circuit_") and n.endswith("_voltage [V]")]
    if not labels:
        return ""
    rows = []
    for lb in labels:
        values = [cols[f"circuit_{lb}_{q}"] for q in ("voltage [V]", "current [A]", "power [W]",
                                                      "lead_loss [W]")]
        last = max(i for i, v in enumerate(values[0]) if v is not None)
        rows.append([v[last] for v in values])
    v, i, p, lead = np.array(rows, float).T
    return format_table({"circuit": np.array(labels, dtype=object), "voltage [V]": v,
                         "current [mA]": 1e3 * i, "power [mW]": 1e3 * p,
                         "lead_loss [mW]": 1e3 * lead})


def _save_interrupted(result, out_dir, meta, where) -> int:
    """Ctrl-C during ``run``: save the accepted increments as a partial result (status
    "interrupted" in meta.json), say so in one line, exit status 130."""
    import signal

    from ._common import EXIT_INTERRUPTED

    signal.signal(signal.SIGINT, signal.SIG_IGN)         # a second Ctrl-C must not cut the save
    out = result.save(out_dir, {**meta, "interrupted": True})
    step = result.steps[-1]
    at = (f", step {step.name!r} at increment {where['done']} of {where['total']}"
          if where else f", step {step.name!r}")
    n = int((result.history["increment"] > 0).sum())     # not the start records (0)
    print(f"interrupted: {n} accepted increment{'s' if n != 1 else ''} saved in {out} as a "
          f"partial result (status \"interrupted\"{at}); run the same command again to start "
          "over", file=sys.stderr, flush=True)
    return EXIT_INTERRUPTED


def _not_saved(args) -> str:
    return ("interrupted: nothing saved (results are written when the run ends); run the same "
            "command again")


# ------------------------------------------------------------------------------ parser
def add_simulate_commands(sub) -> None:
    """Register ``demo``, ``cases`` and ``run`` on an argparse subparsers object."""
    demo = sub.add_parser("demo", help="the main demo: a crease with a residual fold on a "
                          "substrate under gravity, heated until it lifts off")
    demo.add_argument("--residual-fold", type=float, default=-10.0, metavar="DEG",
                      help="residual fold angle of the crease in degrees, in (-180, 180] "
                           "(default -10)")
    demo.add_argument("--no-gravity", action="store_true", help="switch gravity off")
    demo.add_argument("--out", metavar="DIR", help="write creases.csv, nodes.npz, meta.json "
                                                   "and demo.png")
    demo.set_defaults(func=_demo, interrupted=_not_saved, short=True)

    cases = sub.add_parser("cases", help="list the paper's cases with parameters and defaults")
    cases.set_defaults(func=_cases)

    run = sub.add_parser("run", help="run a case or a FOLD model file and write creases.csv, "
                                     "nodes.npz, meta.json")
    run.add_argument("case", metavar="CASE|FILE.fold",
                     help="case name, e.g. single-fold (see 'etorigami cases'), or a FOLD model "
                          "file (see 'etorigami export')")
    run.add_argument("--set", action="append", metavar="NAME=VALUE",
                     help="override a case parameter in the CLI unit 'etorigami cases' lists "
                          "(lengths um, powers mW, angles deg, times s; repeatable), e.g. "
                          "--set crease_width=200 --set gravity=true; for a FOLD file "
                          "power.<crease id>=mW or thermal_steps=N")
    run.add_argument("--out", required=True, metavar="DIR", help="output folder")
    run.add_argument("--branch", choices=("lower", "other"), default="lower",
                     help="where a state turns unstable (a flat sheet heated at a bifurcation), "
                          "leave it for the branch of lower energy (default) or the other one")
    run.add_argument("--stability", choices=("switch", "check", "off"), default="switch",
                     help="check every accepted state and leave an unstable one (switch, "
                          "default), only report it (check; a run ending unstable fails) or "
                          "neither (off, the reference's behaviour)")
    from .files import add_reader_options

    add_reader_options(run)
    run.set_defaults(func=_run, interrupted=_not_saved, short=True)
