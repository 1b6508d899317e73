"""Self-contained HTML viewer of a saved simulation result.

:func:`write_viewer` reads a result directory written by
:meth:`~simulator.results.SimulationResult.save` (``nodes.npz``, ``creases.csv``,
``meta.json``) and writes one HTML file that opens offline (script, style and data inlined):
the deformed mesh in 3-D coloured by nodal temperature with a colour bar, a slider over the
records (initial state, then every accepted increment), play/pause, and the fold angle,
temperature and power of a picked crease (dropdown, or click near a crease in the view).
Creases are named by their crease id (the pattern's edge id), as in ``creases.csv``, the CLI
and FOLD files. The page opens on the most folded record (largest change of any fold angle
from the first record; the last record if nothing folds) with its most folded crease picked,
draws a length scale bar, labels the total power of all creases apart from the picked
crease's, and draws the substrate (panels held at room temperature, ``triangle_kind`` of
``nodes.npz``) in grey, apart from the temperature-coloured sheet.

Data are compressed for the page: positions are quantised to uint16 inside the bounding box
of all records (error below 1/65535 of the box size), temperatures to uint16 inside their
min/max, fold angles and powers are float32; all base64. If the data would exceed
``max_bytes``, records are thinned evenly (first and last kept) and the page says so.
"""

from __future__ import annotations

import base64
import html
import json
import logging
import math
import pathlib
from importlib import resources

import numpy as np

from ..._validate import integer
from ...errors import ParameterError

__all__ = ["write_viewer", "viewer_html", "load_viewer_data"]

logger = logging.getLogger(__name__)

_FILES = ("nodes.npz", "creases.csv", "meta.json")
_NPZ_KEYS = ("positions", "temperature", "power", "crease_ids", "triangles")
#: Default budget for the encoded per-record data [bytes] (the page adds ~30 kB of script).
MAX_DATA_BYTES = 4_500_000


def load_viewer_data(result_dir) -> dict:
    """Read the arrays the viewer needs from a result directory.

    Parameters
    ----------
    result_dir : str or path
        Directory written by :meth:`SimulationResult.save`.

    Returns
    -------
    dict
        ``positions`` (m, n, 3) [m], ``temperature`` (m, n) [deg C], ``power`` (m, C) [W],
        ``fold_angle`` (m, C) [deg], ``crease_ids`` (C,), ``triangles`` (nt, 3),
        ``crease_temperature`` (m, C) [deg C] or None, ``stage`` (m,) stage names,
        ``increment`` (m,), ``time`` (m,) [s] or None, ``meta`` (the parsed ``meta.json``).
    """
    path = pathlib.Path(result_dir)
    if not path.is_dir():
        raise ParameterError(f"result_dir = {str(path)!r} is not a directory; pass a directory "
                             "written by SimulationResult.save (or `etorigami run --out DIR`).")
    missing = [f for f in _FILES if not (path / f).is_file()]
    if missing:
        raise ParameterError(f"result_dir = {str(path)!r} has no {', '.join(missing)}; pass a "
                             "directory written by SimulationResult.save.")
    import pandas as pd

    with np.load(path / "nodes.npz") as npz:
        absent = [k for k in _NPZ_KEYS if k not in npz.files]
        if absent:
            raise ParameterError(f"{path / 'nodes.npz'} lacks {', '.join(absent)}; re-save the "
                                 "result with SimulationResult.save.")
        data = {k: np.asarray(npz[k]) for k in _NPZ_KEYS}
        data["triangle_kind"] = (np.asarray(npz["triangle_kind"])    # older results lack it
                                 if "triangle_kind" in npz.files else None)
    frame = pd.read_csv(path / "creases.csv")
    bad = [k for k in ("positions", "temperature") if not np.isfinite(data[k]).all()]
    if bad:
        raise ParameterError(f"{path / 'nodes.npz'}: {bad[0]} has non-finite values; the viewer "
                             "needs finite positions and temperatures of every record.")
    data["meta"] = json.loads((path / "meta.json").read_text())
    data.update(_record_columns(frame, data, path))
    return data


