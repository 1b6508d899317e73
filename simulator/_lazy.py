"""Lazy public names of a package or namespace module (PEP 562): each is imported from its
submodule on first use.

``import simulator`` (or ``import design``) then costs almost nothing; ``from simulator import
simulate`` imports only what :func:`simulate` needs. A package calls :func:`attach` once::

    __getattr__, __dir__ = attach(__name__, {".cases": ("Case", "get_case"), ...})

Submodule names are relative to the package (for a plain module such as ``simulator.schedules``,
to the package it is in, as Python's relative imports are). An entry ``"newton as
solve_equilibrium"`` publishes the submodule's ``newton`` under the name ``solve_equilibrium``.

Attribute access to a submodule that is not imported yet (``simulator.thermal`` after
``import simulator``) imports it, as the eager package did. A public name that is also the
name of a submodule (a function ``pkg.f`` defined in the module ``pkg.f``)
stays bound to the public object when the submodule is imported: the import system binds the
submodule on the package after loading it, and the package's module class turns that back
into the public name.

Old spellings: ``moved`` names a submodule whose ``MOVED`` table (loaded on the first unknown
name) maps each namespace to the names that left the package's door for it,
``{"fold": ("read_fold", ...), "solvers": ("displacement_control as control_displacement",)}``;
such a name still resolves, to the same object as its new spelling, with an
:class:`~simulator.errors.EtorigamiDeprecationWarning` naming the new place. Renamed names:
``renamed`` names a submodule whose ``RENAMED`` table maps an old name to its new one in the
same place (``{"build_mesh": "make_mesh"}``); a package or namespace that publishes the new
name resolves the old one the same way.
"""

from __future__ import annotations

import importlib
import sys
import types

__all__ = ["attach", "split_entry", "moved_names"]


class _LazyPackage(types.ModuleType):
    """Module class of a lazy package: keeps public names over submodules of the same name."""

    def __setattr__(self, name, value):
        where = self.__dict__.get("_lazy_where", {})
        if (name in where and isinstance(value, types.ModuleType)
                and value.__name__ == f"{self.__name__}.{name}"):
            value = self.__dict__["__getattr__"](name)
        super().__setattr__(name, value)


def split_entry(entry: str) -> tuple[str, str]:
    """``(source name, public name)`` of an entry ``"name"`` or ``"source as public"``."""
    source, _, public = entry.partition(" as ")
    return source.strip(), (public or source).strip()


def moved_names(table: dict, package: str) -> dict:
    """``{old name: (new module, new name)}`` of a ``MOVED`` table (see the module docstring)."""
    out = {}
    for namespace, entries in table.items():
        for entry in entries:
            old, new = split_entry(entry)
            out[old] = (f"{package}.{namespace}", new)
    return out


def attach(package: str, exports: dict, modules: dict | None = None,
           moved: str | None = None, renamed: str | None = None) -> tuple:
    """``(__getattr__, __dir__)`` of the package (or module) ``package``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : dict
        Relative submodule name (``".cases"``) -> tuple of the public names it defines
        (``"source as public"`` to publish a name under another one).
    modules : dict, optional
        Public name -> relative name of a submodule that is public under that name
        (``{"example_patterns": ".geometry.example_patterns"}``), imported on first access.
    moved : str, optional
        Relative name of the submodule whose ``MOVED`` table lists the old spellings.
    renamed : str, optional
        Name (relative or absolute) of the module whose ``RENAMED`` table ``{old: new}`` lists
        the renamed names; those whose new name ``package`` publishes resolve here.
    """
    modules = dict(modules or {})
    module = sys.modules[package]
    anchor = package if hasattr(module, "__path__") else package.rpartition(".")[0]
    where, source = {}, {}
    for sub, entries in exports.items():
        for entry in entries:
            name, public = split_entry(entry)
            if public in where:
                raise ValueError(f"{package}: the public name {public!r} is listed twice")
            where[public], source[public] = sub, name
    module._lazy_where = where
    module.__class__ = _LazyPackage
    old, renames = {}, {}

    def __getattr__(name: str):
        if name in where:
            value = getattr(importlib.import_module(where[name], anchor), source[name])
        elif name in modules:
            value = importlib.import_module(modules[name], anchor)
        elif name.startswith("__"):
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        else:
            target = None
            try:
                value = _submodule(package, name)
            except AttributeError:
                if moved is not None and name in _moved(old, moved, anchor):
                    target = old[name]
                elif renamed is not None and _renamed(renames, renamed, anchor).get(
                        name) in where:
                    target = (package, renames[name])
                else:
                    raise
            if target is not None:            # warned outside the handler: no chained error
                return _deprecated(package, name, *target)
        module.__dict__[name] = value
        return value

    def __dir__():
        return sorted(set(module.__dict__) | set(where) | set(modules))

    return __getattr__, __dir__


def _moved(old: dict, table: str, anchor: str) -> dict:
    """The package's old spellings, read from ``table``'s ``MOVED`` on first use."""
    if not old:
        old.update(moved_names(importlib.import_module(table, anchor).MOVED, anchor))
    return old


def _renamed(renames: dict, table: str, anchor: str) -> dict:
    """The ``RENAMED`` table ``{old: new}`` of the module ``table``, read on first use."""
    if not renames:
        renames.update(getattr(importlib.import_module(table, anchor), "RENAMED", {}))
    return renames


def _deprecated(package: str, name: str, namespace: str, new: str):
    """The object an old spelling ``package.name`` stands for, with a deprecation warning (not
    cached: every use warns, Python shows it once per line)."""
    from ._deprecation import warn_deprecated

    value = getattr(importlib.import_module(namespace), new)
    warn_deprecated(f"{package}.{name} is deprecated (it goes in the next release): use "
                    f"{namespace}.{new} (from {namespace} import {new}).")
    return value


def _submodule(package: str, name: str):
    """The submodule ``package.name``, imported; AttributeError if there is none."""
    full = f"{package}.{name}"
    try:
        return importlib.import_module(full)
    except ModuleNotFoundError as exc:
        if exc.name != full:
            raise
    raise AttributeError(f"module {package!r} has no attribute {name!r}")
