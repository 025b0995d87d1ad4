"""Options shared by ``odomkit predict`` and ``odomkit simulate``: the robot/noise model
(by flags, or a robot file with ``--robot``), the path of segments and the initial state,
parsed the same way for both."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from odomkit.errors import ModelError

if TYPE_CHECKING:
    from odomkit.path import Segment
    from odomkit.propagate.plan import NoiseArg
    from odomkit.robot import Robot

__all__ = [
    "MODEL_FLAGS", "CompassPeriodOption", "GyroNoiseOption", "HeadingNoiseOption",
    "InitialCovMatrixOption", "InitialCovOption", "LateralNoiseOption",
    "InitialPoseOption", "JsonOption", "KLeftOption", "KRightOption", "ModelOption", "noise_from_flags",
    "NoiseOption", "Opt", "parse_matrix", "parse_numbers", "path_problem", "PathProblem", "RobotFileOption",
    "SamplePeriodOption", "SegmentOption", "SigmaAngleOption", "SigmaDistanceOption", "SpeedNoiseOption",
    "TurnNoiseOption", "TurnTravelNoiseOption", "WheelBaseOption"
]

Opt = typer.Option

MODEL_FLAGS = {
    "diff": {"--wheel-base", "--k-left", "--k-right", "--sigma-distance", "--sigma-angle",
             "--lateral-noise"},
    "gyro": {"--speed-noise", "--gyro-noise", "--turn-noise", "--turn-travel-noise", "--lateral-noise",
             "--sample-period"},
    "compass": {"--speed-noise", "--heading-noise", "--compass-period", "--lateral-noise"},
}
#: The flags a robot file (``--robot``) may come with: the file gives the vehicle and noise.
ROBOT_FILE_FLAGS = {"--compass-period", "--sample-period"}

SegmentOption = Annotated[list[str], Opt("--segment", help=(
    "Path segment, repeatable. diff: arc:L,R (wheel travels [m]) | straight:D [m] | "
    "spin:DTHETA [rad]; gyro/compass (and a unicycle): arc:V,OMEGA,T [m/s, rad/s, s] | "
    "straight:V,T [m/s, s]; a tricycle or car (--robot): arc:V,ALPHA,T (wheel speed, "
    "steering angle, duration [m/s, rad, s]) | straight:V,T [m/s, s]."))]
ModelOption = Annotated[str | None, Opt("--model", help="diff (default) | gyro | compass")]
RobotFileOption = Annotated[Path | None, Opt("--robot", help=(
    "Robot file (TOML): its vehicle and [noise] as they are (e.g. fit-noise --out), instead "
    "of --model and the noise flags; any vehicle, any noise that track takes for it."))]
SamplePeriodOption = Annotated[float | None, Opt("--sample-period", help=(
    "Sample period T of the odometry [s]: each segment lasts a whole number of periods and "
    "its samples are the steps (not --partitions). Required by noise given per sample (a "
    "tricycle's or car's sigma_speed, sigma_steer, sigma_dt)."))]
NoiseOption = Annotated[str, Opt("--noise", help="diff model: wheel (Chong–Kleeman) | classical (eq. 1–3)")]
WheelBaseOption = Annotated[float | None, Opt("--wheel-base", help="Wheel base B [m].")]
KLeftOption = Annotated[float | None, Opt("--k-left", help="Left wheel k_L [m^½].")]
KRightOption = Annotated[float | None, Opt("--k-right", help="Right wheel k_R [m^½].")]
SigmaDistanceOption = Annotated[float | None, Opt(
    "--sigma-distance", help="Classical model: σ of each step's distance [m].")]
SigmaAngleOption = Annotated[float | None, Opt(
    "--sigma-angle", help="Classical model: σ of each step's rotation [rad].")]
SpeedNoiseOption = Annotated[float | None, Opt(
    "--speed-noise", help="Kelly α_ss [m] (distance variance per metre).")]
GyroNoiseOption = Annotated[float | None, Opt(
    "--gyro-noise", help="Kelly σ_gg, yaw-rate noise density [rad²/s].")]
TurnNoiseOption = Annotated[float | None, Opt(
    "--turn-noise", help=("Gyro model: α_turn [rad²/rad], the heading variance per radian turned "
                          "(TurnNoise; AMCL's α1 made linear in the turn)."))]
TurnTravelNoiseOption = Annotated[float | None, Opt(
    "--turn-travel-noise", help=("Gyro model: α_turn_travel [m²/rad], the travel variance per radian "
                                 "turned (TurnNoise; AMCL's α4 made linear in the turn)."))]
HeadingNoiseOption = Annotated[float | None, Opt(
    "--heading-noise", help="Kelly σ_θθ, compass noise density [rad²·s].")]
LateralNoiseOption = Annotated[float | None, Opt(
    "--lateral-noise", help=("Any model: lateral slip α_lat [m²/m], the variance of the "
                             "sideways displacement per metre travelled."))]
CompassPeriodOption = Annotated[float | None, Opt(
    "--compass-period", help=(
        "Compass model: sample period T of the compass [s] (default 0.1). Each reading has "
        "an independent error of variance σ_θθ/T (the end θ variance, as track uses for a "
        "compass log); every segment must last a whole number of periods."))]
InitialPoseOption = Annotated[str, Opt("--initial-pose", help="x,y,θ [m, m, rad].")]
InitialCovOption = Annotated[str | None, Opt(
    "--initial-cov", help="Initial variances var_x,var_y,var_θ (diagonal) [m², m², rad²].")]
InitialCovMatrixOption = Annotated[str | None, Opt(
    "--initial-cov-matrix", help="Full initial covariance 'a,b,c;d,e,f;g,h,i' [m², m·rad, rad²].")]
JsonOption = Annotated[bool, Opt("--json", help="Print one JSON object.")]


def parse_numbers(text: str, flag: str, count: int | None = None) -> list[float]:
    """``"1,2,3"`` -> [1.0, 2.0, 3.0]; a clear error naming ``flag`` otherwise."""
    try:
        values = [float(v) for v in text.replace(" ", "").split(",")]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) for v in values) or (
        count is not None and len(values) != count
    ):
        want = f"{count} comma-separated numbers" if count else "comma-separated numbers"
        raise ModelError(f"{flag} expects {want}, got {text!r}")
    return values


def parse_matrix(text: str) -> list[list[float]]:
    """``"a,b,c;d,e,f;g,h,i"`` -> a 3×3 nested list."""
    matrix = [parse_numbers(r, "--initial-cov-matrix") for r in text.split(";")]
    if len(matrix) != 3 or any(len(r) != 3 for r in matrix):
        raise ModelError(f"--initial-cov-matrix expects 3 rows of 3 numbers 'a,b,c;d,e,f;g,h,i', "
                         f"got {text!r}")
    return matrix


def _non_negative(flag: str, value: float | None, unit: str) -> float:
    if value is None:
        raise ModelError(f"{flag} is required for this model ({unit})")
    if not (math.isfinite(value) and value >= 0):
        raise ModelError(f"{flag} must be a non-negative number ({unit}), got {value!r}")
    return value


def _positive_or_none(flag: str, value: float | None, unit: str) -> float | None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise ModelError(f"{flag} must be a positive number ({unit}), got {value!r}")
    return value


def noise_from_flags(model: str, noise: str, given: dict[str, float | None]) -> NoiseArg:
    """The noise model(s) the flags describe (see :func:`odomkit.propagate.predict.predict`)."""
    from odomkit.noise import LateralSlipNoise

    base = _base_noise(model, noise, given)
    if given.get("--lateral-noise") is None:
        return base
    slip = LateralSlipNoise(_non_negative("--lateral-noise", given["--lateral-noise"], "m^2/m"))
    return (*(base if isinstance(base, tuple) else (base,)), slip)


def _base_noise(model: str, noise: str, given: dict[str, float | None]) -> NoiseArg:
    """The noise of the model's own flags (without a lateral slip)."""
    from odomkit.noise import ClassicalNoise, CompassNoise, GyroNoise, SpeedNoise, TurnNoise, WheelNoise

    if model == "diff" and noise == "wheel":
        return WheelNoise(_non_negative("--k-left", given["--k-left"], "m^½"),
                          _non_negative("--k-right", given["--k-right"], "m^½"))
    if model == "diff" and noise == "classical":
        return ClassicalNoise(_non_negative("--sigma-distance", given["--sigma-distance"], "m"),
                              _non_negative("--sigma-angle", given["--sigma-angle"], "rad"))
    if model == "diff":
        raise ModelError(f"--noise must be 'wheel' or 'classical', got {noise!r}")
    speed = SpeedNoise(_non_negative("--speed-noise", given["--speed-noise"] or 0.0, "m"))
    if model == "gyro":
        turn, travel = given.get("--turn-noise"), given.get("--turn-travel-noise")
        # A base whose heading noise is all turning needs no time-driven density: 0 then.
        density = given["--gyro-noise"]
        if density is None and (turn is not None or travel is not None):
            density = 0.0
        gyro = GyroNoise(_non_negative("--gyro-noise", density, "rad^2/s"))
        if turn is None and travel is None:
            return speed, gyro
        return speed, gyro, TurnNoise(_non_negative("--turn-noise", turn or 0.0, "rad^2/rad"),
                                      _non_negative("--turn-travel-noise", travel or 0.0, "m^2/rad"))
    return speed, CompassNoise(_non_negative("--heading-noise", given["--heading-noise"],
                                             "rad^2*s"))


