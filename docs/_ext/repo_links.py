"""Markdown links from a page to a file of the repository outside ``docs/``, on the site.

The pages are written for GitHub, where ``[the model](../analytic/model.py)`` opens the file; the
site holds only ``docs/``, so MyST would copy a source file as a download and warn on a Markdown
file (``../README.md``) or a directory. This transform (run as the pages are read, before MyST
resolves its links) renders each such link to a file or directory that exists as the file's
path from the repository's root, in code (``analytic/model.py``), as the pages write paths
elsewhere; with ``repo_source_url`` set (``-D repo_source_url=<base>``, the base under which the
repository's files are browsable, such as a forge's ``blob/<commit>/``) as a link to the file
there. A link to a path that does not exist is left to MyST, which warns: with ``-W`` a failed
build, as for a broken link between pages.
"""

from __future__ import annotations

from pathlib import Path, PurePosixPath
from typing import Any

from docutils import nodes
from sphinx import addnodes
from sphinx.application import Sphinx
from sphinx.transforms import SphinxTransform


def outside_target(node: nodes.Element, srcdir: Path, root: Path) -> Path | None:
    """The path a MyST link ``node`` points to when it is in ``root`` but not in ``srcdir``."""
    if node.get("reftype") != "myst":
        return None
    target = str(node.get("reftarget") or "")
    if node.get("refdomain") == "doc" and target.startswith("/"):
        # a link to a Markdown file: MyST gives its document name, the suffix removed
        candidates = [Path(target + suffix) for suffix in (".md", ".rst")]
    else:
        relative = target.partition("#")[0]
        page_dir = (srcdir / str(node.get("refdoc", ""))).parent
        candidates = [(page_dir / relative).resolve()]
    for path in candidates:
        path = path.resolve()
        if path.is_relative_to(root) and not path.is_relative_to(srcdir) and path.exists():
            return path
    return None


def rendered(node: nodes.Element, path: Path, root: Path, base_url: str | None) -> nodes.Node:
    """The link's text and the path from the repository's root (a link under ``base_url``)."""
    relative = PurePosixPath(path.relative_to(root).as_posix())
    shown = f"{relative}/" if path.is_dir() else str(relative)
    code = nodes.literal(shown, shown)
    text = node.astext().strip().strip("`")
    if base_url:
        fragment = node.get("reftargetid") or str(node.get("reftarget") or "").partition("#")[2]
        target = base_url.rstrip("/") + "/" + str(relative) + (f"#{fragment}" if fragment else "")
        if text in {shown, str(relative), path.name}:
            return nodes.reference("", "", code, refuri=target)
        return nodes.reference("", text, refuri=target)
    if text in {shown, str(relative), path.name}:
        return code
    return nodes.inline("", "", nodes.Text(f"{text} ("), code, nodes.Text(")"))


class RepoLinks(SphinxTransform):
    """Each MyST link to a repository file outside the source directory, as :func:`rendered`."""

    default_priority = 5  # after the parse, before MyST's reference resolver

    def apply(self, **kwargs: Any) -> None:
        srcdir = Path(self.env.srcdir).resolve()
        root = srcdir.parent
        base_url = self.config.repo_source_url
        links = list(
            self.document.findall(
                lambda n: isinstance(n, (addnodes.pending_xref, addnodes.download_reference))
            )
        )
        for node in links:
            path = outside_target(node, srcdir, root)
            if path is not None:
                node.replace_self(rendered(node, path, root, base_url))


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_config_value("repo_source_url", None, "html", types=frozenset({str, type(None)}))
    app.add_transform(RepoLinks)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
