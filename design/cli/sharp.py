"""Sharp creases (concentrated hinges) at the command line: ``check`` and ``run`` of a FOLD
file with ``--crease-model sharp`` (or crease width 0).

Flags: ``--crease-model sharp``; ``--fold-stiffness K`` the fold stiffness per unit crease
length in N m/rad/m (default ``E t^3 / (12 W)`` of the crease data, from the file or the layer
stack); ``--panel-bending-width UM`` (default the mean crease width); ``--panel-mesh``
N5B8 | N4B5. A sharp model is driven mechanically: ``run FILE.fold --fold WHICH=DEG`` folds
the chosen creases (all, M, V, ids '3,5' or heater names) to ``DEG`` in their assigned
directions (M to -DEG, V and U to +DEG; a negative DEG folds against the assignment) by a
self-fold step of ``--fold-steps`` increments, with one panel clamped (``--fix-panel``).
Heating needs creases with a width and is refused.
"""

from __future__ import annotations

import math

from ._common import CLIError, length_um

__all__ = ["add_sharp_options", "sharp_options", "is_sharp_request", "sharp_case",
           "check_sharp", "refuse_heated_sharp"]

_HEAT = ("heating needs creases with a width (compliant creases): drop --crease-model sharp "
         "and give the creases a width, or fold the sharp model with --fold WHICH=DEG")


def add_sharp_options(parser, running: bool) -> None:
    """The concentrated-hinge flags (and, for ``run``, the mechanical drive)."""
    parser.add_argument("--crease-model", choices=["compliant", "sharp"],
                        help="compliant creases with a width (default) or sharp creases "
                             "(concentrated hinges; also chosen by crease width 0)")
    parser.add_argument("--fold-stiffness", type=float, metavar="N_M_PER_RAD_M",
                        help="sharp creases: fold stiffness per unit crease length [N m/rad/m] "
                             "(default E t^3/(12 W) of the crease width and thickness)")
    parser.add_argument("--panel-bending-width", type=float, metavar="UM",
                        help="sharp creases: length of the panel bending rule E t^3/(12 w) in "
                             "um (default the mean crease width)")
    parser.add_argument("--panel-mesh", choices=["N5B8", "N4B5"],
                        help="sharp creases: meshing of quadrilateral panels (default N5B8)")
    if running:
        parser.add_argument("--fold", action="append", metavar="WHICH=DEG",
                            help="sharp creases: fold the creases WHICH (all, M, V, ids '3,5', "
                                 "heater names) to DEG degrees in their assigned directions "
                                 "(M to -DEG, V/U to +DEG) by a self-fold step (repeatable)")
        parser.add_argument("--fold-steps", type=int, default=20, metavar="N",
                            help="increments of the --fold self-fold step (default 20)")


def sharp_options(args) -> dict:
    """Model-reader keywords of the sharp flags (fold stiffness SI, bending width um -> m)."""
    out = {}
    k = getattr(args, "fold_stiffness", None)
    if k is not None:
        if not (math.isfinite(k) and k > 0):
            raise CLIError(f"--fold-stiffness = {k:g} N m/rad/m must be a positive stiffness per "
                           "unit crease length")
        out["fold_stiffness"] = k
    if getattr(args, "panel_bending_width", None) is not None:
        out["panel_bending_width"] = length_um("--panel-bending-width", args.panel_bending_width)
    if getattr(args, "panel_mesh", None) is not None:
        out["panel_mesh"] = args.panel_mesh
    if out and getattr(args, "crease_model", None) != "sharp" and args.crease_width != 0:
        raise CLIError(f"--{next(iter(out)).replace('_', '-')} applies to sharp creases only; add "
                       "--crease-model sharp")
    return out


def is_sharp_request(options: dict, geo=None) -> bool:
    """Whether the flags (or the file, through ``geo``) ask for sharp creases."""
    return options.get("crease_model") == "sharp" or options.get("crease_width") == 0 or \
        (geo is not None and geo.crease_model == "sharp")


def refuse_heated_sharp(model, steps, path) -> None:
    """Refuse, in one line, a run of a sharp model with heating steps."""
    from simulator import Heat
    from simulator.model import SharpHingeMesh

    heats = [s.name for s in steps if isinstance(s, Heat)]
    if heats and isinstance(model.mesh, SharpHingeMesh):
        raise CLIError(f"{path} is read with sharp creases (concentrated hinges) but its steps "
                       f"heat ({', '.join(heats)}): {_HEAT}")