def _record_columns(frame, data, path) -> dict:
    """Per-record stage, increment, time and (m, C) fold angles from the crease table."""
    m, n = data["temperature"].shape
    creases = data["crease_ids"]
    need = ["step", "stage", "increment", "crease", "fold_angle [deg]"]
    lacking = [c for c in need if c not in frame.columns]
    if lacking or data["positions"].shape != (m, n, 3) or len(data["power"]) != m:
        raise ParameterError(f"{path}: inconsistent result files (missing columns {lacking}, "
                             f"positions {data['positions'].shape}, temperature {(m, n)}); "
                             "re-save the result with SimulationResult.save.")
    fold = frame.pivot(index="step", columns="crease", values="fold_angle [deg]")
    fold = fold.reindex(index=np.arange(m), columns=creases)
    if fold.isna().to_numpy().any():
        raise ParameterError(f"{path / 'creases.csv'} does not have a fold angle for every one "
                             f"of the {m} records and {len(creases)} creases of nodes.npz.")
    temp = None
    if "temperature [degC]" in frame.columns:
        temp = frame.pivot(index="step", columns="crease", values="temperature [degC]")
        temp = temp.reindex(index=np.arange(m), columns=creases).to_numpy(float)
    first = frame.groupby("step").first().reindex(np.arange(m))
    time = first["time [s]"].to_numpy(float) if "time [s]" in frame.columns else None
    return {"fold_angle": fold.to_numpy(float), "stage": first["stage"].astype(str).to_numpy(),
            "increment": first["increment"].to_numpy(int), "time": time,
            "crease_temperature": temp}


def _b64(array, dtype) -> str:
    return base64.b64encode(np.ascontiguousarray(array, dtype=dtype).tobytes()).decode("ascii")


def _quantise(values, lo, hi) -> np.ndarray:
    """Map ``values`` in [lo, hi] (broadcast) to uint16 0..65535."""
    span = np.where(hi > lo, hi - lo, 1.0)
    return np.rint((values - lo) / span * 65535).clip(0, 65535).astype("<u2")


