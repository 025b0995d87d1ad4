"""The HTML report: sections of text, tables, figures and parameter snippets in one page.

Only strings here. The page is self-contained and works offline: the style is inline,
figures are embedded as ``data:`` URIs (SVG or PNG), there is no script and no web font,
and a Content-Security-Policy forbids the browser to fetch anything else. Every text is
escaped with :func:`html.escape`. :mod:`odomkit.workflows.report` runs the workflows,
draws the figures and writes the file.

Each numeric table cell may carry its exact value (``data-key``, ``data-value``, the
shortest round-tripping text of the float), so a test or a script can read the numbers
back from the page without parsing the rounded text.
"""

from __future__ import annotations

import base64
import html
import math
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["Cell", "Code", "Figure", "Paragraph", "Section", "Table", "number", "png_figure",
           "render_report", "svg_figure"]


@dataclass(frozen=True)
class Paragraph:
    """A paragraph of plain text; ``kind`` "text", "note" (set apart) or "warning"."""

    text: str
    kind: str = "text"


@dataclass(frozen=True)
class Cell:
    """A table cell: the text shown and, for a number, its key and exact value."""

    text: str
    key: str | None = None
    value: float | None = None


@dataclass(frozen=True)
class Table:
    """A table: a header row and rows of cells (plain strings or :class:`Cell`)."""

    header: tuple[str, ...]
    rows: tuple[tuple[str | Cell, ...], ...]
    caption: str = ""


@dataclass(frozen=True)
class Figure:
    """An embedded image: a ``data:`` URI (:func:`svg_figure`, :func:`png_figure`), the
    caption under it and the text that replaces it for a reader who cannot see it."""

    uri: str
    caption: str
    alt: str


@dataclass(frozen=True)
class Code:
    """A preformatted block (a ROS parameter snippet), shown as is."""

    text: str
    caption: str = ""


Block = Paragraph | Table | Figure | Code


@dataclass(frozen=True)
class Section:
    """One section of the report: ``key`` is its anchor (and its name in ``--json``)."""

    key: str
    title: str
    blocks: tuple[Block, ...]


def svg_figure(svg: str, caption: str, alt: str) -> Figure:
    """A figure from an SVG document (``odomkit.plot.figure_svg``), embedded as a base64
    ``data:`` URI: each figure stays its own document, so the element ids of two figures
    cannot clash as they would inline."""
    start = svg.find("<svg")
    if start < 0:
        raise ValueError("not an SVG document: no <svg element")
    data = base64.b64encode(svg[start:].encode("utf-8")).decode("ascii")
    return Figure(f"data:image/svg+xml;base64,{data}", caption, alt)


def png_figure(png: bytes, caption: str, alt: str) -> Figure:
    """A figure from PNG bytes, embedded as a base64 ``data:`` URI."""
    if not png.startswith(b"\x89PNG\r\n\x1a\n"):
        raise ValueError("not a PNG image")
    return Figure(f"data:image/png;base64,{base64.b64encode(png).decode('ascii')}", caption, alt)


def number(value: float | None, unit: str = "", digits: int = 4, *, key: str | None = None,
           scale: float = 1.0, decimals: int | None = None) -> Cell:
    """A numeric cell: ``value`` × ``scale`` to ``digits`` significant digits (or to
    ``decimals`` decimal places) with ``unit`` ("n/a" for None or NaN); ``key`` and the
    unscaled ``value`` are kept for machines.

    Examples
    --------
    >>> number(0.012345678, "m", key="ate_rmse")
    Cell(text='0.01235 m', key='ate_rmse', value=0.012345678)
    >>> number(0.9, "%", 3, scale=100).text, number(0.0067, "m", 3).text, number(None).text
    ('90.0 %', '0.00670 m', 'n/a')
    """
    if value is None or not math.isfinite(value):
        return Cell("n/a", key, value)
    # "#": trailing zeros kept, so 0.00670 shows its three digits
    text = f"{value * scale:.{decimals}f}" if decimals is not None else f"{value * scale:#.{digits}g}"
    text = text.rstrip(".")
    return Cell(f"{text} {unit}" if unit else text, key, float(value))


