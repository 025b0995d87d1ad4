"""The documentation's examples work (issue 13, item 4): README.md and every page of docs/.

* every ```` ```python ```` block runs: in a temporary folder, each page's blocks in order in
  one namespace (a block may use what an earlier block of its page defined);
* every ``odomkit ...`` command shown in any other block names a command that exists and
  only flags that command has (synopses included: ``[--method exact|midpoint|euler]``);
* the commands of the console blocks marked ``<!-- run -->`` run for real on the built-in
  OptiOdom data, each page's in one temporary folder in page order, exit 0, and print every
  line the page shows (``...`` stands for lines left out), in that order;
* ``mkdocs build --strict`` passes (skipped, with the reason, where mkdocs is not installed);
* the README starts with the two commands and stays short, and ``.ci/run`` runs exactly the
  README's test command.

A block that cannot run is marked ``<!-- skip: why -->`` on the line before it, a long one
``<!-- slow -->`` (its page's Python test is then marked ``slow``).
"""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
DATA = REPO / "src" / "odomkit" / "data"
PAGES = [REPO / "README.md"] + sorted(p for p in DOCS.rglob("*.md") if "hooks" not in p.parts)
#: Blocks that hold no command lines.
NOT_SHELL = {"python", "toml", "yaml", "json"}
_MARKER = re.compile(r"<!--\s*(skip|slow|run)\b[^>]*-->")
_FLAG = re.compile(r"(?<![\w-])(--[a-z][a-z0-9-]*)")


@dataclass(frozen=True)
class Block:
    page: Path
    line: int  # of the opening fence, 1-based
    lang: str
    text: str
    marker: str | None  # "skip", "slow", "run" or None

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(REPO)}:{self.line}"


def blocks(page: Path) -> list[Block]:
    """The fenced code blocks of a Markdown page, with the marker comment just before each."""
    out, lines = [], page.read_text(encoding="utf-8").split("\n")
    i = 0
    while i < len(lines):
        fence = re.match(r"^(\s*)(`{3,})\s*([\w-]*)", lines[i])
        if not fence:
            i += 1
            continue
        indent, ticks, lang = fence.groups()
        before = next((ln for ln in reversed(lines[:i]) if ln.strip()), "")
        marker = _MARKER.search(before)
        end = i + 1
        while end < len(lines) and not lines[end].strip().startswith(ticks):
            end += 1
        body = "\n".join(ln[len(indent):] if ln.startswith(indent) else ln for ln in lines[i + 1:end])
        out.append(Block(page, i + 1, lang.lower(), body, marker.group(1) if marker else None))
        i = end + 1
    return out


def _page_id(page: Path) -> str:
    return str(page.relative_to(REPO))


# ------------------------------------------------------------------------- python blocks
def _python_pages() -> list:
    params = []
    for page in PAGES:
        found = [b for b in blocks(page) if b.lang == "python" and b.marker != "skip"]
        if found:
            marks = [pytest.mark.slow] if any(b.marker == "slow" for b in found) else []
            params.append(pytest.param(page, marks=marks, id=_page_id(page)))
    return params


@pytest.mark.parametrize("page", _python_pages())
def test_python_examples_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    namespace: dict[str, object] = {"__name__": "__docs__"}
    for block in blocks(page):
        if block.lang != "python" or block.marker == "skip":
            continue
        code = compile(block.text, block.where, "exec")
        try:
            exec(code, namespace)
        except Exception as exc:  # name the page and line of the block that failed
            raise AssertionError(f"the ```python block at {block.where} fails: "
                                 f"{type(exc).__name__}: {exc}") from exc


def test_skipped_blocks_are_few():
    skipped = [b.where for page in PAGES for b in blocks(page) if b.marker == "skip"]
    assert len(skipped) <= 3, skipped


# ------------------------------------------------------------------------- commands shown
def command_lines(block: Block) -> list[str]:
    """The ``odomkit ...`` command lines of a block, continuation lines joined. In a
    transcript (a block with ``$ `` prompts) only the prompted lines are commands."""
    lines = block.text.split("\n")
    transcript = any(ln.startswith("$ ") for ln in lines)
    out: list[str] = []
    joining = False
    for line in lines:
        if joining:
            out[-1] += " " + line.strip().rstrip("\\").rstrip()
            joining = line.rstrip().endswith("\\")
            continue
        if out and not transcript and line[:1].isspace() and line.strip().startswith(("[", "--", "$(")):
            out[-1] += " " + line.strip().rstrip("\\").rstrip()
            continue
        text = line[2:] if transcript and line.startswith("$ ") else (None if transcript else line)
        if text is not None and text.startswith("odomkit "):
            out.append(text.rstrip().rstrip("\\").rstrip())
            joining = text.rstrip().endswith("\\")
    return out


