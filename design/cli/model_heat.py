"""A FOLD model file heated from the flags: ``run MODEL.fold --heat WHICH --power MW`` (or
``--voltage V``, ``--current MA``).

A model file (``etorigami:`` steps, written by ``etorigami export`` or
:func:`simulator.fold.write_model`) carries its own layers, bimorph, heat loss and supports; the
flags choose only what to heat and how hard. The file's steps up to its first heating step
(self-fold, gravity) are kept, and its heating is replaced by one ``Heat`` of the chosen
creases at ``--power`` (with the increments and coupling of the file's first heating step).
The values used are printed in one line. ``--stack`` and ``--fix-panel``, which give a plain
pattern what it lacks, are refused: the file has its own.
"""

from __future__ import annotations

from ._common import CLIError, distinct

__all__ = ["model_file_heat_case", "refuse_unheatable", "model_summary"]


def refuse_unheatable(model, steps, path) -> None:
    """Refuse, in one line, heating steps on a model the file gives no way to heat: sharp
    creases, or no thermal parameters."""
    from simulator import Heat

    from .sharp import refuse_heated_sharp

    refuse_heated_sharp(model, steps, path)
    heats = [s.name for s in steps if isinstance(s, Heat)]
    if heats and model.thermal is None:
        raise CLIError(f"{path} heats ({', '.join(heats)}) but has no thermal parameters (the "
                       "heat loss to its surroundings): add etorigami:thermal to the file (see "
                       "docs/fold-format.md, or 'etorigami export' of a heated case)")


def model_file_heat_case(path, data, options: dict, sharp: dict, heating) -> tuple:
    """``(model, steps, parameters, geo)`` of a model file run with ``--heat`` and
    ``--power``: the file's own model, its steps up to its first heating step, then one
    ``Heat`` of the flags."""
    from dataclasses import replace

    from simulator import Heat
    from simulator.fold import parse_fold, read_model

    from .plain import (drive_parameters, driven, heat_drive, heat_fields, print_notes,
                        refuse_creaseless, select_creases)

    for flag, value in (("--stack", heating.stack), ("--fix-panel", heating.fix_panel)):
        if value is not None:
            raise CLIError(f"{flag} applies to plain crease patterns; {path} is a model file "
                           f"with its own layers and supports (etorigami: fields): drop {flag}")
    if not driven(heating):
        raise CLIError(f"--heat {heating.heat} needs --power MW (the power per heated crease), "
                       "--voltage V or --current MA")
    drive = heat_drive(heating)
    model, steps = read_model(path, **options, **sharp)
    geo = parse_fold(data, **options)
    print_notes(geo)
    refuse_creaseless(path, geo.pattern, "heat")
    heated = select_creases(heating.heat, geo)
    first = next((k for k, s in enumerate(steps) if isinstance(s, Heat)), len(steps))
    fields = heat_fields(heated, drive)
    if "circuits" in fields:                 # circuits are not followed past a limit point
        fields["on_limit_point"] = "stop"
    heat = replace(steps[first], **{"power": {}, **fields}) if first < len(steps) else \
        Heat(**fields, increments=200)
    steps = (*steps[:first], heat)
    refuse_unheatable(model, steps, path)
    print(model_summary(model, heated))
    params = {"model_file_parameters": True, "heat": heating.heat,
              **drive_parameters(heating), "heated_creases": heated,
              "steps": [s.name for s in steps]}
    return model, steps, params, geo


def model_summary(model, heated) -> str:
    """One line of the layer values a model file's heating uses (um, GPa, 1/K, W/(m K))."""
    pattern, thermal, act = model.mesh.pattern, model.thermal, model.actuators
    line = (f"model file's own parameters: heated creases {distinct(pattern.crease_width[heated])}"
            f" um wide, {distinct(pattern.crease_thickness[heated])} um thick")
    alphas = {} if act is None else {int(k): v for k, v in dict(act.delta_alpha).items()}
    passive = [c for c in heated if not alphas.get(c)]
    if act is not None:
        b = act.bimorph
        line += (f"; bimorph: active layer {b.t1 * 1e6:.4g} um at {b.E1 / 1e9:.4g} GPa, passive "
                 f"layer {b.t2 * 1e6:.4g} um at {b.E2 / 1e9:.4g} GPa")
        active = [abs(alphas[c]) for c in heated if alphas.get(c)]
        if active:
            line += f", delta_alpha {distinct(active, 1)} /K"
    if passive:
        from simulator._validate import capped

        line += f"; creases {capped(passive)} are no actuators: heated, they do not fold"
    line += f"; panels {distinct(pattern.panel_thickness)} um"
    if thermal is not None:
        loss = thermal.loss
        what = (f"chains, t_env {loss.thickness * 1e6:.4g} um" if loss.model == "chain" else
                f"integral, m = {loss.refinement}")
        name = thermal.medium.name if " with " not in thermal.medium.name else "the medium"
        k_env = thermal.medium.thermal_conductivity
        line += f"; heat loss: {what}, to {name} at {k_env:.4g} W/(m K)"
    fixed = int(model.fixed_mask.sum()) if hasattr(model, "fixed_mask") else 0
    return line + f"; supports: {fixed} fixed degrees of freedom"
