"""Every option with a unit shows it in ``--help``, as ``[unit]`` (issue 10, item 9).

The help is read as the user sees it (``odomkit COMMAND --help``, rendered by click), so a
renderer that eats ``[m]`` as markup (rich did) fails here too. A float option that is in
neither table below fails: a new option has to say its unit, or say that it has none.
"""

from __future__ import annotations

import re

import pytest

COMMANDS = ("track", "predict", "simulate", "umbmark", "calibrate", "calibrate-noise", "evaluate",
            "fit-noise", "fit-amcl", "check", "demo", "report")

#: option -> the unit(s) its help must show, each as "[...]", in every command that has it.
UNITS: dict[str, tuple[str, ...]] = {
    # log and truth options
    "--period": ("s",),
    "--truth-sigma": ("m",),
    "--truth-heading-sigma": ("rad",),
    "--truth-time-sigma": ("s",),
    "--truth-time-offset": ("s",),
    "--max-gap": ("s",),
    # poses and covariances
    "--initial-pose": ("m, m, rad",),
    "--initial-cov": ("m², m², rad²",),
    "--initial-cov-matrix": ("m², m·rad, rad²",),
    # paths and noise (predict, simulate)
    "--segment": ("m", "rad", "m/s, rad/s, s", "m/s, s"),
    "--wheel-base": ("m",),
    "--k-left": ("m^½",),
    "--k-right": ("m^½",),
    "--sigma-distance": ("m",),
    "--sigma-angle": ("rad",),
    "--speed-noise": ("m",),
    "--gyro-noise": ("rad²/s",),
    "--heading-noise": ("rad²·s",),
    "--compass-period": ("s",),
    "--sample-period": ("s",),
    "--lateral-noise": ("m²/m",),
    "--turn-noise": ("rad²/rad",),
    "--turn-travel-noise": ("m²/rad",),
    # calibration and evaluation
    "--side": ("m",),
    "--heading-weight": ("m/rad",),
    "--wheel-radius": ("m",),
    "--twist-speed": ("m/s",),
    "--controller-period": ("s",),
    "--min-travel": ("m",),
    "--rpe": ("m",),
    "--update-min-d": ("m",),
    "--update-min-a": ("rad",),
}

#: Float options that are pure numbers: a probability or a count of work.
UNITLESS = {"--level", "--alpha", "--max-work", "--trim"}


def _options(help_text: str) -> dict[str, str]:
    """Each option of a rendered help (every spelling, e.g. --time-unit and --time-scale) ->
    its help text on one line."""
    section = help_text.split("Options:", 1)[1]
    entries: list[list[str]] = []
    for line in section.splitlines():
        if re.match(r"^  -", line):
            entries.append([line])
        elif entries and line.startswith("   "):
            entries[-1].append(line)
    options = {}
    for lines in entries:
        first = re.match(r"^  (\S.*?)(?:\s{2,}(.*))?$", lines[0])
        assert first, lines[0]
        head, text = first.group(1), first.group(2) or ""
        text = " ".join(" ".join([text, *lines[1:]]).split())
        for flag in re.findall(r"(?<![\w-])--[\w-]+", head):
            options[flag] = text
    return options


@pytest.fixture(scope="module")
def helps() -> dict[str, dict[str, str]]:
    import contextlib
    import io

    from odomkit.cli import main

    out = {}
    for command in COMMANDS:
        text = io.StringIO()
        with contextlib.redirect_stdout(text):
            assert main([command, "--help"]) == 0
        out[command] = _options(text.getvalue())
    return out


def test_the_parser_reads_wrapped_help():
    text = ("Usage: x\n\nOptions:\n  --side FLOAT      Side L of the square [m]\n"
            "                    (required).\n  --time-unit, --time-scale <str>\n"
            "                    Unit of the time column.  [default: s]\n  --help  Show this.\n")
    assert _options(text) == {"--side": "Side L of the square [m] (required).",
                              "--time-unit": "Unit of the time column. [default: s]",
                              "--time-scale": "Unit of the time column. [default: s]",
                              "--help": "Show this."}


@pytest.mark.parametrize("command", COMMANDS)
def test_every_option_with_a_unit_shows_it(helps, command):
    missing = [f"{flag} lacks [{unit}]: {text!r}" for flag, text in helps[command].items()
               for unit in UNITS.get(flag, ()) if f"[{unit}]" not in text]
    assert not missing, "\n".join(missing)


@pytest.mark.parametrize("command", COMMANDS)
def test_every_float_option_is_in_a_table(command):
    """A float option says its unit (UNITS) or that it has none (UNITLESS)."""
    import typer

    from odomkit.cli import commands  # noqa: F401  (registers the commands)
    from odomkit.cli.application import app

    group = typer.main.get_command(app)
    floats = {param.opts[0] for param in group.commands[command].params  # type: ignore[attr-defined]
              if getattr(param.type, "name", "") == "float"}
    unknown = sorted(floats - set(UNITS) - UNITLESS)
    assert not unknown, f"{command}: give {unknown} a unit in its help and in UNITS (or UNITLESS)"


def test_units_are_written_one_way(helps):
    """One style: square brackets, ½ not 1/2, no unit spelled out in words beside a number."""
    for command, options in helps.items():
        for flag, text in options.items():
            assert "m^1/2" not in text, (command, flag, text)
            assert not re.search(r"\bin metres\b|, metres\b", text), (command, flag, text)
