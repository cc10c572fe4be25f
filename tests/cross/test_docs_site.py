"""The docs site's structure, without building it: every ``docs/*.md`` page is in a toctree, and
every module an API page names exists and is public.

The build itself (``python -m sphinx -W --keep-going -q -b html docs build/docs``, ~13 s of CPU) is a
CI step of its own; these checks catch, in milliseconds, a page added without a place in the
site and an API page left naming a module that was moved or renamed. The pages are read by the
build's own reader (``docs/_ext/public_api.py``); the named modules are not imported, their files
are looked up (as ``tests/cross/test_layers.py`` does).
"""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
API = DOCS / "api"


def _load_public_api():
    """``docs/_ext/public_api.py``, the build's reader of the API pages, loaded from its file
    (the docs' extensions are not a package, and the session's ``sys.path`` stays as it is)."""
    spec = importlib.util.spec_from_file_location("public_api", DOCS / "_ext" / "public_api.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_PUBLIC_API = _load_public_api()
DIRECTIVE, public_modules = _PUBLIC_API.DIRECTIVE, _PUBLIC_API.public_modules

NOT_PAGES = frozenset({"index.md"})
"""``docs/*.md`` files that are not pages of a toctree: the root page holds the toctrees."""

TOCTREE = re.compile(r"^```\{toctree\}\n(.*?)^```", re.MULTILINE | re.DOTALL)
RST_TOCTREE = re.compile(r"^\.\. toctree::\n((?:[ \t]+.*\n|\n)*)", re.MULTILINE)


def _md_toctree_entries(page: Path) -> list[str]:
    """The entries of the ```{toctree} blocks of a Markdown page (its option lines left out)."""
    entries = []
    for block in TOCTREE.findall(page.read_text(encoding="utf-8")):
        entries += [line.strip() for line in block.splitlines() if line.strip()]
    return [e for e in entries if not e.startswith(":")]


def _rst_toctree_entries(page: Path) -> list[str]:
    """The entries of the ``.. toctree::`` directives of a reStructuredText page."""
    entries = []
    for block in RST_TOCTREE.findall(page.read_text(encoding="utf-8")):
        entries += [line.strip() for line in block.splitlines() if line.strip()]
    return [e for e in entries if not e.startswith(":")]


def _module_file(name: str) -> Path | None:
    """The source file of the dotted module ``name`` in this checkout, or None."""
    base = ROOT.joinpath(*name.split("."))
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def test_every_page_is_in_the_root_toctree():
    """Each ``docs/*.md`` page is an entry of ``docs/index.md``'s toctrees (a page outside them
    is built but unreachable, and Sphinx warns), and every entry is a page that exists."""
    entries = _md_toctree_entries(DOCS / "index.md")
    pages = {p.stem for p in DOCS.glob("*.md") if p.name not in NOT_PAGES}
    assert not pages - set(entries), (
        f"not in docs/index.md's toctree: {sorted(pages - set(entries))}"
    )
    missing = [
        e for e in entries if not (DOCS / f"{e}.md").is_file() and not (DOCS / f"{e}.rst").is_file()
    ]
    assert not missing, f"docs/index.md lists pages that do not exist: {missing}"
    assert "api/index" in entries


def test_every_api_page_is_in_the_api_toctree_and_documents_one_module():
    """Each ``docs/api/*.rst`` page (but the index) is listed by ``docs/api/index.rst`` and is
    the page of exactly one module, named as the page is."""
    listed = set(_rst_toctree_entries(API / "index.rst"))
    pages = {p.stem for p in API.glob("*.rst") if p.name != "index.rst"}
    assert pages == listed, (
        f"pages not listed: {sorted(pages - listed)}; listed, no page: {sorted(listed - pages)}"
    )
    for stem in sorted(pages):
        named = DIRECTIVE.findall((API / f"{stem}.rst").read_text(encoding="utf-8"))
        assert named == [stem], f"docs/api/{stem}.rst documents {named}, expected [{stem!r}]"


def test_every_module_an_api_page_names_exists_and_is_public():
    """Every module named on an API page is a module of this checkout, no part of its name
    private (``_x``), and each is named once; the public API has the packages' faces."""
    modules = public_modules()
    assert len(modules) == len(set(modules)), "a module is documented on two pages"
    absent = [m for m in modules if _module_file(m) is None]
    assert not absent, f"API pages name modules that do not exist: {absent}"
    private = [m for m in modules if any(part.startswith("_") for part in m.split("."))]
    assert not private, f"API pages document private modules: {private}"
    assert {"analytic", "mj_bridge", "model_xml", "validation"} <= set(modules)


@pytest.mark.parametrize("text", [".. publicmodule:: analytic.scene\n", ".. automodule:: x.y\n"])
def test_the_page_reader_finds_a_module_line(text, tmp_path):
    """:func:`public_modules` reads both directives, one module per line, from a planted page."""
    (tmp_path / "a.rst").write_text(f"Title\n=====\n\n{text}")
    assert public_modules(tmp_path) == [text.split()[-1]]


def test_a_reference_that_names_nothing_fails_the_build(tmp_path, monkeypatch):
    """The ``references`` extension on a planted site: a reference to a name that does not exist
    is a warning (so ``-W`` fails the build); one to an object that exists but is not documented
    stays plain code, silently; one written by the object's defining path links to where it is
    documented under a re-exported name."""
    from sphinx.cmd.build import build_main

    monkeypatch.setattr(sys, "path", list(sys.path))  # the planted conf.py prepends to it
    src = tmp_path / "src"
    (src / "planted_pkg").mkdir(parents=True)
    (src / "planted_pkg" / "__init__.py").write_text(
        '"""Face."""\nfrom planted_pkg.inner import thing\n__all__ = ["thing"]\n'
    )
    (src / "planted_pkg" / "inner.py").write_text('def thing():\n    """A thing."""\n')
    (src / "conf.py").write_text(
        "import sys\n"
        f"sys.path[:0] = [{str(src)!r}, {str(DOCS / '_ext')!r}]\n"
        'extensions = ["sphinx.ext.autodoc", "references"]\n'
    )
    (src / "index.rst").write_text(
        "T\n=\n\n.. automodule:: planted_pkg\n   :members:\n\n"
        ":func:`planted_pkg.inner.thing` :func:`os.path.join` :func:`planted_pkg.inner.gone`\n"
    )
    warnings = tmp_path / "warnings.txt"
    out = tmp_path / "out"
    try:
        status = build_main(["-q", "-b", "html", "-w", str(warnings), str(src), str(out)])
    finally:
        for name in ("planted_pkg", "planted_pkg.inner"):
            sys.modules.pop(name, None)
    assert status == 0
    lines = warnings.read_text().splitlines()
    assert len(lines) == 1 and "'planted_pkg.inner.gone' names nothing" in lines[0], lines
    page = (out / "index.html").read_text()
    assert 'href="#planted_pkg.thing"' in page  # the defining path, linked to the re-export


@pytest.mark.filterwarnings(
    # myst-parser 5.2's own use of a Sphinx API deprecated for Sphinx 11, not this project's
    "ignore:.*myst_refs.MystReferenceResolver.app' is deprecated"
)
def test_a_link_to_a_repository_file_is_its_path_and_a_broken_one_fails(tmp_path, monkeypatch):
    """The ``repo_links`` extension on a planted site (``docs/`` in a repository): a page's
    Markdown links to a file, a Markdown file and a directory outside ``docs/`` are shown as their
    paths from the root (or linked under ``repo_source_url``); a link to a path that does not
    exist stays MyST's warning."""
    from sphinx.cmd.build import build_main

    monkeypatch.setattr(sys, "path", list(sys.path))
    repo = tmp_path / "repo"
    (repo / "docs").mkdir(parents=True)
    (repo / "pkg").mkdir()
    (repo / "pkg" / "mod.py").write_text("")
    (repo / "NOTES.md").write_text("# Notes\n")
    (repo / "docs" / "conf.py").write_text(
        f"import sys\nsys.path.insert(0, {str(DOCS / '_ext')!r})\n"
        'extensions = ["myst_parser", "repo_links"]\n'
    )
    page = (
        "# Page\n\n[the module](../pkg/mod.py), [`NOTES.md`](../NOTES.md#notes), [a dir](../pkg/)\n"
    )
    (repo / "docs" / "index.md").write_text(page)
    warnings, out = tmp_path / "w.txt", tmp_path / "out"
    assert build_main(["-q", "-b", "html", "-w", str(warnings), str(repo / "docs"), str(out)]) == 0
    assert warnings.read_text() == ""
    html = (out / "index.html").read_text()
    for path in ("pkg/mod.py", "NOTES.md", "pkg/"):
        assert f'<span class="pre">{path}</span></code>' in html
    assert "_downloads" not in html
    linked = tmp_path / "linked"
    args = ["-q", "-b", "html", "-D", "repo_source_url=https://example.invalid/blob/c0ffee/"]
    assert build_main([*args, str(repo / "docs"), str(linked)]) == 0
    assert (
        'href="https://example.invalid/blob/c0ffee/NOTES.md#notes"'
        in (linked / "index.html").read_text()
    )
    (repo / "docs" / "index.md").write_text(page + "\n[gone](../pkg/gone.py)\n")
    assert (
        build_main(["-q", "-E", "-b", "html", "-w", str(warnings), str(repo / "docs"), str(out)])
        == 0
    )
    assert "'../pkg/gone.py'" in warnings.read_text()
