"""``odomkit track``: dead-reckon a log with a robot file."""

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
    parse_initial_cov,
    with_truth_options,
)
from odomkit.errors import InputError

if TYPE_CHECKING:
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["parse_pose", "track"]


def parse_pose(text: str | None, degrees: bool = False) -> tuple[float, float, float] | None:
    """``"x,y,theta"`` -> a tuple (θ in degrees when ``degrees``)."""
    if text is None:
        return None
    try:
        x, y, th = (float(v) for v in text.split(","))
    except ValueError:
        raise InputError(f"--initial-pose {text!r} must be three numbers x,y,theta") from None
    if degrees:
        from math import radians

        th = radians(th)
    return x, y, th


@app.command()
@with_log_options
@with_truth_options
def track(
    log: Annotated[Path, typer.Argument(help="The log file.")],
    robot: Annotated[Path, typer.Option(help="Robot file (TOML).")],
    method: Annotated[str, typer.Option(help="exact | midpoint | euler")] = "exact",
    initial_pose: Annotated[str | None, typer.Option(
        help="x,y,theta [m, m, rad]; default: first ground-truth pose or the origin")] = None,
    theta0_deg: Annotated[bool, typer.Option(help="Read theta of --initial-pose in degrees.")] = False,
    initial_cov: Annotated[str | None, typer.Option(
        help="Initial covariance: var_x,var_y,var_theta [m², m², rad²] or 9 numbers (3x3 row by "
             "row); default: the truth's start uncertainty, else zero.")] = None,
    truth: TruthOption = None,
    covariance: Annotated[bool, typer.Option(help="Propagate the robot file's noise.")] = True,
    engine: Annotated[str | None, typer.Option(
        help="Covariance engine: recursion (step recursion, the default) | transition (Kelly).",
        show_default=False)] = None,
    out: Annotated[Path | None, typer.Option(help="Write the track as CSV here.")] = None,
    tum: Annotated[Path | None, typer.Option(help="Write a TUM trajectory here.")] = None,
    kitti: Annotated[Path | None, typer.Option(
        help="Write KITTI poses here (12 numbers a row, planar: z = 0, rotation about z) and their "
             "times beside it, NAME.times.txt (evo pairs KITTI poses by index).")] = None,
    bag_out: Annotated[Path | None, typer.Option(
        help="Write nav_msgs/Odometry (pose and twist with covariance) as a ROS bag here: a .bag "
             "path is ROS 1, any other path a ROS 2 bag folder.")] = None,
    bag_format: Annotated[str | None, typer.Option(
        help="ros1 | db3 | mcap (default: ros1 for a .bag path, else mcap).")] = None,
    frame_id: Annotated[str, typer.Option(help="--bag-out header frame id.")] = "odom",
    child_frame_id: Annotated[str, typer.Option(help="--bag-out child frame id (the body).")] = "base_link",
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Draw the track with its 95 % ellipses against truth, the covariance over time, "
                       "the error in its ±2σ band and the integration methods' drift into this file "
                       "(.png, .svg or .pdf; needs the plot extra).")] = None,
    force: Annotated[bool, typer.Option(help="Replace existing output files.")] = False,
    json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    *,
    log_opts: LogOptions,
    truth_base: TruthOptions,
) -> None:
    """Dead-reckon LOG with the robot file (and the covariance of every pose when it has a noise table)."""
    from odomkit.workflows.track import run_track
    from odomkit.workflows.truth import with_truth_topic

    options, topts = with_truth_topic(log_opts, replace(truth_base, path=truth), truth is not None)
    with reported_warnings() as warned, progress_bar(json) as progress:
        result = run_track(
            log, robot, method=method,  # type: ignore[arg-type]
            log_options=options, pose0=parse_pose(initial_pose, theta0_deg),
            cov0=parse_initial_cov(initial_cov),
            truth=topts,
            with_covariance=covariance, engine=engine, out=out, tum=tum, kitti=kitti, overwrite=force,
            bag_out=bag_out, bag_format=bag_format, frame_id=frame_id, child_frame_id=child_frame_id,
            progress=progress, plot=plot,
        )
        summary = result.summary(note_nees=json)  # the text shows no NEES to warn of
    if json:
        print_json(with_warnings(summary, warned))
        return
    x, y, th = summary["pose"]
    print(f"{summary['samples']} poses over {summary['duration']:.3f} s, "
          f"path length {summary['path_length']:.4f} m")
    print(f"final pose x={x:.4f} m  y={y:.4f} m  theta={th:.4f} rad")
    if "ground_truth" in summary:
        g = summary["ground_truth"]
        print(f"vs ground truth: final position error {g['final_position_error']:.4f} m, "
              f"heading error {g['final_heading_error']:.4f} rad")
    elif "final_position_error" in summary:
        print(f"vs truth: final position error {summary['final_position_error']:.4f} m, "
              f"max {summary['max_position_error']:.4f} m")
    for kind, path in summary["outputs"].items():
        print(f"wrote {kind}: {path}")
