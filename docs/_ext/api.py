"""API reference machinery of the documentation build (mkdocs.yml): the public names of
``simulator`` and ``design`` become pages, and docstrings written for numpydoc render here.

Three parts, all driven by the packages' own sources (read, not imported):

* :func:`public_names` reads a package's or namespace's ``__all__`` and where each name comes
  from (the lazy-import map that ``simulator._lazy.attach`` gets, an import, or a definition in
  the module itself); the modules a package's ``__all__`` lists are its namespaces
  (``simulator.thermal``, ``simulator.fold``, ...).
* The MkDocs hooks ``on_config`` and ``on_files`` generate one page for each package's door
  (``api/simulator/index.md``) and one per namespace (``api/simulator/thermal.md``, ...) with a
  ``::: simulator.thermal.ThermalModel`` entry for every public name (a namespace's name that
  is also at the door links to the door's entry), and put the pages in the navigation: a new
  name in an ``__all__`` appears without editing anything here; a name whose module is unknown
  stops the build. ``on_page_markdown`` fills ``<!-- moved names: simulator -->`` with the
  table of old spellings (the package's ``_moved.py``) and their new places.
* :class:`PublicApi`, a griffe extension, makes the lazily exported names visible to griffe
  (as aliases on the package or namespace, so ``simulator.simulate`` and
  ``simulator.thermal.ThermalModel`` resolve statically) and rewrites the
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
    """One entry of a namespace's ``__all__``: ``name`` in ``package`` (``simulator`` or a
    namespace such as ``simulator.thermal``), defined in ``module`` as ``source``."""

    package: str
    name: str
    module: str          # dotted module that defines it (for a public submodule, that module)
    is_module: bool
    source: str = ""     # its name in ``module`` when published under another one

    @property
    def target(self) -> str:
        """Dotted path of the object the public name stands for."""
        return self.module if self.is_module else f"{self.module}.{self.source or self.name}"

    @property
    def ident(self) -> str:
        """The documented identifier, ``package.name``."""
        return f"{self.package}.{self.name}"


def _module_file(module: str) -> pathlib.Path:
    path = ROOT.joinpath(*module.split("."))
    return path / "__init__.py" if path.is_dir() else path.with_suffix(".py")


def _absolute(relative: str, anchor: str) -> str:
    """A relative module name (``"..state"``) seen from the package ``anchor``."""
    level = len(relative) - len(relative.lstrip("."))
    if not level:
        return relative
    base = anchor.split(".")[:len(anchor.split(".")) - level + 1]
    return ".".join(base + [p for p in [relative[level:]] if p])


def _entry(entry: str) -> tuple[str, str]:
    """``(source, public)`` of a lazy entry ``"name"`` or ``"source as public"``."""
    source, _, public = entry.partition(" as ")
    return source.strip(), (public or source).strip()


def public_names(package: str, as_name: str | None = None) -> list[PublicName]:
    """Every name of ``package.__all__`` (a package or module; published as ``as_name``) with
    its defining module, in ``__all__`` order: lazily mapped (``_attach(...)``), imported, or
    defined in the module itself."""
    path = _module_file(package)
    anchor = package if path.name == "__init__.py" else package.rpartition(".")[0]
    found, exported = {}, None
    for node in ast.parse(path.read_text()).body:
        value = getattr(node, "value", None)
        if isinstance(value, ast.Call) and getattr(value.func, "id", "") == "_attach":
            for key, names in zip(value.args[1].keys, value.args[1].values):
                for n in names.elts:
                    source, public = _entry(n.value)
                    found[public] = (_absolute(key.value, anchor), False, source)
            for kw in value.keywords:
                if kw.arg == "modules":
                    found.update({k: (_absolute(v, anchor), True, "")
                                  for k, v in ast.literal_eval(kw.value).items()})
        elif isinstance(node, ast.ImportFrom):
            module = _absolute("." * node.level + (node.module or ""), anchor)
            found.update({a.asname or a.name: (module, False, a.name) for a in node.names})
        elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            found[node.name] = (package, False, node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if getattr(target, "id", "") == "__all__":
                    exported = ast.literal_eval(node.value)
                elif isinstance(target, ast.Name):
                    found[target.id] = (package, False, target.id)
    if exported is None:
        raise RuntimeError(f"{path.relative_to(ROOT)} has no literal __all__")
    out = []
    for name in exported:
        if name not in found:
            raise RuntimeError(f"{package}.__all__ lists {name!r}, but {path.name} neither "
                               "imports it nor maps it in _attach(...): add it there")
        module, is_module, source = found[name]
        out.append(PublicName(as_name or package, name, module, is_module,
                              "" if source == name else source))
    return out


def namespaces(package: str) -> list[PublicName]:
    """The namespaces of ``package``: the modules its ``__all__`` lists."""
    return [item for item in public_names(package) if item.is_module]


def namespace_names(item: PublicName) -> list[PublicName]:
    """The public names of the namespace ``item`` (``simulator.thermal``), as its own."""
    return public_names(item.module, as_name=item.ident)


def _pages(package: str) -> dict[str, tuple[str, list[PublicName], set]]:
    """Page path -> (documented module, its public names, door targets) of the door and of
    every namespace of ``package``."""
    door = public_names(package)
    at_door = {item.target for item in door if not item.is_module}
    pages = {_page_path(package, ""): (package, door, set())}
    for ns in namespaces(package):
        pages[_page_path(package, ns.name)] = (ns.ident, namespace_names(ns), at_door)
    return pages


def _page_path(package: str, namespace: str) -> str:
    return f"{API_DIR}/{package}/{namespace or 'index'}.md"


def _title(module: str, package: str) -> str:
    return module if module != package else f"{package} (the door)"


def _page(module: str, items: list[PublicName], at_door: set) -> str:
    """One API page: the module's docstring, then every public name (a name also at the
    package's door is a link to its entry there)."""
    package = module.split(".")[0]
    lines = [f"# {module}", ""]
    if module == package:
        lines += [f"The names at `{package}`'s door (`from {package} import ...`). Families "
                  "of further names are in the namespaces, each on its own page: "
                  + ", ".join(f"[`{ns.ident}`]({ns.name}.md)" for ns in namespaces(package))
                  + ".", ""]
    lines += [f"::: {module}", "    options:", "      members: false",
              "      show_root_heading: false", ""]
    door = [i for i in items if i.target in at_door]
    if door:
        lines += [f"Also here, documented at the door: "
                  + ", ".join(f"[`{i.name}`][{package}.{i.name}]" for i in door) + ".", ""]
    for item in items:
        if not item.is_module and item.target not in at_door:
            lines += [f"::: {item.ident}", ""]
    return "\n".join(lines)


