"""``odomkit fit-amcl``: nav2 AMCL α1–α4 (α5 for omni) from odometry with ground truth.

::

    odomkit fit-amcl ODOM [ODOM ...] [--truth GT ...] [--robot ROBOT.toml] [--model diff|omni]
        [--update-min-d 0.25] [--update-min-a 0.2] [--yaml-out amcl.yaml] [--force] [--json]
"""

from __future__ import annotations

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
    TruthListOption,
    with_truth_options,
)

if TYPE_CHECKING:
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["fit_amcl_command", "print_fit"]


@app.command("fit-amcl")
@with_log_options
@with_truth_options
def fit_amcl_command(
    odometry: Annotated[list[Path], typer.Argument(
        help="Odometry pose tracks (odomkit track --out, TUM, t,x,y,theta), ROS bags with a "
             "nav_msgs/Odometry topic, or logs with --robot.")],
    robot: Annotated[Path | None, typer.Option(
        "--robot", help="Robot file (TOML): ODOM files are raw logs, dead-reckoned with it.")] = None,
    model: Annotated[str, typer.Option("--model", help="AMCL motion model: diff | omni.")] = "diff",
    update_min_d: Annotated[float, typer.Option(
        "--update-min-d", help="AMCL's update_min_d [m]: an update when |dx| or |dy| exceeds it.")] = 0.25,
    update_min_a: Annotated[float, typer.Option(
        "--update-min-a", help="AMCL's update_min_a [rad]: an update when the turn exceeds it.")] = 0.2,
    level: Annotated[float, typer.Option("--level", help="Confidence level of the intervals.")] = 0.95,
    yaml_out: Annotated[Path | None, typer.Option(
        "--yaml-out", help="Write the nav2 amcl parameter snippet (YAML).")] = None,
    truth: TruthListOption = None,
    method: Annotated[str, typer.Option("--method", help="exact | midpoint | euler (logs)")] = "exact",
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Draw each α's profile likelihood with its interval into this file (.png, .svg "
                       "or .pdf; needs the plot extra).")] = None,
    force: Annotated[bool, typer.Option(
        "--force", help="Replace an existing --yaml-out or --plot file.")] = False,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    *,
    log_opts: LogOptions,
    truth_base: TruthOptions,
) -> None:
    """Maximum-likelihood nav2 AMCL motion-model alphas, with profile-likelihood intervals,
    from AMCL's own differential or omni model between its update thresholds."""
    from odomkit.errors import InputError
    from odomkit.workflows.fit_amcl import fit_amcl_files
    from odomkit.workflows.truth import truth_options_per_log, with_truth_topic

    if not 0 < level < 1:
        raise InputError(f"--level must be in (0, 1), got {level}")
    options, base = with_truth_topic(log_opts, truth_base, bool(truth))
    per_file = truth_options_per_log(base, list(truth or []), len(odometry))
    with reported_warnings() as warned:
        out = fit_amcl_files(odometry, per_file, robot_path=robot, log_options=options, model=model,
                             update_min_d=update_min_d, update_min_a=update_min_a, level=level,
                             method=method, yaml_out=yaml_out, overwrite=force, plot=plot)
    out = with_warnings(out, warned)
    if json_out:
        print_json(out)
        return
    print_fit(out)


def print_fit(out: dict[str, Any]) -> None:
    """The short text report of ``odomkit fit-amcl``."""
    key = next(k for k in out if k.startswith("interval"))
    print(f"AMCL {out['model']} motion model from {out['updates']} updates "
          f"(update_min_d {out['update_min_d']:g} m, update_min_a {out['update_min_a']:g} rad)")
    for name, value in out["alpha"].items():
        lo, hi = out[key][name]
        print(f"  {name} = {value:.4g}   ({key.removeprefix('interval')} % interval {lo:.4g} .. "
              f"{'unbounded' if hi is None else format(hi, '.4g')})")
    for kind, path in out["outputs"].items():
        print(f"wrote {kind}: {path}")
