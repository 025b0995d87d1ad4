"""The shared-flag decorator (odomkit.cli.shared_flags): every command that reads a log has
exactly the log flags of LOG_FLAGS, every command with truth those of TRUTH_FLAGS, declared
once; the parsed value reaches the command; and it composes with typer's own parsing."""

from __future__ import annotations

import inspect
from typing import Annotated

import click
import pytest
import typer
from typer.testing import CliRunner

from odomkit.cli.log_options import LOG_FLAGS
from odomkit.cli.shared_flags import with_flags
from odomkit.cli.truth_options import TRUTH_FLAGS


def _commands():
    from odomkit.cli import commands  # noqa: F401  (registers them)
    from odomkit.cli.application import app

    return typer.main.get_command(app).commands  # type: ignore[attr-defined]


def _flags(command: click.Command) -> set[str]:
    return {opt for p in command.params for opt in p.opts}


@pytest.mark.parametrize("name", ["track", "calibrate", "calibrate-noise", "umbmark", "fit-noise", "evaluate",
                                  "check", "fit-amcl", "report"])
def test_every_log_reading_command_has_each_log_flag_once(name):
    command = _commands()[name]
    flags = [opt for p in command.params for opt in p.opts]
    for _, annotation, _default in LOG_FLAGS:
        declared = annotation.__metadata__[0].param_decls
        assert set(declared) <= set(flags), (name, declared)
        assert all(flags.count(d) == 1 for d in declared), (name, declared)


@pytest.mark.parametrize("name", ["track", "calibrate", "fit-noise", "evaluate", "check", "fit-amcl",
                                  "report"])
def test_every_truth_command_has_the_truth_flags(name):
    flags = _flags(_commands()[name])
    for _, annotation, _ in TRUTH_FLAGS:
        assert set(annotation.__metadata__[0].param_decls) <= flags


def test_the_parsed_value_reaches_the_command_through_typer():
    app = typer.Typer()
    flag = ("level", Annotated[int, typer.Option("--level")], 3)
    seen = {}

    @app.command()
    @with_flags([flag], "twice", lambda v: 2 * v["level"])
    def run(name: Annotated[str, typer.Option("--name")] = "x", twice: int = 0) -> None:
        seen.update(name=name, twice=twice)

    assert CliRunner().invoke(app, ["--name", "y", "--level", "5"]).exit_code == 0
    assert seen == {"name": "y", "twice": 10}
    assert CliRunner().invoke(app, []).exit_code == 0
    assert seen == {"name": "x", "twice": 6}  # the flag's default, parsed


def test_a_command_must_take_the_value_and_not_declare_the_flags_itself():
    flag = ("level", Annotated[int, typer.Option("--level")], 3)
    with pytest.raises(TypeError, match="must take a parameter 'twice'"):
        with_flags([flag], "twice", lambda v: v)(lambda name: name)
    with pytest.raises(TypeError, match="declares shared flags itself"):
        with_flags([flag], "twice", lambda v: v)(lambda level, twice: level)


def test_force_and_json_stay_last():
    from odomkit.cli.fit_noise import fit_noise_command

    names = list(inspect.signature(fit_noise_command).parameters)
    assert names[-2:] == ["force", "json_out"]
