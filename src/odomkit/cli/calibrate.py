"""``odomkit calibrate`` and ``odomkit calibrate-noise``.

::

    odomkit calibrate RUN.csv ... --robot ROBOT.toml [--method exact|umbmark]
        [--from endpoints|trajectory] [--side S] [--out-robot new.toml]
        [--truth GT ... [TRUTH OPTIONS]] [--window 60s|20m] [--fix NAME ...]
        [--ros-yaml params.yaml --wheel-radius R] [--twist-speed V --controller-period T]
        [LOG OPTIONS] [--force] [--json]
    odomkit calibrate-noise RUN.csv ... --robot ROBOT.toml [--components x,y,theta]
        [--known-mean] [--level 0.95] [LOG OPTIONS] [--json]

LOG OPTIONS are those of ``odomkit track`` (:mod:`odomkit.cli.log_options`), TRUTH OPTIONS
the shared ones (:mod:`odomkit.cli.truth_options`). With ``--truth`` (the i-th for the i-th
run) the fit compares the odometry with every truth fix on the truth's own clock and fits
each run's start pose (:func:`odomkit.calibrate.positions.calibrate_positions`):
position-only, noisy truth such as GPS works. ``--window`` cuts each run into windows, each
fitted from its own start pose (a long drive whose heading wanders biases a whole-run fit);
without ``--truth`` the logs' own ground truth is then compared as position fixes.
``--heading-weight`` W [m/rad] compares the truth's heading too, W·wrap(θ − θ_truth) beside
each fix's position. ``--fix NAME`` (repeatable) holds a parameter at the robot file's value
in every fit (a car whose drive hardly turns: ``--fix wheel_base``).
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
from odomkit.cli.progress import progress_bar
from odomkit.cli.truth_options import (
    TruthListOption,
    with_truth_options,
)
from odomkit.errors import InputError

if TYPE_CHECKING:
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["calibrate_command", "calibrate_noise_command"]


@app.command("calibrate")
@with_log_options
@with_truth_options
def calibrate_command(
    runs: Annotated[list[Path], typer.Argument(help="Logs with ground truth (e.g. OptiOdom run files).")],
    robot: Annotated[Path, typer.Option("--robot", help="Robot file (TOML) the odometry used.")],
    method: Annotated[str, typer.Option("--method", help="exact | umbmark")] = "exact",
    source: Annotated[str | None, typer.Option(
        "--from", help="exact: fit the run 'endpoints' (default) or the whole 'trajectory'.")] = None,
    side: Annotated[float | None, typer.Option(
        "--side", help="Square side [m]: required by umbmark; with exact, E_max,syst is reported.")] = None,
    heading_weight: Annotated[float | None, typer.Option(
        "--heading-weight",
        help="exact: weight of the heading residual [m/rad] (default 0: positions only); with --truth "
             "or --window the truth's heading (TUM, t,x,y,theta, motion capture) beside each fix.")] = None,
    out_robot: Annotated[Path | None, typer.Option(
        "--out-robot", help="Write the corrected robot file.")] = None,
    ros_yaml: Annotated[Path | None, typer.Option(
        "--ros-yaml", help="Write ROS 2 diff_drive_controller (tricycle: tricycle_controller) "
                           "parameters (YAML).")] = None,
    wheel_radius: Annotated[float | None, typer.Option(
        "--wheel-radius", help="Nominal wheel radius [m] for --ros-yaml.")] = None,
    twist_speed: Annotated[float | None, typer.Option(
        "--twist-speed", help="The (v, ω) covariance a controller publishes at this speed [m/s], from the "
                              "robot file's white [noise], for robot_localization (any robot); with "
                              "--ros-yaml also its twist_covariance_diagonal.")] = None,
    controller_period: Annotated[float | None, typer.Option(
        "--controller-period", help="--twist-speed: the controller's update period [s] "
                                    "(1/update_rate).")] = None,
    velocity_window: Annotated[int, typer.Option(
        "--velocity-window", help="--twist-speed: updates the published velocity averages "
                                  "(velocity_rolling_window_size).")] = 10,
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Draw the runs with the robot file's and the calibrated parameters against the "
                       "truth (with --side: UMBmark's return errors before and after) into this file "
                       "(.png, .svg or .pdf; needs the plot extra).")] = None,
    fit_steering_cubic: Annotated[bool, typer.Option(
        "--fit-steering-cubic", help="car: fit steering_cubic too, a steering ratio that varies with the "
                                     "angle (needs large steering angles in the logs).")] = False,
    window: Annotated[str | None, typer.Option(
        "--window", help="Fit the truth positions in consecutive windows of this length, each from its own "
                         "start pose, the robot's parameters shared: 60s (time) or 20m (odometry travel). "
                         "For long drives whose heading drifts (a whole-run fit shrinks the path); "
                         "without --truth the logs' own truth is compared as positions.")] = None,
    fix: Annotated[list[str] | None, typer.Option(
        "--fix", help="exact: hold this parameter at the robot file's value (repeatable), e.g. wheel_base "
                      "for a car whose drive hardly turns (it pins only tan(steer)/wheel_base).")] = None,
    force: Annotated[bool, typer.Option("--force", help="Replace existing output files.")] = False,
    truth: TruthListOption = None,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    *,
    log_opts: LogOptions,
    truth_base: TruthOptions,
) -> None:
    """Calibrate wheel scales and wheel base, or a tricycle's or car's speed scale, steering
    offset and wheel base (exact least squares or UMBmark) from logs with ground truth."""
    from odomkit.workflows.calibration import calibrate_files
    from odomkit.workflows.truth import truth_options_per_log, with_truth_topic

    options, base = with_truth_topic(log_opts, truth_base, bool(truth))
    per_run = truth_options_per_log(base, list(truth), len(runs)) if truth else None
    with reported_warnings() as warned:
        # Flags that do not apply to the method are refused by the workflow, not dropped.
        out = calibrate_files(runs, robot, method=method, source=source, side=side,
                              out_robot=out_robot, ros_yaml=ros_yaml, wheel_radius=wheel_radius, plot=plot,
                              twist_speed=twist_speed, controller_period=controller_period,
                              velocity_window=velocity_window,
                              overwrite=force, log_options=options, truth=per_run, own_truth=base,
                              heading_weight=heading_weight, steering_cubic=fit_steering_cubic, window=window,
                              fixed=list(fix or ()))
    if json_out:
        print_json(with_warnings(out, warned))
        return
    _print_text(out)


def _print_text(out: dict[str, Any]) -> None:
    if out["method"] == "exact":
        windows = out.get("windows")
        cut = "" if windows is None else (
            f" in {windows['fitted']} window(s) of {windows['length']}, each from its own start pose"
            + (f" ({windows['left_out']} left out, see the notes)" if windows["left_out"] else ""))
        print(f"exact calibration from {out['source']} of {out['n_runs']} run(s){cut}")
        between = out.get("std_errors_between_runs", {})
        clusters = "runs" if windows is None else "windows"
        held = out.get("held", ())
        for name, value in out["parameters"].items():
            if name in held:  # --fix: not fitted
                print(f"  {name:16s} {value:.6f}  held at the robot file's value (--fix)")
                continue
            # The standard error to two significant digits: a fixed six decimals shows
            # "± 0.000000" for a steering offset pinned to 1e-7 rad.
            line = f"  {name:16s} {value:.6f} ± {out['std_errors'][name]:.2g}"
            if name in between:  # from the runs' spread, where the fit's own may be optimistic
                line += f"  (between {clusters} ± {between[name]:.2g})"
            print(line)
        offset = out.get("truth_time_offset")
        if offset is not None:  # a fix stamped t is the pose at log time t - offset
            how = f"± {offset['std_error']:.2g}" if offset.get("fitted") else "(given)"
            if "std_error_between_runs" in offset:
                how += f"  (between {clusters} ± {offset['std_error_between_runs']:.2g})"
            way = "lag" if offset["value"] >= 0 else "lead"
            print(f"  {'truth clock':16s} {offset['value']:+.6f} s {how}  "
                  f"(the truth's fixes {way} the log by {abs(offset['value']):.3g} s)")
        if "E_d" in out:
            print(f"  E_d = {out['E_d']:.6f}  E_b = {out['E_b']:.6f}  E_s = {out['E_s']:.6f}  "
                  f"wheel base {out['wheel_base']:.6f} m")
        for note in out["notes"]:
            print(f"  note: {note}")
    else:
        print(f"UMBmark: E_d = {out['E_d']:.6f}  E_b = {out['E_b']:.6f}  "
              f"c_left = {out['c_left']:.6f}  c_right = {out['c_right']:.6f}")
    twist = out.get("twist_covariance")
    if twist is not None:
        print(f"twist covariance at {twist['speed']:g} m/s (controller period "
              f"{twist['controller_period']:g} s, {twist['velocity_window']} update(s) averaged): "
              f"var v {twist['var_speed']:.3g} m²/s², "
              f"var ω {twist['var_yaw_rate']:.3g} rad²/s², cov {twist['cov_speed_yaw_rate']:.3g} m·rad/s²")
    if "e_max_syst_before" in out:
        print(f"E_max,syst on these runs: {1e3 * out['e_max_syst_before']:.2f} mm before, "
              f"{1e3 * out['e_max_syst_after']:.2f} mm after")
    for kind, path in out["outputs"].items():
        print(f"wrote {kind}: {path}")


@app.command("calibrate-noise")
@with_log_options
def calibrate_noise_command(
    runs: Annotated[list[Path], typer.Argument(help="Repeated runs of one path, with ground truth.")],
    robot: Annotated[Path, typer.Option("--robot", help="Calibrated robot file (TOML).")],
    components: Annotated[str, typer.Option(
        "--components", help="End-pose components in the likelihood, e.g. x,theta.")] = "x,y,theta",
    known_mean: Annotated[bool, typer.Option(
        "--known-mean", help="Assume zero mean end error instead of estimating it.")] = False,
    level: Annotated[float, typer.Option("--level", help="Confidence level of the intervals.")] = 0.95,
    plot: Annotated[Path | None, typer.Option(
        "--plot", help="Draw the errors with fitted and empirical 95 % ellipses (.png, .svg or .pdf; "
                       "needs the plot extra).")] = None,
    force: Annotated[bool, typer.Option("--force", help="Replace an existing --plot file.")] = False,
    json_out: Annotated[bool, typer.Option("--json", help="Print one JSON object.")] = False,
    *,
    log_opts: LogOptions,
) -> None:
    """Maximum-likelihood k_L, k_R (per-wheel noise [m^½]) with profile-likelihood intervals."""
    from odomkit.workflows.calibration import noise_files

    comps = tuple(c.strip() for c in components.split(",") if c.strip())
    if not 0 < level < 1:
        raise InputError(f"--level must be in (0, 1), got {level}")
    kwargs: dict[str, Any] = {"components": comps, "level": level}
    if known_mean:
        kwargs["mean"] = [0.0] * len(comps)
    options = log_opts
    with reported_warnings() as warned, progress_bar(json_out) as progress:
        out = noise_files(runs, robot, log_options=options, plot=plot, overwrite=force,
                          progress=progress, **kwargs)
    if json_out:
        print_json(with_warnings(out, warned))
        return
    pct = f"{100 * out['level']:g} %"
    print(f"k_left  = {out['k_left']:.6g} m^1/2  ({pct} profile-likelihood interval "
          f"{out['ci_left'][0]:.6g} .. {out['ci_left'][1]:.6g})")
    print(f"k_right = {out['k_right']:.6g} m^1/2  ({pct} interval "
          f"{out['ci_right'][0]:.6g} .. {out['ci_right'][1]:.6g})")
    print(f"from {out['n_runs']} runs, components {', '.join(out['components'])}")
    if "plot" in out:
        print(f"wrote plot: {out['plot']}")
