"""``odomkit predict``: closed-form error prediction for a path of segments."""

from __future__ import annotations

import math
from typing import Annotated, Any

import typer

from odomkit.cli import app
from odomkit.cli.output import print_json
from odomkit.errors import ModelError
from odomkit.noise import ClassicalNoise, CompassNoise, GyroNoise, SpeedNoise, WheelNoise
from odomkit.path import parse_segment
from odomkit.propagate.predict import ENGINES, Prediction, predict

_MODEL_FLAGS = {
    "diff": {"--wheel-base", "--k-left", "--k-right", "--sigma-distance", "--sigma-angle"},
    "gyro": {"--speed-noise", "--gyro-noise"},
    "compass": {"--speed-noise", "--heading-noise"},
}


def _numbers(text: str, flag: str, count: int | None = None) -> list[float]:
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


def _matrix(text: str) -> list[list[float]]:
    rows = [r for r in text.split(";")]
    matrix = [_numbers(r, "--initial-cov-matrix") for r in rows]
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


def _noise(model: str, noise: str, given: dict[str, float | None]) -> Any:
    if model == "diff" and noise == "wheel":
        return WheelNoise(_non_negative("--k-left", given["--k-left"], "m^1/2"),
                          _non_negative("--k-right", given["--k-right"], "m^1/2"))
    if model == "diff" and noise == "classical":
        return ClassicalNoise(_non_negative("--sigma-distance", given["--sigma-distance"], "m"),
                              _non_negative("--sigma-angle", given["--sigma-angle"], "rad"))
    if model == "diff":
        raise ModelError(f"--noise must be 'wheel' or 'classical', got {noise!r}")
    speed = SpeedNoise(_non_negative("--speed-noise", given["--speed-noise"] or 0.0, "m"))
    if model == "gyro":
        return speed, GyroNoise(_non_negative("--gyro-noise", given["--gyro-noise"], "rad^2/s"))
    return speed, CompassNoise(_non_negative("--heading-noise", given["--heading-noise"],
                                             "rad^2*s"))


def _print_table(result: Prediction) -> None:
    from rich.console import Console
    from rich.table import Table

    data = result.to_dict()
    table = Table(title=f"odomkit predict ({result.model} model, {result.engine} engine)")
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


Opt = typer.Option


@app.command("predict")
def predict_command(
    segment: Annotated[list[str], Opt("--segment", help=(
        "Path segment, repeatable. diff: arc:L,R (wheel travels, m) | straight:D | "
        "spin:DTHETA (rad); gyro/compass: arc:V,OMEGA,T | straight:V,T."))],
    model: Annotated[str, Opt("--model", help="diff | gyro | compass")] = "diff",
    noise: Annotated[str, Opt(
        "--noise", help="diff model: wheel (Chong–Kleeman) | classical (eq. 1–3)")] = "wheel",
    wheel_base: Annotated[float | None, Opt("--wheel-base", help="Wheel base B (m).")] = None,
    k_left: Annotated[float | None, Opt("--k-left", help="Left wheel k_L (m^1/2).")] = None,
    k_right: Annotated[float | None, Opt("--k-right", help="Right wheel k_R (m^1/2).")] = None,
    sigma_distance: Annotated[float | None, Opt(
        "--sigma-distance", help="Classical model: σ of each step's distance (m).")] = None,
    sigma_angle: Annotated[float | None, Opt(
        "--sigma-angle", help="Classical model: σ of each step's rotation (rad).")] = None,
    speed_noise: Annotated[float | None, Opt(
        "--speed-noise", help="Kelly α_ss (m) (distance variance per metre).")] = None,
    gyro_noise: Annotated[float | None, Opt(
        "--gyro-noise", help="Kelly σ_gg, yaw-rate noise density (rad²/s).")] = None,
    heading_noise: Annotated[float | None, Opt(
        "--heading-noise", help="Kelly σ_θθ, compass noise density (rad²·s).")] = None,
    initial_pose: Annotated[str, Opt("--initial-pose", help="x,y,θ (m, m, rad).")] = "0,0,0",
    initial_cov: Annotated[str | None, Opt(
        "--initial-cov", help="Initial variances var_x,var_y,var_θ (diagonal).")] = None,
    initial_cov_matrix: Annotated[str | None, Opt(
        "--initial-cov-matrix", help="Full initial covariance 'a,b,c;d,e,f;g,h,i'.")] = None,
    engine: Annotated[str, Opt("--engine", help="closed | recursion | transition")] = "closed",
    partitions: Annotated[int | None, Opt(
        "--partitions", help="Steps per segment (recursion engines; classical pieces).")] = None,
    json_out: Annotated[bool, Opt("--json", help="Print one JSON object.")] = False,
) -> None:
    """Predict the end pose and its covariance for a path of segments (closed form)."""
    if model not in _MODEL_FLAGS:
        raise ModelError(f"--model must be one of {', '.join(_MODEL_FLAGS)}, got {model!r}")
    if engine not in ENGINES:
        raise ModelError(f"--engine must be one of {', '.join(ENGINES)}, got {engine!r}")
    given = {"--wheel-base": wheel_base, "--k-left": k_left, "--k-right": k_right,
             "--sigma-distance": sigma_distance, "--sigma-angle": sigma_angle,
             "--speed-noise": speed_noise, "--gyro-noise": gyro_noise,
             "--heading-noise": heading_noise}
    stray = [flag for flag, v in given.items() if v is not None and flag not in _MODEL_FLAGS[model]]
    if stray:
        raise ModelError(f"{', '.join(stray)} does not apply to --model {model}")
    if initial_cov is not None and initial_cov_matrix is not None:
        raise ModelError("give --initial-cov or --initial-cov-matrix, not both")
    cov0: Any = None
    if initial_cov is not None:
        var = _numbers(initial_cov, "--initial-cov", 3)
        if min(var) < 0:
            raise ModelError(f"--initial-cov holds variances, which must be >= 0; got {var}")
        cov0 = [[var[0], 0.0, 0.0], [0.0, var[1], 0.0], [0.0, 0.0, var[2]]]
    elif initial_cov_matrix is not None:
        cov0 = _matrix(initial_cov_matrix)
    if model == "diff" and wheel_base is None:
        raise ModelError("--model diff needs --wheel-base (metres)")
    result = predict(
        [parse_segment(s, model) for s in segment],
        _noise(model, noise, given),
        wheel_base=wheel_base,
        pose0=_numbers(initial_pose, "--initial-pose", 3),
        cov0=cov0,
        engine=engine,  # type: ignore[arg-type]
        partitions=partitions,
    )
    if json_out:
        print_json(result.to_dict())
    else:
        _print_table(result)
