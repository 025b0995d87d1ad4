"""``odomkit simulate``: Monte Carlo runs of a segment path against the prediction.

::

    odomkit simulate --model diff --wheel-base 0.4 --k-left 0.001 --k-right 0.001 \\
        --segment arc:3,1 --runs 10000 --partitions 10000 --seed 1 [--json]

Same robot, noise and segment options as ``odomkit predict`` (parsed by its helpers; a
robot file with ``--robot``), plus ``--runs --partitions --seed --workers --chunk-runs
--scheduler --systematic``.
"""

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
    parse_numbers,
    path_problem,
)
from odomkit.cli.output import print_json
from odomkit.cli.progress import progress_bar
from odomkit.errors import ModelError

__all__ = ["simulate_command"]


def _fmt(v: float, digits: int = 5) -> str:
    return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.{digits}g}"


def _print_table(r: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    th, sim, z = r["theory"], r["simulation"], r["z"]
    se = sim["se"]
    table = Table(title=f"odomkit simulate: {r['runs']} runs × {r['partitions']} "
                        f"partitions per segment, {r['seconds']:.2f} s")
    for col in ("", "theory", "simulation", "± s.e.", "z"):
        table.add_column(col, justify="right")
    names = ("x (m)", "y (m)", "θ (rad)")
    # display only: the theory's θ is shown wrapped, so the simulated mean θ (continuous
    # in the JSON) is shown the same whole turns away, i.e. theory + mean error
    shown = [sim["mean"][0], sim["mean"][1], th["pose"][2] + sim["mean_error"][2]]
    for i, name in enumerate(names):
        table.add_row(f"mean {name}", _fmt(th["pose"][i], 6), _fmt(shown[i], 6),
                      _fmt(se["mean"][i], 2), _fmt(z["mean"][i], 2))
    for i, name in enumerate(names):
        table.add_row(f"std {name}", _fmt(th["std"][i]), _fmt(sim["std"][i]),
                      _fmt(se["std"][i], 2), _fmt(z["std"][i], 2))
    for key, label in (("xtheta", "corr xθ"), ("ytheta", "corr yθ"), ("xy", "corr xy")):
        table.add_row(label, _fmt(th["corr"][key], 4), _fmt(sim["corr"][key], 4),
                      _fmt(se["corr"][key], 2), _fmt(z["corr"][key], 2))
    checks = r["checks"]
    lines = []
    if "nees" in checks:
        lo, hi = checks["nees"]["bounds"]
        lines.append(f"mean NEES {checks['nees']['mean']:.4g} "
                     f"(expected {checks['nees']['expected']:g}, {1 - r['alpha']:.0%} "
                     f"interval [{lo:.4g}, {hi:.4g}])")
        lines.append(f"covariance LR {checks['cov']['statistic']:.4g} "
                     f"(accept ≤ {checks['cov']['critical']:.4g}, "
                     f"p = {checks['cov']['p_value']:.3g}); mean test p = "
                     f"{checks['mean']['p_value']:.3g}")
    console = Console()
    console.print(table)
    for line in lines + [f"verdict: {r['verdict']}"]:
        console.print(line, highlight=False, markup=False)


@app.command("simulate")
def simulate_command(
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
    runs: Annotated[int, Opt("--runs", help="Number of Monte Carlo runs N.")] = 10_000,
    partitions: Annotated[int, Opt(
        "--partitions", help=(
            "Partitions K of each segment: the numerical resolution (speed, wheel and gyro "
            "noise are split over them). A compass draws one heading error per compass "
            "sample (--compass-period), and K is rounded up to whole steps per sample; with "
            "--sample-period the steps are the samples; the output reports the K used."))] = 1000,
    seed: Annotated[int, Opt("--seed", help="Random seed (same seed, same numbers).")] = 0,
    workers: Annotated[int | None, Opt(
        "--workers", help="Threads for a local run (default: CPU count).")] = None,
    chunk_runs: Annotated[int | None, Opt(
        "--chunk-runs", help="Runs per task (whole blocks of 256); never changes numbers.")] = None,
    scheduler: Annotated[str | None, Opt(
        "--scheduler", help="Dask scheduler address, e.g. tcp://host:8786.")] = None,
    systematic: Annotated[str | None, Opt(
        "--systematic", help="Diff model: true E_d,E_b,E_s (Borenstein–Feng) of the robot.")] = None,
    alpha: Annotated[float, Opt("--alpha", help="Level of each consistency check.")] = 0.01,
    max_work: Annotated[float | None, Opt(
        "--max-work", help="Largest runs x partitions x segments to accept (default 1e10, "
                           "a few minutes).")] = None,
    plot: Annotated[Path | None, Opt(
        "--plot", help="Draw the runs' end poses with the predicted 95 % ellipse into this file "
                       "(.png, .svg or .pdf; needs the plot extra; the first 4096 runs are "
                       "simulated again for it).")] = None,
    force: Annotated[bool, Opt("--force", help="Replace an existing --plot file.")] = False,
    json_out: JsonOption = False,
) -> None:
    """Simulate noisy runs of a path and compare them with the predicted covariance."""
    # The Monte Carlo stack (scipy.stats, numba, dask) loads only when the command runs.
    from odomkit.robot import SystematicErrors
    from odomkit.workflows.simulate import run_simulate

    problem = path_problem(
        model, noise, segment,
        {"--wheel-base": wheel_base, "--k-left": k_left, "--k-right": k_right,
         "--sigma-distance": sigma_distance, "--sigma-angle": sigma_angle,
         "--speed-noise": speed_noise, "--gyro-noise": gyro_noise, "--turn-noise": turn_noise,
         "--turn-travel-noise": turn_travel_noise,
         "--heading-noise": heading_noise, "--compass-period": compass_period,
         "--lateral-noise": lateral_noise, "--sample-period": sample_period},
        initial_pose, initial_cov, initial_cov_matrix, robot)
    sys_err = None
    if systematic is not None:
        e_d, e_b, e_s = parse_numbers(systematic, "--systematic", 3)
        sys_err = SystematicErrors(E_d=e_d, E_b=e_b, E_s=e_s)
    if not (0 < alpha < 1):
        raise ModelError(f"--alpha must be between 0 and 1, got {alpha!r}")
    # The bar (stderr, a terminal only) closes before the warnings and the table are printed.
    with reported_warnings() as warned, progress_bar(json_out) as progress:
        result = run_simulate(
            problem.segments,
            problem.noise,
            problem.wheel_base,
            runs=runs, partitions=partitions, seed=seed,
            pose0=problem.pose0, cov0=problem.cov0,
            systematic=sys_err, alpha=alpha, workers=workers, chunk_runs=chunk_runs,
            scheduler=scheduler, progress=progress, compass_period=problem.compass_period,
            max_work=max_work, plot=plot, overwrite=force,
            robot=problem.robot, sample_period=problem.sample_period,
        )
    if json_out:
        print_json(with_warnings(result, warned))
    else:
        _print_table(result)
        for kind, path in result.get("outputs", {}).items():
            print(f"wrote {kind}: {path}")
