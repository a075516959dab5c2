"""The HTML page of the reproduction: self-contained, offline, no external resources.

Building blocks (each returns an HTML string, every text escaped):
:func:`table`, :func:`formula`, :func:`figure`, :func:`animation`,
:func:`section`, and :func:`page`, which wraps the sections with inline CSS, a
table of contents and a self-check script.

Formulas are MathML (:func:`nilpotent.typeset.formula_html`), rendered by the
browser itself: no script, no font and no stylesheet from the network.  Each
keeps its LaTeX source in ``data-latex`` and a "copy LaTeX" button.

The self-check (inline JavaScript, no library) runs when the page has loaded:
it counts the ``<img>`` elements and those that decoded (``complete`` and
``naturalWidth > 0``), the formulas (``.formula``), those that are a MathML
``<math>`` element with a non-empty rendered box, counts script errors
(``window.onerror``), and writes the result on ``#selfcheck`` as
``data-images``, ``data-images-loaded``, ``data-formulas``,
``data-formulas-sized``, ``data-errors`` and ``data-done="true"``; a headless
browser reads them with ``--dump-dom`` (``tests/test_browser.py``).  Images are
relative files under ``figures/``; nothing is fetched from the network.
"""

from __future__ import annotations

import html
from collections.abc import Iterable, Sequence

from nilpotent.typeset import formula_html

__all__ = ["animation", "code", "figure", "formula", "page", "section", "table"]

_CSS = """
:root { --fg: #1d1d1f; --muted: #5b5b60; --line: #d8d8dc; --ok: #1a7f37; --bad: #b42318;
        --okbg: #e9f6ec; --badbg: #fdecea; }
* { box-sizing: border-box; }
body { font: 15px/1.5 system-ui, -apple-system, "Segoe UI", sans-serif; color: var(--fg);
       margin: 0 auto; max-width: 1180px; padding: 1.2em 1.4em 4em; }
h1 { font-size: 1.6em; margin-bottom: .2em; }
h2 { font-size: 1.25em; border-bottom: 1px solid var(--line); padding-bottom: .2em;
     margin-top: 2.2em; }
h3 { font-size: 1.05em; margin-top: 1.6em; }
p.lead { color: var(--muted); margin-top: 0; }
nav ol { columns: 2; font-size: .93em; }
code, .mono { font-family: ui-monospace, "SFMono-Regular", Menlo, Consolas, monospace;
              font-size: .88em; }
table { border-collapse: collapse; margin: .8em 0; width: 100%; font-size: .88em; }
th, td { border: 1px solid var(--line); padding: .3em .5em; text-align: left;
         vertical-align: top; }
th { background: #f4f4f6; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
td.mono { font-family: ui-monospace, "SFMono-Regular", Menlo, Consolas, monospace;
          font-size: .82em; overflow-wrap: anywhere; }
table.audit td { overflow-wrap: anywhere; }
table.audit .formula { overflow-x: visible; flex-wrap: wrap; row-gap: .15em; }
table.audit math { font-size: 1em; }
tr.agrees td.verdict { color: var(--ok); background: var(--okbg); font-weight: 600; }
tr.differs td.verdict { color: var(--bad); background: var(--badbg); font-weight: 600; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid var(--line); }
figcaption { color: var(--muted); font-size: .9em; }
.summary { display: flex; gap: 1em; flex-wrap: wrap; }
.card { border: 1px solid var(--line); border-radius: 6px; padding: .6em 1em; }
.card b { font-size: 1.3em; display: block; }
.note { background: #f7f7f9; border-left: 3px solid var(--line); padding: .5em .8em; }
math { font-size: 1.08em; font-family: math, "STIX Two Math", "Latin Modern Math",
       "Cambria Math", serif; }
.formula { display: inline-flex; align-items: center; gap: .35em; max-width: 100%;
           overflow-x: auto; vertical-align: middle; }
div.formula { display: flex; margin: .6em 0; }
.copy-latex { font: 600 .68em system-ui, sans-serif; color: var(--muted); background: #fff;
              border: 1px solid var(--line); border-radius: 3px; padding: 0 .3em;
              cursor: pointer; opacity: .35; flex: none; }
.formula:hover .copy-latex, .copy-latex:focus { opacity: 1; }
"""

