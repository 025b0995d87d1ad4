"""``odomkit umbmark``: Borenstein–Feng calibration from return position errors.

::

    odomkit umbmark ERRORS.csv --side 4 --wheel-base 0.34 [--json]
    odomkit umbmark --runs RUN.csv [RUN.csv ...] --robot ROBOT.toml --side 0.75 [LOG OPTIONS] [--json]

ERRORS.csv has a header naming the columns ``direction,x,y`` (see
:mod:`odomkit.io.umbmark_errors`); the work is done by :mod:`odomkit.workflows.umbmark`.
LOG OPTIONS are those of ``odomkit track`` (:mod:`odomkit.cli.log_options`) and apply to
the logs of ``--runs``.
"""

from __future__ import annotations

import math
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
from odomkit.errors import InputError

if TYPE_CHECKING:
    from odomkit.workflows.logs import LogOptions

__all__ = ["umbmark_command"]


def _print_text(out: dict[str, Any]) -> None:
    mm = 1000.0
    print(f"centre of gravity CW : x = {out['cg']['cw'][0] * mm:9.2f} mm  "
          f"y = {out['cg']['cw'][1] * mm:9.2f} mm")
    print(f"centre of gravity CCW: x = {out['cg']['ccw'][0] * mm:9.2f} mm  "
          f"y = {out['cg']['ccw'][1] * mm:9.2f} mm")
    print(f"E_max,syst           : {out['e_max_syst'] * mm:9.2f} mm")
    print(f"alpha (Type A)       : {math.degrees(out['alpha']):9.4f} deg  "
          f"(x: {math.degrees(out['alpha_x']):.4f}, y: {math.degrees(out['alpha_y']):.4f})")
    print(f"beta  (Type B)       : {math.degrees(out['beta']):9.4f} deg  "
          f"(x: {math.degrees(out['beta_x']):.4f}, y: {math.degrees(out['beta_y']):.4f})")
    radius = out["radius"]
    print(f"radius R             : {'infinite' if radius is None else f'{radius:.3f} m'}")
    print(f"E_d = D_R/D_L        : {out['E_d']:.6f}")
    print(f"E_b = b_act/b_nom    : {out['E_b']:.6f}")
    print(f"c_left, c_right      : {out['c_left']:.6f}, {out['c_right']:.6f}")
    print(f"corrected wheel base : {out['wheel_base']:.6f} m "
          f"(was {out['wheel_base_nominal']:.6f} m)")
    sem, runs = out["sem"], out["runs"]
    shown = [f"{sem[d] * mm:.2f} mm" if sem[d] is not None and math.isfinite(sem[d]) else "n/a"
             for d in ("cw", "ccw")]
    short = min(runs.values()) < 2
    print(f"SEM CW, CCW          : {shown[0]}, {shown[1]}"
          + (f" ({runs['cw']} CW, {runs['ccw']} CCW runs: a spread needs 2 or more runs per direction)"
             if short else ""))
    advised = out["second_compensation_advised"]
    verdict = {True: "advised", False: "not needed", None: "unknown (< 2 runs)"}[advised]
    print(f"(further) compensation: {verdict} (3·SEM rule)")
    if "e_max_syst_after" in out:
        print(f"E_max,syst corrected : {out['e_max_syst_after'] * mm:9.2f} mm (same runs)")
    ck = out.get("chong_kleeman")
    if ck:
        print(f"Chong–Kleeman c_b    : {ck['c_b']:.6f} (half the needed correction; "
              "use E_b)")


@app.command("umbmark")
@with_log_options
def umbmark_command(
    errors_csv: Annotated[list[Path] | None, typer.Argument(
        help="CSV with columns direction,x,y (cw/ccw, return errors [m]).")] = None,
    side: Annotated[float, typer.Option(
        "--side", help="Side L of the square [m] (required).",
        show_default=False)] = math.nan,
    wheel_base: Annotated[float | None, typer.Option(
        "--wheel-base",
        help="Wheel base the odometry used [m] (default: from --robot).")] = None,
    runs: Annotated[list[Path] | None, typer.Option(
        "--runs", help="Logs with ground truth (calibrate from logs).")] = None,
    robot: Annotated[Path | None, typer.Option("--robot", help="Robot file (TOML).")] = None,
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Draw the return errors, their centres of gravity and E_max,syst (with --runs: "
                       "before and after the correction) into this file (.png, .svg or .pdf; needs the "
                       "plot extra).")] = None,
    force: Annotated[bool, typer.Option("--force", help="Replace an existing --plot file.")] = False,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    *,
    log_opts: LogOptions,
) -> None:
    """UMBmark (Borenstein–Feng): E_max,syst and the corrections E_d, E_b, c_L, c_R, b."""
    from odomkit.workflows import umbmark as workflow

    positional = list(errors_csv or [])
    options = log_opts
    if not (math.isfinite(side) and side > 0):
        raise InputError(f"--side must be a positive length in metres, got {side!r} "
                         "(it is required)")
    with reported_warnings() as warned:
        if runs:
            # `--runs a.csv b.csv` leaves b.csv as a positional argument: they are all runs.
            if robot is None:
                raise InputError("--runs needs --robot ROBOT.toml (the parameters the odometry used)")
            out = workflow.umbmark_from_files(list(runs) + positional, robot, side,
                                              log_options=options, plot=plot,
                                              overwrite=force).to_dict()
        else:
            if options.given():
                raise InputError(f"{', '.join(options.given())} applies to the logs of --runs, "
                                 "not to an ERRORS.csv")
            if len(positional) != 1:
                raise InputError(
                    "give exactly one ERRORS.csv (or --runs RUN.csv ... --robot ROBOT.toml)")
            out = workflow.umbmark_from_errors_file(positional[0], side, wheel_base=wheel_base,
                                                    robot_path=robot, plot=plot, overwrite=force)
    if plot is not None:
        out["outputs"] = {"plot": str(plot)}
    if json_out:
        print_json(with_warnings(out, warned))
    else:
        _print_text(out)
        for kind, path in out.get("outputs", {}).items():
            print(f"wrote {kind}: {path}")
