"""Plain crease patterns at the command line: ``check`` and ``run`` of a FOLD file drawn in an
editor, with no ``etorigami:`` fields.

A named layer stack (:data:`simulator.model.STACKS`, default ``su8-au``, the paper's SU-8/Au
bimorph) supplies the physical parameters the file lacks; ``--crease-width`` /
``--crease-thickness`` / ``--panel-thickness`` [um] override it. ``run FILE.fold --heat
all|M|V|IDS|NAMES --power MW`` makes the chosen creases actuators folding in their assigned
directions, clamps one panel (``--fix-panel``, default the central one), switches panel
contact on (``--no-contact``: off; :func:`simulator.model.plain_contact`) and heats them in
``--thermal-steps`` increments.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace

from ._common import CLIError, distinct, power_mw

__all__ = ["add_plain_options", "is_plain", "plain_case", "check_plain", "select_creases",
           "heater_names", "refuse_creaseless", "chosen_stack", "print_notes", "DEFAULT_STACK",
           "heat_failure_hint", "driven", "heat_drive", "heat_fields", "drive_parameters",
           "refuse_electrical_without_heat"]

_NS = "etorigami:"
#: The layer stack of a plain pattern when ``--stack`` is not given.
DEFAULT_STACK = "su8-au"


def add_plain_options(parser, heating: bool = True) -> None:
    """``--stack``, ``--frame``, ``--lay-flat``, ``--keep-collinear`` and, for ``run``,
    ``--heat``, ``--power``, ``--fix-panel``, ``--loss-model``, ``--contact`` /
    ``--no-contact``."""
    parser.add_argument("--stack", metavar="NAME",
                        help="layer stack giving a plain pattern's physical parameters "
                             "(default su8-au, the paper's SU-8/Au bimorph; see "
                             "simulator.model.STACKS)")
    parser.add_argument("--frame", metavar="INDEX|CLASS",
                        help="FOLD frame to read: an index (0 = key frame) or creasePattern / "
                             "foldedForm")
    parser.add_argument("--lay-flat", action=argparse.BooleanOptionalAction, default=None,
                        help="lay a flat sheet drawn in another plane (e.g. x-z) in x-y, top "
                             "side up (default for a plain pattern; a model file stays in its "
                             "own axes); --no-lay-flat keeps it standing")
    parser.add_argument("--keep-collinear", action="store_true",
                        help="keep vertices in the middle of straight crease lines")
    if heating:
        parser.add_argument("--heat", metavar="WHICH",
                            help="creases to heat in a plain pattern: all, M, V, crease ids "
                                 "'3,5' or heater names from the file")
        parser.add_argument("--power", type=float, metavar="MW",
                            help="power per heated crease [mW]")
        parser.add_argument("--voltage", type=float, metavar="V",
                            help="instead of --power: voltage [V] across each heated crease's "
                                 "heater (a gold film over the crease, its resistance rising "
                                 "0.34 %% per K: self-limiting; theory 8.8)")
        parser.add_argument("--current", type=float, metavar="MA",
                            help="instead of --power: current [mA] through each heated "
                                 "crease's heater (may run away: theory 8.8)")
        parser.add_argument("--fix-panel", type=int, metavar="ID",
                            help="clamped panel (default: the panel nearest the centre)")
        parser.add_argument("--loss-model", choices=("integral", "chain"), default=None,
                            help="heat loss of a heated plain pattern to the air: the "
                                 "boundary-integral model (default; theory 4.7: nothing "
                                 "fitted, within 1 %% of the 3-D FE) or the paper's chains "
                                 "(seconds, 20-40 %% too cool). Above the integral model's "
                                 "dense limit (about 440 triangles) it takes a fast path at "
                                 "m = 2 (2-4 %% above its default), about a minute per "
                                 "thermal solve at 20,000 triangles")
        parser.add_argument("--contact", action=argparse.BooleanOptionalAction, default=True,
                            help="panel contact of a heated plain pattern (default on: panels "
                                 "never pass through each other; --no-contact: off, a run "
                                 "stops with an event where they would)")


def chosen_stack(name):
    """The layer stack of ``--stack`` (default :data:`DEFAULT_STACK`)."""
    from simulator.model import get_stack

    return get_stack(DEFAULT_STACK if name is None else name)


def frame_option(text):
    """``--frame`` value: an int index or a class name."""
    if text is None:
        return None
    return int(text) if text.strip().lstrip("-").isdigit() else text


def is_plain(data: dict) -> bool:
    """True for a FOLD dict that is not a model file: no ``etorigami:steps`` (a pattern drawn
    in an editor, perhaps with some ``etorigami:`` crease or panel data)."""
    return not data.get(f"{_NS}steps")


def heater_names(geo) -> dict:
    """{heater name: crease ids} from ``edges_etorigami:heater`` of a parsed FOLD file."""
    out = {}
    names = geo.data.get(f"edges_{_NS}heater")
    for i, name in enumerate(names if isinstance(names, list) else ()):
        e = int(geo.edge[i])
        if isinstance(name, str) and e >= 0 and geo.pattern.is_crease[e]:
            out.setdefault(name, []).append(e)
    return {k: tuple(sorted(v)) for k, v in out.items()}


def refuse_creaseless(path, pattern, what: str) -> None:
    """Refuse, in one line, a run of a pattern without a crease (``what``: heat or fold)."""
    if not len(pattern.creases):
        raise CLIError(f"{path} has no crease to {what}: its edges are all boundary (B) or "
                       "flat (F, J) edges; draw the creases as M, V or U edges")


def select_creases(spec: str, geo) -> list:
    """Crease ids of ``--heat``: all, M, V (or M,V), ids, heater names (comma separated)."""
    pattern = geo.pattern
    creases = pattern.creases.tolist()
    letters = pattern.edge_assignment
    names = heater_names(geo)
    out = []
    for word in (w.strip() for w in spec.split(",") if w.strip()):
        if word.lower() == "all":
            out += creases
        elif word.upper() in ("M", "V", "U"):
            out += [c for c in creases if letters[c] == word.upper()]
        elif word.isdigit():
            if int(word) not in creases:
                raise CLIError(f"--heat {spec}: {word} is not a crease; creases are {creases}")
            out.append(int(word))
        elif word in names:
            out += list(names[word])
        else:
            raise CLIError(f"--heat {spec}: {word!r} is not all, M, V, a crease id or a heater "
                           f"name (heaters: {', '.join(names) or 'none'})")
    out = sorted(set(out))
    if not out:
        raise CLIError(f"--heat {spec} selects no crease (the pattern has {len(creases)} "
                       f"creases: {sum(letters[c] == 'M' for c in creases)} M, "
                       f"{sum(letters[c] == 'V' for c in creases)} V)")
    return out


def print_notes(geo, stack=None) -> None:
    """What the reader repaired or recognised, one ``note:`` line each, in CLI spelling; with
    the layer ``stack``, also the values that the file or the flags give instead of it
    (compliant creases; a sharp read's stiffness rules are printed by :func:`.sharp.check_sharp`)."""
    from ._terms import cli_terms

    for note in geo.notes:
        print(f"  note: {cli_terms(note)}")
    pattern = geo.pattern
    instead = [] if stack is None or geo.crease_model == "sharp" else [
        f"{name} {distinct(values)} um" for name, values, nominal in (
            ("crease width", pattern.crease_width[pattern.creases], stack.crease_width),
            ("crease thickness", pattern.crease_thickness[pattern.creases],
             stack.crease_thickness),
            ("panel thickness", pattern.panel_thickness, stack.panel_thickness))
        if len(values) and any(abs(v - nominal) > 1e-9 * nominal for v in values)]
    if instead:
        print(f"  note: used instead of the stack's values (from the file or the flags): "
              f"{', '.join(instead)}")


def large_sheet_loss():
    """The integral loss of a plain pattern whose default loss would take the fast path (above
    the dense limit): plain m = 2, one level (the default, m = 3 extrapolated from 2, has 13
    sub-triangles per triangle: 264,000 on the 36 x 36-cell Miura sheet)."""
    from simulator import IntegralLoss

    return IntegralLoss(refinement=2, extrapolation=False)


def heat_loss_line(model) -> str:
    """The heat loss of a plain pattern's model, in CLI units: the integral model (with the
    cost of its fast path on a large sheet) or the paper's chains, and the air."""
    thermal = model.thermal
    loss, k_env = thermal.loss, thermal.medium.thermal_conductivity
    if loss.model == "chain":
        return (f"the paper's chains, t_env {loss.thickness * 1e6:.4g} um, to air at "
                f"{k_env:.4g} W/(m K)")
    line = f"{loss.describe()}, to air at {k_env:.4g} W/(m K)"
    n = len(model.mesh.triangles)
    if (r := thermal.sheet_refinement_for(n)) > 1:
        line += f", sheet refined r = {r}"
    if loss == large_sheet_loss():
        line += ("; m = 2 without extrapolation: the default, m = 3 extrapolated, is above its "
                 "dense limit here and takes too long (m = 2 is 2-4 % hotter on bent Miura "
                 "sheets)")
    if loss.takes_fast_path(n):
        line += (f"; {n} triangles take its fast path (theory 4.7): about a minute per "
                 "thermal solve at 20,000 triangles")
    return line


def stack_reader_options(stack, options: dict) -> dict:
    """Reader keywords: the stack's crease / panel values unless the flags give them."""
    out = {"crease_width": stack.crease_width, "crease_thickness": stack.crease_thickness,
           "panel_thickness": stack.panel_thickness}
    out.update(options)
    return out


def plain_case(path: str, data: dict, options: dict, heating) -> tuple:
    """``(model, steps, parameters)`` of a plain pattern heated from the flags."""
    from simulator import Heat
    from simulator.fold import parse_fold
    from simulator.model import stack_model

    stack = chosen_stack(heating.stack)
    print(f"layer stack {stack.summary()}")
    geo = parse_fold(data, **stack_reader_options(stack, options))
    print_notes(geo, stack)
    if geo.crease_model == "sharp":
        raise CLIError(f"{path} has sharp creases (width 0 in edges_etorigami:width): heating "
                       "needs creases with a width; fold it with --fold WHICH=DEG instead")
    refuse_creaseless(path, geo.pattern, "heat")
    if heating.heat is None or not driven(heating):
        missing = [f for f, v in (("--heat all|M|V|IDS", heating.heat),
                                  ("--power MW", driven(heating))) if not v]
        raise CLIError(f"{path} is a plain crease pattern (no etorigami: steps); heating it "
                       f"needs {' and '.join(missing)}")
    heated = select_creases(heating.heat, geo)
    drive = heat_drive(heating)
    contact = getattr(heating, "contact", True)
    loss = getattr(heating, "loss_model", None)
    model = stack_model(geo.pattern, stack, heated, heating.fix_panel, contact=contact,
                        loss_model=loss or "integral")
    n = len(model.mesh.triangles)
    if loss is None and model.thermal.loss.takes_fast_path(n):
        model = replace(model, thermal=replace(model.thermal, loss=large_sheet_loss()))
    loss = loss or "integral"
    print(f"  heat loss: {heat_loss_line(model)}")
    print(f"  {contact_line(model, contact)}")
    steps = (Heat(**heat_fields(heated, drive), increments=200),)
    params = {"stack": stack.name, "heat": heating.heat, **drive_parameters(heating),
              "heated_creases": heated, "contact": contact, "loss_model": loss}
    return model, steps, params, geo


#: Largest voltage [V] and current [mA] the CLI accepts per heated crease: a gold heater over a
#: crease has about 0.1-10 Ohm, so 100 V or 10 A would vaporise it; a larger value is a typo.
MAX_VOLTAGE_V, MAX_CURRENT_MA = 100.0, 1e4
#: The drives of a heating run: flag, CLI unit, SI factor, largest value, Drive keyword.
_DRIVES = (("--power", "mW", 1e-3, None, "power"),
           ("--voltage", "V", 1.0, MAX_VOLTAGE_V, "voltage"),
           ("--current", "mA", 1e-3, MAX_CURRENT_MA, "current"))


def driven(heating) -> list:
    """The drive flags given (``--power``, ``--voltage``, ``--current``)."""
    return [flag for flag, *_ in _DRIVES if getattr(heating, flag[2:], None) is not None]


def heat_drive(heating) -> tuple:
    """``(kind, value [W, V or A])`` of the one drive flag given, checked in CLI units;
    refused in one line if none or several are given or a value is out of range."""
    given = driven(heating)
    if len(given) != 1:
        raise CLIError(f"give one of --power MW, --voltage V or --current MA per heated crease "
                       f"(got {', '.join(given) or 'none'})")
    flag, unit, si, top, kind = next(d for d in _DRIVES if d[0] == given[0])
    value = getattr(heating, flag[2:])
    if kind == "power":
        return kind, power_mw(flag, value)
    if not (math.isfinite(value) and 0.0 <= value <= top):
        raise CLIError(f"{flag} = {value:g} {unit} is outside the plausible range 0 to {top:g} "
                       f"{unit} per heated crease (a gold heater over a crease has 0.1-10 Ohm)")
    return kind, value * si


def refuse_electrical_without_heat(args, what: str) -> None:
    """Refuse, in one line, ``--voltage`` / ``--current`` without ``--heat`` (``what``: why
    they would be ignored)."""
    given = [f for f in driven(args) if f != "--power"]
    if given:
        raise CLIError(f"{' and '.join(given)} drive the creases of --heat WHICH; {what}: add "
                       "--heat all|M|V|IDS or drop them")


def heat_fields(heated, drive) -> dict:
    """``Heat`` keywords of the heated creases at ``drive`` (:func:`heat_drive`): a power per
    crease, or per crease one circuit (named by its crease id) of a gold-film heater over it
    (:class:`simulator.Heater` defaults, squares from the crease's length over its width)."""
    from simulator import Circuit, Drive

    kind, value = drive
    if kind == "power":
        return {"power": {c: value for c in heated}}
    return {"circuits": {Circuit((c,), name=str(c)): Drive(**{kind: value}) for c in heated}}


def drive_parameters(heating) -> dict:
    """The drive flag as typed, for ``meta.json`` (``power_mW``, ``voltage_V``, ``current_mA``)."""
    return {f"{flag[2:]}_{unit}": getattr(heating, flag[2:])
            for flag, unit, *_ in _DRIVES if getattr(heating, flag[2:], None) is not None}


#: The crease width a plain pattern is retried with after load control gave up heating it, as a
#: fraction of the width it had: the four flat-folder patterns of issue 28 (Pig, Kirby, Little
#: Bird, Teddy Bear) at 10 mm give up at a critical state with the stack's 200 um creases and
#: all run with 50 um (17-80 s), as with 200 um creases on a sheet ten times larger.
NARROWER = 0.25


def heat_failure_hint(params: dict, model, result, unit_scale) -> str:
    """What to change, in CLI flags, when load control gave up heating a plain pattern with
    compliant creases (status "failed") (``params`` of :func:`plain_case`, ``unit_scale`` the one given or None):
    narrower creases against the panels (``--crease-width``, :data:`NARROWER` of the widest),
    or, for a file in plain units, a larger sheet (``--unit-scale`` ten times larger); "" for
    any other outcome."""
    if "heat" not in params or result.success or result.status != "failed":
        return ""                    # (status "failed": a heating step's equilibrium failed)
    pattern = getattr(model.mesh, "pattern", None)
    if pattern is None or getattr(model.mesh, "sharp", False) or not len(pattern.creases):
        return ""
    width = float(pattern.crease_width[pattern.creases].max()) * 1e6
    if not width > 0:
        return ""
    text = (f"what to change: narrower creases against the panels, e.g. --crease-width "
            f"{NARROWER * width:.3g} (now {width:.3g} um)")
    if unit_scale is not None:
        text += f", or a larger sheet, e.g. --unit-scale {10 * unit_scale:g} (now {unit_scale:g})"
    return text


def contact_line(model, asked: bool) -> str:
    """What the run does about panels passing through each other, in one line."""
    from simulator import ParameterError
    from simulator.model import plain_contact

    crossing = "a run stops with an event where panels pass through each other"
    if model.contact is not None:
        return (f"panel contact: on, from {model.contact.d0_corner * 1e6:.3g} um (creases "
                "stay within +-180 deg; --no-contact: off)")
    if not asked:
        return f"panel contact: off (--no-contact); {crossing}"
    try:
        plain_contact(model.mesh.pattern, model.params, required=True)
    except ParameterError as error:
        return f"panel contact: off: {str(error).rstrip('.')}; {crossing}"
    return f"panel contact: off; {crossing}"


def check_plain(args, data: dict, options: dict, sharp: dict | None = None) -> int:
    """``check`` of a plain pattern: geometry summary, then what a run needs, in CLI flags
    (sharp creases: :func:`.sharp.check_sharp`)."""
    import numpy as np

    from simulator import make_mesh
    from simulator.fold import parse_fold
    from simulator.model import central_panel, check_supported, start_fold_angles

    from .sharp import check_sharp

    stack = chosen_stack(args.stack)
    needs = []
    unit = data.get("frame_unit", "unit")
    if unit == "unit" and "unit_scale" not in options:
        needs.append("--unit-scale METRES (frame_unit is 'unit': metres per file unit)")
        options = {**options, "unit_scale": 1e-3}
    geo = parse_fold(data, **stack_reader_options(stack, options))
    pattern = geo.pattern
    panel = getattr(args, "fix_panel", None)
    panel = central_panel(pattern) if panel is None else pattern.check_panel(panel, "--fix-panel")
    check_supported(pattern, panel, "clamped panel")
    letters = pattern.edge_assignment[pattern.creases]
    fold = np.degrees(start_fold_angles(pattern)[pattern.creases])
    size = np.ptp(pattern.vertices, axis=0) * 1e6
    print(f"{args.file}: valid FOLD crease pattern (no etorigami: model or steps)")
    print(f"  vertices {pattern.n_vertices}, panels {pattern.n_panels}, creases "
          f"{len(pattern.creases)} ({sum(letters == 'M')} M, {sum(letters == 'V')} V, "
          f"{sum(letters == 'U')} U), size {size[0]:.1f} x {size[1]:.1f} x {size[2]:.1f} um"
          + (" (provisional 1 mm per unit)" if needs else ""))
    shape = "flat" if not len(fold) or np.abs(fold).max() < 1e-6 else \
        f"folded, start fold angles {fold.min():.1f} to {fold.max():.1f} deg"
    print(f"  start shape: {shape}")
    print_notes(geo, stack)
    refuse_creaseless(args.file, pattern, "heat or fold")
    if geo.crease_model == "sharp":
        check_sharp(args, geo, sharp or {}, needs)
        print("  a run needs: " + "; ".join(needs))
        print(f"  e.g. etorigami run {args.file} --crease-model sharp --fold all=90 --out DIR")
        return 0
    mesh = make_mesh(pattern)
    widths = pattern.crease_width[pattern.creases]
    print(f"  mesh: {mesh.n_nodes} nodes, {len(mesh.bars)} bars, {len(mesh.springs)} springs "
          f"(checked with crease width {widths.min() * 1e6:g} um)")
    print(f"  physical parameters from layer stack {stack.summary()}")
    print("  a run needs: " + "; ".join(needs + ["--heat all|M|V|IDS", "--power MW"]) +
          " (or --voltage V, --current MA)")
    print(f"  e.g. etorigami run {args.file} --heat all --power 2 --out DIR")
    return 0
