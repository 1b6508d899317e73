"""Run every FOLD file of a folder through ``etorigami check`` and ``run`` (issues 20, 28).

Question: does every FOLD file of the ecosystem either run heated or get refused in one line
that says what to change? (Issue 28: none may end in a traceback, a NaN, an exit 1 without a
named cause, or "converged" on a state the run knows to be unstable.)

Method: for each ``*.fold`` file, in a subprocess with a timeout, ``etorigami check FILE`` and
``etorigami run FILE --heat all --power P --out TMP --quiet`` (the default frame, as the CLI
reads it). A file in FOLD's default ``frame_unit`` 'unit' gets ``--unit-scale S`` in both (default
1e-2: a unit square becomes a 10 mm sheet, the size of the drawn patterns of
``studies/pattern_robustness``; at 1e-3 most public patterns are refused for their crease widths
before the solver is reached). The subprocess inherits ``PYTHONPATH``, so
``PYTHONPATH=/path/to/worktree`` measures that worktree's code.

Outcome classes, the first that applies:

``timeout``            check or run took longer than ``--timeout`` seconds;
``traceback``          a Python traceback in the output of check or run;
``nan``                a NaN in the output of check or run or in the run's ``creases.csv``;
``unstable-converged`` run exit 0, while ``meta.json`` says the final state is unstable (read
                       defensively: any ``*stab*`` field that is False / 'unstable', or a
                       positive count of negative eigenvalues, in the last step or at the top);
``ran``                run exit 0;
``refused``            exit 2 with exactly one line on stderr;
``refused-multiline``  exit 2 with more than one line on stderr;
``failed-named``       exit 1 whose message names a cause (one of ``CAUSES``);
``exit1-no-cause``     exit 1 whose message names none (e.g. "gave up ... no convergence");
``other``              any other exit code.

The public corpus of issue 28 (171 files: FOLD examples, robbykraft/Origami, Rabbit Ear's test
files, Origami Simulator box pleats, flat-folder) is not in the repository; its files are listed
in ``benchmarks/fold_corpus_sources.tsv`` (local name, then ``owner/repo@commit:path``), from
which it can be fetched again.

Outputs: a table (file, outcome, exit codes, run time, the refusal or failure message) and the
count per class on stdout; ``--csv FILE`` writes the same table.

Usage::

    PYTHONPATH=$PWD python benchmarks/fold_corpus.py [--dir FOLDER] [--power MW] [--timeout S]
        [--unit-scale M] [--csv FILE] [--out DIR]
"""

from __future__ import annotations

import argparse
import collections
import csv
import json
import pathlib
import re
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
DEFAULT_DIR = ROOT / "tests" / "data" / "fold"
CLASSES = ("ran", "refused", "refused-multiline", "failed-named", "exit1-no-cause", "traceback",
           "nan", "unstable-converged", "timeout", "other")
GOOD = ("ran", "refused", "failed-named")
CAUSES = ("limit point", "bifurcation", "unstable", "stability", "negative eigenvalue",
          "crosses", "crossing", "passes", "180 deg", "contact", "penetrat", "temperature limit")
_NAN = re.compile(r"(?<![A-Za-z_])nan(?![A-Za-z_])", re.IGNORECASE)
FIELDS = ("file", "outcome", "check_exit", "run_exit", "time [s]", "status", "message")
# Counted apart: a refusal by ``run`` of a file that ``check`` passed (issue 20: nothing should
# pass ``check`` that then fails on its geometry), and a run of a file that ``check`` refused.


def run_cli(args, timeout):
    """Run ``etorigami ARGS`` in a subprocess; (exit code or None on timeout, stdout, stderr)."""
    cmd = [sys.executable, "-m", "design.cli", *map(str, args)]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, "", ""
    return done.returncode, done.stdout or "", done.stderr or ""


def _unstable_value(key, value):
    """True when one meta.json field says 'unstable'."""
    key = key.lower()
    if "stab" in key and (value is False or str(value).lower() == "unstable"):
        return True
    if "negative" in key and "eig" in key and isinstance(value, (int, float)):
        return value > 0
    return False


def final_state_unstable(meta):
    """Does a run's ``meta.json`` (a dict) say that its final state is unstable?

    Read defensively: the top level and the last step are searched (one dict level deep) for
    a stability field that is False or 'unstable', or a positive negative-eigenvalue count.
    """
    steps = meta.get("steps") or [{}]
    places = [meta, steps[-1] if isinstance(steps[-1], dict) else {}]
    for place in list(places):
        places += [v for k, v in place.items() if isinstance(v, dict) and "stab" in k.lower()]
    return any(_unstable_value(k, v) for place in places for k, v in place.items())


def _read_meta(out):
    try:
        return json.loads((out / "meta.json").read_text())
    except (OSError, ValueError):
        return {}


def _has_nan(text, out=None):
    """A NaN in ``text`` or in ``out/creases.csv``."""
    if _NAN.search(text):
        return True
    if out is None:
        return False
    try:
        return bool(_NAN.search((out / "creases.csv").read_text()))
    except OSError:
        return False


def _lines(text):
    return [ln.strip() for ln in text.splitlines() if ln.strip()]


def _run_message(stdout, stderr):
    """The failure line of a run: the summary line with 'failed', else the last stderr line."""
    failed = [ln for ln in _lines(stdout) if ": failed (" in ln or "gave up" in ln]
    return (failed or _lines(stderr) or _lines(stdout) or [""])[0]


