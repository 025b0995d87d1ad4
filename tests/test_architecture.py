"""The architecture of DESIGN.md, checked on the source with :mod:`ast` (issue 9).

* no import cycle among odomkit's modules: one check on the imports that run when a
  module is imported, one that also counts the imports inside functions (a lazy import is
  still a dependency of the design; it only hides the cycle from the interpreter);
* no module imports another module's underscore names; a private *module* (``_numba``)
  may be imported only from inside the package that holds it;
* the core (everything except ``io/``, ``workflows/``, ``cli/``, ``plot.py``,
  ``report.py``, ``demo.py``) never imports matplotlib, typer, rich, a file-format library
  or any of those edge modules, not even inside a function;
* no public function has a parameter annotated ``Any`` (nor a public dataclass a field);
* every module has ``__all__``; every name it lists exists, and every public function or
  class a module defines is listed there or is underscored.

Each rule is a function from parsed sources to a list of violations; each has a self-test
on a synthetic snippet, so a rule that can never fire would be noticed.

``python tests/test_architecture.py`` writes the documentation's Python API pages
(``docs/reference/api/``) from the ``__all__`` lists: an index of every module's public names
and one mkdocstrings page per package (``test_docs_list_the_public_api`` checks that the
pages hold exactly that).
"""

from __future__ import annotations

import ast
import importlib
import sys
import textwrap
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SRC = REPO / "src"
ROOT = "odomkit"

#: The edges of DESIGN.md ("The core (everything above io/) never imports a file format,
#: typer, rich or matplotlib"). A module is core unless it is or lies inside one of these.
EDGE = ("odomkit.io", "odomkit.workflows", "odomkit.cli", "odomkit.plot", "odomkit.report",
        "odomkit.demo")
#: What a core module must never import: the user-interface and plotting libraries, the
#: file-format libraries (they belong in ``io/``), and the edge modules themselves (imports
#: point downwards only).
FORBIDDEN_IN_CORE = ("matplotlib", "typer", "rich", "click", "tomllib", "tomli_w", "rosbags",
                     "polars", "pymap3d") + EDGE


@dataclass(frozen=True)
class Import:
    """One import statement (or ``importlib.import_module("...")`` call) of a module."""

    importer: str
    target: str  # the module imported: a submodule when ``from pkg import sub`` names one
    name: str | None  # the name taken by ``from target import name``; None for a module
    line: int
    kind: str  # "module" (runs on import), "function" (lazy) or "typing" (TYPE_CHECKING)


@dataclass(frozen=True)
class Module:
    name: str
    path: str
    tree: ast.Module
    is_package: bool


def module_name(path: Path, src: Path = SRC) -> tuple[str, bool]:
    parts = list(path.relative_to(src).with_suffix("").parts)
    is_package = parts[-1] == "__init__"
    return ".".join(parts[:-1] if is_package else parts), is_package


def load_sources(sources: Mapping[str, str]) -> dict[str, Module]:
    """Parse ``{"pkg/mod.py": source}`` (paths relative to ``src``) into modules."""
    modules = {}
    for rel, text in sources.items():
        name, is_package = module_name(Path(rel), Path("."))
        modules[name] = Module(name, rel, ast.parse(text, filename=rel), is_package)
    return modules


def load_tree(src: Path = SRC) -> dict[str, Module]:
    return load_sources({str(p.relative_to(src)): p.read_text(encoding="utf-8")
                         for p in sorted((src / ROOT).rglob("*.py"))})


# --------------------------------------------------------------------------- imports
def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def _resolve(module: Module, level: int, target: str | None) -> str:
    if level == 0:
        return target or ""
    base = module.name.split(".")
    keep = len(base) - level + (1 if module.is_package else 0)
    return ".".join(base[:keep] + ([target] if target else []))


