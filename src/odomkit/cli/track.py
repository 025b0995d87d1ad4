"""``odomkit track`` and ``odomkit demo``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from odomkit.cli import app
from odomkit.cli.output import print_json
from odomkit.errors import InputError
from odomkit.workflows import LOG_FORMATS, LogOptions, run_track


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


@app.command()
def demo(
    out: Annotated[Path, typer.Option(help="Folder for the outputs.")] = Path("demo-output"),
    force: Annotated[bool, typer.Option(help="Replace existing outputs.")] = False,
) -> None:
    """Dead-reckon, calibrate and predict on the built-in OptiOdom UMBmark runs."""
    from odomkit.demo import run_demo

    s = run_demo(out, overwrite=force)
    print("Built-in data: OptiOdom experiment 230620202042 (0.75 m UMBmark square, MIT licence)")
    for stem, run in s["runs"].items():
        print(f"  {stem} ({run['direction']:>3}): path {run['path_length']:.2f} m, final error vs "
              f"OptiTrack {1000 * run['final_position_error']:.1f} mm, heading "
              f"{run['final_heading_error']:+.3f} rad, inside 95 % ellipse "
              f"{100 * run['inside_95_fraction']:.0f} % of the time "
              f"({100 * run['calibrated']['inside_95_fraction']:.0f} % once calibrated)")
    c = s["calibration"]
    print(f"E_max,syst {1000 * c['e_max_syst_before']:.1f} mm uncalibrated; "
          f"{1000 * c['umbmark']['e_max_syst_after']:.1f} mm after UMBmark "
          f"(E_d {c['umbmark']['E_d']:.5f}, E_b {c['umbmark']['E_b']:.5f}); "
          f"{1000 * c['exact']['e_max_syst_after']:.1f} mm after the exact fit "
          f"(E_d {c['exact']['E_d']:.5f}, E_b {c['exact']['E_b']:.5f})")
    p = s["prediction_one_square"]
    print(f"predicted end-of-square std (k = 0.001 m^1/2): x {1000 * p['std'][0]:.1f} mm, "
          f"y {1000 * p['std'][1]:.1f} mm, theta {p['std'][2]:.4f} rad")
    print(f"outputs in {Path(out).resolve()}:")
    for path in s["outputs"]:
        print(f"  {path}")
