"""The pieces every HTML report is made of: one self-contained page (:func:`page`), its verdict
banner first (:class:`Banner`), sortable tables (:func:`table` of :class:`Cell`), embedded figures
(:func:`figure`) and the link to a recording (:func:`recording`).

Contract:

* **Self-contained, no network.** The style and the sorting script are inline; a figure is a
  ``data:`` URI of its bytes (PNG or SVG); nothing is loaded from anywhere. The page's
  Content-Security-Policy says so to the browser too (``default-src 'none'``; only ``data:``
  images and the page's own style and script, by their SHA-256), so a reference to the network
  slipped in by mistake is refused, not fetched. Links (``<a href>``) are only ever relative
  (the recording, a counterexample beside the report).
* **Every value is text.** Whatever a scene file or an error message brings is escaped with
  :func:`html.escape` where it is placed (:func:`esc`); a :class:`Cell`'s ``text`` is escaped when
  rendered; only the markup built here (:attr:`Cell.markup`, :func:`raw`) is passed through.
* **Sorting.** A click on a header of a ``sortable`` table sorts its rows by that column (again:
  the other way); a numeric column sorts by each cell's ``data-v`` (the exact value; a missing
  or NaN value last), shown readably (:func:`readable`, the exact value in its tooltip). The URL
  fragment ``#sort=TABLE.COLUMN.asc`` (or ``.desc``) sorts a table when the page opens; the
  script marks ``<body data-js="ready">`` when it has run.
"""

from __future__ import annotations

import base64
import hashlib
import html
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

STYLE = """
body{font:15px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0 auto;
max-width:1280px;padding:0 1.2em 3em;color:#1d1d1f;background:#fff}
h1{font-size:1.6em;margin:.6em 0 .2em}h2{font-size:1.25em;margin:1.6em 0 .4em;
border-bottom:1px solid #ddd}h3{font-size:1.05em;margin:1.2em 0 .3em}
.banner{border-radius:6px;padding:.8em 1.1em;margin:.8em 0 1.2em;border:2px solid}
.banner .word{font-size:2em;font-weight:700;letter-spacing:.04em}
.banner.pass{background:#e9f7ec;border-color:#2e8540}.banner.pass .word{color:#1e6b30}
.banner.fail{background:#fdecea;border-color:#c62828}.banner.fail .word{color:#b71c1c}
.banner.stop{background:#fff6e0;border-color:#c77c00}.banner.stop .word{color:#8a5600}
.banner p{margin:.3em 0}.banner ul{margin:.3em 0 .2em 1.2em;padding:0}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:.92em}
th,td{border:1px solid #d6d6d6;padding:.25em .55em;text-align:left;vertical-align:top}
th{background:#f3f3f3;position:sticky;top:0}
table.sortable th{cursor:pointer;user-select:none}
table.sortable th::after{content:" \\2195";color:#aaa}
table.sortable th[aria-sort=ascending]::after{content:" \\2191";color:#333}
table.sortable th[aria-sort=descending]::after{content:" \\2193";color:#333}
td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
tr.pass td.state,td.pass{background:#e9f7ec;color:#1e6b30;font-weight:600}
tr.fail td{background:#fdecea}tr.fail td.state,td.fail{color:#b71c1c;font-weight:700}
tr.idle td,td.idle{color:#777}
td{max-width:42em;overflow-wrap:break-word}
.details li{margin:.4em 0}.details code{overflow-wrap:anywhere}
details{margin:.4em 0 1em}summary{cursor:pointer;color:#333}
code,pre{font:.9em ui-monospace,SFMono-Regular,Menlo,Consolas,monospace;background:#f5f5f5}
code{padding:0 .25em;border-radius:3px}pre{padding:.7em;overflow:auto;border-radius:4px}
figure{margin:1em 0 1.6em}figure img{max-width:100%;border:1px solid #e3e3e3}
figcaption{font-size:.9em;color:#444;max-width:75em}.note{color:#555}
.recording{background:#f4f7fb;border:1px solid #cbd7e6;border-radius:6px;padding:.5em 1em}
"""
"""The page's style (inline; system fonts only)."""

SCRIPT = """
(function(){
function key(td,num){var v=td.getAttribute("data-v");if(v===null)v=td.textContent;
if(!num)return v.toLowerCase();var x=parseFloat(v);return isNaN(x)?null:x;}
function sortBy(th,dir){var table=th.closest("table"),body=table.tBodies[0];
var i=Array.prototype.indexOf.call(th.parentNode.children,th),num=th.getAttribute("data-type")==="num";
var rows=Array.prototype.slice.call(body.rows);
rows.sort(function(a,b){var x=key(a.cells[i],num),y=key(b.cells[i],num);
if(x===null||y===null)return (x===null)-(y===null);return dir*(x<y?-1:x>y?1:0);});
rows.forEach(function(r){body.appendChild(r);});
Array.prototype.forEach.call(th.parentNode.children,function(h){h.removeAttribute("aria-sort");});
th.setAttribute("aria-sort",dir>0?"ascending":"descending");}
var heads=document.querySelectorAll("table.sortable thead th");
Array.prototype.forEach.call(heads,function(th){th.tabIndex=0;
function go(){sortBy(th,th.getAttribute("aria-sort")==="ascending"?-1:1);}
th.addEventListener("click",go);
th.addEventListener("keydown",function(e){if(e.key==="Enter"||e.key===" "){e.preventDefault();go();}});});
var m=/^#sort=([\\w-]+)\\.(\\d+)\\.(asc|desc)$/.exec(location.hash);
if(m){var t=document.getElementById(m[1]);var th=t&&t.tHead&&t.tHead.rows[0].cells[+m[2]];
if(th)sortBy(th,m[3]==="asc"?1:-1);}
document.body.setAttribute("data-js","ready");
})();
"""
"""The sorting script (inline, no library; module docstring)."""