def imports_of(module: Module, known: Mapping[str, Module]) -> Iterator[Import]:
    """Every import of ``module``, with where it runs."""

    def visit(node: ast.AST, kind: str) -> Iterator[Import]:
        for child in ast.iter_child_nodes(node):
            child_kind = kind
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda) and kind == "module":
                child_kind = "function"
            if isinstance(child, ast.If) and _is_type_checking(child.test):
                for stmt in child.body:
                    yield from visit_stmt(stmt, "typing")
                for stmt in child.orelse:
                    yield from visit_stmt(stmt, kind)
                continue
            yield from visit_stmt(child, child_kind)

    def visit_stmt(node: ast.AST, kind: str) -> Iterator[Import]:
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield Import(module.name, alias.name, None, node.lineno, kind)
        elif isinstance(node, ast.ImportFrom):
            base = _resolve(module, node.level, node.module)
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                if sub in known:
                    yield Import(module.name, sub, None, node.lineno, kind)
                else:
                    yield Import(module.name, base, alias.name, node.lineno, kind)
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute | ast.Name)
              and (node.func.attr if isinstance(node.func, ast.Attribute) else node.func.id)
              == "import_module" and node.args and isinstance(node.args[0], ast.Constant)
              and isinstance(node.args[0].value, str)):
            yield Import(module.name, node.args[0].value, None, node.lineno, kind)
        yield from visit(node, kind)

    yield from visit(module.tree, "module")


def _inside(name: str, prefix: str) -> bool:
    return name == prefix or name.startswith(prefix + ".")


def is_core(name: str) -> bool:
    return not any(_inside(name, edge) for edge in EDGE)


def _where(module: Module, line: int) -> str:
    return f"src/{module.path}:{line}"


# --------------------------------------------------------------------------- rule: cycles
def import_graph(modules: Mapping[str, Module], kinds: set[str]) -> dict[str, dict[str, Import]]:
    """importer -> {imported odomkit module: the first import making that edge}."""
    graph: dict[str, dict[str, Import]] = {name: {} for name in modules}
    for module in modules.values():
        for imp in imports_of(module, modules):
            if imp.kind in kinds and imp.target in modules and imp.target != module.name:
                graph[module.name].setdefault(imp.target, imp)
    return graph


