"""FOLD files (https://github.com/edemaine/fold, spec 1.0-1.2): patterns, model files and
simulation histories.

* :func:`read_fold` / :func:`write_fold`: a :class:`~simulator.geometry.pattern.Pattern` from / to FOLD;
* :func:`read_model` / :func:`write_model`: a model and its loading steps (one file holds a
  whole simulation input under the ``etorigami:`` namespace);
* :func:`write_fold_frames`: a simulation history as multi-frame FOLD for viewers.

The format, with every ``etorigami:`` field, its unit and default, is in
``docs/fold-format.md``.
"""

from .model_file import fold_to_model, model_to_fold, read_model, write_model
from .reader import FoldGeometry, fold_to_pattern, load_fold_json, parse_fold, read_fold
from .writer import pattern_to_fold, result_to_fold_frames, write_fold, write_fold_frames

__all__ = ["read_fold", "write_fold", "fold_to_pattern", "pattern_to_fold", "load_fold_json",
           "parse_fold", "FoldGeometry",
           "read_model", "write_model", "fold_to_model", "model_to_fold", "write_fold_frames",
           "result_to_fold_frames"]
