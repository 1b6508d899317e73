"""Shared plumbing of the study scripts: command line, output folder, metadata, progress.

Every study module defines ``run(quick=False, progress=True) -> pandas.DataFrame`` (no file
I/O), ``plot(df) -> Figure`` (re-creatable from the CSV alone) and
``main(argv=None)`` built with :func:`study_main`.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import pathlib
import signal
import threading
import time
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import pandas as pd

from simulator._result import provenance
from simulator.cases import get_case

__all__ = ["RESULTS", "QUICK_RESULTS", "default_out", "refusal", "run_was_quick", "study_main", "replot", "progress_bar", "write_outputs", "node_frame",
           "shape_from_frame", "heating_records", "run_case", "XYZ", "TEMP",
           "time_limit", "EvaluationTimeout", "TimeLimited"]

#: The repository's committed ``results/`` (inputs some studies read, e.g. the gripper's
#: coordinate descent); outputs go to :func:`default_out` instead.
RESULTS = pathlib.Path(__file__).resolve().parents[1] / "results"


#: Folder (of the current directory) that ``--quick`` runs write into by default: not
#: ``results/``, so a quick run never overwrites full results; git-ignored.
QUICK_RESULTS = "results-quick"


def default_out(name: str, quick: bool = False) -> pathlib.Path:
    """Default output folder of a study: ``./results/<name>`` of the current directory
    (never the installed package's folder), or ``./results-quick/<name>`` for a quick run."""
    return pathlib.Path.cwd() / (QUICK_RESULTS if quick else "results") / name


def _as_json(value):
    """``value`` as ``meta.json`` stores it (so settings compare like they read back)."""
    return json.loads(json.dumps(value, default=str))


def refusal(out: pathlib.Path, name: str, settings: dict) -> str | None:
    """Why ``out`` must not receive this run's results, or None if it may.

    ``out`` is refused when its ``meta.json`` records another study or other ``settings``
    (quick and full runs differ), or cannot be read: writing there would mix files of
    different runs. A folder without ``meta.json`` is accepted.
    """
    meta_path = pathlib.Path(out) / "meta.json"
    if not meta_path.is_file():
        return None
    try:
        meta = json.loads(meta_path.read_text())
        study, old = meta.get("study"), meta.get("settings")
    except (OSError, ValueError, AttributeError) as exc:
        return f"{meta_path} cannot be read ({exc.__class__.__name__})"
    if study != name:
        return f"{out} holds results of the study {study!r}, not {name!r}"
    if old != _as_json(settings):
        return (f"{out} holds results of other settings ({json.dumps(old)} there, "
                f"{json.dumps(_as_json(settings))} now)")
    return None


def run_was_quick(out: pathlib.Path, default: bool = False) -> bool:
    """Whether the results in ``out`` come from a ``--quick`` run (its ``meta.json``);
    ``default`` when there is no readable ``meta.json``."""
    try:
        return bool(json.loads((pathlib.Path(out) / "meta.json").read_text())["settings"]["quick"])
    except (OSError, ValueError, KeyError, TypeError):
        return default


#: Column names of node tables (positions in um, temperatures in deg C).
XYZ = ["x [um]", "y [um]", "z [um]"]
TEMP = "temperature [degC]"


def progress_bar(iterable, enabled: bool = True, **kwargs):
    """A tqdm progress bar around ``iterable`` (plain iterable when disabled; a silent bar when
    stderr is not a terminal: frames redirected into a log file are noise)."""
    import sys

    if not enabled:
        return iterable
    from tqdm import tqdm

    terminal = hasattr(sys.stderr, "isatty") and sys.stderr.isatty()
    return tqdm(iterable, **kwargs, **({} if terminal else {"disable": True}))


def write_outputs(out: pathlib.Path, name: str, frame, figures: dict, settings: dict,
                  wall_time: float) -> None:
    """Write ``<name>.csv``, one PNG per figure and ``meta.json`` into ``out``.

    ``settings["quick"]`` true (a ``--quick`` run) stamps every figure as a quick run
    (:func:`studies.plotting.save_figure`); ``meta.json`` records the study, the version,
    the commit (when known), the date and the machine (``simulator._result.provenance``), the
    settings, the row count and the wall time [s].
    """
    from studies.plotting import save_figure

    quick = bool(settings.get("quick", False))
    out.mkdir(parents=True, exist_ok=True)
    frame.to_csv(out / f"{name}.csv", index=False)
    for fig_name, fig in figures.items():
        save_figure(fig, out / f"{fig_name}.png", quick=quick)
    meta = {"study": name, **provenance(), "settings": settings,
            "rows": len(frame), "wall_time [s]": round(wall_time, 3)}
    (out / "meta.json").write_text(json.dumps(meta, indent=2, default=str))


def _parser(name: str, doc: str) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog=f"python -m studies.{name}",
                                     description=doc.strip().splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"coarse, fast version (for tests): written to ./{QUICK_RESULTS}/"
                             f"{name} (not ./results) unless --out is given; its figures are "
                             "stamped as a quick run")
    parser.add_argument("--out", type=pathlib.Path, default=None,
                        help=f"output folder (default ./results/{name} of the current "
                             f"directory, ./{QUICK_RESULTS}/{name} with --quick)")
    parser.add_argument("--overwrite", action="store_true",
                        help="write into OUT even if its meta.json records another study or "
                             "other settings (quick and full runs differ); without it such a "
                             "folder is refused (exit 2) before the study runs")
    parser.add_argument("-q", "--quiet", "--no-progress", dest="no_progress",
                        action="store_true", help="quiet: no progress bar (none either when "
                        "stderr is not a terminal); --no-progress is the older name")
    parser.add_argument("--figures-only", action="store_true",
                        help=f"only re-draw the figures from OUT/{name}.csv")
    return parser