@pytest.fixture(scope="module")
def cli_commands() -> dict[str, set[str]]:
    """command name -> every flag it takes (click's own option objects)."""
    import typer.main

    from odomkit.cli import (
        app,
        commands,  # noqa: F401  (registers the commands)
    )

    group = typer.main.get_command(app)
    out = {}
    for name, command in group.commands.items():  # type: ignore[attr-defined]
        flags = {"--help"}
        for param in command.params:
            flags |= {o for o in (*param.opts, *getattr(param, "secondary_opts", ())) if o.startswith("--")}
        out[name] = flags
    return out


def _shell_blocks() -> list:
    params = []
    for page in PAGES:
        found = [b for b in blocks(page) if b.lang not in NOT_SHELL and command_lines(b)]
        if found:
            params.append(pytest.param(page, id=_page_id(page)))
    return params


@pytest.mark.parametrize("page", _shell_blocks())
def test_commands_shown_exist(page, cli_commands):
    wrong = []
    for block in blocks(page):
        if block.lang in NOT_SHELL:
            continue
        for command in command_lines(block):
            name = command.split()[1]
            if name not in cli_commands:
                wrong.append(f"{block.where}: no command {name!r} in `{command}`")
                continue
            unknown = sorted(set(_FLAG.findall(command)) - cli_commands[name])
            if unknown:
                wrong.append(f"{block.where}: odomkit {name} has no {', '.join(unknown)}")
    assert not wrong, "\n".join(wrong)


def test_command_lines_are_found():
    """Self-test of the extraction, on a synopsis and a transcript."""
    page = REPO / "x.md"
    synopsis = Block(page, 1, "", "odomkit track LOG --robot R [--out F] \\\n    [--tum T]\n"
                     "odomkit fit-amcl ODOM [--model diff|omni]\n    [--yaml-out Y]\n"
                     "  odomkit simulate: 100 runs", None)
    assert command_lines(synopsis) == ["odomkit track LOG --robot R [--out F] [--tum T]",
                                       "odomkit fit-amcl ODOM [--model diff|omni] [--yaml-out Y]"]
    transcript = Block(page, 1, "console", "$ odomkit predict --k-left 1 \\\n    --json\n"
                       "   odomkit predict (wheel model)\n$ cat x", None)
    assert command_lines(transcript) == ["odomkit predict --k-left 1 --json"]
    assert _FLAG.findall("odomkit track x --no-covariance [--engine recursion|transition]") == [
        "--no-covariance", "--engine"]


# ------------------------------------------------------------------------- commands run
def transcript(block: Block) -> list[tuple[str, list[str]]]:
    """``[(command, lines shown after it)]`` of a console block."""
    steps: list[tuple[str, list[str]]] = []
    continued = False
    for line in block.text.split("\n"):
        if continued:
            steps[-1] = (steps[-1][0] + "\n" + line, steps[-1][1])
        elif line.startswith("$ "):
            steps.append((line[2:], []))
        elif steps and line.strip():
            steps[-1][1].append(line.rstrip())
        continued = line.rstrip().endswith("\\") and bool(steps) and not steps[-1][1]
    return steps


def _run_pages() -> list:
    return [pytest.param(page, id=_page_id(page)) for page in PAGES
            if any(b.marker == "run" for b in blocks(page))]


@pytest.mark.parametrize("page", _run_pages())
def test_commands_marked_run_print_what_the_page_shows(page, tmp_path):
    for path in [*DATA.glob("230620202042_*"), DATA / "optiodom_diff.toml"]:
        shutil.copy(path, tmp_path / path.name)
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}",
           "COLUMNS": "200", "MPLBACKEND": "Agg"}
    for block in blocks(page):
        if block.marker != "run":
            continue
        assert block.lang == "console", f"{block.where}: only ```console blocks can be run"
        for command, shown in transcript(block):
            done = subprocess.run(["bash", "-c", command], cwd=tmp_path, env=env, capture_output=True,
                                  text=True, timeout=300)
            assert done.returncode == 0, (f"{block.where}: `{command}` exited {done.returncode}:\n"
                                          f"{done.stderr}")
            printed = [ln.rstrip() for ln in (done.stdout + done.stderr).split("\n")]
            at = 0
            for line in shown:
                if line.strip() == "...":
                    continue
                try:
                    at = printed.index(line, at) + 1
                except ValueError:
                    pytest.fail(f"{block.where}: `{command}` no longer prints (in this order)\n  {line}\n"
                                f"it printed:\n{done.stdout}{done.stderr}\nupdate the page with what it "
                                "prints now")