def strongly_connected(graph: Mapping[str, Mapping[str, object]]) -> list[list[str]]:
    """Tarjan's strongly connected components with more than one module."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def connect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 10_000))
    try:
        for v in sorted(graph):
            if v not in index:
                connect(v)
    finally:
        sys.setrecursionlimit(limit)
    return sorted(found)


def cycle_violations(modules: Mapping[str, Module], kinds: set[str]) -> list[str]:
    graph = import_graph(modules, kinds)
    out = []
    for component in strongly_connected(graph):
        members = set(component)
        edges = [f"{a} -> {b} ({imp.kind}, {_where(modules[a], imp.line)})"
                 for a in component for b, imp in sorted(graph[a].items()) if b in members]
        out.append("import cycle among " + ", ".join(component) + ": " + "; ".join(edges))
    return out


# --------------------------------------------------------------------------- rule: private names
def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _private_module_owner(target: str) -> str | None:
    """The package that may import ``target``, when a component of it is private."""
    parts = target.split(".")
    for i, part in enumerate(parts):
        if _private(part):
            return ".".join(parts[:i])
    return None


def private_violations(modules: Mapping[str, Module]) -> list[str]:
    out = []
    for module in modules.values():
        aliases: dict[str, str] = {}
        for imp in imports_of(module, modules):
            if imp.target not in modules:
                continue  # numpy and friends keep their own conventions
            owner = _private_module_owner(imp.target)
            if owner is not None and not _inside(module.name, owner):
                out.append(f"{_where(module, imp.line)}: {module.name} imports private module "
                           f"{imp.target} from outside {owner}")
            if imp.name is not None and _private(imp.name) and imp.target != module.name:
                out.append(f"{_where(module, imp.line)}: {module.name} imports private name "
                           f"{imp.name} from {imp.target}")
        # ``import odomkit.x as x; x._helper`` and ``from odomkit import x; x._helper``
        for node in ast.walk(module.tree):
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.name in modules:
                        aliases[a.asname or a.name] = a.name
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(module, node.level, node.module)
                for a in node.names:
                    if f"{base}.{a.name}" in modules:
                        aliases[a.asname or a.name] = f"{base}.{a.name}"
        for node in ast.walk(module.tree):
            if (isinstance(node, ast.Attribute) and _private(node.attr)
                    and isinstance(node.value, ast.Name) and node.value.id in aliases
                    and aliases[node.value.id] != module.name
                    and f"{aliases[node.value.id]}.{node.attr}" not in modules):
                out.append(f"{_where(module, node.lineno)}: {module.name} uses private name "
                           f"{node.attr} of {aliases[node.value.id]}")
    return sorted(set(out))


# --------------------------------------------------------------------------- rule: layers
def layer_violations(modules: Mapping[str, Module]) -> list[str]:
    out = []
    for module in modules.values():
        if not is_core(module.name):
            continue
        for imp in imports_of(module, modules):
            bad = next((f for f in FORBIDDEN_IN_CORE if _inside(imp.target, f)), None)
            if bad is not None:
                out.append(f"{_where(module, imp.line)}: core module {module.name} imports "
                           f"{imp.target} ({imp.kind} level)")
    return sorted(out)


# --------------------------------------------------------------------------- rule: Any
def _is_any(annotation: ast.expr | None) -> bool:
    if annotation is None:
        return False
    if isinstance(annotation, ast.Constant) and isinstance(annotation.value, str):
        try:
            annotation = ast.parse(annotation.value, mode="eval").body
        except SyntaxError:
            return False
    if isinstance(annotation, ast.Name):
        return annotation.id == "Any"
    if isinstance(annotation, ast.Attribute):
        return annotation.attr == "Any"
    if isinstance(annotation, ast.BinOp) and isinstance(annotation.op, ast.BitOr):
        return _is_any(annotation.left) or _is_any(annotation.right)  # Any | None is Any
    if isinstance(annotation, ast.Subscript) and isinstance(annotation.value, ast.Name | ast.Attribute):
        outer = annotation.value.id if isinstance(annotation.value, ast.Name) else annotation.value.attr
        if outer in ("Optional", "Union"):
            inner = annotation.slice
            items = inner.elts if isinstance(inner, ast.Tuple) else [inner]
            return any(_is_any(i) for i in items)
    return False


def _public_module(name: str) -> bool:
    return not any(_private(part) for part in name.split("."))


def _public_functions(module: Module) -> Iterator[tuple[str, ast.FunctionDef | ast.AsyncFunctionDef]]:
    for node in module.tree.body:
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and not _private(node.name):
            yield node.name, node
        elif isinstance(node, ast.ClassDef) and not _private(node.name):
            for item in node.body:
                if isinstance(item, ast.FunctionDef | ast.AsyncFunctionDef) and (
                        not item.name.startswith("_") or item.name in ("__init__", "__call__")):
                    yield f"{node.name}.{item.name}", item


def _dataclass_fields(module: Module) -> Iterator[tuple[str, ast.ClassDef, list[ast.AnnAssign]]]:
    """Public dataclasses and their fields: the parameters of their generated ``__init__``."""
    for node in module.tree.body:
        if (isinstance(node, ast.ClassDef) and not _private(node.name)
                and any("dataclass" in ast.unparse(d) for d in node.decorator_list)):
            fields = [item for item in node.body if isinstance(item, ast.AnnAssign)
                      and isinstance(item.target, ast.Name)
                      and "ClassVar" not in ast.unparse(item.annotation)]
            yield node.name, node, fields


def any_violations(modules: Mapping[str, Module]) -> list[str]:
    """Public functions (and public methods of public classes, and the fields of public
    dataclasses, which are parameters of their ``__init__``) of public modules with a
    parameter annotated ``Any`` (``*args: Any`` and ``**kwargs: Any`` only forward)."""
    out = []
    for module in modules.values():
        if not _public_module(module.name):
            continue
        for qualname, fn in _public_functions(module):
            a = fn.args
            bad = [p.arg for p in a.posonlyargs + a.args + a.kwonlyargs if _is_any(p.annotation)]
            if bad:
                out.append(f"{_where(module, fn.lineno)}: {module.name}.{qualname} has parameter(s) "
                           f"annotated Any: {', '.join(bad)}")
        for name, cls, fields in _dataclass_fields(module):
            bad = [f.target.id for f in fields if _is_any(f.annotation)]  # type: ignore[union-attr]
            if bad:
                out.append(f"{_where(module, cls.lineno)}: {module.name}.{name} (a dataclass) has "
                           f"field(s) annotated Any: {', '.join(bad)}")
    return sorted(out)


# --------------------------------------------------------------------------- rule: __all__
def declared_all(module: Module) -> list[str] | None:
    """The names of a module's literal ``__all__``; None when it has none."""
    for node in module.tree.body:
        targets = (node.targets if isinstance(node, ast.Assign)
                   else [node.target] if isinstance(node, ast.AnnAssign) and node.value else [])
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
            value = node.value
            if isinstance(value, ast.List | ast.Tuple) and all(
                    isinstance(e, ast.Constant) and isinstance(e.value, str) for e in value.elts):
                return [e.value for e in value.elts]  # type: ignore[attr-defined]
            return ["<__all__ is not a literal list of strings>"]
    return None


