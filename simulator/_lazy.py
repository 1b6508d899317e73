"""Lazy public names of a package (PEP 562): each is imported from its submodule on first use.

``import simulator`` (or ``import design``) then costs almost nothing; ``from simulator import
simulate`` imports only what :func:`simulate` needs. A package calls :func:`attach` once::

    __getattr__, __dir__ = attach(__name__, {".cases": ("Case", "get_case"), ...})

Attribute access to a submodule that is not imported yet (``simulator.thermal`` after
``import simulator``) imports it, as the eager package did. A public name that is also the
name of a submodule (a function ``pkg.f`` defined in the module ``pkg.f``)
stays bound to the public object when the submodule is imported: the import system binds the
submodule on the package after loading it, and the package's module class turns that back
into the public name.
"""

from __future__ import annotations

import importlib
import sys
import types

__all__ = ["attach"]


class _LazyPackage(types.ModuleType):
    """Module class of a lazy package: keeps public names over submodules of the same name."""

    def __setattr__(self, name, value):
        where = self.__dict__.get("_lazy_where", {})
        if (name in where and isinstance(value, types.ModuleType)
                and value.__name__ == f"{self.__name__}.{name}"):
            value = getattr(importlib.import_module(where[name], self.__name__), name)
        super().__setattr__(name, value)


def attach(package: str, exports: dict, modules: dict | None = None) -> tuple:
    """``(__getattr__, __dir__)`` of the package ``package``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : dict
        Relative submodule name (``".cases"``) -> tuple of the public names it defines.
    modules : dict, optional
        Public name -> relative name of a submodule that is public under that name
        (``{"example_patterns": ".geometry.example_patterns"}``), imported on first access.
    """
    modules = dict(modules or {})
    module = sys.modules[package]
    where = {name: sub for sub, names in exports.items() for name in names}
    if len(where) != sum(len(names) for names in exports.values()):
        raise ValueError(f"{package}: a public name is listed under two submodules")
    module._lazy_where = where
    module.__class__ = _LazyPackage

    def __getattr__(name: str):
        if name in where:
            value = getattr(importlib.import_module(where[name], package), name)
        elif name in modules:
            value = importlib.import_module(modules[name], package)
        elif name.startswith("__"):
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        else:
            value = _submodule(package, name)
        module.__dict__[name] = value
        return value

    def __dir__():
        return sorted(set(module.__dict__) | set(where) | set(modules))

    return __getattr__, __dir__


def _submodule(package: str, name: str):
    """The submodule ``package.name``, imported; AttributeError if there is none."""
    full = f"{package}.{name}"
    try:
        return importlib.import_module(full)
    except ModuleNotFoundError as exc:
        if exc.name != full:
            raise
    raise AttributeError(f"module {package!r} has no attribute {name!r}")
