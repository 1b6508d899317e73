"""FOLD files (https://github.com/edemaine/fold, spec 1.0-1.2): crease patterns, whole simulation
inputs and simulation histories.

To read a file, use :func:`read_fold` for a crease pattern and :func:`read_model` for a model
with its loading steps (the ``etorigami:`` fields of one file hold a whole simulation input);
to write one, :func:`write_fold`, :func:`write_model` and :func:`write_fold_frames` (a
simulation history as multi-frame FOLD for viewers). The ``*_to_*`` functions do the same on
parsed dicts, in memory. Tools that need the file's own indices read in two steps:
:func:`load_fold_json` (the checked JSON) and :func:`parse_fold` (a :class:`FoldGeometry`:
the pattern and the maps from file vertices, faces and edges to pattern ids).

The format, with every ``etorigami:`` field, its unit and default, is in
``docs/fold-format.md``.
"""

from .io.fold import (FoldGeometry, fold_to_model, fold_to_pattern, load_fold_json,
                      model_to_fold, parse_fold, pattern_to_fold, read_fold, read_model,
                      result_to_fold_frames, write_fold, write_fold_frames, write_model)

__all__ = ["read_fold", "read_model", "write_fold", "write_model", "write_fold_frames",
           "fold_to_pattern", "pattern_to_fold", "fold_to_model", "model_to_fold",
           "result_to_fold_frames", "load_fold_json", "parse_fold", "FoldGeometry"]