@dataclass(frozen=True)
class PathProblem:
    """A parsed path problem: what ``predict`` and ``simulate`` both take."""

    segments: list[Segment]
    noise: NoiseArg
    wheel_base: float | None
    pose0: list[float]
    cov0: list[list[float]] | None
    compass_period: float | None = None
    sample_period: float | None = None
    robot: Robot | None = None


def path_problem(
    model: str | None, noise: str, segments: list[str], given: dict[str, float | None],
    initial_pose: str, initial_cov: str | None, initial_cov_matrix: str | None,
    robot_file: Path | None = None,
) -> PathProblem:
    """Check and parse the shared options.

    ``given`` maps each model flag (``--wheel-base``, ``--k-left``, ...) to its value or
    None; a flag that does not belong to ``model`` is an error, not silently ignored.
    ``robot_file`` (``--robot``) gives the vehicle and its noise instead of ``model`` and
    the noise flags (which it excludes); the segments are then the vehicle's.
    """
    from odomkit.path import parse_segment  # not at import time: keeps --help fast

    if robot_file is not None:
        return _robot_problem(robot_file, model, noise, segments, given, initial_pose, initial_cov,
                              initial_cov_matrix)
    model = "diff" if model is None else model
    if model not in MODEL_FLAGS:
        raise ModelError(f"--model must be one of {', '.join(MODEL_FLAGS)}, got {model!r}")
    stray = [flag for flag, v in given.items() if v is not None and flag not in MODEL_FLAGS[model]]
    if stray:
        raise ModelError(f"{', '.join(stray)} does not apply to --model {model}")
    wheel_base = given.get("--wheel-base")
    if model == "diff" and wheel_base is None:
        raise ModelError("--model diff needs --wheel-base (metres)")
    return PathProblem(
        segments=[parse_segment(s, model) for s in segments],
        noise=noise_from_flags(model, noise, given),
        wheel_base=wheel_base,
        pose0=parse_numbers(initial_pose, "--initial-pose", 3),
        cov0=_initial_cov(initial_cov, initial_cov_matrix),
        compass_period=_positive_or_none("--compass-period", given.get("--compass-period"), "s"),
        sample_period=_positive_or_none("--sample-period", given.get("--sample-period"), "s"),
    )


