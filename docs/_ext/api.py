"""API reference machinery of the documentation build (mkdocs.yml): the public names of
``simulator`` and ``design`` become pages, and docstrings written for numpydoc render here.

Three parts, all driven by the packages' own ``__init__.py`` (read as source, not imported):

* :func:`public_names` reads ``__all__`` and the lazy-import map that ``simulator._lazy.attach``
  gets, giving every public name and the module it lives in.
* The MkDocs hooks ``on_config`` and ``on_files`` generate one page per subpackage
  (``api/simulator/geometry.md``, ...) with a ``::: simulator.Pattern`` entry for every public
  name that lives there, and put the pages in the navigation: a new name in ``__all__`` appears
  without editing anything here; a name in ``__all__`` whose module is unknown stops the build.
* :class:`PublicApi`, a griffe extension, makes the lazily exported names visible to griffe
  (as aliases on the package, so ``simulator.simulate`` resolves statically) and rewrites the
  Sphinx roles of the docstrings (``:func:`~simulator.simulate``` and friends) into
  mkdocs-autorefs cross-references, which ``mkdocs build --strict`` checks. A role whose target
  is in our packages but not rendered (a private helper) becomes inline code; a role naming an
  object of ours that does not exist is a warning, so the strict build fails on it. Roles naming
  other libraries (numpy, scipy, ...) become inline code: the build has no network, so it cannot
  check them against those projects' inventories. Citations of the method, "theory 4.3",
  become links to that section of docs/theory.md; a section that does not exist is a warning.
"""

from __future__ import annotations

import ast
import builtins
import logging
import pathlib
import re
from dataclasses import dataclass

try:
    import griffe
except ImportError:  # tests/test_docs.py reads the public names without the docs extra
    griffe = None

ROOT = pathlib.Path(__file__).resolve().parents[2]
PACKAGES = ("simulator", "design")
API_DIR = "api"
NAV_TITLE = "API reference"
logger = logging.getLogger("mkdocs.hooks.api")


# ---------------------------------------------------------------- the packages' public names
@dataclass(frozen=True)
class PublicName:
    """One entry of a package's ``__all__``: ``name`` in ``package``, defined in ``module``."""

    package: str
    name: str
    module: str          # dotted module that defines it (for a public submodule, that module)
    is_module: bool

    @property
    def target(self) -> str:
        """Dotted path of the object the public name stands for."""
        return self.module if self.is_module else f"{self.module}.{self.name}"

    @property
    def group(self) -> str:
        """Subpackage the name lives in ("" for modules at the package's top level)."""
        parts = self.module.split(".")
        sub = ROOT.joinpath(*parts[:2])
        return parts[1] if len(parts) > 2 or sub.is_dir() else ""


def public_names(package: str) -> list[PublicName]:
    """Every name of ``package.__all__`` with its defining module, in ``__all__`` order."""
    tree = ast.parse((ROOT / package / "__init__.py").read_text())
    lazy, modules, imported, exported = {}, {}, {}, None
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "_attach":
            for key, names in zip(node.args[1].keys, node.args[1].values):
                lazy.update({n.value: key.value for n in names.elts})
            for kw in node.keywords:
                if kw.arg == "modules":
                    modules = ast.literal_eval(kw.value)
        elif isinstance(node, ast.ImportFrom) and node.level == 1:
            imported.update({a.asname or a.name: "." + (node.module or "") for a in node.names})
        elif isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "__all__":
            exported = ast.literal_eval(node.value)
    if exported is None:
        raise RuntimeError(f"{package}/__init__.py has no literal __all__")
    out = []
    for name in exported:
        if name in modules:
            out.append(PublicName(package, name, package + modules[name], True))
        elif name in lazy or name in imported:
            out.append(PublicName(package, name, package + (lazy.get(name) or imported[name]),
                                  False))
        else:
            raise RuntimeError(f"{package}.__all__ lists {name!r}, but {package}/__init__.py "
                               "neither imports it nor maps it in _attach(...): add it there")
    return out


def _groups(package: str) -> dict[str, list[PublicName]]:
    groups: dict[str, list[PublicName]] = {"": []}
    for item in public_names(package):
        groups.setdefault(item.group, []).append(item)
    return groups


