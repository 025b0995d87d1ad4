"""``odomkit report``: one self-contained HTML page about one log.

::

    odomkit report LOG --robot ROBOT.toml [--truth GT] --out report.html [--wheel-radius R] [--force] [--json]
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from odomkit.cli.application import app
from odomkit.cli.log_options import (
    reported_warnings,
    with_log_options,
    with_warnings,
)
from odomkit.cli.output import print_json
from odomkit.cli.progress import progress_bar
from odomkit.cli.truth_options import (
    TruthOption,
    with_truth_options,
)

if TYPE_CHECKING:
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions


__all__ = ["report"]


@app.command()
@with_log_options
@with_truth_options
def report(
    log: Annotated[Path, typer.Argument(help="The log file.")],
    robot: Annotated[Path, typer.Option(help="Robot file (TOML), with [noise] for the covariance.")],
    out: Annotated[Path, typer.Option(help="The HTML file to write (one file, works offline).")],
    truth: TruthOption = None,
    window: Annotated[str | None, typer.Option(
        help="Honesty-test windows: 30s (time) or 5m (odometry travel); default 10s when the log has "
             "three of them with truth, else the whole log.")] = None,
    kinds: Annotated[str, typer.Option(
        help="Noise kinds to fit: white, bias or white,bias (default white: one log shows one draw of a "
             "bias, not its spread).")] = "white",
    method: Annotated[str, typer.Option(help="exact | midpoint | euler")] = "exact",
    initial_pose: Annotated[str | None, typer.Option(
        help="x,y,theta [m, m, rad] of the track's start; default: the truth pose at the first row")] = None,
    wheel_radius: Annotated[float | None, typer.Option(
        "--wheel-radius", help="Nominal wheel radius [m] for the ROS 2 controller snippet, as calibrate's "
                               "for --ros-yaml: needed where the robot file gives metres per tick (wheel "
                               "speeds: m_per_tick = 1), not a wheel size.")] = None,
    force: Annotated[bool, typer.Option(help="Replace an existing --out file.")] = False,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    *,
    log_opts: LogOptions,
    truth_base: TruthOptions,
) -> None:

    """Write one HTML page about LOG: the track with its covariance and, with ground truth, the
    errors, the honesty test, the calibration, the fitted noise and the ROS parameters."""
    from odomkit.cli.track import parse_pose
    from odomkit.workflows.fit_noise import parse_kinds
    from odomkit.workflows.report import run_report

    fitted = parse_kinds(kinds)
    from odomkit.workflows.truth import with_truth_topic

    options, topts = with_truth_topic(log_opts, replace(truth_base, path=truth), truth is not None)
    with reported_warnings() as warned, progress_bar(json_out) as progress:
        result = run_report(log, robot, out, truth=topts,
                            log_options=options, window=window, kinds=fitted, method=method,
                            pose0=parse_pose(initial_pose), wheel_radius=wheel_radius, overwrite=force,
                            progress=progress)
    result = with_warnings(result, warned)
    if json_out:
        print_json(result)
        return
    print(f"wrote {result['report']}: {', '.join(result['sections'])} "
          f"({len(result['warnings'])} warning(s))")
