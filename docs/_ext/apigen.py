"""Write the API reference's pages from the packages' ``__all__`` (run by ``docs/conf.py``).

Every public module of motosim (no path component starting with ``_``) gets one page. A name
is documented once, on the page of the shortest public path that exports it: the names of a
package's ``__all__`` on the package's page, the other names of a module's ``__all__`` on the
module's page. Each page opens with the module's docstring and a summary table (autosummary),
followed by the entries (autodoc, through numpydoc). ``tests/unit/test_docs.py`` checks that
every name of every ``__all__`` is on a page, without Sphinx.
"""

import functools
import importlib
import inspect
import pkgutil
from pathlib import Path
from types import ModuleType

PACKAGE = "motosim"


def public_modules() -> list[str]:
    """Names of the public modules and packages of motosim, in import order of the layers."""
    root = importlib.import_module(PACKAGE)
    names = [PACKAGE]
    for info in pkgutil.walk_packages(root.__path__, prefix=f"{PACKAGE}."):
        parts = info.name.split(".")
        if any(part.startswith("_") for part in parts):
            continue
        names.append(info.name)
    return sorted(names)


def exported(module: ModuleType) -> list[str]:
    """The names a module declares public (its ``__all__``)."""
    return list(getattr(module, "__all__", []))


@functools.cache
def homes() -> dict[tuple[str, str], str]:
    """(module, name) of every ``__all__`` entry -> the module whose page documents it.

    The home of an object is the public module exporting it under the same name whose path
    is a prefix of the object's defining module (for classes and functions), else the
    shortest such path (alphabetical among equals).
    """
    exporters: dict[tuple[str, int], list[str]] = {}
    for name in public_modules():
        module = importlib.import_module(name)
        for item in exported(module):
            exporters.setdefault((item, id(getattr(module, item))), []).append(name)
    out = {}
    for (item, _), names in exporters.items():
        obj = getattr(importlib.import_module(names[0]), item)
        origin = getattr(obj, "__module__", None) if callable(obj) else None
        ranked = sorted(
            names,
            key=lambda n: (
                not (isinstance(origin, str) and (origin + ".").startswith(n + ".")),
                n.count("."),
                n,
            ),
        )
        for name in names:
            out[(name, item)] = ranked[0]
    return out


def page_names(name: str) -> list[str]:
    """The names documented on the page of module ``name`` (those whose home it is)."""
    module = importlib.import_module(name)
    return [item for item in exported(module) if homes()[(name, item)] == name]


def _directive(obj: object) -> str:
    if inspect.isclass(obj):
        return "autoexception" if issubclass(obj, BaseException) else "autoclass"
    if callable(obj) and not isinstance(obj, type):
        return "autofunction"
    return "autodata"


def _title(text: str, mark: str) -> str:
    return f"{text}\n{mark * len(text)}\n"


def module_page(name: str) -> str:
    """The reStructuredText of module ``name``'s page."""
    module = importlib.import_module(name)
    names = page_names(name)
    lines = [_title(f"``{name}``", "="), f".. automodule:: {name}", "   :no-members:"]
    parent_name, _, last = name.rpartition(".")
    if parent_name and getattr(importlib.import_module(parent_name), last) is not module:
        lines.append("   :no-index:")  # the package exports a function of the same name
    lines.append("")
    if names:
        lines += [".. currentmodule:: " + name, "", ".. autosummary::", ""]
        lines += [f"   {item}" for item in names]
        lines.append("")
    moved = [item for item in exported(module) if item not in names]
    if moved:
        links = ", ".join(f":obj:`{homes()[(name, item)]}.{item}`" for item in moved)
        lines += [f"Also exported here (documented where they are defined): {links}.", ""]
    for item in names:
        directive = _directive(getattr(module, item))
        lines.append(f".. {directive}:: {name}.{item}")
        if directive == "autoclass":
            lines.append("   :members:")
        elif directive == "autodata":
            lines.append("   :no-value:")
        lines.append("")
    subs = [sub for sub in public_modules() if sub.rpartition(".")[0] == name]
    if subs:
        lines += [".. rubric:: Modules", "", ".. toctree::", "   :maxdepth: 1", ""]
        lines += [f"   {sub}" for sub in subs]
        lines.append("")
    return "\n".join(lines)


def documented(pages: dict[str, str]) -> set[str]:
    """The full names documented by autodoc directives on the given pages."""
    found = set()
    for text in pages.values():
        for line in text.splitlines():
            if line.startswith(".. auto") and "::" in line and "automodule" not in line:
                found.add(line.split("::", 1)[1].strip())
    return found


def pages() -> dict[str, str]:
    """Every page of the API reference: file name (without suffix) -> reStructuredText."""
    out = {name: module_page(name) for name in public_modules()}
    top = [
        _title("API reference", "="),
        "Generated from the docstrings: one page per public module, each public name (those in",
        "a module's ``__all__``) documented once, under the shortest public path that exports",
        "it. Start with the package of the layer you work in (see :doc:`../organisation`).",
        "",
        ".. toctree::",
        "   :maxdepth: 2",
        "",
        f"   {PACKAGE}",
    ]
    out["index"] = "\n".join(top) + "\n"
    return out


def write(folder: Path) -> None:
    """Write the pages into ``folder`` (rewriting only those that changed)."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in pages().items():
        path = folder / f"{name}.rst"
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")


def data_names() -> list[str]:
    """Full names of the documented data (constants, tables, type aliases), not callables.

    numpydoc's validation reads the docstring of a value's type (a dict's, a tuple's), not
    the attribute docstring autodoc shows, so ``docs/conf.py`` excludes these from it.
    """
    out = []
    for name in public_modules():
        module = importlib.import_module(name)
        for item in page_names(name):
            if _directive(getattr(module, item)) == "autodata":
                out.append(f"{name}.{item}")
    return out