def test_transcript_is_parsed():
    block = Block(REPO / "x.md", 1, "console", "$ odomkit a \\\n    --b\nline 1\n...\n\n$ cat f\nx", "run")
    assert transcript(block) == [("odomkit a \\\n    --b", ["line 1", "..."]), ("cat f", ["x"])]


# ------------------------------------------------------------------------- the site builds
def test_site_builds_strict(tmp_path):
    missing = [m for m in ("mkdocs", "material", "mkdocstrings_handlers.python")
               if importlib.util.find_spec(m.split(".")[0]) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed: `make docs` (or pip install -e '.[docs]') "
                    "installs them")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                           str(tmp_path / "site")], cwd=REPO, capture_output=True, text=True,
                          env={**os.environ, "NO_MKDOCS_2_WARNING": "1"}, timeout=600)
    problems = [ln for ln in done.stderr.splitlines() if ln.startswith(("WARNING", "ERROR"))]
    assert done.returncode == 0, "mkdocs build --strict failed:\n" + "\n".join(problems or [done.stderr])
    assert (tmp_path / "site" / "index.html").is_file()


# ------------------------------------------------------------------------- the README
def test_readme_starts_with_the_two_commands_and_stays_short():
    text = (REPO / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) < 200
    first = blocks(REPO / "README.md")[0]
    commands = [ln.split("#")[0].strip() for ln in first.text.splitlines()]
    assert commands == ["make demo", "make test"]
    assert text.index("make demo") < text.index("\n## ")


def test_ci_runs_exactly_the_readme_test_command():
    ci = [ln.strip() for ln in (REPO / ".ci" / "run").read_text().splitlines()
          if ln.strip() and not ln.startswith("#") and not ln.startswith(("set ", "cd "))]
    assert ci == ["make test"]


# ------------------------------------------------------------------------- the honesty page
def honesty_table(page: Path = DOCS / "results" / "honesty.md") -> dict[tuple[str, str], list[str]]:
    """``{(noise, fitted in): cells}`` of the OptiOdom differential table."""
    text = page.read_text(encoding="utf-8").split("**OptiOdom differential**", 1)[1]
    rows = {}
    for line in text.split("\n| noise |", 1)[1].splitlines()[2:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        rows[(cells[0], cells[1])] = cells
    return rows


def test_honesty_page_is_the_table_test_honesty_checks():
    """tests/test_honesty.py (slow, real data) holds the page's numbers true; here, that its
    numbers are the page's (the lead updates both, issue 11)."""
    spec = importlib.util.spec_from_file_location("honesty_test", REPO / "tests" / "test_honesty.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    rows = honesty_table()
    which = {"guess": ("robot file's guess", "—"), "white 10s": ("white", "10 s windows"),
             "white+slip+bias trimmed": ("white + slip + bias, trimmed", "10 s and 30 s"),
             "defaults": ("white + slip + bias + truth noise, trimmed (fit-noise's defaults)",
                          "10 s and 30 s")}
    for fit, (noise, fitted_in) in which.items():
        assert (noise, fitted_in) in rows, (
            f"docs/results/honesty.md has no row ({noise!r}, {fitted_in!r}) for tests/test_honesty.py's "
            f"{fit!r}: keep the page's table and that test's README dict in step")
        cells = rows[(noise, fitted_in)]
        met = [m.strip().strip("*").split()[0] == "yes" for m in cells[7].split("/")]
        for (window, (coverage, nees, meets)), inside, mean, page_meets in zip(
                module.README[fit].items(), (cells[3], cells[5]), (cells[4], cells[6]), met, strict=True):
            # "0.51 / 0.87 / 0.91 / 0.95 (0.88–0.94)": the four fractions, then the interval.
            assert tuple(float(c) for c in inside.split("(")[0].split("/")) == coverage, (fit, window)
            assert float(mean) == nees, (fit, window)
            assert page_meets is meets, (fit, window)
