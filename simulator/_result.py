"""The result interface shared by every public result type (simulator and design layer).

Every result carries ``success``, ``status`` and ``message`` (fields or properties of the
class) and gets from :class:`ResultFiles`:

- ``to_frame()``: a tidy :class:`pandas.DataFrame` with unit-bearing column names; the default
  is one row made of :meth:`ResultFiles._row` (the class's ``to_dict()`` when it has one, else
  its scalar fields), for results that are one outcome;
- ``save(directory, metadata=None)``: the tables of :meth:`ResultFiles._tables` as CSV plus
  ``meta.json`` (:func:`write_meta`: version, git hash, result type, success, status, message,
  the class's :meth:`ResultFiles._meta` and ``metadata``).

A class with more than a table (arrays, a model) overrides ``save`` and calls
``super().save`` for the shared part. Not a public module: users see the methods only.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib

import numpy as np

from ._version import __version__

__all__ = ["ResultFiles", "write_meta", "provenance", "jsonable", "git_hash"]


class ResultFiles:
    """Mixin giving ``to_frame()`` and ``save(directory)`` to a result with ``success``,
    ``status`` and ``message``.

    Subclasses set :attr:`_csv_name` and override :meth:`to_frame` (or :meth:`_row`),
    :meth:`_meta` (what ``meta.json`` records besides the outcome) and :meth:`_tables` (when
    there is more than one table). No fields and no properties named like dataclass fields,
    so the mixin never becomes a dataclass default.
    """

    #: File name of :meth:`to_frame` in :meth:`save`.
    _csv_name = "result.csv"

    def to_frame(self):
        """One row: the result's summary (``to_dict()`` when the class has one, else its
        scalar fields)."""
        import pandas as pd

        return pd.DataFrame([self._row()])

    def _row(self) -> dict:
        to_dict = getattr(self, "to_dict", None)
        if callable(to_dict):
            return dict(to_dict())
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if _scalar(getattr(self, f.name))}

    def _meta(self) -> dict:
        """Extra ``meta.json`` entries (JSON-able; numpy values are converted)."""
        return {}

    def _tables(self) -> dict:
        """{file name: DataFrame} written by :meth:`save` (default: :meth:`to_frame`)."""
        return {self._csv_name: self.to_frame()}

    def save(self, directory, metadata: dict | None = None) -> pathlib.Path:
        """Write the result's table(s) as CSV and ``meta.json`` into ``directory`` (created if
        needed); ``metadata`` (e.g. the case and its parameters) is added to ``meta.json``.
        Returns the directory."""
        out = pathlib.Path(directory)
        out.mkdir(parents=True, exist_ok=True)
        tables = {name: frame for name, frame in self._tables().items() if frame is not None}
        for name, frame in tables.items():
            frame.to_csv(out / name, index=False)
        write_meta(out, self, {"tables": sorted(tables), **self._meta(), **(metadata or {})})
        return out


def write_meta(directory, result, extra: dict | None = None) -> pathlib.Path:
    """Write ``meta.json`` for ``result`` into ``directory``: ``etorigami_version``, ``git``
    (commit hash or None), ``result`` (type name), ``success``, ``status``, ``message``, then
    ``extra``. Returns the file's path."""
    meta = {"etorigami_version": __version__, "git": git_hash(),
            "result": type(result).__name__, "success": bool(result.success),
            "status": result.status, "message": result.message, **(extra or {})}
    path = pathlib.Path(directory) / "meta.json"
    path.write_text(json.dumps(meta, indent=2, default=jsonable))
    return path


def _scalar(v) -> bool:
    return v is None or isinstance(v, (bool, int, float, str, np.generic))


def jsonable(obj):
    """JSON form of what :func:`json.dumps` cannot write (arrays, numpy scalars, dataclasses)."""
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.integer, np.floating, np.bool_)):
        return obj.item()
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}
    return str(obj)


def provenance() -> dict:
    """What produced a result, for its ``meta.json``: ``etorigami_version``, ``git`` (the
    commit of the checkout the package is imported from, None when unknown: an installed copy,
    no git), ``date`` (now, UTC, ISO 8601) and ``machine`` (operating system, architecture,
    CPU model where the system names it, logical CPUs, Python version; no host name)."""
    import datetime                       # here: the CLI's start-up imports this module
    import platform

    return {"etorigami_version": __version__, "git": git_hash(),
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "machine": {"system": f"{platform.system()} {platform.release()}",
                        "architecture": platform.machine(), "cpu": _cpu_model(),
                        "cpus": os.cpu_count(), "python": platform.python_version()}}


def _cpu_model() -> str | None:
    """The CPU's model name (Linux: /proc/cpuinfo), else ``platform.processor()`` or None."""
    import platform

    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.partition(":")[2].strip() or None
    except OSError:
        pass
    return platform.processor() or None


def git_hash() -> str | None:
    """The commit of the git checkout this package is imported from, read from its ``.git``
    files (``HEAD``, the branch's ref file or ``packed-refs``; a worktree's ``.git`` file
    pointing elsewhere), without running git; None for an installed copy or an unreadable
    checkout. Called when a result is saved, never on import."""
    try:
        dot_git = pathlib.Path(__file__).resolve().parent.parent / ".git"
        if dot_git.is_file():                  # a worktree: "gitdir: <path>"
            text = dot_git.read_text().strip()
            if not text.startswith("gitdir:"):
                return None
            git_dir = (dot_git.parent / text[len("gitdir:"):].strip()).resolve()
        elif dot_git.is_dir():
            git_dir = dot_git
        else:
            return None
        head = (git_dir / "HEAD").read_text().strip()
        if not head.startswith("ref:"):
            return head or None                # a detached HEAD holds the commit
        ref = head[len("ref:"):].strip()
        common = git_dir
        if (git_dir / "commondir").is_file():  # refs live in the main repository's .git
            common = (git_dir / (git_dir / "commondir").read_text().strip()).resolve()
        for folder in dict.fromkeys((git_dir, common)):
            if (folder / ref).is_file():
                return (folder / ref).read_text().strip() or None
        for line in (common / "packed-refs").read_text().splitlines():
            if line.endswith(" " + ref) and not line.startswith(("#", "^")):
                return line.split()[0]
    except OSError:
        pass
    return None
