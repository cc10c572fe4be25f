"""The import graph of the four packages: every layer points down, and no module cycle.

Layers, lowest first (``docs/architecture.md``): ``analytic`` (the paper) < ``model_xml`` (the MJCF
twin) < ``mj_bridge`` (the engine plants) < ``validation`` (comparison, reports, CLI). A module may
import from its own layer or a lower one, never a higher one; and no set of modules may import each
other in a cycle (counting imports inside functions too: a lazy import hides a cycle from the
interpreter, not from a reader).

The graph is read from the source with :mod:`ast`; no module is imported, so the test needs none of
the engines and cannot be fooled by an import that fails. Every ``import`` and ``from ... import``
statement counts, wherever it stands (module level, inside a function, under ``TYPE_CHECKING``).
``from pkg import name`` is an edge to the module ``pkg.name`` when that module exists, else to
``pkg`` (its ``__init__``). A package importing its own submodules is not a cycle by itself: the
implicit import of a parent package by its submodule is not an edge.

Exceptions are named below with the reason and what must change; an entry that no longer matches
the code fails :func:`test_allow_lists_name_only_what_is_still_there`, so the list only shrinks.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

LAYERS = ("analytic", "model_xml", "mj_bridge", "validation")
"""The packages, lowest layer first."""

KNOWN_UPWARD: Mapping[tuple[str, str], str] = {}
"""Upward edges tolerated for now: ``(importer, imported) -> reason and what must change``.

Empty: the upward edges found when this test was written (``analytic.fast_bench`` importing
``validation.bench`` and ``model_xml``) were removed by moving that benchmark into ``validation``.
Add an entry only for an edge in a module someone else is restructuring, saying what must change.
"""

KNOWN_CYCLES: Mapping[frozenset[str], str] = {}
"""Import cycles tolerated for now: ``frozenset(modules) -> reason and what must change``.

