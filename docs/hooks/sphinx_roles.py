"""Griffe extension: the Sphinx roles of odomkit's numpydoc docstrings as mkdocstrings links.

The docstrings cite other objects the numpydoc way, ``:func:`~odomkit.evaluate.nees```.
mkdocstrings reads Markdown, where that would show as literal text; this extension turns
each role into a cross-reference (``[`nees`][odomkit.evaluate.nees]``) when its target is
on an API page, and into plain code otherwise, so that ``mkdocs build --strict`` never
meets a link it cannot resolve. Names resolve as Sphinx resolves them: absolute, then
relative to the class and the module the docstring belongs to.

It also turns a heading that is no numpydoc section (``What counts as what`` underlined)
into a bold line, reStructuredText simple tables (rows between ``=====  =====`` borders) into
Markdown tables, and keeps a quantity and its units, ``[x, y, θ] [m, m, rad]``, as text:
Markdown would read the pair as a reference link.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import griffe

__all__ = ["SphinxRoles"]

_ROLE = re.compile(r":(?:py:)?(func|class|data|mod|meth|attr|obj|exc|const):`(~?)([^`<>]+?)`")
_UNITS = re.compile(r"\] \[")
_BORDER = re.compile(r"^(\s*)=+( +=+)+\s*$")
#: The API pages: the modules they render are their ``::: module`` lines
#: (``tests/test_architecture.py`` keeps them complete).
API_PAGES = Path(__file__).resolve().parents[1] / "reference" / "api"


def documented_modules(pages: Path = API_PAGES) -> set[str]:
    return {m.group(1) for page in pages.glob("*.md")
            for m in re.finditer(r"^::: ([\w.]+)\s*$", page.read_text(encoding="utf-8"), re.M)}


class SphinxRoles(griffe.Extension):
    """Rewrite every docstring of the package once it is loaded."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        self.root = pkg
        self.documented = documented_modules()
        for obj in _walk(pkg):
            if obj.docstring is not None:
                text = plain_headings(rst_tables(obj.docstring.value))
                text = _ROLE.sub(lambda m, o=obj: self._link(m, o), text)
                obj.docstring.value = "\n".join(_units(line) for line in text.split("\n"))

    def _find(self, path: str) -> griffe.Object | None:
        if path == self.root.path:
            return self.root
        if not path.startswith(self.root.path + "."):
            return None
        try:
            return self.root[path[len(self.root.path) + 1:]]
        except (KeyError, ValueError, griffe.AliasResolutionError, griffe.CyclicAliasError):
            return None

    def _resolve(self, target: str, where: griffe.Object) -> griffe.Object | None:
        target = target.lstrip(".")
        scopes = [where, *_parents(where)]
        for candidate in [target] + [f"{s.path}.{target}" for s in scopes]:
            found = self._find(candidate)
            if found is not None:
                return found
        return None

    def _rendered(self, obj: griffe.Object) -> bool:
        """Whether the API pages show ``obj`` (and so give it an anchor)."""
        if obj.is_module:
            return obj.path in self.documented
        parent = obj.parent
        if parent is None or obj.name.startswith("_"):
            return False
        if parent.is_module:
            exports = {e if isinstance(e, str) else e.name for e in (parent.exports or ())}
            return parent.path in self.documented and obj.name in exports
        return parent.is_class and self._rendered(parent)

    def _link(self, match: re.Match[str], where: griffe.Object) -> str:
        _, tilde, target = match.groups()
        target = target.strip().removesuffix("()")
        shown = target.rsplit(".", 1)[-1] if tilde else target
        found = self._resolve(target, where)
        if found is not None and found.is_alias:
            try:
                found = found.final_target  # type: ignore[union-attr]
            except (griffe.AliasResolutionError, griffe.CyclicAliasError):
                found = None
        if found is not None and self._rendered(found):
            return f"[`{shown}`][{found.path}]"
        return f"`{shown}`"


def _walk(obj: griffe.Object) -> Iterator[griffe.Object]:
    yield obj
    for member in obj.members.values():
        if not member.is_alias and member.parent is obj:
            yield from _walk(member)  # type: ignore[arg-type]


def _parents(obj: griffe.Object) -> list[griffe.Object]:
    out = []
    while obj.parent is not None:
        obj = obj.parent
        out.append(obj)
    return out


def _units(line: str) -> str:
    if line.lstrip().startswith((">>>", "...")):  # doctest lines are code
        return line
    return _UNITS.sub(r"] \\[", line)


def rst_tables(text: str) -> str:
    """Every reStructuredText simple table of ``text`` as a Markdown table. Cells are split
    at runs of two or more spaces; a line whose first column is blank continues the last
    cell of the row above; with three borders the first row is the header."""
    lines, out, i = text.split("\n"), [], 0
    while i < len(lines):
        borders = [i] if _BORDER.match(lines[i]) else []
        j = i + 1
        while borders and j < len(lines) and (lines[j].strip() or j == i + 1):
            if _BORDER.match(lines[j]):
                borders.append(j)
            j += 1
        if len(borders) < 2:
            out.append(lines[i])
            i += 1
            continue
        indent = len(_BORDER.match(lines[i]).group(1))  # type: ignore[union-attr]
        width = len(lines[i].split())
        header = borders[1] - borders[0] - 1 if len(borders) >= 3 else 0
        rows: list[list[str]] = []
        for k in range(borders[0] + 1, borders[-1]):
            if k in borders:
                continue
            line = lines[k][indent:]
            if rows and line[:1].isspace():
                rows[-1][-1] += " " + line.strip()
                continue
            cells = re.split(r"\s{2,}", line.strip(), maxsplit=width - 1)
            rows.append(cells + [""] * (width - len(cells)))
        head = rows[:header] if header else [[""] * width]
        body = rows[header:] if header else rows
        table = [_row(head[0]), "|" + "---|" * width] + [_row(r) for r in body]
        out += ["", *table, ""]
        i = borders[-1] + 1
    return "\n".join(out)


def _row(cells: list[str]) -> str:
    return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"


#: The numpydoc sections griffe parses; any other underlined heading is a title.
SECTIONS = {"parameters", "other parameters", "returns", "yields", "receives", "raises", "warns",
            "warnings", "examples", "attributes", "functions", "methods", "classes", "modules",
            "notes", "references", "see also", "deprecated"}


def plain_headings(text: str) -> str:
    lines = text.split("\n")
    out, i = [], 0
    while i < len(lines):
        title, under = lines[i].strip(), lines[i + 1].strip() if i + 1 < len(lines) else ""
        if (title and re.fullmatch(r"-{3,}", under) and len(under) == len(title)
                and title.lower() not in SECTIONS):
            out += [f"{lines[i][:len(lines[i]) - len(lines[i].lstrip())]}**{title}**", ""]
            i += 2
            continue
        out.append(lines[i])
        i += 1
    return "\n".join(out)