def defined_names(module: Module) -> set[str]:
    """Names bound at the top level of a module (including under ``if``/``try``)."""
    names: set[str] = set()

    def bind(target: ast.expr) -> None:
        if isinstance(target, ast.Name):
            names.add(target.id)
        elif isinstance(target, ast.Tuple | ast.List):
            for t in target.elts:
                bind(t)

    def scan(body: list[ast.stmt]) -> None:
        for node in body:
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                names.add(node.name)
            elif isinstance(node, ast.Assign):
                for t in node.targets:
                    bind(t)
            elif isinstance(node, ast.AnnAssign | ast.AugAssign):
                bind(node.target)
            elif isinstance(node, ast.Import | ast.ImportFrom):
                for a in node.names:
                    names.add(a.asname or a.name.split(".")[0])
            elif isinstance(node, ast.If | ast.Try | ast.With):
                scan(node.body)
                scan(getattr(node, "orelse", []))
                scan(getattr(node, "finalbody", []))
                for handler in getattr(node, "handlers", []):
                    scan(handler.body)
            elif isinstance(node, ast.TypeAlias) if sys.version_info >= (3, 12) else False:
                bind(node.name)

    scan(module.tree.body)
    return names


def all_violations(modules: Mapping[str, Module], import_lazy: bool = True) -> list[str]:
    out = []
    for module in modules.values():
        listed = declared_all(module)
        if listed is None:
            out.append(f"src/{module.path}: {module.name} has no __all__")
            continue
        defined = defined_names(module)
        lazy = "__getattr__" in defined
        for name in listed:
            if name in defined or (module.is_package and f"{module.name}.{name}" in modules):
                continue
            if lazy and import_lazy and hasattr(importlib.import_module(module.name), name):
                continue  # provided by the module's PEP 562 __getattr__
            out.append(f"src/{module.path}: {module.name}.__all__ lists {name!r}, "
                       "which the module does not define")
        for node in module.tree.body:
            if (isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef)
                    and not _private(node.name) and node.name not in listed
                    and not node.name.startswith("__")):
                out.append(f"{_where(module, node.lineno)}: {module.name}.{node.name} is neither "
                           "in __all__ nor underscored")
    return sorted(out)