def study_main(name: str, doc: str, run, plot, argv=None) -> pathlib.Path:
    """Command line of a study: ``--quick``, ``--out DIR``, ``--overwrite``,
    ``-q/--quiet`` (also ``--no-progress``), ``--figures-only``.

    ``plot(df)`` may return one Figure or a dict {file stem: Figure}. ``--figures-only``
    re-creates the figures from ``<out>/<name>.csv`` without running the study (the CSV and
    ``meta.json`` are left as they are). A ``--quick`` run goes to ``./results-quick/<name>``
    by default, so it never overwrites full results. An output folder holding results of
    another study or other settings is refused (one line, exit 2) unless ``--overwrite``.
    """
    parser = _parser(name, doc)
    args = parser.parse_args(argv)
    args.out = default_out(name, args.quick) if args.out is None else args.out
    logging.basicConfig(level=logging.WARNING)
    if args.figures_only:
        return replot(name, plot, args.out, quick=args.quick)
    settings = {"quick": args.quick}
    reason = None if args.overwrite else refusal(args.out, name, settings)
    if reason:
        parser.exit(2, f"{parser.prog}: error: {reason}; choose another --out or pass "
                       "--overwrite.\n")
    t0 = time.perf_counter()
    frame = run(quick=args.quick, progress=not args.no_progress)
    with _figure_style():
        figs = _as_dict(plot(frame), name)
        write_outputs(args.out, name, frame, figs, settings, time.perf_counter() - t0)
    kind = " (quick run: coarse settings, not the published results)" if args.quick else ""
    print(f"{name}: {len(frame)} rows written to {args.out} in "
          f"{time.perf_counter() - t0:.1f} s{kind}")
    return args.out


def _figure_style():
    """The study figures' style (:func:`studies.plotting.figure_style`), for drawing and
    saving (colours named ``C0``... resolve when a figure is saved)."""
    from studies.plotting import figure_style

    return figure_style()


def _as_dict(figs, name: str) -> dict:
    """A study's ``plot`` output as {file stem: Figure}."""
    return figs if isinstance(figs, dict) else {name: figs}


def replot(name: str, plot, out: pathlib.Path, quick: bool = False) -> pathlib.Path:
    """Re-create a study's figures from ``out/<name>.csv`` (written by an earlier run).

    The figures are stamped as a quick run when ``out/meta.json`` says the results come
    from one (``quick`` when there is no ``meta.json``).
    """
    from studies.plotting import save_figure

    csv = pathlib.Path(out) / f"{name}.csv"
    if not csv.is_file():
        raise SystemExit(f"--figures-only needs {csv}; run the study first (without it).")
    quick = run_was_quick(out, default=quick)
    with _figure_style():
        figs = _as_dict(plot(pd.read_csv(csv)), name)
        for fig_name, fig in figs.items():
            save_figure(fig, pathlib.Path(out) / f"{fig_name}.png", quick=quick)
    print(f"{name}: {len(figs)} figure(s) re-drawn in {out}")
    return pathlib.Path(out)