def classify(check, run, out=None):
    """Outcome (class, message) of one file.

    ``check`` and ``run`` are (exit code or None on timeout, stdout, stderr) of the two
    commands; ``out`` the run's output folder (for ``meta.json`` and ``creases.csv``).
    """
    out = pathlib.Path(out) if out is not None else pathlib.Path("/nonexistent")
    (c_rc, c_out, c_err), (r_rc, r_out, r_err) = check, run
    text = c_out + c_err + r_out + r_err
    if c_rc is None or r_rc is None:
        return "timeout", "check" if c_rc is None else "run"
    tb = [err for err in (c_err, r_err) if "Traceback (most recent call last)" in err]
    if tb or "Traceback (most recent call last)" in text:
        return "traceback", (_lines(tb[0]) if tb else [""])[-1][:200]
    if _has_nan(text, out if r_rc == 0 else None):
        first = next((ln for ln in _lines(text) if _NAN.search(ln)), "NaN in creases.csv")
        return "nan", first[:200]
    if r_rc == 0:
        meta = _read_meta(out)
        unstable = meta.get("status") == "converged" and final_state_unstable(meta)
        return ("unstable-converged" if unstable else "ran"), ""
    if r_rc == 2:
        err = _lines(r_err)
        return ("refused" if len(err) == 1 else "refused-multiline"), (err or [""])[0][:200]
    if r_rc == 1:
        msg = _run_message(r_out, r_err)
        named = any(c in msg.lower() for c in CAUSES)
        return ("failed-named" if named else "exit1-no-cause"), msg[:200]
    return "other", f"exit {r_rc}: " + (_lines(r_err) or [""])[-1][:200]


def _unit_args(path, unit_scale):
    """``--unit-scale S`` for a file in FOLD's default frame_unit 'unit'."""
    try:
        unit = json.loads(path.read_text()).get("frame_unit", "unit")
    except (ValueError, OSError, AttributeError):
        return []
    return ["--unit-scale", repr(unit_scale)] if unit == "unit" else []


def run_file(path, out, power=2.0, timeout=120.0, unit_scale=1e-2):
    """One row of the table (a dict with ``FIELDS``) for one FOLD file."""
    units = _unit_args(path, unit_scale)
    check = run_cli(["check", path, *units], timeout)
    t0 = time.perf_counter()
    run = run_cli(["run", path, "--heat", "all", "--power", power, "--out", out, "--quiet",
                   *units], timeout)
    seconds = time.perf_counter() - t0
    outcome, message = classify(check, run, out)
    return {"file": path.name, "outcome": outcome, "check_exit": check[0], "run_exit": run[0],
            "time [s]": round(seconds, 2), "status": _read_meta(out).get("status"),
            "message": message}


def _print_row(row, width):
    rc = lambda v: "-" if v is None else str(v)  # noqa: E731
    print(f"{row['file']:<{width}}  {row['outcome']:<18}  {rc(row['check_exit']):>5}  "
          f"{rc(row['run_exit']):>3}  {row['time [s]']:>7.1f}  {row['message'][:110]}", flush=True)


def _print_counts(rows):
    counts = collections.Counter(r["outcome"] for r in rows)
    print("\ncount per outcome:")
    for name in CLASSES:
        if counts[name]:
            print(f"  {name:<18} {counts[name]:>4}")
    late = sum(r["outcome"].startswith("refused") and r["check_exit"] == 0 for r in rows)
    loose = sum(r["outcome"] == "ran" and r["check_exit"] != 0 for r in rows)
    print(f"  refused by run after check passed: {late}; ran although check failed: {loose}")
    bad = sum(n for name, n in counts.items() if name not in GOOD)
    print(f"{len(rows)} files, {bad} bad outcomes")


def _write_csv(rows, path):
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=FIELDS)
        writer.writeheader()
        writer.writerows(rows)


def _parser():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", type=pathlib.Path, default=None,
                        help="folder of FOLD files (same as --dir)")
    parser.add_argument("--dir", type=pathlib.Path, default=None,
                        help=f"folder of FOLD files (default {DEFAULT_DIR.relative_to(ROOT)})")
    parser.add_argument("--power", type=float, default=2.0, help="power per crease [mW]")
    parser.add_argument("--timeout", type=float, default=120.0, help="per command [s]")
    parser.add_argument("--unit-scale", type=float, default=1e-2,
                        help="metres per unit of files in frame_unit 'unit' [m]")
    parser.add_argument("--csv", type=pathlib.Path, default=None, help="write the table here")
    parser.add_argument("--out", type=pathlib.Path, default=None,
                        help="folder for the runs' outputs (default a temporary folder)")
    return parser


def main(argv=None):
    args = _parser().parse_args(argv)
    folder = args.folder or args.dir or DEFAULT_DIR
    files = sorted(folder.glob("*.fold"))
    if not files:
        print(f"no *.fold file in {folder}")
        return 1
    out = args.out or pathlib.Path(tempfile.mkdtemp(prefix="fold_corpus_"))
    width = max(len(f.name) for f in files)
    print(f"{'file':<{width}}  {'outcome':<18}  check  run  time[s]  message")
    rows = []
    for f in files:
        rows.append(run_file(f, out / f.stem, args.power, args.timeout, args.unit_scale))
        _print_row(rows[-1], width)
    _print_counts(rows)
    if args.csv:
        _write_csv(rows, args.csv)
    return 0


if __name__ == "__main__":
    sys.exit(main())
