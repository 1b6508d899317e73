"""Example crease patterns of the paper's devices (geometry only, SI units): each function
returns a :class:`~simulator.Pattern` whose vertex and panel order is that of the reference
scripts (theory 10), so that crease and node numbers match the reference (0-based = reference
id - 1)."""

from .geometry.example_patterns import (crane_pattern, double_fold_pattern, gripper_pattern,
                                        miura_sheet_pattern, roof_pattern, single_fold_pattern,
                                        strip_pattern)

__all__ = ["single_fold_pattern", "strip_pattern", "double_fold_pattern", "miura_sheet_pattern",
           "gripper_pattern", "crane_pattern", "roof_pattern"]