Empty: the cycle ``validation.bench`` <-> ``validation.goals`` was broken by moving the chain scene
and the timing loop into ``validation.timing`` and dropping ``goals``' own command line.
"""


WINGS: tuple[tuple[str, ...], ...] = (
    ("runs",),  # how work is carried out and kept: output directories, atomic writes, workers
    ("compare",),  # differences, checks, thresholds, the referee
    ("scenes", "preflight"),  # a scene name resolved; a run's inputs checked, once
    ("report", "recording"),  # the evidence a run leaves
    ("validate", "external"),  # the jobs: N plants compared; another engine's file judged
    ("studies", "testing", "bench"),  # many runs; the pytest face; the speed goals
    ("cli", "commands", "__main__"),  # parse and dispatch; each command's options and handler
)
"""The wings of ``validation``, lowest first: a module may import from its own wing, from a wing
of its level or from a lower level, never from a higher one (``docs/architecture.md``). A wing is a
subpackage (``validation/compare/``) or a top-level module (``validation/cli.py``); the private
helpers ``_lazy`` and ``_version`` sit below every wing. The one exception is a ``__main__`` module
(``python -m validation.studies.sweep`` is ``tumble sweep``), which may import the command line."""

RUNTIME = "analytic.runtime"
"""The lowest layer of all, inside ``analytic``: how code is compiled, cached, locked and read
(numba plumbing, the disk cache and its check, compile locks, safe file reads, lazy imports), none
of it physics. It imports nothing of the rest of ``analytic`` (nor of a higher package), and every
module may import it; the physics (``analytic.kernel``, ``analytic.fast`` ...) does."""


@dataclass(frozen=True)
class Edge:
    """``importer`` imports ``imported`` at ``path:line``."""

    importer: str
    imported: str
    path: str
    line: int

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.importer} imports {self.imported}"


def discover(root: Path, packages: Iterable[str]) -> dict[str, Path]:
    """Dotted module name -> source file, for every ``.py`` file under each package directory."""
    modules: dict[str, Path] = {}
    for pkg in packages:
        for path in sorted((root / pkg).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            modules[".".join(parts)] = path
    return modules


def _owner(name: str, modules: Mapping[str, Path]) -> str | None:
    """The longest prefix of dotted ``name`` that is one of ``modules`` (None: outside them)."""
    parts = name.split(".")
    while parts:
        candidate = ".".join(parts)
        if candidate in modules:
            return candidate
        parts.pop()
    return None


def import_edges(root: Path, modules: Mapping[str, Path]) -> list[Edge]:
    """Every import from one of ``modules`` to another (self-imports dropped), in file order."""
    edges: list[Edge] = []
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:  # relative: resolved against the importing module's package
                    base = name.split(".") if is_package else name.split(".")[:-1]
                    base = base[: len(base) - (node.level - 1)]
                    source = ".".join([*base, *([node.module] if node.module else [])])
                else:
                    source = node.module or ""
                for alias in node.names:
                    sub = f"{source}.{alias.name}"
                    targets.append(sub if sub in modules else source)
            for target in targets:
                owner = _owner(target, modules)
                if owner is not None and owner != name:
                    rel = path.relative_to(root).as_posix()
                    edges.append(Edge(name, owner, rel, node.lineno))
    return sorted(set(edges), key=lambda e: (e.path, e.line, e.imported))


def layer_of(module: str) -> int:
    return LAYERS.index(module.split(".")[0])


def upward_edges(edges: Iterable[Edge]) -> list[Edge]:
    return [e for e in edges if layer_of(e.imported) > layer_of(e.importer)]


def cycles(edges: Iterable[Edge]) -> list[frozenset[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    graph: dict[str, set[str]] = {}
    for e in edges:
        graph.setdefault(e.importer, set()).add(e.imported)
        graph.setdefault(e.imported, set())
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[frozenset[str]] = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            v, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[v])
                if low[v] == index[v]:
                    component = set()
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.add(w)
                        if w == v:
                            break
                    if len(component) > 1:
                        found.append(frozenset(component))
    return found


def _describe_cycle(component: frozenset[str], edges: Iterable[Edge]) -> str:
    inside = [str(e) for e in edges if e.importer in component and e.imported in component]
    return f"{sorted(component)}:\n    " + "\n    ".join(inside)


@pytest.fixture(scope="module")
def graph() -> tuple[dict[str, Path], list[Edge]]:
    modules = discover(ROOT, LAYERS)
    return modules, import_edges(ROOT, modules)


def test_the_graph_sees_every_layer(graph):
    """Not vacuous: every package has modules, and edges known to exist are found (a module-level
    import, a ``from pkg import submodule`` inside a function, and one between layers)."""
    modules, edges = graph
    for pkg in LAYERS:
        assert pkg in modules, f"{pkg}/__init__.py not found under {ROOT}"
        assert any(m.startswith(pkg + ".") for m in modules), f"no modules found in {pkg}"
    pairs = {(e.importer, e.imported) for e in edges}
    assert ("analytic.model", "analytic.scene") in pairs
    assert ("validation.bench.goals", "analytic.fast") in pairs  # `from analytic import fast`, in a def
    assert ("validation.commands.bench", "validation.bench.command") in pairs
    assert ("analytic.fast", "analytic.kernel.layout") in pairs  # a subpackage is seen too
    assert any(layer_of(e.imported) < layer_of(e.importer) for e in edges)


def test_every_package_is_installed():
    """``[tool.setuptools] packages`` in pyproject.toml is an explicit list, so a subpackage
    missing from it (``analytic.kernel``) would be left out of an installed wheel: every directory
    of the layers with an ``__init__.py`` must be listed."""
    import tomllib

    listed = set(
        tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    )
    found = {
        ".".join(init.parent.relative_to(ROOT).parts)
        for pkg in LAYERS
        for init in (ROOT / pkg).rglob("__init__.py")
    }
    assert found <= listed, f"packages missing from pyproject.toml: {sorted(found - listed)}"


def test_no_module_imports_from_a_higher_layer(graph):
    _, edges = graph
    bad = [e for e in upward_edges(edges) if (e.importer, e.imported) not in KNOWN_UPWARD]
    assert not bad, (
        f"imports pointing up the layers {' < '.join(LAYERS)}:\n  "
        + "\n  ".join(map(str, bad))
        + "\nmove what is shared down into the lower layer, or the importer up"
    )


def test_no_import_cycles(graph):
    _, edges = graph
    bad = [c for c in cycles(edges) if c not in KNOWN_CYCLES]
    assert not bad, "import cycles between modules:\n  " + "\n  ".join(
        _describe_cycle(c, edges) for c in bad
    )


def test_allow_lists_name_only_what_is_still_there(graph):
    """An exception that the code no longer needs is removed from the list, so it only shrinks."""
    _, edges = graph
    up = {(e.importer, e.imported) for e in upward_edges(edges)}
    stale = [pair for pair in KNOWN_UPWARD if pair not in up]
    stale += [sorted(c) for c in KNOWN_CYCLES if c not in set(cycles(edges))]
    assert not stale, f"no longer in the code, remove from the allow-list: {stale}"


def in_package(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


def runtime_violations(edges: Iterable[Edge]) -> list[Edge]:
    """Imports from :data:`RUNTIME` of any module outside it."""
    return [
        e for e in edges if in_package(e.importer, RUNTIME) and not in_package(e.imported, RUNTIME)
    ]


def test_the_runtime_is_the_lowest_layer(graph):
    """``analytic.runtime`` imports nothing from the rest of ``analytic`` (:data:`RUNTIME`), and
    the physics imports it (not vacuous: the kernel's halves are compiled by it)."""
    modules, edges = graph
    assert RUNTIME in modules and any(m.startswith(RUNTIME + ".") for m in modules)
    bad = runtime_violations(edges)
    assert not bad, (
        f"{RUNTIME} is the lowest layer, yet imports:\n  "
        + "\n  ".join(map(str, bad))
        + f"\nmove what it needs down into {RUNTIME}, or pass it in"
    )
    assert any(
        in_package(e.importer, "analytic.kernel") and in_package(e.imported, RUNTIME) for e in edges
    )


def test_the_runtime_checker_finds_an_import_of_physics(tmp_path):
    """On a planted tree: the runtime importing the kernel (inside a function) is found; the
    kernel importing the runtime, and the runtime importing itself, are not."""
    files = {
        "analytic/__init__.py": "",
        "analytic/kernel/__init__.py": "",
        "analytic/kernel/layout.py": "from analytic.runtime import jit\n",
        "analytic/runtime/__init__.py": "",
        "analytic/runtime/jit.py": "from analytic.runtime import cache_dir\n",
        "analytic/runtime/cache_dir.py": "def f():\n    from analytic.kernel import layout\n",
    }
    for rel, text in files.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text)
    edges = import_edges(tmp_path, discover(tmp_path, ("analytic",)))
    assert [(e.importer, e.imported) for e in runtime_violations(edges)] == [
        ("analytic.runtime.cache_dir", "analytic.kernel.layout")
    ]


