"""File subcommands: ``export``, ``check``, ``view`` (and the FOLD side of ``run``).

* ``etorigami export CASE [--set ...] --format fold --out FILE``: a built-in case as a FOLD model
  file (pattern, materials, supports, thermal model, actuators and loading steps under the
  ``etorigami:`` namespace) that ``etorigami run FILE`` runs back to the same result;
* ``etorigami check FILE``: validate a FOLD file and print its summary (for a plain crease
  pattern, also what a run still needs, in flags: :mod:`.plain`);
* ``etorigami view RESULT_DIR [--out FILE.html]``: one self-contained HTML page with the
  folded shape in 3-D over the run.
"""

from __future__ import annotations

import math
import pathlib

from ._common import CLIError, length_um, power_mw
from ._terms import cli_spelling

__all__ = ["add_file_commands", "add_reader_options", "fold_case", "is_fold_file",
           "reader_options"]


def is_fold_file(name: str) -> bool:
    """True if ``name`` names a FOLD file rather than a built-in case."""
    return name.lower().endswith(".fold") or pathlib.Path(name).is_file()


@cli_spelling()
def fold_case(path: str, overrides: list | None, options: dict | None = None):
    """``(name, model, steps, parameters)`` of a FOLD file with ``--set`` overrides.

    A model file runs its own steps, or, given ``--heat``, its own model heated from the flags
    (:mod:`.model_heat`); a plain crease pattern (no ``etorigami:`` steps) is heated from the
    flags with a layer stack (:mod:`.plain`).
    Overrides: ``power.<crease id or heater name>=MW`` sets the power added by the last heating
    step on that crease (or on the heater circuit that contains it), ``thermal_steps=N`` the
    increments of its heating steps.
    """
    from simulator.fold import load_fold_json, parse_fold, read_model

    from .model_heat import model_file_heat_case, refuse_unheatable
    from .plain import heater_names, is_plain, plain_case, refuse_electrical_without_heat
    from .sharp import is_sharp_request, sharp_case

    options = dict(options or {})
    heating = options.pop("_heating", None)
    sharp = options.pop("_sharp", {})
    data = load_fold_json(path)
    geo = None
    drive = heating is not None and (heating.heat is not None or getattr(heating, "fold", None)
                                     or is_plain(data))
    if heating is not None and not drive:
        refuse_electrical_without_heat(heating, f"{path} runs its own steps")
    if drive and (is_sharp_request(options) or getattr(heating, "fold", None)):
        model, steps, params, geo = sharp_case(path, data, options, sharp, heating)
    elif drive and is_plain(data):
        model, steps, params, geo = plain_case(path, data, options, heating)
    elif drive:
        model, steps, params, geo = model_file_heat_case(path, data, options, sharp, heating)
    else:
        model, steps = read_model(path, **options, **sharp)
        refuse_unheatable(model, steps, path)
        params = {}
    names = {}
    if any(not o.partition("=")[0].strip()[len("power."):].isdigit()
           for o in overrides or [] if o.strip().startswith("power.")):
        names = heater_names(geo or parse_fold(data, **options))
    steps = _apply_overrides(path, list(steps), overrides, names, params)
    return pathlib.Path(path).stem, model, tuple(steps), params


def _apply_overrides(path, steps, overrides, names, params) -> list:
    from simulator import Heat

    for pair in overrides or []:
        name, sep, text = pair.partition("=")
        if not sep:
            raise CLIError(f"--set expects name=value, got {pair!r}")
        name = name.strip()
        heats = [k for k, s in enumerate(steps) if isinstance(s, Heat)]
        if not heats:
            raise CLIError(f"{path} has no heating step; --set {name} needs one (a plain "
                           "pattern is heated with --heat and --power)")
        if name == "thermal_steps":
            n = _number(name, text, int)
            steps = [_replace(s, increments=n) if isinstance(s, Heat) else s for s in steps]
        elif name.startswith("power."):
            key = name[len("power."):]
            if key.isdigit():
                creases = (int(key),)
            elif key in names:
                creases = names[key]
            else:
                raise CLIError(f"--set {name}: {key!r} is neither a crease id nor a heater name "
                               f"of the file (heaters: {', '.join(names) or 'none'})")
            k = heats[-1]
            watts = power_mw(f"--set {name}", _number(name, text, float))
            steps[k] = _replace(steps[k], power=_set_power(steps[k].power, creases, watts))
        else:
            raise CLIError(f"--set {name}: a FOLD model takes power.<crease id>=mW, "
                           "power.<heater name>=mW or thermal_steps=N")
        params[name] = text
    return steps