# --------------------------------------------------------------------------- the API pages
#: The documentation's Python API pages (mkdocs, ``mkdocs.yml``): generated, never edited.
API_DOCS = REPO / "docs" / "reference" / "api"
#: Packages with an API page of their own; every other module is on the ``odomkit`` page.
API_GROUPS = ("calibrate", "io", "noise", "plot", "propagate", "simulate", "workflows")
GENERATED = "<!-- generated by `python tests/test_architecture.py` from the __all__ lists: do not edit -->"


def api_modules(modules: Mapping[str, Module]) -> list[str]:
    """The modules whose ``__all__`` is the documented Python API: every public module
    except the command line (its interface is the commands, documented on their pages)."""
    return sorted(m for m in modules if _public_module(m) and not _inside(m, "odomkit.cli"))


def api_group(name: str) -> str:
    """The API page (without ``.md``) that documents module ``name``."""
    parts = name.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in API_GROUPS else "odomkit"


def render_api_pages(modules: Mapping[str, Module]) -> dict[str, str]:
    """``{file name in docs/reference/api: text}``: ``index.md``, every module's ``__all__``
    with the module linked to its page, and one page per group holding a mkdocstrings
    ``::: module`` entry for each of its modules (which renders exactly ``__all__``)."""
    names = api_modules(modules)
    groups = sorted({api_group(n) for n in names}, key=lambda g: (g != "odomkit", g))
    pages = ", ".join("[odomkit](odomkit.md) (the top-level modules)" if g == "odomkit"
                      else f"[odomkit.{g}]({g}.md)" for g in groups)
    lines = ["# Python API", "", GENERATED, "",
             "The stable Python surface is exactly what each module's `__all__` lists; any other",
             "name (and every underscored one) may change without notice. "
             "`tests/test_architecture.py`",
             "checks these pages against the code (`python tests/test_architecture.py` rewrites them).",
             f"One page per package: {pages}.", ""]
    for name in names:
        listed = declared_all(modules[name])
        if listed is None:
            shown = "(no `__all__` yet)"
        elif not listed:
            shown = "its modules, listed here"
        else:
            shown = ", ".join(f"`{n}`" for n in listed)
        lines.append(f"- [`{name}`][{name}]: {shown}")
    out = {"index.md": "\n".join(lines) + "\n"}
    for group in groups:
        title = "odomkit: the top-level modules" if group == "odomkit" else f"odomkit.{group}"
        body = [f"# {title}", "", GENERATED, ""]
        body += [f"::: {n}\n" for n in names if api_group(n) == group]
        out[f"{group}.md"] = "\n".join(body)
    return out


def write_api_pages(modules: Mapping[str, Module], folder: Path = API_DOCS) -> list[Path]:
    """Write the generated pages (and remove generated pages of groups that are gone)."""
    folder.mkdir(parents=True, exist_ok=True)
    pages = render_api_pages(modules)
    for stale in folder.glob("*.md"):
        if stale.name not in pages and GENERATED in stale.read_text(encoding="utf-8"):
            stale.unlink()
    written = []
    for name, text in pages.items():
        path = folder / name
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
            written.append(path)
    return written


# =========================================================================== the checks
@pytest.fixture(scope="module")
def tree() -> dict[str, Module]:
    return load_tree()


def _report(violations: list[str]) -> str:
    return f"{len(violations)} violation(s):\n  " + "\n  ".join(violations)


def test_the_tree_is_found(tree):
    assert {"odomkit", "odomkit.cli", "odomkit.robot", "odomkit.errors"} <= set(tree)


def test_no_import_cycle_at_import_time(tree):
    found = cycle_violations(tree, {"module"})
    assert not found, _report(found)


def test_no_import_cycle_counting_lazy_imports(tree):
    found = cycle_violations(tree, {"module", "function"})
    assert not found, _report(found)


def test_no_private_name_crosses_modules(tree):
    found = private_violations(tree)
    assert not found, _report(found)


def test_core_imports_no_edge(tree):
    found = layer_violations(tree)
    assert not found, _report(found)


def test_no_public_parameter_is_any(tree):
    found = any_violations(tree)
    assert not found, _report(found)


