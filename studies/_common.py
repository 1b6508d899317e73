"""Shared plumbing of the study scripts: command line, output folder, metadata, progress.

Every study module defines ``run(quick=False, progress=True) -> pandas.DataFrame`` (no file
I/O), ``plot(df) -> Figure`` (re-creatable from the CSV alone) and
``main(argv=None)`` built with :func:`study_main`.
"""

from __future__ import annotations

import argparse
import json
import logging
import pathlib
import time

from simulator import __version__

__all__ = ["RESULTS", "study_main", "progress_bar", "write_outputs"]

#: Default output root: ``results/`` at the top of the repository.
RESULTS = pathlib.Path(__file__).resolve().parents[1] / "results"


def progress_bar(iterable, enabled: bool = True, **kwargs):
    """A tqdm progress bar around ``iterable`` (plain iterable when disabled)."""
    if not enabled:
        return iterable
    from tqdm import tqdm

    return tqdm(iterable, **kwargs)


def write_outputs(out: pathlib.Path, name: str, frame, figures: dict, settings: dict,
                  wall_time: float) -> None:
    """Write ``<name>.csv``, one PNG per figure and ``meta.json`` into ``out``."""
    from studies.plotting import save_figure

    out.mkdir(parents=True, exist_ok=True)
    frame.to_csv(out / f"{name}.csv", index=False)
    for fig_name, fig in figures.items():
        save_figure(fig, out / f"{fig_name}.png")
    meta = {"study": name, "etorigami_version": __version__, "settings": settings,
            "rows": len(frame), "wall_time [s]": round(wall_time, 3)}
    (out / "meta.json").write_text(json.dumps(meta, indent=2, default=str))


def study_main(name: str, doc: str, run, plot, argv=None) -> pathlib.Path:
    """Command line of a study: ``--quick``, ``--out DIR``, ``--no-progress``.

    ``plot(df)`` may return one Figure or a dict {file stem: Figure}.
    """
    parser = argparse.ArgumentParser(prog=f"python -m studies.{name}",
                                     description=doc.strip().splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="coarse, fast version (for tests)")
    parser.add_argument("--out", type=pathlib.Path, default=RESULTS / name,
                        help=f"output folder (default results/{name})")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    t0 = time.perf_counter()
    frame = run(quick=args.quick, progress=not args.no_progress)
    figs = plot(frame)
    figs = figs if isinstance(figs, dict) else {name: figs}
    write_outputs(args.out, name, frame, figs, {"quick": args.quick},
                  time.perf_counter() - t0)
    print(f"{name}: {len(frame)} rows written to {args.out} in {time.perf_counter() - t0:.1f} s")
    return args.out