_SELFCHECK = """
(function () {
  var errors = 0;
  window.addEventListener("error", function () { errors += 1; report(); }, true);
  function report() {
    var imgs = Array.prototype.slice.call(document.images);
    var loaded = imgs.filter(function (im) { return im.complete && im.naturalWidth > 0; });
    var box = document.getElementById("selfcheck");
    box.dataset.images = String(imgs.length);
    box.dataset.imagesLoaded = String(loaded.length);
    box.dataset.errors = String(errors);
    box.dataset.missing = imgs.filter(function (im) {
      return !(im.complete && im.naturalWidth > 0);
    }).map(function (im) { return im.getAttribute("src"); }).join(" ");
    var formulas = Array.prototype.slice.call(document.querySelectorAll(".formula"));
    var sized = formulas.filter(function (f) {
      var m = f.firstElementChild;
      if (!m || m.namespaceURI !== "http://www.w3.org/1998/Math/MathML") { return false; }
      var r = m.getBoundingClientRect();
      return r.width > 0 && r.height > 0 && f.hasAttribute("data-latex");
    });
    box.dataset.formulas = String(formulas.length);
    box.dataset.formulasSized = String(sized.length);
    box.dataset.done = "true";
    box.textContent = "self-check: " + loaded.length + "/" + imgs.length +
      " images loaded, " + sized.length + "/" + formulas.length + " formulas rendered, " +
      errors + " script errors";
  }
  window.addEventListener("load", report);
})();
"""


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def code(text: str) -> str:
    """Inline monospace text."""
    return f"<code>{_e(text)}</code>"


def formula(latex: str, *, display: bool = False) -> str:
    """A typeset formula (MathML) with its LaTeX source and a "copy LaTeX" button."""
    return formula_html(latex, display=display)


def table(
    headers: Sequence[str],
    rows: Iterable[Sequence[object]],
    *,
    row_classes: Sequence[str] | None = None,
    cell_classes: Sequence[str] | None = None,
    raw_columns: Sequence[int] = (),
    widths: Sequence[str] | None = None,
    css_class: str | None = None,
) -> str:
    """An HTML table; cells are escaped except in ``raw_columns`` (already HTML).

    ``widths`` (CSS widths, one per column) fixes the layout; ``css_class`` names the table.
    """
    head = "".join(f"<th>{_e(h)}</th>" for h in headers)
    cols = ""
    if widths:
        cols = (
            "<colgroup>" + "".join(f'<col style="width:{_e(w)}">' for w in widths) + "</colgroup>"
        )
    body = []
    for r, row in enumerate(rows):
        cls = f' class="{_e(row_classes[r])}"' if row_classes else ""
        cells = []
        for c, value in enumerate(row):
            ccls = f' class="{_e(cell_classes[c])}"' if cell_classes and cell_classes[c] else ""
            text = str(value) if c in raw_columns else _e(value)
            cells.append(f"<td{ccls}>{text}</td>")
        body.append(f"<tr{cls}>{''.join(cells)}</tr>")
    cls_attr = f' class="{_e(css_class)}"' if css_class else ""
    fixed = ' style="table-layout:fixed"' if widths else ""
    return (
        f"<table{cls_attr}{fixed}>{cols}<thead><tr>{head}</tr></thead>"
        f"<tbody>{''.join(body)}</tbody></table>"
    )


def figure(
    src: str, caption: str, *, alt: str | None = None, links: Sequence[tuple[str, str]] = ()
) -> str:
    """An image (relative path) with a caption and links to other formats."""
    extra = "".join(f' · <a href="{_e(href)}">{_e(label)}</a>' for label, href in links)
    return (
        f'<figure><img src="{_e(src)}" alt="{_e(alt or caption)}" loading="eager">'
        f"<figcaption>{_e(caption)}{extra}</figcaption></figure>"
    )


def animation(gif: str, player: str, caption: str, *, mp4: str | None = None) -> str:
    """An animated GIF with links to the self-contained HTML player (and the MP4)."""
    links = [("interactive player (HTML, offline)", player)]
    if mp4:
        links.append(("MP4", mp4))
    return figure(gif, caption, links=links)


def section(anchor: str, heading: str, body: str) -> str:
    return f'<section id="{_e(anchor)}"><h2>{_e(heading)}</h2>{body}</section>'


def page(title: str, lead: str, sections: Sequence[tuple[str, str, str]]) -> str:
    """The whole document: ``sections`` are ``(anchor, heading, html body)``."""
    toc = "".join(f'<li><a href="#{_e(a)}">{_e(h)}</a></li>' for a, h, _ in sections)
    body = "".join(section(a, h, b) for a, h, b in sections)
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>{_e(title)}</title><style>{_CSS}</style>"
        f"<script>{_SELFCHECK}</script></head><body>"
        f'<h1>{_e(title)}</h1><p class="lead">{_e(lead)}</p>'
        f"<nav><ol>{toc}</ol></nav>{body}"
        '<p id="selfcheck" class="mono" data-done="false"></p>'
        "</body></html>\n"
    )