def _initial_cov(initial_cov: str | None, initial_cov_matrix: str | None) -> list[list[float]] | None:
    """The start covariance of ``--initial-cov`` (variances) or ``--initial-cov-matrix``."""
    if initial_cov is not None and initial_cov_matrix is not None:
        raise ModelError("give --initial-cov or --initial-cov-matrix, not both")
    if initial_cov is not None:
        var = parse_numbers(initial_cov, "--initial-cov", 3)
        if min(var) < 0:
            raise ModelError(f"--initial-cov holds variances, which must be >= 0; got {var}")
        return [[var[0], 0.0, 0.0], [0.0, var[1], 0.0], [0.0, 0.0, var[2]]]
    if initial_cov_matrix is not None:
        return parse_matrix(initial_cov_matrix)
    return None


def _robot_problem(
    robot_file: Path, model: str | None, noise: str, segments: list[str], given: dict[str, float | None],
    initial_pose: str, initial_cov: str | None, initial_cov_matrix: str | None,
) -> PathProblem:
    """The path problem of ``--robot``: the file's vehicle and [noise] (the shared reader,
    :func:`odomkit.io.robotfile.read_robot`), its segment syntax, and no model flags."""
    from odomkit.errors import InputError
    from odomkit.io.robotfile import read_robot
    from odomkit.path import parse_segment

    stray = [flag for flag, v in given.items() if v is not None and flag not in ROBOT_FILE_FLAGS]
    stray += ["--model"] * (model is not None) + ["--noise"] * (noise != "wheel")
    if stray:
        raise ModelError(f"--robot takes the vehicle and its noise from the robot file: drop "
                         f"{', '.join(stray)}")
    robot, models = read_robot(robot_file)
    if not models:
        raise InputError("has no [noise] table: nothing to predict (add one, e.g. fit-noise --out)",
                         source=str(robot_file))
    return PathProblem(
        segments=[parse_segment(s, robot.type_name) for s in segments],
        noise=models,
        wheel_base=None,
        pose0=parse_numbers(initial_pose, "--initial-pose", 3),
        cov0=_initial_cov(initial_cov, initial_cov_matrix),
        compass_period=_positive_or_none("--compass-period", given.get("--compass-period"), "s"),
        sample_period=_positive_or_none("--sample-period", given.get("--sample-period"), "s"),
        robot=robot,
    )
