"""What every HTML report must be, checked with the standard library's :mod:`html.parser`:
well-formed (every element closed, in order), no resource from anywhere but itself (no
``src``/``href``/``srcset``/``poster``/``action``/``data`` with a scheme or a host other than a
``data:`` image, no ``url()`` or ``@import`` in its style), the verdict before the checks, and its
tables' cells as text (entities decoded: what a reader sees).

:func:`open_in_chromium` opens a page in headless Chromium (Debian's ``chromium``) with no network
and returns the DOM after its script ran, writing a screenshot when asked.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path

VOID = frozenset("area base br col embed hr img input link meta param source track wbr".split())
RESOURCE_ATTRS = frozenset({"src", "href", "srcset", "poster", "action", "data", "formaction"})
SCHEME = re.compile(r"^\s*([a-zA-Z][a-zA-Z0-9+.-]*):")


@dataclass
class Element:
    tag: str
    attrs: dict[str, str]
    children: list[Element | str] = field(default_factory=list)

    def text(self) -> str:
        return "".join(c if isinstance(c, str) else c.text() for c in self.children)

    def iter(self):
        yield self
        for c in self.children:
            if isinstance(c, Element):
                yield from c.iter()

    def find(self, tag: str | None = None, **attrs: str) -> list[Element]:
        return [
            e
            for e in self.iter()
            if (tag is None or e.tag == tag) and all(e.attrs.get(k) == v for k, v in attrs.items())
        ]


class _Builder(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.root = Element("#document", {})
        self.stack = [self.root]
        self.errors: list[str] = []
        self.doctype = ""

    def handle_decl(self, decl: str) -> None:
        self.doctype = decl

    def handle_starttag(self, tag, attrs):
        e = Element(tag, {k: (v or "") for k, v in attrs})
        self.stack[-1].children.append(e)
        if tag not in VOID:
            self.stack.append(e)

    def handle_startendtag(self, tag, attrs):
        self.stack[-1].children.append(Element(tag, {k: (v or "") for k, v in attrs}))

    def handle_endtag(self, tag):
        if tag in VOID:
            return
        if len(self.stack) < 2 or self.stack[-1].tag != tag:
            self.errors.append(f"</{tag}> closes <{self.stack[-1].tag}>")
            return
        self.stack.pop()

    def handle_data(self, data):
        self.stack[-1].children.append(data)


def parse(markup: str) -> Element:
    """The document tree; AssertionError when it is not well-formed."""
    b = _Builder()
    b.feed(markup)
    b.close()
    assert b.doctype.lower() == "doctype html", f"no <!DOCTYPE html> (got {b.doctype!r})"
    assert not b.errors, b.errors
    assert len(b.stack) == 1, f"unclosed: {[e.tag for e in b.stack[1:]]}"
    return b.root


def external_references(doc: Element) -> list[str]:
    """Every reference to a resource outside the page: an attribute naming a URL with a scheme
    (``data:`` only allowed as an image's ``src``) or a host (``//host``), a ``url(`` or
    ``@import`` in a style. A relative link (``run.rrd``) is not one."""
    out = []
    for e in doc.iter():
        for k, v in e.attrs.items():
            if k not in RESOURCE_ATTRS and k != "style":
                continue
            if k == "style":
                if "url(" in v.lower():
                    out.append(f"<{e.tag} style={v!r}>")
                continue
            m = SCHEME.match(v)
            if v.strip().startswith("//") or (
                m and not (m.group(1).lower() == "data" and e.tag == "img" and k == "src")
            ):
                out.append(f"<{e.tag} {k}={v[:80]!r}>")
        if e.tag == "link" or (e.tag == "script" and "src" in e.attrs):
            out.append(f"<{e.tag} {e.attrs}>")
        if e.tag == "style" and re.search(r"url\(|@import", e.text(), re.I):
            out.append("<style> with url() or @import")
    return out


def rows(doc: Element, table_id: str) -> list[list[str]]:
    """The body rows of the table ``table_id``, each cell's text."""
    [t] = doc.find("table", id=table_id)
    [body] = t.find("tbody")
    return [[td.text() for td in tr.find("td")] for tr in body.find("tr")]


def headers(doc: Element, table_id: str) -> list[str]:
    [t] = doc.find("table", id=table_id)
    return [th.text() for th in t.find("th")]


def order_of(doc: Element, *ids: str) -> list[int]:
    """The position in document order of each element ``id``."""
    where = {e.attrs.get("id"): i for i, e in enumerate(doc.iter()) if "id" in e.attrs}
    return [where[i] for i in ids]


def assert_report_page(markup: str, first: str = "verdict") -> Element:
    """The checks every report page passes: well-formed, self-contained, one ``<h1>``, the
    verdict banner (``#verdict``) before every table. Returns the tree."""
    doc = parse(markup)
    assert external_references(doc) == []
    assert len(doc.find("h1")) == 1
    [csp] = doc.find("meta", **{"http-equiv": "Content-Security-Policy"})
    assert "default-src 'none'" in csp.attrs["content"]
    ids = [e.attrs["id"] for e in doc.iter() if "id" in e.attrs]
    assert len(ids) == len(set(ids)), "an id used twice"
    banner = order_of(doc, first)[0]
    for t in doc.find("table"):
        assert order_of(doc, t.attrs["id"])[0] > banner, f"table {t.attrs['id']} before the verdict"
    return doc


CHROMIUM_FLAGS = (
    "--headless=new",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-dev-shm-usage",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--disable-extensions",
    "--proxy-server=127.0.0.1:9",  # any request that did go out would fail, not reach a network
)


def chromium() -> str | None:
    return shutil.which("chromium") or shutil.which("chromium-browser")


def open_in_chromium(
    page: Path, fragment: str = "", screenshot: Path | None = None, size=(1280, 1600)
) -> str:
    """The DOM of ``page`` (a file) after its script ran in headless Chromium, the URL fragment
    ``fragment`` given; a PNG screenshot into ``screenshot`` when asked."""
    exe = chromium()
    assert exe is not None
    url = page.resolve().as_uri() + (f"#{fragment}" if fragment else "")
    with tempfile.TemporaryDirectory(prefix="tumble-chromium-") as profile:
        base = [exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}"]
        dom = subprocess.run(
            [*base, "--dump-dom", url], capture_output=True, text=True, timeout=120, check=True
        ).stdout
        if screenshot is not None:
            subprocess.run(
                [*base, f"--window-size={size[0]},{size[1]}", f"--screenshot={screenshot}", url],
                capture_output=True,
                timeout=120,
                check=True,
                cwd=profile,
            )
    return dom