def _page_path(package: str, group: str) -> str:
    return f"{API_DIR}/{package}/{group or 'index'}.md"


def _title(package: str, group: str) -> str:
    return f"{package}.{group}" if group else f"{package} (top level)"


def _page(package: str, group: str, items: list[PublicName]) -> str:
    module = f"{package}.{group}" if group else package
    lines = [f"# {module}", ""]
    if group:
        lines += [f"Public names of `{package}` that live in `{module}`; import them from "
                  f"`{package}` itself (`from {package} import {items[0].name}`).", ""]
    lines += [f"::: {module}", "    options:", "      members: false",
              "      show_root_heading: false", ""]
    for item in items:
        lines += [f"::: {package}.{item.name}", ""]
    return "\n".join(lines)


# ---------------------------------------------------------------- MkDocs hooks
def on_config(config, **kwargs):
    """Fill the navigation's API section with one page per package and subpackage."""
    nav = config["nav"] or []
    for entry in nav:
        if isinstance(entry, dict) and NAV_TITLE in entry:
            entry[NAV_TITLE] = [
                {package: [{_title(package, g): _page_path(package, g)} for g in _groups(package)]}
                for package in PACKAGES]
            return config
    raise RuntimeError(f"mkdocs.yml: the nav needs an entry '{NAV_TITLE}: []' to fill")


def on_files(files, config, **kwargs):
    """Add the generated API pages to the documentation files."""
    from mkdocs.structure.files import File

    for package in PACKAGES:
        for group, items in _groups(package).items():
            files.append(File.generated(config, _page_path(package, group),
                                        content=_page(package, group, items)))
    return files


# ---------------------------------------------------------------- griffe extension
_ROLE = re.compile(r":(?:py:)?(class|func|meth|attr|data|mod|exc|obj):`(~?)([^`<]+?)"
                   r"(?:\s*<([^>`]+)>)?`")
_LITERAL_BLOCK = re.compile(r"::(\n[ \t]*\n)")
_NUMBER = r"\d+(?:\.\d+)?"
_CITATION = re.compile(rf"\b(theory )({_NUMBER}(?:(?:-|, | and ){_NUMBER}(?![\d.]))*)", re.I)
_EXTERNAL = ("numpy", "np", "scipy", "pandas", "pd", "matplotlib", "dask", "nlopt", "cvxpy",
             "numba", "pymetis", "mkl", "logging", "dataclasses", "concurrent", "pathlib",
             "functools", "typing", "collections", "json", "os", "io", "warnings", "tqdm")


def theory_anchors() -> dict[str, str]:
    """Section number -> heading anchor of docs/theory.md ("4.3" -> "43-environment-chains")."""
    from markdown.extensions.toc import slugify

    heading = re.compile(r"^#{2,3} ((\d+(?:\.\d+)?)\.? .*)$", re.M)
    text = (ROOT / "docs" / "theory.md").read_text()
    return {m.group(2): slugify(m.group(1), "-") for m in heading.finditer(text)}


def _link_citations(text: str, where: str, anchors: dict[str, str]) -> str:
    """"theory 4.3-4.4" -> links to both sections (autorefs knows every heading's anchor)."""
    def number(m: re.Match) -> str:
        if m.group(0) not in anchors:
            logger.warning("%s: cites theory %s, which docs/theory.md does not have", where,
                           m.group(0))
            return m.group(0)
        return f"[{m.group(0)}][{anchors[m.group(0)]}]"

    def citation(m: re.Match) -> str:
        linked = re.sub(_NUMBER, number, m.group(2))
        return linked.replace("[", f"[{m.group(1)}", 1) if linked.startswith("[") \
            else m.group(1) + linked

    return _CITATION.sub(citation, text)


def _member(obj, dotted: str):
    """``obj.<dotted>`` through griffe members and aliases, or None."""
    for part in dotted.split("."):
        try:
            obj = obj.members[part] if part in obj.members else None
        except Exception:  # an alias whose target is not loaded  # noqa: BLE001
            return None
        if obj is None:
            return None
    return obj