# ----------------------------------------------------------------------------- records
def node_frame(result, records, **labels) -> pd.DataFrame:
    """Rows ``table = "nodes"``: positions [um] and temperatures [degC] of some records.

    ``labels`` become constant columns (e.g. ``variant="free"``).
    """
    h, mesh = result.history, result.model.mesh
    recs = np.array([range(len(h["u"]))[int(r)] for r in np.atleast_1d(records)])
    n = mesh.n_nodes
    x = (mesh.nodes[None] + h["u"][recs]) * 1e6
    frame = pd.DataFrame({"table": "nodes", **labels,
                          "step": np.repeat(recs, n), "stage": np.repeat(h["stage_name"][recs], n),
                          "increment": np.repeat(h["increment"][recs], n),
                          "node": np.tile(np.arange(n), len(recs))})
    for k, col in enumerate(XYZ):
        frame[col] = x[:, :, k].ravel()
    frame[TEMP] = h["temperature"][recs].ravel()
    return frame


def shape_from_frame(nodes: pd.DataFrame, mesh) -> SimpleNamespace:
    """A stand-in for a SimulationResult, built from ``nodes`` rows and the case's mesh.

    It has the ``history`` (``u`` [m], ``temperature``, ``stage_name``, ``increment``, one
    record per distinct ``step``) and ``model.mesh`` that ``plot_shape`` and ``animate`` use.
    """
    nodes = nodes.sort_values(["step", "node"], kind="stable")
    steps = nodes["step"].unique()
    n = mesh.n_nodes
    if len(nodes) != len(steps) * n:
        raise ValueError(f"node rows do not cover the {n} nodes of the mesh for every step.")
    x = nodes[XYZ].to_numpy(float).reshape(len(steps), n, 3) * 1e-6
    first = nodes.groupby("step", sort=True).first()
    history = {"u": x - mesh.nodes[None],
               "temperature": nodes[TEMP].to_numpy(float).reshape(len(steps), n),
               "stage_name": first["stage"].to_numpy(str),
               "increment": first["increment"].to_numpy(int)}
    return SimpleNamespace(history=history, model=SimpleNamespace(mesh=mesh))


def heating_records(result) -> np.ndarray:
    """Record indices from the last pre-heating record through the end of the heat step."""
    heat = np.flatnonzero(result.history["stage_name"] == "heat")
    return np.r_[heat[0] - 1, heat]


def run_case(name: str, params: dict, progress: bool, desc: str):
    """Build and run a case with a tqdm bar over its heating increments; must converge."""
    case = get_case(name, **params)
    bar = progress_bar(None, enabled=progress, desc=desc, unit="inc", leave=False)

    def callback(done, total):
        bar.total = total
        bar.update(done - bar.n)

    res = case.run(progress=callback if progress else None)
    if progress:
        bar.close()
    if not res.success:
        raise RuntimeError(f"{name} ({desc}): {res.message}")
    return case, res


# ----------------------------------------------------------------------------- time limit
class EvaluationTimeout(Exception):
    """An evaluation ran longer than its time limit."""


@contextlib.contextmanager
def time_limit(seconds: float):
    """Raise :class:`EvaluationTimeout` inside the block after ``seconds`` [s].

    Uses ``SIGALRM``, so it works only in the main thread of a process (the serial executor
    and process-pool workers); elsewhere the block runs without a limit. Not nestable: an
    inner block cancels the timer of an outer one.
    """
    if seconds is None or threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        raise EvaluationTimeout(f"evaluation stopped after the time limit of {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@dataclass(frozen=True)
class TimeLimited:
    """Mixin for frozen dataclass problems: each evaluation stops (and fails) after
    ``time_limit`` [s] (None: no limit). An opt-in safety net for long studies: the solvers
    end every path on their own (step-cut budgets), and a limit makes results depend on the
    machine's speed."""

    time_limit: float | None = None

    def _evaluate(self, values):
        with time_limit(self.time_limit):
            return super()._evaluate(values)

    def settings(self) -> dict:
        return {**super().settings(), "time_limit [s]": self.time_limit}

