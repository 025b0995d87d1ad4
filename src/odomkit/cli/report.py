"""``odomkit report``: one self-contained HTML page about one log.

::

    odomkit report LOG --robot ROBOT.toml [--truth GT] --out report.html [--force] [--json]
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

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
from odomkit.cli.progress import progress_bar
from odomkit.cli.truth_options import (
    MaxGapOption,
    TruthColumnsOption,
    TruthFormatOption,
    TruthOption,
    TruthSigmaOption,
    TruthTimeUnitOption,
    truth_options,
)

__all__ = ["report"]


@app.command()
def report(
    log: Annotated[Path, typer.Argument(help="The log file.")],
    robot: Annotated[Path, typer.Option(help="Robot file (TOML), with [noise] for the covariance.")],
    out: Annotated[Path, typer.Option(help="The HTML file to write (one file, works offline).")],
    truth: TruthOption = None,
    truth_format: TruthFormatOption = "auto",
    truth_columns: TruthColumnsOption = None,
    truth_time_unit: TruthTimeUnitOption = "s",
    truth_sigma: TruthSigmaOption = 0.0,
    max_gap: MaxGapOption = 0.5,
    window: Annotated[str | None, typer.Option(
        help="Honesty-test windows: 30s (time) or 5m (odometry travel); default 10s when the log has "
             "three of them with truth, else the whole log.")] = None,
    kinds: Annotated[str, typer.Option(help="Noise kinds to fit: white, bias or white,bias.")] = "white",
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
    method: Annotated[str, typer.Option(help="exact | midpoint | euler")] = "exact",
    initial_pose: Annotated[str | None, typer.Option(
        help="x,y,theta [m, m, rad] of the track's start; default: the truth pose at the first row")] = None,
    force: Annotated[bool, typer.Option(help="Replace an existing --out file.")] = False,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
) -> None:
    """Write one HTML page about LOG: the track with its covariance and, with ground truth, the
    errors, the honesty test, the calibration, the fitted noise and the ROS parameters."""
    from odomkit.cli.track import parse_pose
    from odomkit.workflows.fit_noise import parse_kinds
    from odomkit.workflows.report import run_report

    fitted = parse_kinds(kinds)
    options = log_options(format, columns, cumulative, wrap_bits, period, time_unit, decimate,
                          topic, joints, bag_time, truth_topic)
    with reported_warnings() as warned, progress_bar(json_out) as progress:
        result = run_report(log, robot, out, truth=truth_options(truth, truth_format, truth_columns,
                                                                 truth_time_unit, truth_sigma, max_gap),
                            log_options=options, window=window, kinds=fitted, method=method,
                            pose0=parse_pose(initial_pose), overwrite=force, progress=progress)
    result = with_warnings(result, warned)
    if json_out:
        print_json(result)
        return
    print(f"wrote {result['report']}: {', '.join(result['sections'])} "
          f"({len(result['warnings'])} warning(s))")