def _csp_hash(text: str) -> str:
    return (
        "'sha256-" + base64.b64encode(hashlib.sha256(text.encode("utf-8")).digest()).decode() + "'"
    )


CSP = (
    f"default-src 'none'; img-src data:; style-src {_csp_hash(STYLE)}; "
    f"script-src {_csp_hash(SCRIPT)}; base-uri 'none'; form-action 'none'"
)
"""The page's Content-Security-Policy: nothing from the network, only its own style and script."""


def esc(value: Any) -> str:
    """``value`` as HTML text (:func:`html.escape`, quotes included: safe in an attribute)."""
    return html.escape(str(value), quote=True)


def readable(x: Any, digits: int = 2) -> str:
    """A number as a reader takes it in: ``2.6e-13``, ``0.0123``, ``42``, ``0``, ``–`` (none or
    NaN), ``∞``; anything else as its text. ``digits`` significant digits."""
    if x is None or isinstance(x, bool):
        return "–" if x is None else ("yes" if x else "no")
    if not isinstance(x, int | float):
        return str(x)
    x = float(x)
    if math.isnan(x):
        return "–"
    if math.isinf(x):
        return "∞" if x > 0 else "−∞"
    if x == 0:
        return "0"
    if x.is_integer() and abs(x) < 1e6:
        return str(int(x))
    if 1e-2 <= abs(x) < 1e4:  # fixed point, three significant digits (1234 whole)
        return f"{x:.{max(0, 2 - math.floor(math.log10(abs(x))))}f}"
    return f"{x:.{digits - 1}e}"


class Tone(StrEnum):
    """The colour of a verdict: passed, failed, stopped part way (interrupted, incomplete), or
    nothing to judge."""

    PASS = "pass"
    FAIL = "fail"
    STOP = "stop"
    IDLE = "idle"


@dataclass(frozen=True)
class Cell:
    """One table cell: ``text`` (escaped when rendered, unless ``markup``), the sort key ``key``
    (a number for a numeric column; None: the text), a CSS class and a tooltip."""

    text: str
    key: float | str | None = None
    css: str = ""
    title: str = ""
    markup: bool = False

    def render(self) -> str:
        attrs = ""
        if self.css:
            attrs += f' class="{esc(self.css)}"'
        if self.key is not None:
            k = self.key
            if isinstance(k, float) and not math.isfinite(k):
                k = "nan" if math.isnan(k) else ("Infinity" if k > 0 else "-Infinity")
            attrs += f' data-v="{esc(k)}"'
        if self.title:
            attrs += f' title="{esc(self.title)}"'
        body = self.text if self.markup else esc(self.text)
        return f"<td{attrs}>{body}</td>"


def text(value: Any, css: str = "") -> Cell:
    """A cell of text (escaped)."""
    return Cell(str(value), css=css)


def num(x: Any, unit: str = "", digits: int = 2, css: str = "") -> Cell:
    """A numeric cell: shown by :func:`readable`, sorted by its exact value, which its tooltip
    gives (with ``unit``)."""
    if x is None or isinstance(x, bool) or not isinstance(x, int | float):
        return Cell(readable(x), key=math.nan, css=f"num {css}".strip())
    exact = repr(float(x)) + (f" {unit}" if unit and unit != "1" else "")
    return Cell(readable(x, digits), key=float(x), css=f"num {css}".strip(), title=exact)


def state(word: str, tone: Tone) -> Cell:
    """A verdict cell (``pass``, ``FAIL``, ``n/a`` ...), coloured by ``tone``."""
    return Cell(word, css=f"state {tone.value}")


def raw(markup: str, key: float | str | None = None, css: str = "") -> Cell:
    """A cell of markup built here from escaped parts (a link, a code span)."""
    return Cell(markup, key=key, css=css, markup=True)


@dataclass(frozen=True)
class Column:
    """A table column: its heading and whether it sorts as numbers."""

    name: str
    numeric: bool = False


@dataclass(frozen=True)
class Row:
    """A table row: its cells and its CSS class (a :class:`Tone` value colours the row)."""

    cells: Sequence[Cell]
    css: str = ""


