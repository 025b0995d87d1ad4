"""The HTML page assembly (odomkit.report): escaping, embedded figures only, numbers kept
for machines; checked by parsing the page with html.parser, not by string matching."""

from __future__ import annotations

import base64
from html.parser import HTMLParser

import pytest

from odomkit.report import (
    Cell,
    Code,
    Paragraph,
    Section,
    Table,
    number,
    png_figure,
    render_report,
    svg_figure,
)


class _Collect(HTMLParser):
    def __init__(self):
        super().__init__()
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def handle_data(self, data):
        self.text.append(data)


def _parse(page: str) -> _Collect:
    parser = _Collect()
    parser.feed(page)
    return parser


SVG = '<?xml version="1.0"?>\n<svg xmlns="http://www.w3.org/2000/svg" width="4" height="4"></svg>'
PNG = b"\x89PNG\r\n\x1a\n" + b"\x00" * 16


def test_user_text_is_escaped_everywhere_and_no_script_or_tag_is_injected():
    evil = '<script>alert(1)</script> & "quotes"'
    page = render_report(evil, [Section("s", evil, (Paragraph(evil), Table((evil,), ((evil, Cell(evil)),)),
                                                    Code(evil, evil)))], subtitle=[evil], warnings=[evil],
                         footer=evil)
    parsed = _parse(page)
    assert not any(tag == "script" for tag, _ in parsed.tags)
    # every occurrence came back as text: title, subtitle, nav, warning, heading, paragraph,
    # header cell, two cells, caption, code, footer
    assert sum(evil in t for t in parsed.text) >= 10


def test_figures_are_data_uris_that_decode_to_the_image():
    svg = svg_figure(SVG, "cap", "alt")
    png = png_figure(PNG, "cap", "alt")
    page = render_report("t", [Section("f", "F", (svg, png))])
    sources = [attrs["src"] for tag, attrs in _parse(page).tags if tag == "img"]
    assert len(sources) == 2
    decoded = base64.b64decode(sources[0].split(",", 1)[1]).decode()
    assert decoded.startswith("<svg") and decoded == SVG[SVG.find("<svg"):]
    assert base64.b64decode(sources[1].split(",", 1)[1]) == PNG


def test_the_page_may_fetch_nothing():
    page = render_report("t", [Section("f", "F", (svg_figure(SVG, "c", "a"),))])
    tags = _parse(page).tags
    policy = next(a["content"] for t, a in tags
                  if t == "meta" and a.get("http-equiv") == "Content-Security-Policy")
    assert "default-src 'none'" in policy and "img-src data:" in policy
    for _, attrs in tags:
        for name in ("src", "href"):
            value = attrs.get(name)
            assert value is None or value.startswith(("data:", "#")), value


@pytest.mark.parametrize("make", [lambda: svg_figure("<html></html>", "c", "a"),
                                  lambda: png_figure(b"GIF89a", "c", "a")])
def test_what_is_not_the_claimed_image_is_refused(make):
    with pytest.raises(ValueError):
        make()


def test_numbers_keep_their_exact_value_and_key_for_machines():
    cell = number(0.0123456789, "m", key="ate_rmse")
    assert cell.text == "0.01235 m"
    page = render_report("t", [Section("m", "M", (Table(("metric", "value"), (("ATE", cell),)),))])
    td = [attrs for tag, attrs in _parse(page).tags if tag == "td" and "data-key" in attrs]
    assert td == [{"class": "num", "data-key": "ate_rmse", "data-value": repr(0.0123456789)}]
    assert number(float("nan")).text == "n/a" and number(None).text == "n/a"
    assert number(0.5, "%", scale=100, decimals=1).text == "50.0 %"


def test_section_keys_are_anchors_and_must_differ():
    page = render_report("t", [Section("a", "A", ()), Section("b", "B", ())])
    anchors = [a["href"] for t, a in _parse(page).tags if t == "a"]
    ids = [a["id"] for t, a in _parse(page).tags if t == "h2"]
    assert anchors == ["#a", "#b"] and ids == ["a", "b"]
    with pytest.raises(ValueError, match="must differ"):
        render_report("t", [Section("a", "A", ()), Section("a", "B", ())])


def test_the_noise_sections_coverage_table_counts_each_noises_own_window_ends():
    """Against a noisy GPS, the fitted truth noise can leave out window starts whose heading
    its fixes no longer support, so the two noises score different numbers of ends (a real
    car: 29 and 22). The table said "Fraction of 22 window ends" over both columns; it must
    give each count."""
    from odomkit.workflows.report import ReportFigures, _noise_section

    cover = {"0.5": 0.5, "0.9": 0.9, "0.95": 0.95, "0.99": 0.99}
    fit = {"windows": 27, "parameters": {"k_left": 0.001}, "interval95": {"k_left": [0.0, 0.002]}}
    figures = ReportFigures()
    figures.enabled = False
    section = _noise_section(fit, None, {"k_left": 0.001}, {"windows": 29, "coverage": cover},
                             {"windows": 22, "coverage": cover}, figures)
    captions = [block.caption for block in section.blocks if hasattr(block, "caption")]
    said = next(c for c in captions if c.startswith("Fraction of"))
    assert "29 with the robot file's noise, 22 with the fitted noise" in said
    same = _noise_section(fit, None, {"k_left": 0.001}, {"windows": 22, "coverage": cover},
                          {"windows": 22, "coverage": cover}, figures)
    assert any(getattr(b, "caption", "").startswith("Fraction of 22 window ends") for b in same.blocks)
