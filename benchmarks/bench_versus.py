"""Old against new, side by side in one run (issues 13 and 18: performance).

Question: how much faster (or slower) is the current tree than commit ``b25f328`` (main when
issue 18 was filed; issue 13 compared against ``ec2be81``, pass ``--commit ec2be81`` with
snippets of that tree's API), task by task, and do both give the same numbers?

Method: a detached git worktree of the old commit is made in a temporary directory (removed at
the end unless ``--keep``). Each task has an old and a new snippet (the old tree's internal
modules differ: ``simulator.newton._solve_linear`` before the reorganisation by physics, the
ladder's ``simulator.linalg.solve`` after the one linear-algebra module). Every
measurement runs in a fresh subprocess, ``sys.executable -c <snippet>``, with ``PYTHONPATH`` set
to the old tree and to the current tree alternately (old, new, old, new, ... for ``--repeat``).
A snippet prints one JSON line: the time of its timed part (``None`` for the start-up tasks,
which are timed from outside as the wall time of the whole subprocess), a result (powers in mW,
fold angles in deg, a step norm) and its peak RSS. The best time of the repeats is reported.

Tasks (``--tasks`` chooses; ``--quick`` drops ``cd_full`` and ``newton_1e5``):

* ``startup_version`` - ``etorigami --version`` (wall time of the process).
* ``startup_import`` - ``import simulator`` (wall time of the process).
* ``first_run`` - a fresh process with empty bytecode and numba caches (as right after
  install) running the single crease with gravity, 20 heating increments (wall time).
* ``gripper_eval`` - one gripper evaluation, start design, bisect mode (after a warm-up).
* ``cd_full`` - the paper's coordinate descent, 15 cycles, serial (~40 s per side).
* ``single_crease`` - single crease over the substrate, residual fold -10 deg, gravity and
  contact, 250 heating increments to 100 mW.
* ``miura_heat`` - the Miura lifter of 3 x 3 cells (a medium model on the sparse ladder:
  PARDISO or SuperLU), 100 heating increments to 4 mW per crease (below its snap).
* ``newton_1e3`` / ``newton_1e4`` / ``newton_1e5`` - one Newton iteration (assembly of forces
  and tangent plus the linear solve, best of 3) on flat Miura sheets of about 1e3, 1e4 and 1e5
  nodes; the growth exponent of the time with node count is printed under the table.

Run: ``python benchmarks/bench_versus.py --quick`` (about 2 minutes on 2 cores); without
``--quick`` about 3 minutes more.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

OLD_COMMIT = "b25f328"
REPO = Path(__file__).resolve().parents[1]

_FOOTER = """
import json as _json, resource as _resource
print("@@" + _json.dumps({"time": _T, "result": _R,
      "rss_mb": _resource.getrusage(_resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""

_GRIPPER = """
import time
from design import GripperDesign, evaluate_gripper
evaluate_gripper(GripperDesign(W=250e-6, La=900e-6, L1=800e-6, L2=900e-6))   # warm-up
t0 = time.perf_counter()
res = evaluate_gripper(GripperDesign(), mode="bisect")
_T = time.perf_counter() - t0
_R = [round(1e3 * res.assembly.power_per_crease, 6), round(1e3 * res.grip.power_per_crease, 6)]
"""

_CD = """
import time
from design import GripperDesign, GripperProblem, evaluate_gripper, optimize
evaluate_gripper(GripperDesign(W=250e-6, La=900e-6, L1=800e-6, L2=900e-6))   # warm-up
t0 = time.perf_counter()
res = optimize(GripperProblem(), "cd", max_cycles=15)
_T = time.perf_counter() - t0
_R = [round(1e3 * res.objective, 6)] + [round(1e6 * float(res.x[k]), 3) for k in sorted(res.x)]
"""

_CREASE = """
import time
import numpy as np
from simulator.cases import get_case
get_case("single_fold", gravity=True, residual_fold_deg=-10.0, thermal_steps=2).run()  # warm-up
t0 = time.perf_counter()
res = get_case("single_fold", gravity=True, residual_fold_deg=-10.0, thermal_steps={steps}).run()
_T = time.perf_counter() - t0
_R = [round(float(np.degrees(res.fold_angle[-1]).ravel()[0]), 6)]
"""

_MIURA = """
import time
import numpy as np
from simulator.cases import get_case
get_case("miura_lifter", cells_x=3, cells_y=3, thermal_steps=2).run()                  # warm-up
t0 = time.perf_counter()
res = get_case("miura_lifter", cells_x=3, cells_y=3, thermal_steps=100, power_mW=4.0).run()
_T = time.perf_counter() - t0
_R = [round(1e6 * float(np.max(np.abs(res.state.u))), 6)]
"""

_NEWTON = """
import time
import numpy as np
{imports}
from simulator import BarHingeParameters, Supports, make_model
model = make_model(miura_sheet_pattern(m={cells}, n={cells}), None, BarHingeParameters())
panel0 = model.mesh.panel_nodes(0)
model = make_model(model.mesh, Supports.nodes(panel0))
u = np.random.default_rng(0).normal(size=(model.mesh.n_nodes, 3)) * 1e-9
u[panel0] = 0
rest = initial_state(model).spring_rest
system = equilibrium_system(model)
times = []
for _ in range(3):
    t0 = time.perf_counter()
    ev = system.evaluate(u, rest)
    du = _solve_linear(ev.K, -ev.f_int[system.free])
    times.append(time.perf_counter() - t0)
_T = min(times)
_R = [model.mesh.n_nodes, float("%.6e" % np.linalg.norm(du))]
"""

_NEWTON_OLD = """
from simulator import initial_state
from simulator.mechanics import equilibrium_system
from simulator.example_patterns import miura_sheet_pattern
from simulator.newton import _solve_linear
"""

_NEWTON_NEW = """
from simulator.mechanics import equilibrium_system
from simulator.steps import initial_state
from simulator.geometry.example_patterns import miura_sheet_pattern
from simulator.linalg import solve as _solve_linear
"""

_VERSION = """
import sys
from design.cli import main
sys.argv = ["etorigami", "--version"]
try:
    main()
except SystemExit:
    pass
_T, _R = None, None
"""

_WARM = """
import simulator, design, design.cli
from design import GripperDesign, GripperProblem, evaluate_gripper, optimize
import simulator.cases
_T, _R = None, None
"""

_IMPORT = """
import simulator
_T, _R = None, None
"""


@dataclass(frozen=True)
class Task:
    """One benchmark: an old and a new snippet, and how it is timed.

    ``outside`` tasks are timed as the wall time of the whole subprocess [s]; ``fresh`` tasks
    run with empty bytecode and numba caches; ``heavy`` tasks are skipped by ``--quick``.
    """

    name: str
    old: str
    new: str
    outside: bool = False
    fresh: bool = False
    heavy: bool = False


def _newton(cells: int) -> tuple:
    snip = textwrap.dedent(_NEWTON)
    return (snip.replace("{imports}", _NEWTON_OLD).replace("{cells}", str(cells)),
            snip.replace("{imports}", _NEWTON_NEW).replace("{cells}", str(cells)))


def _same(snippet: str) -> tuple:
    return snippet, snippet


TASKS = (
    Task("startup_version", *_same(_VERSION), outside=True),
    Task("startup_import", *_same(_IMPORT), outside=True),
    Task("first_run", *_same(_CREASE.replace("{steps}", "20")), outside=True, fresh=True),
    Task("gripper_eval", *_same(_GRIPPER)),
    Task("cd_full", *_same(_CD), heavy=True),
    Task("single_crease", *_same(_CREASE.replace("{steps}", "250"))),
    Task("miura_heat", *_same(_MIURA)),
    Task("newton_1e3", *_newton(10)),
    Task("newton_1e4", *_newton(30)),
    Task("newton_1e5", *_newton(96), heavy=True),
)
TASK_NAMES = tuple(t.name for t in TASKS)


def parse_args(argv=None) -> argparse.Namespace:
    """Command-line options; ``--tasks`` names are checked against :data:`TASK_NAMES`."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", choices=TASK_NAMES, metavar="TASK",
                    help=f"tasks to run (default: all); one of {', '.join(TASK_NAMES)}")
    ap.add_argument("--repeat", type=int, default=1, help="best of N runs per side (default 1)")
    ap.add_argument("--quick", action="store_true", help="skip cd_full and newton_1e5")
    ap.add_argument("--keep", action="store_true", help="keep the old worktree")
    ap.add_argument("--old-tree", type=Path, help="reuse this checkout of the old commit")
    ap.add_argument("--commit", default=OLD_COMMIT, help=f"old commit (default {OLD_COMMIT})")
    args = ap.parse_args(argv)
    if args.repeat < 1:
        ap.error(f"--repeat = {args.repeat} must be >= 1")
    return args


def selected_tasks(args: argparse.Namespace) -> list:
    """The tasks to run: ``--tasks`` (default all), minus the heavy ones under ``--quick``."""
    names = args.tasks or TASK_NAMES
    return [t for t in TASKS if t.name in names and not (args.quick and t.heavy)]


def run_snippet(snippet: str, tree: Path, pycache: Path | None = None,
                fresh: bool = False) -> dict:
    """Run ``snippet`` in a fresh interpreter with ``PYTHONPATH=tree``.

    Returns the snippet's JSON line plus ``wall`` (wall time of the subprocess [s]). Bytecode
    goes to ``pycache`` (so both trees start from written ``.pyc`` files even where
    ``PYTHONDONTWRITEBYTECODE`` is set); with ``fresh`` the bytecode and numba caches point to
    new empty directories instead (as right after install).
    """
    env = dict(os.environ, PYTHONPATH=str(tree), PYTHONHASHSEED="0")
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    with tempfile.TemporaryDirectory(prefix="bench_versus_cache_") as cache:
        if fresh:
            env.update(PYTHONPYCACHEPREFIX=cache, NUMBA_CACHE_DIR=cache)
        elif pycache is not None:
            env["PYTHONPYCACHEPREFIX"] = str(pycache)
        code = textwrap.dedent(snippet) + _FOOTER
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-c", code], cwd=tree, env=env,
                              capture_output=True, text=True)
        wall = time.perf_counter() - t0
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("@@")]
    if proc.returncode != 0 or not lines:
        return {"time": None, "result": None, "rss_mb": None, "wall": wall,
                "error": (proc.stderr.strip().splitlines() or ["no output"])[-1]}
    out = json.loads(lines[-1][2:])
    out["wall"] = wall
    return out


def measure(task: Task, old: Path, new: Path, repeat: int, pycache: Path | None = None) -> dict:
    """Best-of-``repeat`` times of ``task`` on both trees, run alternately old, new, ..."""
    runs = {"old": [], "new": []}
    for _ in range(repeat):
        for side, tree, snip in (("old", old, task.old), ("new", new, task.new)):
            out = run_snippet(snip, tree, pycache, fresh=task.fresh)
            if task.outside and "error" not in out:
                out["time"] = out["wall"]
            runs[side].append(out)
    row = {"task": task.name}
    for side, outs in runs.items():
        ok = [o for o in outs if o["time"] is not None]
        row[side] = min(o["time"] for o in ok) if ok else None
        row[f"{side}_result"] = (ok or outs)[-1]["result"]
        row[f"{side}_rss"] = max((o["rss_mb"] for o in ok), default=None)
        row[f"{side}_error"] = next((o["error"] for o in outs if "error" in o), None)
    row["same"] = _same_result(row["old_result"], row["new_result"])
    return row


def _same_result(a, b, rtol: float = 1e-6):
    """'yes'/'no' when both results are numbers to compare, '-' when there is nothing to compare."""
    if a is None or b is None:
        return "-"
    a, b = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    if a.shape != b.shape:
        return "no"
    return "yes" if np.allclose(a, b, rtol=rtol, atol=1e-12) else "no"


def format_table(rows: list) -> str:
    """The Markdown table: task, old [s], new [s], speed-up, same result?, peak RSS, results."""
    head = ("| task | old [s] | new [s] | speed-up | same result? | old RSS [MB] | new RSS [MB] "
            "| old result | new result |")
    lines = [head, "|" + "---|" * 9]
    f = lambda x, p: "-" if x is None else f"{x:.{p}f}"  # noqa: E731
    for r in rows:
        speed = r["old"] / r["new"] if r["old"] and r["new"] else None
        lines.append(f"| {r['task']} | {f(r['old'], 3)} | {f(r['new'], 3)} | "
                     f"{'-' if speed is None else f'{speed:.2f}x'} | {r['same']} | "
                     f"{f(r['old_rss'], 0)} | {f(r['new_rss'], 0)} | "
                     f"{r['old_error'] or r['old_result']} | {r['new_error'] or r['new_result']} |")
    return "\n".join(lines)


def growth_exponents(rows: list) -> dict:
    """Slope of log(time) against log(nodes) over the newton_* rows, per side."""
    out = {}
    for side in ("old", "new"):
        pts = [(r[f"{side}_result"][0], r[side]) for r in rows
               if r["task"].startswith("newton_") and r[side] and r[f"{side}_result"]]
        if len(pts) >= 2:
            n, t = np.array(pts, float).T
            out[side] = float(np.polyfit(np.log(n), np.log(t), 1)[0])
    return out


def _old_worktree(commit: str) -> Path:
    tmp = Path(tempfile.mkdtemp(prefix="etorigami_old_"))
    subprocess.run(["git", "-C", str(REPO), "worktree", "add", "--detach", str(tmp), commit],
                   check=True, capture_output=True)
    return tmp


def main(argv=None) -> list:
    args = parse_args(argv)
    tasks = selected_tasks(args)
    old = args.old_tree.resolve() if args.old_tree else _old_worktree(args.commit)
    print(f"old: {args.commit} at {old}; new: {REPO}; python {sys.version.split()[0]}; "
          f"load {os.getloadavg()[0]:.2f}", flush=True)
    rows = []
    pycache = Path(tempfile.mkdtemp(prefix="bench_versus_pyc_"))
    try:
        for tree in (old, REPO):        # untimed: writes the bytecode both sides then load
            run_snippet(_WARM, tree, pycache)
        for task in tasks:
            rows.append(measure(task, old, REPO, args.repeat, pycache))
            r = rows[-1]
            print(f"  {task.name}: old {r['old']} s, new {r['new']} s", flush=True)
    finally:
        shutil.rmtree(pycache, ignore_errors=True)
        if not args.old_tree and not args.keep:
            subprocess.run(["git", "-C", str(REPO), "worktree", "remove", "--force", str(old)],
                           capture_output=True)
    print()
    print(format_table(rows))
    for side, slope in growth_exponents(rows).items():
        print(f"\n{side}: time per Newton iteration grows as nodes^{slope:.2f}")
    return rows


if __name__ == "__main__":
    main()