def _thin(m: int, per_record: int, max_bytes: int) -> np.ndarray:
    """Evenly spaced record indices (first and last kept) whose data fit ``max_bytes``."""
    keep = max(2, min(m, max_bytes // max(per_record, 1)))
    return np.unique(np.rint(np.linspace(0, m - 1, keep)).astype(int))


def _start(fold: np.ndarray) -> tuple:
    """(record, crease row) the page opens on: the most folded record of ``fold`` (R, C) [deg]
    (largest change of any crease from the first record) and its most folded crease; the last
    record and crease row 0 if nothing folds."""
    change = np.abs(fold - fold[:1])
    if not change.size or change.max() < 1e-6:
        return len(fold) - 1, 0
    record = int(np.argmax(change.max(axis=1)))
    return record, int(np.argmax(change[record]))


def _triangle_kinds(data: dict) -> np.ndarray:
    """(nt,) kinds: 0 crease, 1 panel, 2 substrate (crease triangles first, six per crease,
    when the file does not say)."""
    kind = data.get("triangle_kind")
    if kind is not None and len(kind) == len(data["triangles"]):
        return np.asarray(kind, np.uint8)
    kind = np.ones(len(data["triangles"]), np.uint8)
    kind[:6 * len(data["crease_ids"])] = 0
    return kind


def _payload(data: dict, max_bytes: int) -> dict:
    """JSON-able page data: quantised base64 arrays plus labels."""
    pos, temp = data["positions"], data["temperature"]
    m, n = temp.shape
    C = len(data["crease_ids"])
    per_record = (n * 3 * 2 + n * 2 + C * 4 * 3) * 4 // 3
    rec = _thin(m, per_record, max_bytes)
    if len(rec) < m:
        logger.warning("viewer: %d records exceed %d bytes; showing %d evenly spaced records",
                       m, max_bytes, len(rec))
    lo, hi = pos.min(axis=(0, 1)), pos.max(axis=(0, 1))
    t_lo, t_hi = float(temp.min()), float(temp.max())
    tri = data["triangles"]
    meta = data["meta"]
    start_record, start_crease = _start(data["fold_angle"][rec])
    return {
        "start_record": start_record, "start_crease": start_crease,
        "triangle_kind": _b64(_triangle_kinds(data), "u1"),
        "title": str(meta.get("case") or meta.get("name") or "simulation result"),
        "status": str(meta.get("status", "")), "message": str(meta.get("message", "")),
        "n_records": int(m), "records": rec.tolist(), "n_nodes": int(n),
        "bbox": [lo.tolist(), hi.tolist()], "t_range": [t_lo, t_hi],
        "positions": _b64(_quantise(pos[rec], lo, hi), "<u2"),
        "temperature": _b64(_quantise(temp[rec], t_lo, t_hi), "<u2"),
        "triangles": _b64(tri, "<u4"), "n_triangles": int(len(tri)),
        "creases": [int(c) for c in data["crease_ids"]],
        "crease_triangles": bool(len(tri) >= 6 * C),
        "fold_angle": _b64(data["fold_angle"][rec], "<f4"),
        "power": _b64(data["power"][rec] * 1e3, "<f4"),
        "crease_temperature": (None if data["crease_temperature"] is None
                               else _b64(data["crease_temperature"][rec], "<f4")),
        "stage": data["stage"][rec].tolist(), "increment": data["increment"][rec].tolist(),
        "time": None if data["time"] is None else      # records without time: null
        [t if math.isfinite(t) else None for t in data["time"][rec].tolist()],
    }


def viewer_html(data: dict, max_bytes: int = MAX_DATA_BYTES) -> str:
    """The viewer page for data from :func:`load_viewer_data`, as one HTML string.

    Parameters
    ----------
    data : dict
        As returned by :func:`load_viewer_data`.
    max_bytes : int
        Budget for the encoded per-record data [bytes]; records are thinned evenly beyond it.
    """
    integer("max_bytes", max_bytes, hint="a budget in bytes")
    assets = resources.files(__name__)
    page = assets.joinpath("viewer.html").read_text(encoding="utf-8")
    script = assets.joinpath("viewer.js").read_text(encoding="utf-8")
    payload = _payload(data, max_bytes)
    text = json.dumps(payload, separators=(",", ":")).replace("</", "<\\/")
    title = html.escape(f"etorigami: {payload['title']}")
    return (page.replace("__TITLE__", title).replace("/*__DATA__*/", text)
            .replace("/*__SCRIPT__*/", script))


def write_viewer(result_dir, out=None, *, max_bytes: int = MAX_DATA_BYTES) -> pathlib.Path:
    """Write the self-contained HTML viewer of a saved result.

    Parameters
    ----------
    result_dir : str or path
        Directory written by :meth:`SimulationResult.save`.
    out : str or path, optional
        HTML file to write; default ``result_dir / "viewer.html"``.
    max_bytes : int
        Budget for the encoded per-record data [bytes]; records are thinned evenly beyond it.

    Returns
    -------
    pathlib.Path
        The written file.
    """
    data = load_viewer_data(result_dir)
    target = pathlib.Path(result_dir) / "viewer.html" if out is None else pathlib.Path(out)
    if target.is_dir():
        raise ParameterError(f"out = {str(target)!r} is a directory; give a file name such as "
                             f"{str(target / 'viewer.html')!r}.")
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(viewer_html(data, max_bytes), encoding="utf-8")
    logger.info("viewer written to %s (%.0f kB)", target, target.stat().st_size / 1e3)
    return target
