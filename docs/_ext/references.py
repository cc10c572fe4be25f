"""Python cross-references: linked wherever the object is documented, refused when they name
nothing.

Sphinx links ``:class:`X``` only when ``X`` is the name an object was documented under. The
docstrings name objects where they are defined (``analytic.trajectory.Trajectory``), where they
are re-exported (``validation.assert_agree``) or relative to the module they stand in; and many
name internal modules, documented nowhere on purpose (``docs/api/index.rst``). For each reference
Sphinx could not link, this extension (the ``missing-reference`` event):

* imports what the reference names, trying the names a reader would (the current class's member,
  the current module's, the dotted name itself, a builtin);
* links it to the documented object that *is* that object (same identity), whatever name it was
  documented under;
* leaves it as plain code when the object exists but is not part of the public reference (an
  internal module, a third-party class: no inventories are fetched, the build needs no network);
* warns when no such object exists, with ``-W`` a failed build: a reference to a renamed or
  removed name is caught by the docs build.
"""

from __future__ import annotations

import builtins
import dataclasses
import importlib
import importlib.util
import inspect
from functools import cache
from typing import Any

from docutils import nodes
from sphinx.application import Sphinx
from sphinx.environment import BuildEnvironment
from sphinx.util import logging

LOGGER = logging.getLogger(__name__)
MISSING = object()
"""What :func:`resolve` gives for a dotted name that names nothing."""


@cache
def _module(name: str) -> Any:
    if name.rpartition(".")[2] == "__main__":  # a program: looked up, never run
        try:
            return importlib.util.find_spec(name) or MISSING
        except (ImportError, ValueError):
            return MISSING
    try:
        return importlib.import_module(name)
    except (ImportError, ValueError):  # ValueError: an empty name
        return MISSING


def _member(owner: Any, name: str) -> Any:
    """``owner.name``, or a declared but unset attribute of a class (a dataclass field without a
    default, an annotation, a slot) as :data:`True`, or :data:`MISSING`."""
    try:
        return getattr(owner, name)
    except AttributeError:
        pass
    if inspect.isclass(owner):
        if dataclasses.is_dataclass(owner) and name in {f.name for f in dataclasses.fields(owner)}:
            return True
        for klass in owner.__mro__:
            if name in vars(klass).get("__annotations__", {}) or name in getattr(
                klass, "__slots__", ()
            ):
                return True
    elif inspect.ismodule(owner) and name in vars(owner).get("__annotations__", {}):
        return True
    return MISSING


@cache
def resolve(dotted: str) -> Any:
    """The object ``dotted`` names (the longest importable module prefix, then attributes), or
    :data:`MISSING`."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        obj = _module(".".join(parts[:cut]))
        if obj is MISSING:
            continue
        for name in parts[cut:]:
            obj = _member(obj, name)
            if obj is MISSING:
                return MISSING
        return obj
    return MISSING


def candidates(
    target: str, module: str | None, klass: str | None, owner: str | None = None
) -> list[str]:
    """The dotted names a reference ``target`` written in ``module`` (and ``klass``) may mean;
    in the docstring of ``owner`` (its dotted name where it is defined), first the names of the
    scopes around it (its class, its module)."""
    target = target.removeprefix(".").removeprefix("~")
    names = []
    if owner:
        parts = owner.split(".")
        names.extend(f"{'.'.join(parts[:cut])}.{target}" for cut in range(len(parts), 0, -1))
    if module and klass:
        names.append(f"{module}.{klass}.{target}")
    if module:
        names.append(f"{module}.{target}")
    names.extend([target, f"builtins.{target}"])
    return names


def docstring_owner(node: nodes.Node) -> str | None:
    """The dotted name (where it is defined) of the object whose docstring holds ``node``:
    autodoc names each docstring's source ``<file>:docstring of <name>``."""
    while node is not None and not node.source:
        node = node.parent
    source = node.source if node is not None else None
    if source and ":docstring of " in source:
        return source.rpartition(":docstring of ")[2]
    return None


def inherited_scopes(owner: str) -> list[str]:
    """The scopes of an inherited docstring: a member of a class that has no docstring of its
    own shows its base's, written in the base's class and module."""
    klass = resolve(owner.rpartition(".")[0])
    if not inspect.isclass(klass):
        return []
    bases = klass.__mro__[1:]
    return [f"{b.__module__}.{b.__qualname__}" for b in bases] + [b.__module__ for b in bases]


_BY_IDENTITY: dict[int, str] = {}
"""``id(object) -> the name it is documented under``, built on the first unlinked reference of a
build (every page read by then) and emptied when a build starts (:func:`forget`): kept in this
process, never in Sphinx's pickled environment, where ids would outlive their objects."""


def forget(app: Sphinx) -> None:
    _BY_IDENTITY.clear()


def _documented_by_identity(env: BuildEnvironment) -> dict[int, str]:
    """:data:`_BY_IDENTITY`, built from every documented Python object that imports."""
    if not _BY_IDENTITY:
        for name in env.get_domain("py").objects:
            obj = resolve(name)
            if obj is not MISSING and not isinstance(obj, (bool, int, float, str, type(None))):
                _BY_IDENTITY.setdefault(id(obj), name)
    return _BY_IDENTITY


def on_missing_reference(
    app: Sphinx, env: BuildEnvironment, node: nodes.Element, contnode: nodes.Element
) -> nodes.Element | None:
    if node.get("refdomain") != "py":
        return None
    written = "refwarn" in node  # a role in a docstring or a page, not a signature's annotation
    target = node["reftarget"]
    module, klass = node.get("py:module"), node.get("py:class")
    domain = env.get_domain("py")
    owner = docstring_owner(node)
    tried = candidates(target, module, klass, owner)
    if owner:
        tried += [f"{scope}.{target}" for scope in inherited_scopes(owner)]
    for name in tried:
        obj = resolve(name)
        if obj is MISSING:
            continue
        documented = None
        if not isinstance(obj, (bool, int, float, str, type(None))):
            documented = _documented_by_identity(env).get(id(obj))
        else:  # a constant: the documented name of the same last part bound to it
            last = "." + name.rpartition(".")[2]
            documented = next(
                (d for d in domain.objects if d.endswith(last) and resolve(d) is obj), None
            )
        if documented is None and name in domain.objects:
            documented = name
        if documented is None:
            return None  # it exists, outside the public reference: plain code
        return domain.resolve_xref(
            env, node["refdoc"], app.builder, "obj", documented, node, contnode
        )
    if not written or builtins.__dict__.get(target) is not None:
        return None
    LOGGER.warning(
        "Python reference %r names nothing (tried %s)",
        target,
        ", ".join(tried),
        location=node,
        type="ref",
        subtype="python",
    )
    return None


def setup(app: Sphinx) -> dict[str, Any]:
    app.connect("builder-inited", forget)
    app.connect("missing-reference", on_missing_reference)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