def _moved_table(package: str, name: str) -> dict:
    """The literal ``name`` (``MOVED``, ``RENAMED``) of ``package``'s ``_moved.py``."""
    tree = ast.parse((ROOT / package / "_moved.py").read_text())
    return next((ast.literal_eval(node.value) for node in tree.body
                 if isinstance(node, ast.Assign) and node.targets[0].id == name), {})


def renamed_table(package: str) -> str:
    """Markdown table old name -> new name of ``package``'s ``RENAMED`` (at the door and in
    the namespaces that publish the new name)."""
    rows = ["| old name | new name |", "| --- | --- |"]
    for old, new in _moved_table(package, "RENAMED").items():
        rows.append(f"| `{old}` | [`{new}`][{package}.{new}] |")
    return "\n".join(rows)


def migration_table(package: str) -> str:
    """Markdown table old spelling -> new spelling of ``package``'s ``_moved.py``."""
    table = _moved_table(package, "MOVED")
    rows = ["| old spelling | new spelling |", "| --- | --- |"]
    for namespace, entries in table.items():
        for entry in entries:
            old, new = _entry(entry)
            rows.append(f"| `{package}.{old}` | [`{package}.{namespace}.{new}`]"
                        f"[{package}.{namespace}.{new}] |")
    return "\n".join(rows)


# ---------------------------------------------------------------- MkDocs hooks
MIGRATION_MARK = re.compile(r"^<!-- moved names: (\w+) -->$", re.M)
RENAMED_MARK = re.compile(r"^<!-- renamed names: (\w+) -->$", re.M)


def on_config(config, **kwargs):
    """Fill the navigation's API section with the door and the namespaces of each package."""
    nav = config["nav"] or []
    for entry in nav:
        if isinstance(entry, dict) and NAV_TITLE in entry:
            entry[NAV_TITLE] = [
                {package: [{_title(module, package): path}
                           for path, (module, _, _) in _pages(package).items()]}
                for package in PACKAGES]
            return config
    raise RuntimeError(f"mkdocs.yml: the nav needs an entry '{NAV_TITLE}: []' to fill")


def on_files(files, config, **kwargs):
    """Add the generated API pages to the documentation files."""
    from mkdocs.structure.files import File

    for package in PACKAGES:
        for path, (module, items, at_door) in _pages(package).items():
            files.append(File.generated(config, path, content=_page(module, items, at_door)))
    return files


def on_page_markdown(markdown, **kwargs):
    """Replace ``<!-- moved names: simulator -->`` by the package's migration table and
    ``<!-- renamed names: simulator -->`` by its table of renamed names."""
    markdown = MIGRATION_MARK.sub(lambda m: migration_table(m.group(1)), markdown)
    return RENAMED_MARK.sub(lambda m: renamed_table(m.group(1)), markdown)


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
    """Make every public name of the doors and namespaces a griffe member (an alias to the
    object it stands for), as the lazy imports make it one at run time."""
    for package in PACKAGES:
        collection = loader.modules_collection
        owners = [(package, public_names(package))]
        owners += [(ns.module, namespace_names(ns)) for ns in namespaces(package)]
        for module, items in owners:
            owner = collection[package] if module == package else \
                _member(collection[package], module.split(".", 1)[1])
            for item in items:
                if item.target == f"{module}.{item.name}":
                    continue                        # the module's own object or submodule
                member = owner.members.get(item.name)
                if member is not None and member.is_alias:
                    continue                        # imported: griffe knows it
                if member is not None and member.kind.value == "module":
                    logger.warning("%s: the public name %r is also the name of a submodule",
                                   module, item.name)
                    continue
                owner.set_member(item.name, griffe.Alias(item.name, item.target, parent=owner))


def _rendered(loader) -> dict[str, str]:
    """Canonical path -> documented identifier of everything the API pages render (the door's
    entry where a name is also in a namespace)."""
    out = {}
    collection = loader.modules_collection
    for package in PACKAGES:
        for _, (module, items, at_door) in _pages(package).items():
            for item in items:
                if item.target in at_door or (item.is_module and module == package):
                    continue
                obj = _final(_member(collection[package], item.ident.split(".", 1)[1]))
                if obj is None:
                    logger.warning("%s: its target %s does not exist", item.ident, item.target)
                    continue
                _register(obj, item.ident, out)
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