def reader_options(args) -> dict:
    """Keyword arguments of :func:`simulator.fold.read_model` from ``--unit-scale``, the
    ``--crease-width`` / ``--crease-thickness`` / ``--panel-thickness`` defaults [um],
    ``--frame``, ``--lay-flat`` / ``--no-lay-flat``, ``--keep-collinear`` and
    ``--crease-model`` (and, under ``_heating``, the flags that drive a plain pattern; under
    ``_sharp``, the model keywords of sharp creases, :mod:`.sharp`)."""
    from .plain import frame_option
    from .sharp import sharp_options

    out = {}
    if args.unit_scale is not None:
        if not (math.isfinite(args.unit_scale) and args.unit_scale > 0):
            raise CLIError(f"--unit-scale = {args.unit_scale:g} must be a positive length in "
                           "metres per file unit")
        out["unit_scale"] = args.unit_scale
    for name in ("crease_width", "crease_thickness", "panel_thickness"):
        value = getattr(args, name)
        if name == "crease_width" and value == 0:
            out[name] = 0.0                          # sharp creases (concentrated hinges)
        elif value is not None:
            out[name] = length_um(f"--{name.replace('_', '-')}", value)
    if getattr(args, "crease_model", None) is not None:
        out["crease_model"] = args.crease_model
    out["_sharp"] = sharp_options(args)
    if getattr(args, "frame", None) is not None:
        out["frame"] = frame_option(args.frame)
    if getattr(args, "lay_flat", None) is not None:
        out["lay_flat"] = args.lay_flat
    if getattr(args, "keep_collinear", False):
        out["merge_collinear"] = False
    if hasattr(args, "heat"):
        out["_heating"] = args
    return out


def _number(name, text, kind):
    try:
        value = kind(text)
    except ValueError:
        raise CLIError(f"--set {name} expects {'an integer' if kind is int else 'a number'}, "
                       f"got {text!r}") from None
    if (kind is float and not math.isfinite(value)) or value < 0:
        raise CLIError(f"--set {name} = {text} must be finite and >= 0")
    return value


def _replace(step, **changes):
    from dataclasses import replace

    return replace(step, **changes)


def _set_power(power, creases: tuple, watts: float) -> dict:
    out = dict(power)
    for key in out:
        if set(creases) & set(key if isinstance(key, tuple) else (key,)):
            out[key] = watts
            return out
    out[creases[0] if len(creases) == 1 else creases] = watts
    return out


# ------------------------------------------------------------------------------ commands
def _export(args) -> int:
    from simulator import get_case
    from simulator.fold import write_model

    from .case_params import case_overrides

    case = get_case(args.case, **case_overrides(args.set, args.case))
    out = pathlib.Path(args.out)
    if out.suffix.lower() != ".fold":
        raise CLIError(f"--out {out} must end in .fold")
    out.parent.mkdir(parents=True, exist_ok=True)
    write_model(case.model, case.steps, out, title=case.name, description=case.description)
    print(f"{case.name}: written to {out} ({out.stat().st_size / 1e3:.1f} kB); run it with "
          f"'etorigami run {out} --out DIR'")
    return 0


