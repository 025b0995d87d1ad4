"""``odomkit check``: is a log fit to calibrate from, and what to record next.

::

    odomkit check LOG --robot ROBOT.toml [--truth GT] [--spin ccw|cw] [LOG OPTIONS] [--json]

Exit status 0 when no check fails, 1 when one does (a finding, not a usage error), 2 for
bad input as everywhere.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from odomkit.cli.application import app
from odomkit.cli.log_options import (
    reported_warnings,
    with_log_options,
    with_warnings,
)
from odomkit.cli.output import print_json
from odomkit.cli.truth_options import (
    TruthOption,
    with_truth_options,
)

if TYPE_CHECKING:
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions


__all__ = ["check_command", "print_findings"]


@app.command("check")
@with_log_options
@with_truth_options
def check_command(
    log: Annotated[Path, typer.Argument(help="The log to check.")],
    robot: Annotated[Path, typer.Option("--robot", help="Robot file (TOML) of the log.")],
    spin: Annotated[str | None, typer.Option(
        "--spin", help="The log is a spin in place, ccw or cw: checks the wheels without truth.")] = None,
    truth: TruthOption = None,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    *,
    log_opts: LogOptions,
    truth_base: TruthOptions,
) -> None:

    """Check a log before calibrating: time jumps, counter wraps, stuck encoders, NaNs, swapped or
    sign-flipped channels, turning both ways, distance, what each parameter can be fitted from;
    and say what to record next. Exit status 1 when a check fails."""
    from odomkit.workflows.check import check_file
    from odomkit.workflows.truth import with_truth_topic

    options, topts = with_truth_topic(log_opts, replace(truth_base, path=truth), truth is not None)
    # Reading the log and the truth may warn (repeated truth times, cumulative-looking
    # counters): one "odomkit: warning:" line each, and in the JSON, as every command does.
    with reported_warnings() as warned:
        out = check_file(log, robot, topts, log_options=options, spin=spin)
    out = with_warnings(out, warned)
    if json_out:
        print_json(out)
    else:
        print_findings(out)
    if not out["ok"]:
        raise typer.Exit(1)


_MARK = {"ok": "ok  ", "warn": "WARN", "fail": "FAIL"}


def print_findings(out: dict[str, Any]) -> None:
    """The text report of ``odomkit check``."""
    print(f"{out['log']}" + (f" (truth: {out['truth']})" if out["truth"] else " (no truth)"))
    for f in out["findings"]:
        print(f"  {_MARK[f['status']]} {f['check']:13s} {f['message']}")
    print("next:")
    for line in out["next"]:
        print(f"  - {line}")