def table(
    table_id: str,
    columns: Sequence[Column | str],
    rows: Iterable[Row | Sequence[Cell]],
    sortable: bool = True,
) -> str:
    """A table (sortable by a click on a header unless ``sortable`` is False); ``table_id`` is
    its ``id`` (letters, digits, ``-``: the ``#sort=`` fragment names it)."""
    if not table_id.replace("-", "").isalnum():
        raise ValueError(f"table_id: letters, digits and '-' only (got {table_id!r})")
    cols = [c if isinstance(c, Column) else Column(c) for c in columns]
    numeric = ' data-type="num"'
    head = "".join(
        f'<th{numeric if c.numeric else ""} scope="col">{esc(c.name)}</th>' for c in cols
    )
    body = []
    for r in rows:
        row = r if isinstance(r, Row) else Row(tuple(r))
        if len(row.cells) != len(cols):
            raise ValueError(
                f"table {table_id}: a row of {len(row.cells)} cells under {len(cols)} columns"
            )
        css = f' class="{esc(row.css)}"' if row.css else ""
        body.append(f"<tr{css}>" + "".join(c.render() for c in row.cells) + "</tr>")
    cls = ' class="sortable"' if sortable else ""
    return (
        f'<table id="{table_id}"{cls}><thead><tr>{head}</tr></thead>'
        f"<tbody>{''.join(body)}</tbody></table>"
    )


@dataclass(frozen=True)
class Banner:
    """The verdict, first on the page: its word (``PASSED``, ``FAILED`` ...), its tone, the
    sentences under it and the list of what failed (plain text, escaped when rendered)."""

    word: str
    tone: Tone
    lines: Sequence[str] = ()
    failed: Sequence[str] = ()

    def render(self) -> str:
        out = [f'<section id="verdict" class="banner {self.tone.value}">']
        out.append(f'<div class="word">{esc(self.word)}</div>')
        out += [f"<p>{esc(line)}</p>" for line in self.lines]
        if self.failed:
            out.append("<ul>" + "".join(f"<li>{esc(x)}</li>" for x in self.failed) + "</ul>")
        out.append("</section>")
        return "".join(out)


def para(value: Any, css: str = "") -> str:
    """A paragraph of text (escaped)."""
    cls = f' class="{esc(css)}"' if css else ""
    return f"<p{cls}>{esc(value)}</p>"


def bullets(items: Iterable[Any]) -> str:
    """A list of text items (escaped); "" when there are none."""
    items = list(items)
    return "<ul>" + "".join(f"<li>{esc(x)}</li>" for x in items) + "</ul>" if items else ""


def section(title: str, *parts: str, section_id: str = "") -> str:
    """A section: its heading (escaped) and its parts (markup built here)."""
    sid = f' id="{esc(section_id)}"' if section_id else ""
    return f"<section{sid}><h2>{esc(title)}</h2>{''.join(parts)}</section>"


MIME = {"png": "image/png", "svg": "image/svg+xml"}
"""The figure formats a page embeds, by file suffix (a PDF is linked, not embedded)."""


def figure(name: str, data: bytes, suffix: str, caption: str) -> str:
    """A figure embedded as a ``data:`` URI of its bytes (``suffix``: a key of :data:`MIME`),
    with its caption (escaped)."""
    try:
        mime = MIME[suffix]
    except KeyError:
        raise ValueError(f"suffix: not an embeddable figure format ({suffix!r})") from None
    uri = f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"
    return (
        f'<figure><img src="{uri}" alt="{esc(name)}"><figcaption>{esc(caption)}</figcaption>'
        "</figure>"
    )


def relative_link(name: str, label: str | None = None) -> str:
    """A link to the file ``name`` beside the page (a plain relative path, never a URL with a
    scheme, never up out of the directory)."""
    if "://" in name or name.startswith(("/", "\\")) or ".." in name.replace("\\", "/").split("/"):
        raise ValueError(f"name: not a path relative to the report ({name!r})")
    return f'<a href="{esc(name)}">{esc(label if label is not None else name)}</a>'


def recording(name: str) -> str:
    """The recording's block: a link to ``name`` (beside the page) and the command that opens it
    in the Rerun viewer."""
    return (
        '<p class="recording">Recording: '
        + relative_link(name)
        + f" — open it in the Rerun viewer with <code>rerun {esc(name)}</code> "
        "(in this report's directory).</p>"
    )


def page(title: str, banner: Banner, body: Sequence[str]) -> str:
    """The whole document: ``title`` (escaped) as its heading, the verdict banner first, then
    ``body`` (markup built here), the style and the sorting script inline."""
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en"><head><meta charset="utf-8">'
        f'<meta http-equiv="Content-Security-Policy" content="{CSP}">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>{esc(title)}</title><style>{STYLE}</style></head>\n"
        f"<body><h1>{esc(title)}</h1>\n{banner.render()}\n"
        + "\n".join(body)
        + f"\n<script>{SCRIPT}</script></body></html>\n"
    )


__all__ = [
    "CSP",
    "MIME",
    "Banner",
    "Cell",
    "Column",
    "Row",
    "Tone",
    "bullets",
    "esc",
    "figure",
    "num",
    "page",
    "para",
    "raw",
    "readable",
    "recording",
    "relative_link",
    "section",
    "state",
    "table",
    "text",
]