def wing_level(module: str) -> int | None:
    """The level of ``module``'s wing in :data:`WINGS`, or ``None`` outside ``validation``'s wings
    (another package, ``validation/__init__``, the private helpers)."""
    parts = module.split(".")
    if parts[0] != "validation" or len(parts) < 2 or parts[1] in ("_lazy", "_version"):
        return None
    for level, wings in enumerate(WINGS):
        if parts[1] in wings:
            return level
    raise AssertionError(f"{module}: its wing {parts[1]!r} is not in WINGS; place it there")


def wing_violations(edges: Iterable[Edge]) -> list[Edge]:
    out = []
    for e in edges:
        a, b = wing_level(e.importer), wing_level(e.imported)
        if a is None or b is None or b <= a:
            continue
        if e.importer.rsplit(".", 1)[-1] == "__main__" and e.imported == "validation.cli":
            continue
        out.append(e)
    return out


def test_validation_wings_point_down(graph):
    """Inside ``validation``, no wing imports from a higher one (:data:`WINGS`), and every module
    belongs to a declared wing."""
    modules, edges = graph
    for m in modules:
        wing_level(m)  # raises for a module outside every wing
    bad = wing_violations(edges)
    assert not bad, (
        "imports pointing up validation's wings "
        + " < ".join("/".join(w) for w in WINGS)
        + ":\n  "
        + "\n  ".join(map(str, bad))
    )


