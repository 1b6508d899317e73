"""The public names of ``simulator`` and ``design``: each package's door (``__all__``) and the
namespaces it lists (``simulator.thermal``, ``design.analysis``, ...), each with its own
``__all__``."""

from __future__ import annotations

import importlib
import types


def namespaces(package) -> dict:
    """{name: module} of the namespaces ``package.__all__`` lists."""
    return {name: getattr(package, name) for name in package.__all__
            if isinstance(getattr(package, name), types.ModuleType)}


def public_names(package) -> set:
    """Every name public at ``package``'s door or in one of its namespaces."""
    names = {n for n in package.__all__ if n not in namespaces(package)}
    for module in namespaces(package).values():
        names |= set(module.__all__)
    return names


def public_object(package, name: str):
    """The object ``name`` stands for at the door or in the first namespace that has it."""
    if name in package.__all__:
        return getattr(package, name)
    for module in namespaces(package).values():
        if name in module.__all__:
            return getattr(module, name)
    raise AttributeError(f"{package.__name__} publishes no {name!r}")


def moved(package) -> dict:
    """{old name at the door: (namespace module name, new name)} of ``package._moved``."""
    from simulator._lazy import moved_names

    table = importlib.import_module(f"{package.__name__}._moved").MOVED
    return moved_names(table, package.__name__)


def renamed(package) -> dict:
    """{(module name, old name): new name} of ``package._moved.RENAMED``: the door and every
    namespace that publishes the new name."""
    table = getattr(importlib.import_module(f"{package.__name__}._moved"), "RENAMED", {})
    places = [package, *namespaces(package).values()]
    return {(m.__name__, old): new for old, new in table.items() for m in places
            if new in m.__all__}
