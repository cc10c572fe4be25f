"""The ``publicmodule`` directive: a public module's page, each object documented once.

``.. publicmodule:: analytic.scene`` is ``automodule`` with ``:members:`` (the module's
``__all__``, or what it defines), less the names that a deeper public module (one whose page is
in ``docs/api/`` too, ``analytic.scene`` below ``analytic``) exports as the same object: a name
re-exported up the package tree is documented where it is most specific and listed (in the
package's docstring) where it is re-exported, so no object is described twice and every short
reference has one target.

:func:`public_modules` reads the list of public modules from the pages themselves (one
``publicmodule`` line each): the pages are the one statement of the public API
(``docs/api/index.rst``), and ``tests/cross/test_docs_site.py`` checks each named module exists.
"""

from __future__ import annotations

import importlib
import re
from pathlib import Path
from types import ModuleType
from typing import Any, ClassVar

from docutils.parsers.rst import directives
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective

API_DIR = Path(__file__).resolve().parent.parent / "api"
DIRECTIVE = re.compile(r"^\.\. (?:publicmodule|automodule):: (\S+)\s*$", re.MULTILINE)
"""A page's module: ``publicmodule`` (its members), or ``automodule`` alone (its docstring: the
pytest plugin, whose interface is its options and items, not functions to call)."""
PROJECT_PACKAGES = frozenset({"analytic", "model_xml", "mj_bridge", "validation"})


def public_modules(api_dir: Path = API_DIR) -> list[str]:
    """Every module a page of ``api_dir`` documents, sorted by page file name."""
    return [
        name
        for page in sorted(api_dir.glob("*.rst"))
        for name in DIRECTIVE.findall(page.read_text(encoding="utf-8"))
    ]


def exported(module: ModuleType) -> dict[str, Any]:
    """The names ``module`` exports and their objects: its ``__all__``, or else the public
    names it defines itself (an object whose ``__module__`` is the module)."""
    names = getattr(module, "__all__", None)
    if names is not None:
        return {name: getattr(module, name) for name in names}
    return {
        name: value
        for name, value in vars(module).items()
        if not name.startswith("_") and getattr(value, "__module__", None) == module.__name__
    }


def documented_deeper(name: str, modules: list[str]) -> list[str]:
    """The names of module ``name`` that a deeper public module of ``modules`` exports as the
    same object under the same name, sorted."""
    module = importlib.import_module(name)
    deeper = [
        exported(importlib.import_module(other))
        for other in modules
        if other.startswith(name + ".")
    ]
    return sorted(
        member
        for member, value in exported(module).items()
        if any(member in table and table[member] is value for table in deeper)
    )


class PublicModule(SphinxDirective):
    """``automodule NAME :members:`` less the members documented on a deeper public page, and
    less those its ``:exclude-members:`` option names (an object two sibling modules export:
    documented on one page, excluded, with the reason beside it, on the other)."""

    required_arguments = 1
    option_spec: ClassVar[dict[str, Any]] = {"exclude-members": directives.unchanged_required}

    def run(self) -> list[Any]:
        name = self.arguments[0]
        lines = [f".. automodule:: {name}", "   :members:"]
        given = [m.strip() for m in self.options.get("exclude-members", "").split(",")]
        skipped = sorted({*documented_deeper(name, public_modules()), *filter(None, given)})
        if skipped:
            lines.append(f"   :exclude-members: {', '.join(skipped)}")
        return self.parse_text_to_nodes("\n".join(lines))


def _class_of(dotted: str) -> type | None:
    """The class ``dotted`` names (a module path, then the class's qualified name), or None."""
    parts = dotted.split(".")
    for cut in range(len(parts) - 1, 0, -1):
        try:
            obj: Any = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for name in parts[cut:]:
            obj = getattr(obj, name, None)
        return obj if isinstance(obj, type) else None
    return None


def docstring_source(full_name: str) -> type | None:
    """The class whose docstring ``help()`` shows for the class member ``full_name`` that has
    none of its own (the first base, in MRO order, defining it with one), else None."""
    owner, _, member = full_name.rpartition(".")
    klass = _class_of(owner) if owner else None
    if klass is None:
        return None
    own = klass.__dict__.get(member)
    if own is None or getattr(own, "__doc__", None):
        return None
    for base in klass.__mro__[1:]:
        if getattr(base.__dict__.get(member), "__doc__", None):
            return base
    return None


def drop_foreign_docstrings(
    app: Sphinx, what: str, name: str, obj: Any, options: Any, lines: list[str]
) -> None:
    """A member without a docstring of its own is shown without one when the docstring it
    would inherit is another project's (pytest's, the standard library's): that text is written
    for their site (their labels, their markup), and says nothing of this project's contract.
    A docstring inherited from a class of this project is kept (a plugin's ``describe``)."""
    if what not in {"method", "property", "attribute", "classmethod", "staticmethod"}:
        return
    base = docstring_source(name)
    if base is not None and base.__module__.partition(".")[0] not in PROJECT_PACKAGES:
        lines.clear()


def api_pages_outdated(
    app: Sphinx, env: Any, added: set[str], changed: set[str], removed: set[str]
) -> list[str]:
    """Every API page, when one is added, changed or removed: what a page leaves out depends
    on which modules the others document (an incremental build would keep a stale choice)."""
    api = sorted(doc for doc in env.found_docs if doc.startswith("api/"))
    return api if any(doc.startswith("api/") for doc in added | changed | removed) else []


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("publicmodule", PublicModule)
    app.connect("env-get-outdated", api_pages_outdated)
    app.connect("autodoc-process-docstring", drop_foreign_docstrings)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