def test_the_wing_checker_finds_an_upward_import(tmp_path):
    """On a planted tree: ``compare`` importing ``report`` (up) is found; ``report`` importing
    ``compare`` (down) and a sweep's ``__main__`` importing the command line are not."""
    files = {
        "validation/__init__.py": "",
        "validation/cli.py": "",
        "validation/compare/__init__.py": "",
        "validation/compare/checks.py": "def f():\n    from validation.report import figures\n",
        "validation/report/__init__.py": "",
        "validation/report/figures.py": "from validation.compare import checks\n",
        "validation/studies/__init__.py": "",
        "validation/studies/sweep/__init__.py": "",
        "validation/studies/sweep/__main__.py": "from validation.cli import run\n",
    }
    for rel, text in files.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text)
    edges = import_edges(tmp_path, discover(tmp_path, ("validation",)))
    assert [(e.importer, e.imported) for e in wing_violations(edges)] == [
        ("validation.compare.checks", "validation.report.figures")
    ]


def test_every_test_file_sits_beside_its_module():
    """The test of ``x/y.py`` is ``tests/x/test_y.py`` (a package ``x/y/`` is tested by
    ``tests/x/test_y.py`` or under ``tests/x/y/``); suites spanning layers are in ``tests/cross/``,
    shared helpers in ``tests/support/``. Every test file under a package's mirror names a module
    or package that exists, so a newcomer finds a module's tests by its path."""
    tests = ROOT / "tests"
    orphans = []
    for path in sorted(tests.rglob("test_*.py")):
        rel = path.relative_to(tests)
        if rel.parts[0] in ("cross", "support"):
            continue
        assert rel.parts[0] in LAYERS, (
            f"tests/{rel}: not under a package's mirror, cross or support"
        )
        source = ROOT.joinpath(*rel.parts[:-1], rel.stem.removeprefix("test_"))
        if not (source.with_suffix(".py").is_file() or (source / "__init__.py").is_file()):
            orphans.append(f"tests/{rel}: no {source.relative_to(ROOT)}.py or package")
    for directory in sorted(p for p in tests.rglob("*") if p.is_dir() and p.name != "__pycache__"):
        rel = directory.relative_to(tests)
        if rel.parts[0] in ("cross", "support"):
            continue
        if not (ROOT / rel / "__init__.py").is_file():
            orphans.append(f"tests/{rel}/: mirrors no package {rel}/")
    assert not orphans, "\n".join(orphans)


def test_the_checker_finds_an_upward_import_and_a_cycle(tmp_path):
    """The functions above on a planted tree: an upward import inside a function, a relative
    import, a ``from pkg import submodule`` cycle; and nothing reported for a clean tree."""
    files = {
        "analytic/__init__.py": "from analytic.model import Model\n",
        "analytic/model.py": "def f():\n    from validation import report\n",
        "analytic/scene.py": "from . import model\n",
        "validation/__init__.py": "",
        "validation/report.py": "from validation import bench\n",
        "validation/bench.py": "import validation.report as r\nimport numpy\n",
    }
    for rel, text in files.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text)
    modules = discover(tmp_path, ("analytic", "validation"))
    edges = import_edges(tmp_path, modules)
    assert [(e.importer, e.imported, e.line) for e in upward_edges(edges)] == [
        ("analytic.model", "validation.report", 2)
    ]
    assert ("analytic.scene", "analytic.model") in {(e.importer, e.imported) for e in edges}
    assert cycles(edges) == [frozenset({"validation.bench", "validation.report"})]
    (tmp_path / "validation/bench.py").write_text("import numpy\n")
    (tmp_path / "analytic/model.py").write_text("from analytic import scene\n")
    (tmp_path / "analytic/scene.py").write_text("import numpy\n")
    clean = import_edges(tmp_path, discover(tmp_path, ("analytic", "validation")))
    assert ("analytic.model", "analytic.scene") in {(e.importer, e.imported) for e in clean}
    assert not upward_edges(clean)
    assert cycles(clean) == []
