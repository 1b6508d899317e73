"""Frames of a FOLD file: the key frame, ``file_frames`` by index or by class, inheritance.

Frame 0 is the key frame (the top-level object), frame k >= 1 is ``file_frames[k - 1]``; a frame
with ``frame_inherit: true`` takes the fields of its ``frame_parent`` (default the key frame)
that it does not give. A frame is also chosen by class: ``"creasePattern"`` or
``"foldedForm"`` (``frame_classes``). The crease pattern read with the fold angles of the
folded form is a valid pairing: a crease-pattern frame without ``edges_foldAngle`` takes them
from a folded-form frame with the same edges.
"""

from __future__ import annotations

import logging

from ._common import fail

logger = logging.getLogger(__name__)

#: Names accepted for the two frame classes (case-insensitive, "-" / "_" / " " ignored).
CLASSES = {"creasepattern": "creasePattern", "cp": "creasePattern", "foldedform": "foldedForm",
           "folded": "foldedForm"}
_FILE_ONLY = ("file_frames", "file_spec", "file_creator", "file_author", "file_title",
              "file_description", "file_classes")


def frames(data: dict) -> list:
    """All frames of a FOLD dict, key frame first, each with its inherited fields."""
    raw = data.get("file_frames") or []
    if not isinstance(raw, list) or not all(isinstance(f, dict) for f in raw):
        fail("file_frames", "must be a list of frame objects.")
    key = {k: v for k, v in data.items() if k not in ("file_frames",)}
    out = [key]
    for i, frame in enumerate(raw):
        out.append(_inherit(frame, out, i + 1))
    return out


def _inherit(frame: dict, done: list, index: int) -> dict:
    if not frame.get("frame_inherit"):
        return dict(frame)
    parent = frame.get("frame_parent", 0)
    if not isinstance(parent, int) or not 0 <= parent < index:
        fail(f"file_frames[{index - 1}].frame_parent", f"{parent!r} must be the index of an "
             f"earlier frame (0..{index - 1}).")
    merged = {k: v for k, v in done[parent].items() if k not in _FILE_ONLY}
    merged.update(frame)
    return merged


def _classes(frame: dict) -> list:
    value = frame.get("frame_classes") or []
    return value if isinstance(value, list) else []


def select_frame(data: dict, frame=None) -> dict:
    """The frame to read: ``None`` (the key frame), an index or a class name."""
    every = frames(data)
    if frame is None:
        if len(every) > 1:
            logger.info("FOLD file has %d frames; reading the key frame (choose with frame=)",
                        len(every))
        return every[0]
    if isinstance(frame, int) and not isinstance(frame, bool):
        if not 0 <= frame < len(every):
            fail("file_frames", f"frame {frame} does not exist: the file has {len(every)} "
                 f"frame(s), 0..{len(every) - 1} (0 = the key frame).")
        return every[frame]
    if isinstance(frame, str):
        name = CLASSES.get(frame.lower().replace("-", "").replace("_", "").replace(" ", ""))
        if name is None:
            fail("frame_classes", f"frame {frame!r} is neither an index nor a class; use "
                 "creasePattern or foldedForm.")
        hits = [f for f in every if name in _classes(f)]
        if not hits:
            found = sorted({c for f in every for c in _classes(f)})
            fail("frame_classes", f"no frame is a {name} (classes in the file: "
                 f"{', '.join(found) or 'none'}); choose a frame by index (0..{len(every) - 1}).")
        chosen = dict(hits[0])
        if name == "creasePattern":
            _pair_angles(chosen, every)
        return chosen
    fail("file_frames", f"frame {frame!r} must be an index or a class name.")


def _pair_angles(cp: dict, every: list) -> None:
    """Give a crease-pattern frame without fold angles those of a folded form with its edges."""
    if "edges_foldAngle" in cp or "edges_foldAngles" in cp:
        return
    for f in every:
        angles = f.get("edges_foldAngle", f.get("edges_foldAngles"))
        if "foldedForm" in _classes(f) and angles is not None \
                and f.get("edges_vertices") == cp.get("edges_vertices"):
            cp["edges_foldAngle"] = angles
            logger.info("FOLD crease pattern frame: fold angles taken from the folded form")
            return
