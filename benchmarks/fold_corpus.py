"""Run every FOLD file of a folder through ``etorigami check`` and ``etorigami run`` (issue 20).

Acceptance of issue 20: every FOLD file either runs or is refused with one line naming the
unsupported feature; no traceback, no NaN, no 'singular' without a named cause, and nothing
passes ``check`` that then fails on its geometry. This script does not ship any files: point
it at a folder of FOLD files (e.g. public examples collected by hand) and it prints a table.

Usage::

    PYTHONPATH=$PWD python benchmarks/fold_corpus.py FOLDER [--out DIR] [--timeout 60]
        [--sharp]          # also run --crease-model sharp --fold all=30

Each file is run with ``--heat all --power 1`` (and ``--unit-scale 1e-3`` when its frame_unit
is FOLD's default 'unit').

Outcomes: ``ran``, ``refused`` (one line naming the cause, shown), ``traceback``, ``nan``,
``singular`` (a 'singular' message without a named cause), ``hang`` (timeout),
``check-ok-run-fails`` (check passed, the run refused), ``failed`` (the run started and
failed without a refusal), ``multi-line`` (a refusal of more than one line).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

PYTHON = sys.executable


def _cli(args, timeout):
    """Run ``etorigami ARGS``; return (returncode or None on timeout, stdout + stderr)."""
    cmd = [PYTHON, "-c", "import sys; from design.cli import main; sys.exit(main())", *args]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, ""
    return done.returncode, (done.stdout or "") + (done.stderr or "")


def _error_lines(text):
    return [ln for ln in text.splitlines() if ln.strip() and "error" in ln.lower()]


def classify(check, run):
    """Outcome of one file from the (returncode, text) of check and of run."""
    (c_rc, c_txt), (r_rc, r_txt) = check, run
    both = c_txt + r_txt
    if c_rc is None or r_rc is None:
        return "hang", ""
    if "Traceback (most recent call last)" in both:
        return "traceback", both.strip().splitlines()[-1][:120]
    if r_rc == 0:
        low = r_txt.lower()
        if "nan" in low.replace("nanos", "").split() or " nan" in low or "nan " in low:
            return "nan", ""
        return "ran", ""
    lines = [ln for ln in r_txt.splitlines() if ln.strip()]
    sing = [ln for ln in lines if "singular" in ln.lower()]
    if sing:
        return "singular", sing[0].strip()[:160]
    errors = _error_lines(r_txt)
    msg = (errors or lines or [""])[-1][:160]
    if not errors:
        return "failed", msg
    if c_rc == 0:
        return "check-ok-run-fails", msg
    if len(errors) > 1:
        return "multi-line", msg
    return "refused", msg


def _unit_args(path):
    """``--unit-scale 1e-3`` (paper scale, millimetres) for a file in FOLD's default 'unit'."""
    try:
        unit = json.loads(path.read_text()).get("frame_unit", "unit")
    except (ValueError, OSError, AttributeError):
        return []
    return ["--unit-scale", "1e-3"] if unit == "unit" else []


def run_file(path, out, timeout, extra=("--heat", "all", "--power", "1")):
    """Outcome (name, message) of ``check`` then ``run`` of one FOLD file."""
    check = _cli(["check", str(path)], timeout)
    run = _cli(["run", str(path), "--out", str(out / path.stem), "-q", *_unit_args(path),
                *extra], timeout)
    return classify(check, run)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=None)
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("--sharp", action="store_true",
                        help="also run each file with --crease-model sharp --fold all=30")
    args = parser.parse_args(argv)
    files = sorted(args.folder.glob("*.fold"))
    if not files:
        print(f"no *.fold file in {args.folder}")
        return 1
    out = args.out or pathlib.Path(tempfile.mkdtemp(prefix="fold_corpus_"))
    modes = [("heat", ("--heat", "all", "--power", "1"))]
    if args.sharp:
        modes.append(("sharp", ("--crease-model", "sharp", "--fold", "all=30")))
    width = max(len(f.name) for f in files)
    bad = 0
    for f in files:
        for mode, extra in modes:
            outcome, msg = run_file(f, out / mode, args.timeout, extra)
            bad += outcome not in ("ran", "refused")
            print(f"{f.name:<{width}}  {mode:<7}  {outcome:<18}  {msg}", flush=True)
    print(f"{len(files)} files, {bad} bad outcomes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