def test_every_module_declares_its_public_names(tree):
    found = all_violations(tree)
    assert not found, _report(found)


def test_docs_list_the_public_api(tree):
    """docs/reference/api/ holds exactly the generated pages: every public module has its
    ``::: module`` entry, and the listing equals the ``__all__`` lists."""
    wanted = render_api_pages(tree)
    found = {p.name: p.read_text(encoding="utf-8") for p in API_DOCS.glob("*.md")}
    stale = sorted(set(wanted) ^ set(found))
    differ = sorted(n for n in set(wanted) & set(found) if wanted[n] != found[n])
    assert not stale and not differ, (
        f"docs/reference/api/ is out of date (missing or extra: {stale}, differing: {differ}); "
        "run `python tests/test_architecture.py` to rewrite it (and add a new page to mkdocs.yml's nav)")


# =========================================================================== self-tests
def _snippets(files: Mapping[str, str]) -> dict[str, Module]:
    """``{"pkg/a": source}`` -> parsed modules (``pkg/__init__`` for a package)."""
    return load_sources({f"{path}.py": textwrap.dedent(text) for path, text in files.items()})


def test_self_cycle_at_import_time_is_found():
    modules = _snippets({"pkg/__init__": "__all__ = []", "pkg/a": "import pkg.b\n__all__ = []",
                         "pkg/b": "from pkg import a\n__all__ = []"})
    found = cycle_violations(modules, {"module"})
    assert len(found) == 1 and "pkg.a, pkg.b" in found[0]


def test_self_lazy_cycle_is_found_only_when_lazy_imports_count():
    modules = _snippets({
        "pkg/__init__": "",
        "pkg/a": "import pkg.b\n",
        "pkg/b": "def f():\n    from pkg.a import g\n",
        "pkg/c": "def h():\n    import importlib\n    importlib.import_module('pkg.a')\n",
    })
    assert cycle_violations(modules, {"module"}) == []
    found = cycle_violations(modules, {"module", "function"})
    assert len(found) == 1 and "pkg.b -> pkg.a (function" in found[0]
    assert "pkg.c" not in found[0]  # c -> a is an edge, but no cycle
    assert "pkg.a" in import_graph(modules, {"function"})["pkg.c"]


def test_self_type_checking_imports_are_no_cycle():
    modules = _snippets({
        "pkg/__init__": "",
        "pkg/a": "import pkg.b\n",
        "pkg/b": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.a import X\n",
    })
    assert cycle_violations(modules, {"module", "function"}) == []


def test_self_private_names_are_found():
    modules = _snippets({
        "pkg/__init__": "",
        "pkg/a": "_x = 1\ndef _f(): pass\n",
        "pkg/b": "from pkg.a import _f\n",  # private name
        "pkg/c": "import pkg.a as a\ny = a._x\n",  # private attribute
        "pkg/d": "from pkg.sub import _kern\n",  # private module, from outside its package
        "pkg/sub/__init__": "",
        "pkg/sub/_kern": "",
        "pkg/sub/e": "from pkg.sub import _kern\nfrom . import _kern as k\n",  # inside: fine
        "pkg/f": "from pkg.a import __doc__\n",  # a dunder is not private
    })
    found = private_violations(modules)
    assert any("pkg.b imports private name _f from pkg.a" in v for v in found)
    assert any("pkg.c uses private name _x of pkg.a" in v for v in found)
    assert any("pkg.d imports private module pkg.sub._kern" in v for v in found)
    assert not any("pkg.sub.e" in v or "pkg.f " in v for v in found), found
    assert len(found) == 3, found


def test_self_core_importing_an_edge_is_found():
    modules = _snippets({
        "odomkit/__init__": "",
        "odomkit/robot": "def f():\n    import matplotlib.pyplot as plt\n",
        "odomkit/track": "from odomkit.io.csvlog import read\n",
        "odomkit/kinematics": "import numpy\nfrom odomkit.robot import f\n",
        "odomkit/io/__init__": "",
        "odomkit/io/csvlog": "import tomllib\n",
        "odomkit/cli/x": "import typer\nfrom rich import print\n",
    })
    found = layer_violations(modules)
    assert len(found) == 2, found
    assert any("odomkit.robot imports matplotlib.pyplot (function level)" in v for v in found)
    assert any("odomkit.track imports odomkit.io.csvlog" in v for v in found)