@cli_spelling()
def _check(args) -> int:
    import numpy as np

    from simulator import Heat
    from simulator.fold import load_fold_json, read_model

    from .plain import check_plain, is_plain

    options = reader_options(args)                   # flags first: they need no file
    sharp = options.pop("_sharp")
    data = load_fold_json(args.file)
    if is_plain(data):
        return check_plain(args, data, options, sharp)
    model, steps = read_model(args.file, **options, **sharp)
    mesh, pattern = model.mesh, model.mesh.pattern
    heated = sorted({int(c) for s in steps if isinstance(s, Heat) for k in dict(s.power)
                     for c in (k if isinstance(k, tuple) else (k,))})
    circuits = [k for s in steps if isinstance(s, Heat) for k in dict(s.power)
                if isinstance(k, tuple)]
    size = np.ptp(pattern.vertices, axis=0) * 1e6
    fixed = int(model.fixed_mask.sum()) if hasattr(model, "fixed_mask") else 0
    print(f"{args.file}: valid FOLD model file")
    print(f"  vertices {pattern.n_vertices}, panels {pattern.n_panels}, creases "
          f"{len(pattern.creases)}, size {size[0]:.1f} x {size[1]:.1f} x {size[2]:.1f} um "
          "(lengths converted to metres inside)")
    kind = " (sharp creases: concentrated hinges)" if getattr(mesh, "sharp", False) else ""
    print(f"  mesh: {mesh.n_nodes} nodes, {len(mesh.bars)} bars, {len(mesh.springs)} "
          f"springs{kind}")
    print(f"  supports: {fixed} fixed degrees of freedom; contact "
          f"{'on' if model.contact is not None else 'off'}; thermal model "
          f"{'yes' if model.thermal is not None else 'no'}; actuated creases "
          f"{0 if model.actuators is None else len(model.actuators.delta_alpha_array(mesh).nonzero()[0])}")
    print(f"  heaters: creases {heated or 'none'}"
          + (f"; circuits {[list(c) for c in circuits]}" if circuits else ""))
    print("  steps: " + (", ".join(f"{s.name}" for s in steps) or "none"))
    return 0


def _view(args) -> int:
    from simulator.viewer import write_viewer

    path = write_viewer(args.result_dir, args.out)
    print(f"viewer written to {path} ({path.stat().st_size / 1e6:.2f} MB); open it in a browser")
    return 0


def add_reader_options(parser, heating: bool = True) -> None:
    """Options for FOLD files drawn in an editor (no etorigami: fields); ``heating`` adds the
    flags that heat a plain pattern (``run``)."""
    from .plain import add_plain_options
    from .sharp import add_sharp_options

    add_plain_options(parser, heating)
    add_sharp_options(parser, heating)
    parser.add_argument("--unit-scale", type=float, metavar="METRES",
                        help="metres per length unit of a FOLD file whose frame_unit is 'unit' "
                             "(e.g. 1e-3 for millimetres)")
    for name, what in (("crease-width", "crease width"), ("crease-thickness", "crease thickness"),
                       ("panel-thickness", "panel thickness")):
        parser.add_argument(f"--{name}", type=float, metavar="UM",
                            help=f"{what} in um for a FOLD file that does not give it"
                        + (" (0: sharp creases)" if name == "crease-width" else ""))


def add_file_commands(sub) -> None:
    """Register ``export``, ``check`` and ``view``."""
    export = sub.add_parser("export", help="write a built-in case as a FOLD model file")
    export.add_argument("case", help="case name, e.g. crane (see 'etorigami cases')")
    export.add_argument("--set", action="append", metavar="NAME=VALUE",
                        help="override a case parameter in the CLI unit 'etorigami cases' "
                        "lists (lengths um, powers mW; repeatable)")
    export.add_argument("--format", choices=["fold"], default="fold", help="file format")
    export.add_argument("--out", required=True, metavar="FILE", help="output file (.fold)")
    export.set_defaults(func=_export, short=True, out_kind="file")

    check = sub.add_parser("check", help="validate a FOLD file and print its summary")
    check.add_argument("file", help="FOLD file")
    add_reader_options(check, heating=False)
    check.set_defaults(func=_check, short=True)

    view = sub.add_parser("view", help="write a self-contained HTML 3-D viewer of a result")
    view.add_argument("result_dir", help="folder written by 'etorigami run' (creases.csv, "
                                         "nodes.npz, meta.json)")
    view.add_argument("--out", metavar="FILE", help="HTML file (default RESULT_DIR/viewer.html)")
    view.set_defaults(func=_view, short=True, out_kind="file")