def _final(obj):
    try:
        return obj.final_target if obj.is_alias else obj
    except Exception:  # noqa: BLE001 - unresolvable alias
        return None


class PublicApi(griffe.Extension if griffe else object):
    """Griffe extension: the lazy exports of our packages and their Sphinx roles (see above)."""

    def __init__(self) -> None:
        super().__init__()
        self.done = False

    def on_package(self, *, pkg, loader, **kwargs) -> None:
        if pkg.name not in PACKAGES or self.done:
            return
        self.done = True
        for name in PACKAGES:                                 # both, for cross-package roles
            if name not in loader.modules_collection:
                loader.load(name)
        _add_lazy_aliases(loader)
        rendered, anchors = _rendered(loader), theory_anchors()
        for name in PACKAGES:
            for obj in _walk(loader.modules_collection[name]):
                _rewrite_docstring(obj, loader, rendered, anchors)


def _add_lazy_aliases(loader) -> None:
    for package in PACKAGES:
        pkg = loader.modules_collection[package]
        for item in public_names(package):
            if item.name not in pkg.members or not pkg.members[item.name].is_alias:
                pkg.set_member(item.name, griffe.Alias(item.name, item.target, parent=pkg))


def _rendered(loader) -> dict[str, str]:
    """Canonical path -> documented identifier of everything the API pages render."""
    out = {}
    for package in PACKAGES:
        for item in public_names(package):
            obj = _final(_member(loader.modules_collection[package], item.name))
            if obj is None:
                logger.warning("%s.%s: its target %s does not exist", package, item.name,
                               item.target)
                continue
            _register(obj, f"{package}.{item.name}", out)
    return out


def _register(obj, ident: str, out: dict[str, str]) -> None:
    """Record ``obj`` and the members mkdocstrings renders with it (public, documented, not
    inherited); an undocumented member's path points to its owner's entry."""
    out.setdefault(obj.path, ident)
    if obj.kind.value in ("class", "module"):
        for name, member in obj.members.items():
            if name.startswith("_") or (obj.kind.value == "module" and member.is_alias):
                continue
            target = _final(member)
            if target is None:
                continue
            if target.has_docstrings:
                _register(target, f"{ident}.{name}", out)
            else:
                out.setdefault(target.path, ident)


def _walk(obj):
    yield obj
    for member in obj.members.values():
        if not member.is_alias:
            yield from _walk(member)


def _resolve(target: str, scope, loader):
    """The griffe object a role's target names, seen from ``scope`` (as Sphinx does)."""
    collection = loader.modules_collection
    head = target.split(".")[0]
    if head in collection:
        return _final(_member(collection[head], target.split(".", 1)[1])
                      if "." in target else collection[head])
    while scope is not None:
        found = _member(scope, target)
        if found is not None:
            return _final(found)
        scope = scope.parent
    for package in PACKAGES:                                 # a public name used bare
        found = _member(collection[package], target)
        if found is not None:
            return _final(found)
    return None


def _rewrite_docstring(obj, loader, rendered, anchors) -> None:
    if obj.docstring is None:
        return
    where = f"{obj.path} ({obj.relative_filepath}:{obj.docstring.lineno})"

    def replace(match: re.Match) -> str:
        role, short, text, explicit = match.groups()
        target = re.sub(r"\s+", "", explicit or text).lstrip(".")
        shown = (" ".join(text.split()) if explicit else target.rsplit(".", 1)[-1] if short
                 else target)
        if role in ("func", "meth") and not explicit:
            shown += "()"
        found = _resolve(target, obj if obj.kind.value in ("class", "module") else obj.parent,
                         loader)
        if found is not None and found.path in rendered:
            return f"[`{shown}`][{rendered[found.path]}]"
        if found is None and (target.split(".")[0] in PACKAGES + ("studies",)
                              or target.split(".")[0] not in _EXTERNAL
                              and not hasattr(builtins, target)):
            logger.warning("%s: %s names %r, which does not exist", where, match.group(0),
                           target)
        return f"`{shown}`"

    text = _link_citations(_ROLE.sub(replace, obj.docstring.value), where, anchors)
    obj.docstring.value = _LITERAL_BLOCK.sub(r":\1", text)
