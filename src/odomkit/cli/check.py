"""``odomkit check``: is a log fit to calibrate from, and what to record next.

::

    odomkit check LOG --robot ROBOT.toml [--truth GT] [--spin ccw|cw] [LOG OPTIONS] [--json]

Exit status 0 when no check fails, 1 when one does (a finding, not a usage error), 2 for
bad input as everywhere.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from odomkit.cli.application import app
from odomkit.cli.log_options import (
    BagTimeOption,
    ColumnsOption,
    CumulativeOption,
    DecimateOption,
    FormatOption,
    JointsOption,
    PeriodOption,
    TimeUnitOption,
    TopicOption,
    TruthTopicOption,
    WrapBitsOption,
    log_options,
    reported_warnings,
    with_warnings,
)
from odomkit.cli.output import print_json
from odomkit.cli.truth_options import (
    MaxGapOption,
    TruthColumnsOption,
    TruthFormatOption,
    TruthOption,
    TruthSigmaOption,
    TruthTimeUnitOption,
    truth_options,
)

__all__ = ["check_command", "print_findings"]


@app.command("check")
def check_command(
    log: Annotated[Path, typer.Argument(help="The log to check.")],
    robot: Annotated[Path, typer.Option("--robot", help="Robot file (TOML) of the log.")],
    spin: Annotated[str | None, typer.Option(
        "--spin", help="The log is a spin in place, ccw or cw: checks the wheels without truth.")] = None,
    truth: TruthOption = None,
    truth_format: TruthFormatOption = "auto",
    truth_columns: TruthColumnsOption = None,
    truth_time_unit: TruthTimeUnitOption = "s",
    truth_sigma: TruthSigmaOption = 0.0,
    max_gap: MaxGapOption = 0.5,
    format: FormatOption = "auto",
    columns: ColumnsOption = None,
    cumulative: CumulativeOption = False,
    wrap_bits: WrapBitsOption = None,
    period: PeriodOption = None,
    time_unit: TimeUnitOption = "s",
    decimate: DecimateOption = 1,
    topic: TopicOption = None,
    joints: JointsOption = None,
    bag_time: BagTimeOption = False,
    truth_topic: TruthTopicOption = None,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
) -> None:
    """Check a log before calibrating: time jumps, counter wraps, stuck encoders, NaNs, swapped or
    sign-flipped channels, turning both ways, distance, what each parameter can be fitted from;
    and say what to record next. Exit status 1 when a check fails."""
    from odomkit.workflows.check import check_file

    options = log_options(format, columns, cumulative, wrap_bits, period, time_unit, decimate,
                          topic, joints, bag_time, truth_topic)
    topts = truth_options(truth, truth_format, truth_columns, truth_time_unit, truth_sigma, max_gap)
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
        print(f"  {_MARK[f['status']]} {f['check']:12s} {f['message']}")
    print("next:")
    for line in out["next"]:
        print(f"  - {line}")
