"""Usage mistakes are one line on stderr, exit 2, like every other error (issue 10, item 8)."""

from __future__ import annotations

import pytest

from odomkit.data import builtin_data_path

RUN = builtin_data_path("230620202042_run-01.csv")
ROBOT = builtin_data_path("optiodom_diff.toml")


def _one_line(code: int, err: str) -> str:
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("odomkit: error: "), err
    return lines[0]


def test_an_unknown_command_lists_the_commands(run_cli):
    line = _one_line(*run_cli("bogus")[::2])
    assert line.startswith("odomkit: error: no such command 'bogus'; commands: ")
    for command in ("track", "predict", "simulate", "umbmark", "calibrate", "calibrate-noise", "demo"):
        assert command in line.split("commands: ")[1].split(", ")


@pytest.mark.parametrize("args, message", [
    (["track", str(RUN), "--robot", str(ROBOT), "--bogus"], "no such option: --bogus"),
    (["track", "--robot", str(ROBOT)], "missing argument"),
    (["track", str(RUN), "--robot"], "'--robot' requires an argument"),
    (["track", str(RUN), "--robot", str(ROBOT), "--decimate", "many"], "'many' is not a valid int"),
])
def test_usage_mistakes_are_one_line_naming_the_help(run_cli, args, message):
    line = _one_line(*run_cli(*args)[::2])
    assert message in line
    assert "odomkit track --help" in line


def test_help_still_works(run_cli):
    code, out, err = run_cli("track", "--help")
    assert code == 0 and "Usage: odomkit track" in out and err == ""