def test_self_any_parameters_are_found():
    modules = _snippets({"pkg/m": """
        from typing import Any, Optional
        def f(x: Any) -> None: ...
        def g(x: "Any | None" = None, *args: Any, **kw: Any) -> Any: ...
        def h(*, x: Optional[Any] = None) -> None: ...
        def ok(x: list[Any], *args: Any, **kw: Any) -> Any: ...
        def _private(x: Any) -> None: ...
        class C:
            def __init__(self, x: Any) -> None: ...
            def _p(self, x: Any) -> None: ...
        @dataclass(frozen=True)
        class D:
            kind: ClassVar[Any] = None
            noise: Any
            ok: list[Any]
        """, "pkg/_hidden": "from typing import Any\ndef f(x: Any): ...\n"})
    found = any_violations(modules)
    assert sorted(v.split(": ", 1)[1] for v in found) == [
        "pkg.m.C.__init__ has parameter(s) annotated Any: x",
        "pkg.m.D (a dataclass) has field(s) annotated Any: noise",
        "pkg.m.f has parameter(s) annotated Any: x",
        "pkg.m.g has parameter(s) annotated Any: x",
        "pkg.m.h has parameter(s) annotated Any: x",
    ]


def test_self_all_rules_are_enforced():
    modules = _snippets({
        "pkg/__init__": "from pkg.a import f\n__all__ = ['f', 'a']\n",
        "pkg/a": "def f(): pass\ndef g(): pass\ndef _h(): pass\n__all__ = ['f', 'missing']\n",
        "pkg/b": "X = 1\n",
        "pkg/c": "import os\nif os.name:\n    Y = 1\n__all__ = ['Y']\n",
    })
    found = all_violations(modules, import_lazy=False)
    assert len(found) == 3, found
    assert any("pkg.b has no __all__" in v for v in found)
    assert any("lists 'missing'" in v for v in found)
    assert any("pkg.a.g is neither in __all__ nor underscored" in v for v in found)


def test_self_api_pages_are_generated(tmp_path):
    modules = _snippets({"odomkit/__init__": "__all__ = ['E']\nclass E(Exception): pass\n",
                         "odomkit/cli/__init__": "__all__ = ['main']\ndef main(): pass\n",
                         "odomkit/_jit": "__all__ = ['k']\nk = 1\n",
                         "odomkit/noise/__init__": "__all__ = ['W']\nW = 1\n",
                         "odomkit/noise/wheel": "__all__ = []\n"})
    pages = render_api_pages(modules)
    assert set(pages) == {"index.md", "odomkit.md", "noise.md"}
    assert "- [`odomkit`][odomkit]: `E`" in pages["index.md"]
    assert "- [`odomkit.noise.wheel`][odomkit.noise.wheel]: its modules, listed here" in pages["index.md"]
    assert "cli" not in "".join(pages.values()) and "_jit" not in "".join(pages.values())
    assert "::: odomkit\n" in pages["odomkit.md"] and "::: odomkit.noise.wheel\n" in pages["noise.md"]
    (tmp_path / "old.md").write_text(f"# x\n\n{GENERATED}\n")
    (tmp_path / "mine.md").write_text("# not generated\n")
    assert len(write_api_pages(modules, tmp_path)) == 3
    assert not (tmp_path / "old.md").exists() and (tmp_path / "mine.md").exists()
    assert write_api_pages(modules, tmp_path) == []


if __name__ == "__main__":
    changed = write_api_pages(load_tree())
    print("\n".join(f"wrote {p.relative_to(REPO)}" for p in changed) or "docs/reference/api/ is up to date")
