"""``odomkit predict``: closed-form error prediction for a path of segments."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

from odomkit.cli.application import app
from odomkit.cli.log_options import reported_warnings, with_warnings
from odomkit.cli.options import (
    CompassPeriodOption,
    GyroNoiseOption,
    HeadingNoiseOption,
    InitialCovMatrixOption,
    InitialCovOption,
    InitialPoseOption,
    JsonOption,
    KLeftOption,
    KRightOption,
    LateralNoiseOption,
    ModelOption,
    NoiseOption,
    Opt,
    RobotFileOption,
    SamplePeriodOption,
    SegmentOption,
    SigmaAngleOption,
    SigmaDistanceOption,
    SpeedNoiseOption,
    TurnNoiseOption,
    TurnTravelNoiseOption,
    WheelBaseOption,
    path_problem,
)
from odomkit.cli.output import print_json
from odomkit.errors import ModelError

__all__ = ["predict_command"]


def _print_table(data: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"odomkit predict ({data['model']} model, {data['engine']} engine)")
    table.add_column("")
    for name in ("x (m)", "y (m)", "θ (rad)"):
        table.add_column(name, justify="right")
    table.add_row("pose", *(f"{v:.6g}" for v in data["pose"]))
    table.add_row("std", *(f"{v:.5g}" for v in data["std"]))
    for name, row in zip(("cov x", "cov y", "cov θ"), data["cov"], strict=True):
        table.add_row(name, *(f"{v:.5g}" for v in row))
    corr = {k: ("n/a" if math.isnan(v) else f"{v:+.4f}") for k, v in data["corr"].items()}
    table.caption = f"corr xy {corr['xy']}, xθ {corr['xtheta']}, yθ {corr['ytheta']}"
    Console().print(table)


@app.command("predict")
def predict_command(
    segment: SegmentOption,
    model: ModelOption = None,
    noise: NoiseOption = "wheel",
    wheel_base: WheelBaseOption = None,
    k_left: KLeftOption = None,
    k_right: KRightOption = None,
    sigma_distance: SigmaDistanceOption = None,
    sigma_angle: SigmaAngleOption = None,
    speed_noise: SpeedNoiseOption = None,
    gyro_noise: GyroNoiseOption = None,
    turn_noise: TurnNoiseOption = None,
    turn_travel_noise: TurnTravelNoiseOption = None,
    heading_noise: HeadingNoiseOption = None,
    lateral_noise: LateralNoiseOption = None,
    compass_period: CompassPeriodOption = None,
    robot: RobotFileOption = None,
    sample_period: SamplePeriodOption = None,
    initial_pose: InitialPoseOption = "0,0,0",
    initial_cov: InitialCovOption = None,
    initial_cov_matrix: InitialCovMatrixOption = None,
    engine: Annotated[str, Opt("--engine", help=(
        "closed | recursion | transition (the step engines, a cross-check; for a compass "
        "the track's direct-heading engines on its samples)."))] = "closed",
    partitions: Annotated[int | None, Opt(
        "--partitions", help=("Steps per segment (recursion engines; classical pieces). A "
                              "compass and --sample-period ignore it: the steps are the "
                              "samples."))] = None,
    plot: Annotated[Path | None, Opt(
        "--plot", help="Draw the path with its 95 % ellipses and the covariance elements over the "
                       "distance into this file (.png, .svg or .pdf; needs the plot extra).")] = None,
    force: Annotated[bool, Opt("--force", help="Replace an existing --plot file.")] = False,
    json_out: JsonOption = False,
) -> None:
    """Predict the end pose and its covariance for a path of segments (closed form, or the
    track's engines where there is none)."""
    # The propagation stack loads only when the command runs (fast --help).
    from odomkit.propagate.predict import ENGINES
    from odomkit.workflows.predict import run_predict

    if engine not in ENGINES:
        raise ModelError(f"--engine must be one of {', '.join(ENGINES)}, got {engine!r}")
    problem = path_problem(
        model, noise, segment,
        {"--wheel-base": wheel_base, "--k-left": k_left, "--k-right": k_right,
         "--sigma-distance": sigma_distance, "--sigma-angle": sigma_angle,
         "--speed-noise": speed_noise, "--gyro-noise": gyro_noise, "--turn-noise": turn_noise,
         "--turn-travel-noise": turn_travel_noise,
         "--heading-noise": heading_noise, "--compass-period": compass_period,
         "--lateral-noise": lateral_noise, "--sample-period": sample_period},
        initial_pose, initial_cov, initial_cov_matrix, robot)
    with reported_warnings() as warned:
        result = run_predict(problem.segments, problem.noise, wheel_base=problem.wheel_base,
                             pose0=problem.pose0, cov0=problem.cov0, engine=engine,
                             partitions=partitions, compass_period=problem.compass_period,
                             robot=problem.robot, sample_period=problem.sample_period,
                             plot=plot, overwrite=force)
    if json_out:
        print_json(with_warnings(result, warned))
    else:
        _print_table(result)
        for kind, path in result.get("outputs", {}).items():
            print(f"wrote {kind}: {path}")
