"""Reading imports from source, for the tests of the package's layering."""

from __future__ import annotations

import ast


def imported_module(package: str, node: ast.ImportFrom) -> str:
    """The absolute module ``from ... import`` reads in a module of ``package`` (relative
    imports resolved)."""
    if not node.level:
        return node.module or ""
    parts = package.split(".")
    base = parts[:len(parts) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))