def _folds(specs, geo) -> dict:
    """{crease id: target fold angle [rad]} of the ``--fold WHICH=DEG`` flags."""
    from .plain import select_creases

    letters = geo.pattern.edge_assignment
    out = {}
    for spec in specs:
        which, sep, text = spec.partition("=")
        try:
            deg = float(text)
        except ValueError:
            deg = math.nan
        if not sep or not math.isfinite(deg) or not abs(deg) < 180:
            raise CLIError(f"--fold {spec}: expected WHICH=DEG with DEG a fold angle in degrees "
                           "in (-180, 180), e.g. --fold all=90")
        for c in select_creases(which, geo):
            out[c] = math.radians(-deg if letters[c] == "M" else deg)
    return out


def sharp_case(path, data, options: dict, sharp: dict, args) -> tuple:
    """``(model, steps, parameters, geo)`` of a FOLD file run with sharp creases and a
    ``--fold`` drive (the layer stack gives the crease data the flags and the file lack)."""
    from simulator import SelfFold, Supports
    from simulator.fold import fold_to_model, parse_fold
    from simulator.model import central_panel, check_supported, sharp_model

    from .plain import chosen_stack, print_notes, refuse_creaseless, stack_reader_options

    if getattr(args, "heat", None) is not None:
        raise CLIError(f"--heat {args.heat}: {path} is read with sharp creases (concentrated "
                       f"hinges); {_HEAT}")
    if not getattr(args, "fold", None):
        raise CLIError(f"{path} read with sharp creases needs a mechanical drive: --fold "
                       "WHICH=DEG (e.g. --fold all=90; heating needs crease widths)")
    stack = chosen_stack(args.stack)
    reader = stack_reader_options(stack, options)
    if parse_fold(data, **reader).crease_model != "sharp":
        raise CLIError(f"--fold drives sharp creases, but {path} is read with compliant creases; "
                       "add --crease-model sharp (compliant creases are driven by --heat)")
    reader["crease_model"] = "sharp"
    geo = parse_fold(data, **reader)
    print_notes(geo)
    refuse_creaseless(path, geo.pattern, "fold")
    read, _ = fold_to_model(data, **reader, **sharp)
    pattern = read.mesh.pattern
    panel = central_panel(pattern) if args.fix_panel is None else \
        pattern.check_panel(args.fix_panel, "--fix-panel")
    check_supported(pattern, panel, "clamped panel")
    clamp = sharp_model(pattern, None, read.params).mesh.panel_nodes(panel)
    model = sharp_model(pattern, Supports.nodes(clamp), read.params)
    folds = _folds(args.fold, geo)
    if args.fold_steps < 1:
        raise CLIError(f"--fold-steps = {args.fold_steps} must be >= 1")
    steps = (SelfFold(folds, increments=args.fold_steps),)
    params = {"crease_model": "sharp", "stack": stack.name, "fold": list(args.fold),
              "fixed_panel": panel, **read.params.to_dict()}
    return model, steps, params, geo


def check_sharp(args, geo, sharp: dict, needs: list) -> None:
    """Lines of ``check`` for a sharp read: mesh, stiffness rules, what a run needs."""
    from simulator.model import build_sharp_mesh

    pattern = geo.pattern
    mesh = build_sharp_mesh(pattern, sharp.get("panel_mesh", "N5B8"))
    print(f"  sharp creases (concentrated hinges): {mesh.n_nodes} nodes, {len(mesh.bars)} bars, "
          f"{len(mesh.springs)} springs ({mesh.n_creases} fold springs, "
          f"{sharp.get('panel_mesh', 'N5B8')} panels)")
    if "fold_stiffness" in sharp:
        rule = f"{sharp['fold_stiffness']:g} N m/rad/m (--fold-stiffness)"
    elif "crease_thickness" in geo.sharp_missing or "crease_width" in geo.sharp_missing:
        rule = "unknown: the crease width or thickness is missing"
        needs.append("--fold-stiffness N_M_PER_RAD_M (fold stiffness per crease length)")
    else:
        w = pattern.crease_width[pattern.creases].mean() * 1e6
        rule = f"E t^3/(12 W) of the crease data (mean width {w:g} um)"
    print(f"  fold stiffness per length: {rule}")
    if "crease_width" in geo.sharp_missing and "panel_bending_width" not in sharp:
        needs.append("--panel-bending-width UM")
    needs.append("--fold all|M|V|IDS=DEG (heating needs crease widths)")