_STYLE = """
:root { color-scheme: light; }
* { box-sizing: border-box; }
body { margin: 0; background: #fff; color: #1d2430; line-height: 1.5;
  font-family: system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
main { max-width: 62rem; margin: 0 auto; padding: 1.5rem 1.25rem 4rem; }
header p { margin: .2rem 0; color: #4a5565; }
h1 { font-size: 1.75rem; margin: .3rem 0 .5rem; }
h2 { font-size: 1.3rem; margin: 2.6rem 0 .6rem; padding-top: .8rem; border-top: 1px solid #d8dee6; }
p { max-width: 48rem; margin: .6rem 0; }
nav { margin: 1rem 0 0; font-size: .95rem; }
nav ol { margin: .3rem 0; padding-left: 1.4rem; columns: 2; column-gap: 2.5rem; max-width: 44rem; }
a { color: #1f5fa8; }
table { border-collapse: collapse; margin: .9rem 0; min-width: 26rem; font-variant-numeric: tabular-nums; }
caption { caption-side: top; text-align: left; font-weight: 600; padding-bottom: .3rem; }
th, td { padding: .32rem .8rem; border-bottom: 1px solid #e3e7ee; text-align: left; vertical-align: top; }
th { border-bottom: 2px solid #c9d1dc; font-weight: 600; }
td.num { text-align: right; white-space: nowrap; }
figure { margin: 1.3rem 0; }
figure img { display: block; max-width: 100%; height: auto; }
figcaption { font-size: .92rem; color: #4a5565; max-width: 48rem; margin-top: .45rem; }
pre { background: #f5f7fa; border: 1px solid #e3e7ee; border-radius: 4px; padding: .8rem 1rem;
  overflow-x: auto; font-size: .84rem; line-height: 1.4;
  font-family: ui-monospace, "DejaVu Sans Mono", Menlo, Consolas, monospace; }
.code-caption { font-size: .92rem; color: #4a5565; margin-bottom: .2rem; }
.note { background: #f3f6fa; border-left: 4px solid #7b93b3; padding: .5rem .8rem; }
.warning { background: #fff7e6; border-left: 4px solid #c77700; padding: .5rem .8rem; }
footer { margin-top: 3rem; font-size: .85rem; color: #6b7685; }
@media print { figure, table, pre { break-inside: avoid; } pre { white-space: pre-wrap; } }
"""

# The page may load nothing: images only from data: URIs, styles only inline, no script.
_POLICY = "default-src 'none'; img-src data:; style-src 'unsafe-inline'"


def _cell(cell: str | Cell, tag: str = "td") -> str:
    if isinstance(cell, str):
        return f"<{tag}>{html.escape(cell)}</{tag}>"
    attrs = ' class="num"' if tag == "td" else ""
    if cell.key is not None:
        attrs += f' data-key="{html.escape(cell.key)}"'
    if cell.value is not None:
        attrs += f' data-value="{html.escape(repr(float(cell.value)))}"'
    return f"<{tag}{attrs}>{html.escape(cell.text)}</{tag}>"


def _block(block: Block) -> str:
    if isinstance(block, Paragraph):
        cls = "" if block.kind == "text" else f' class="{html.escape(block.kind)}"'
        return f"<p{cls}>{html.escape(block.text)}</p>"
    if isinstance(block, Table):
        caption = f"<caption>{html.escape(block.caption)}</caption>" if block.caption else ""
        head = "".join(f"<th>{html.escape(h)}</th>" for h in block.header)
        body = "".join("<tr>" + "".join(_cell(c) for c in row) + "</tr>" for row in block.rows)
        return f"<table>{caption}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"
    if isinstance(block, Figure):
        if not block.uri.startswith(("data:image/svg+xml;base64,", "data:image/png;base64,")):
            raise ValueError("a report figure must be an embedded SVG or PNG data: URI")
        return (f'<figure><img src="{block.uri}" alt="{html.escape(block.alt)}">'
                f"<figcaption>{html.escape(block.caption)}</figcaption></figure>")
    caption = f'<div class="code-caption">{html.escape(block.caption)}</div>' if block.caption else ""
    return f"{caption}<pre>{html.escape(block.text)}</pre>"


def render_report(title: str, sections: Sequence[Section], *, subtitle: Sequence[str] = (),
                  warnings: Sequence[str] = (), footer: str = "") -> str:
    """The whole page: title, lines under it (``subtitle``), a table of contents, the
    warnings, the sections in order and a footer.

    Examples
    --------
    >>> page = render_report("Run <1>", [Section("a", "A & B", (Paragraph("x < y"),))])
    >>> "<h1>Run &lt;1&gt;</h1>" in page and '<h2 id="a">A &amp; B</h2>' in page
    True
    >>> "<p>x &lt; y</p>" in page and "<script" not in page
    True
    """
    keys = [s.key for s in sections]
    if len(set(keys)) != len(keys):
        raise ValueError(f"section keys must differ, got {keys}")
    parts = ["<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
             f'<meta http-equiv="Content-Security-Policy" content="{_POLICY}">',
             '<meta name="viewport" content="width=device-width, initial-scale=1">',
             f"<title>{html.escape(title)}</title>", f"<style>{_STYLE}</style>", "</head>",
             "<body>", "<main>", "<header>", f"<h1>{html.escape(title)}</h1>"]
    parts += [f"<p>{html.escape(line)}</p>" for line in subtitle]
    if sections:
        items = "".join(f'<li><a href="#{html.escape(s.key)}">{html.escape(s.title)}</a></li>'
                        for s in sections)
        parts.append(f'<nav aria-label="Contents"><strong>Contents</strong><ol>{items}</ol></nav>')
    parts.append("</header>")
    if warnings:
        items = "".join(f"<li>{html.escape(w)}</li>" for w in warnings)
        parts.append(f'<div class="warning"><strong>Warnings</strong><ul>{items}</ul></div>')
    for section in sections:
        parts.append(f'<section><h2 id="{html.escape(section.key)}">{html.escape(section.title)}</h2>')
        parts += [_block(b) for b in section.blocks]
        parts.append("</section>")
    if footer:
        parts.append(f"<footer>{html.escape(footer)}</footer>")
    parts += ["</main>", "</body>", "</html>", ""]
    return "\n".join(parts)
