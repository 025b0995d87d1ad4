"""``odomkit track``: dead-reckon a log with a robot file."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from odomkit.cli.application import app
from odomkit.cli.output import print_json
from odomkit.errors import InputError
from odomkit.workflows.logs import LOG_FORMATS, LogOptions

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
def track(
    log: Annotated[Path, typer.Argument(help="The log file.")],
    robot: Annotated[Path, typer.Option(help="Robot file (TOML).")],
    format: Annotated[str, typer.Option(help=f"Log format: {', '.join(LOG_FORMATS)}.")] = "auto",
    method: Annotated[str, typer.Option(help="exact | midpoint | euler")] = "exact",
    columns: Annotated[str | None, typer.Option(
        help="CSV column mapping, e.g. t=time,ticks_left=L,ticks_right=R")] = None,
    cumulative: Annotated[bool, typer.Option(help="CSV counters are cumulative.")] = False,
    wrap_bits: Annotated[int | None, typer.Option(help="Unwrap counters of this width.")] = None,
    period: Annotated[float | None, typer.Option(help="Sample period [s] for logs without time.")] = None,
    time_scale: Annotated[float, typer.Option(help="Multiply CSV time by this to get s.")] = 1.0,
    decimate: Annotated[int, typer.Option(help="Use every n-th sample.")] = 1,
    initial_pose: Annotated[str | None, typer.Option(
        help="x,y,theta [m, m, rad]; default: first ground-truth pose or the origin")] = None,
    theta0_deg: Annotated[bool, typer.Option(help="Read theta of --initial-pose in degrees.")] = False,
    covariance: Annotated[bool, typer.Option(help="Propagate the robot file's noise.")] = True,
    engine: Annotated[str, typer.Option(
        help="Covariance engine: recursion (step recursion) | transition (Kelly).")] = "recursion",
    out: Annotated[Path | None, typer.Option(help="Write the track as CSV here.")] = None,
    tum: Annotated[Path | None, typer.Option(help="Write a TUM trajectory here.")] = None,
    force: Annotated[bool, typer.Option(help="Replace existing output files.")] = False,
    json: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
) -> None:
    """Dead-reckon LOG with the robot file (and the covariance of every pose when it has a noise table)."""
    from odomkit.workflows.track import run_track

    result = run_track(
        log, robot, method=method,  # type: ignore[arg-type]
        log_options=LogOptions(format, columns, cumulative, wrap_bits, period, time_scale),
        decimate=decimate, pose0=parse_pose(initial_pose, theta0_deg),
        with_covariance=covariance, engine=engine, out=out, tum=tum, overwrite=force,
    )
    summary = result.summary()
    if json:
        print_json(summary)
        return
    x, y, th = summary["pose"]
    print(f"{summary['samples']} poses over {summary['duration']:.3f} s, "
          f"path length {summary['path_length']:.4f} m")
    print(f"final pose x={x:.4f} m  y={y:.4f} m  theta={th:.4f} rad")
    if "ground_truth" in summary:
        g = summary["ground_truth"]
        print(f"vs ground truth: final position error {g['final_position_error']:.4f} m, "
              f"heading error {g['final_heading_error']:.4f} rad")
    for kind, path in summary["outputs"].items():
        print(f"wrote {kind}: {path}")
