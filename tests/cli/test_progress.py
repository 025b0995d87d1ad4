"""The progress bar of the long commands (issue 13 item 3): on a terminal's stderr, and
nothing extra when the output is piped or ``--json``.

The terminal is a real pseudo-terminal (:mod:`pty`) given to a fresh ``odomkit`` process as
its stderr; stdout stays a pipe, so the test also sees that the bar never lands there.
"""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys

import pytest

from odomkit.cli.progress import progress_bar, wants_bar
from odomkit.progress import NO_PROGRESS

pty = pytest.importorskip("pty", reason="pseudo-terminals need a POSIX system")

ODOMKIT = [sys.executable, "-c", "import sys; from odomkit.cli import main; sys.exit(main(sys.argv[1:]))"]
DIFF = ["--segment", "arc:3,1", "--wheel-base", "0.4", "--k-left", "0.001", "--k-right", "0.001"]
#: 10⁸ partition steps, about 2 s: longer than the bar's delay (0.5 s) on any machine.
LONG = ["--runs", "20000", "--partitions", "5000", "--seed", "3", "--workers", "1"]
BAR = "━"  # rich's bar; the table's rules are ─ and ━ too, so stderr alone is searched


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("ODOMKIT_NO_PROGRESS", "NO_COLOR")}
    env.update({"TERM": "xterm-256color", "COLUMNS": "100", **extra})
    return env


def _run(args: list[str], *, terminal: bool, env: dict[str, str] | None = None) -> tuple[int, str, str]:
    """Run odomkit with stdout a pipe and stderr a pseudo-terminal (``terminal``) or a pipe."""
    if not terminal:
        done = subprocess.run(ODOMKIT + args, capture_output=True, text=True, env=env or _env(), timeout=300)
        return done.returncode, done.stdout, done.stderr
    master, slave = pty.openpty()
    proc = subprocess.Popen(ODOMKIT + args, stdout=subprocess.PIPE, stderr=slave, env=env or _env())
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # the child closed its end
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    out, _ = proc.communicate(timeout=300)
    return proc.returncode, out.decode(), b"".join(chunks).decode(errors="replace")


def _table_rows(text: str) -> list[str]:
    """The table's rows (the title holds the wall-clock time and is left out)."""
    return [line for line in text.splitlines() if line.startswith(("│", "|"))]


# --- when a bar is wanted ------------------------------------------------------------------------

def test_a_bar_needs_a_terminal_no_json_and_no_opt_out():
    env = {"TERM": "xterm"}
    assert wants_bar(False, _Terminal(), env)
    assert not wants_bar(True, _Terminal(), env)  # --json: a machine reads the output
    assert not wants_bar(False, io.StringIO(), env)  # piped or redirected
    assert not wants_bar(False, _Terminal(), {"TERM": "dumb"})
    assert not wants_bar(False, _Terminal(), {"TERM": "xterm", "ODOMKIT_NO_PROGRESS": "1"})
    assert wants_bar(False, _Terminal(), {"TERM": "xterm", "ODOMKIT_NO_PROGRESS": ""})


def test_without_a_terminal_the_commands_get_the_null_progress():
    with progress_bar(False) as progress:  # pytest captures stderr: not a terminal
        assert progress is NO_PROGRESS
    with progress_bar(True) as progress:
        assert progress is NO_PROGRESS


def test_importing_the_command_line_loads_no_rich():
    code = ("import sys; from odomkit.cli import commands, progress; import odomkit.progress; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'rich'))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


# --- piped: nothing extra -----------------------------------------------------------------------

def test_in_process_runs_print_no_bar(run_cli):
    code, out, err = run_cli("simulate", *DIFF, "--runs", "2000", "--partitions", "50")
    assert code == 0 and err == "", err
    assert _table_rows(out)


def test_a_piped_long_run_prints_no_bar_and_the_same_json():
    code, out, err = _run(["simulate", *DIFF, *LONG, "--json"], terminal=False)
    assert code == 0 and err == "", err
    piped = json.loads(out)
    # --json on a terminal: still no bar, and the same numbers
    code, out, err = _run(["simulate", *DIFF, *LONG, "--json"], terminal=True)
    assert code == 0 and BAR not in err and "\x1b[" not in err, err
    on_terminal = json.loads(out)
    piped.pop("seconds"), on_terminal.pop("seconds")
    assert on_terminal == piped


# --- a terminal: a bar on stderr ----------------------------------------------------------------

def test_simulate_on_a_terminal_shows_a_bar_on_stderr_only():
    code, out, err = _run(["simulate", *DIFF, *LONG], terminal=True)
    assert code == 0, err
    assert "Monte Carlo runs" in err and BAR in err and "/20000" in err, err[:500]
    assert "Monte Carlo runs" not in out and "\x1b[" not in out  # stdout: the table only
    code, piped, _ = _run(["simulate", *DIFF, *LONG], terminal=False)
    assert code == 0 and _table_rows(out) == _table_rows(piped) != []


@pytest.mark.parametrize("env", [{"TERM": "dumb"}, {"ODOMKIT_NO_PROGRESS": "1"}])
def test_the_bar_can_be_turned_off_on_a_terminal(env):
    code, _, err = _run(["simulate", *DIFF, *LONG], terminal=True, env=_env(**env))
    assert code == 0 and "Monte Carlo runs" not in err and BAR not in err, err[:500]


def test_an_error_on_a_terminal_is_its_one_line(tmp_path):
    code, out, err = _run(["track", str(tmp_path / "missing.csv"), "--robot", str(tmp_path / "r.toml")],
                          terminal=True)
    assert code == 2 and out == ""
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("odomkit: error: ") and "\x1b[" not in err, err
