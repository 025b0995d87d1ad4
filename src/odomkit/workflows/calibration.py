"""Calibration from files: read runs and robot files, calibrate, write what robots use.

The maths lives in :mod:`odomkit.calibrate`; this module is the file side behind
``odomkit calibrate`` and ``odomkit calibrate-noise`` (``odomkit umbmark --runs`` is
:mod:`odomkit.workflows.umbmark`).
Nothing existing is overwritten unless ``overwrite=True`` (CLI ``--force``).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from odomkit.calibrate.check_ratios import COVERS_ONE
from odomkit.calibrate.exact import ExactCalibration, calibrate_exact
from odomkit.calibrate.export import turn_noise_note, twist_covariance
from odomkit.calibrate.noise_fit import fit_wheel_noise_from_runs
from odomkit.calibrate.positions import calibrate_positions, runs_disagree
from odomkit.calibrate.realdata import (
    SquareRow,
    e_max_syst_of_runs,
    square_table,
    umbmark_from_runs,
)
from odomkit.calibrate.residuals import CALIBRATED_ROBOTS
from odomkit.errors import InputError, ModelError
from odomkit.io.files import check_outputs
from odomkit.io.optiodom import read_experiment
from odomkit.io.robotfile import read_robot, read_robot_name, read_truth_table, robot_to_dict, write_robot
from odomkit.io.ros import write_ros2_yaml
from odomkit.progress import NO_PROGRESS, Progress, stage
from odomkit.robot import Car, DiffDrive, Tricycle
from odomkit.truth import Truth
from odomkit.windows import WindowSpec, parse_window
from odomkit.workflows.logs import LogOptions, load_log
from odomkit.workflows.results import check_result, numeric_guard
from odomkit.workflows.truth import TruthOptions, load_truth

if TYPE_CHECKING:
    from odomkit.log import OdometryLog
    from odomkit.robot import Robot

__all__ = ["calibrate_files", "CUBIC_HINT", "file_wheel_radius", "noise_files", "optiodom_square_table"]


#: What a car whose drive's halves disagree is told to try (a caller without the flag, the
#: report, names its own way to it).
CUBIC_HINT = "try --fit-steering-cubic (a steering ratio that varies with the angle)"


def calibrate_files(
    run_paths: str | Path | Sequence[str | Path],
    robot_path: str | Path,
    *,
    method: str = "exact",
    source: str | None = None,
    side: float | None = None,
    out_robot: str | Path | None = None,
    ros_yaml: str | Path | None = None,
    wheel_radius: float | None = None,
    twist_speed: float | None = None,
    controller_period: float | None = None,
    velocity_window: int = 10,
    overwrite: bool = False,
    log_options: LogOptions | None = None,
    truth: TruthOptions | Sequence[TruthOptions] | None = None,
    own_truth: TruthOptions | None = None,
    plot: str | Path | None = None,
    steering_cubic: bool = False,
    cubic_hint: str = CUBIC_HINT,
    window: str | WindowSpec | None = None,
    fixed: Sequence[str] = (),
    **exact_kwargs: Any,
) -> dict[str, Any]:
    """Read runs and a robot file, calibrate, write the requested outputs (CLI backend).

    Parameters
    ----------
    run_paths : log files with ground truth (any format
        :func:`odomkit.workflows.logs.load_log` reads), or one.
    robot_path : robot file (TOML) with the parameters the odometry used.
    method : {"exact", "umbmark"}
    source : {"endpoints", "trajectory"}, optional
        Exact only (default "endpoints"); an error with UMBmark, which ignores it.
    side : square side [m] (UMBmark only; required there).
    out_robot, ros_yaml : optional output paths (never overwritten unless ``overwrite``);
        all outputs are checked before anything is read or computed.
    wheel_radius : nominal wheel radius for the ROS snippet [m]; default the radius the
        robot file gives (``wheel_radius``/``wheel_diameter``), and an error if it differs.
        The snippet is a ``diff_drive_controller``'s or, for a tricycle, a
        ``tricycle_controller``'s.
    twist_speed, controller_period, velocity_window : with ``twist_speed`` [m/s] the summary
        (``twist_covariance``, any robot) and the snippet, where there is one, get
        ``twist_covariance_diagonal``, the twist covariance the robot
        file's white ``[noise]`` implies at that speed for a controller updating every
        ``controller_period`` [s] and averaging ``velocity_window`` updates
        (:func:`odomkit.calibrate.export.twist_covariance`).
    log_options : :class:`odomkit.workflows.logs.LogOptions`.
    truth : one :class:`odomkit.workflows.truth.TruthOptions` per run (``--truth``; or one for
        every run), optional
        Exact only: compare every truth fix, on the truth's own clock, with the odometry
        and fit each run's start pose with the robot's parameters
        (:func:`odomkit.calibrate.positions.calibrate_positions`; position-only, noisy truth
        such as GPS is enough). ``--from`` does not apply; ``--heading-weight`` W > 0 [m/rad]
        compares a truth's heading too, W·wrap(θ − θ_truth) beside each fix's position (an
        error naming a truth that has none).
    own_truth : how to take the logs' own position-only truth (a ROS bag's GPS topic,
        ``--truth-topic``: σ, clock offset) where ``truth`` is None; such logs are then
        calibrated from their fixes as with ``truth``.
    plot : .png, .svg or .pdf file, optional
        Draw the runs before and after calibration against the truth and, with ``side``,
        UMBmark's return errors (:func:`odomkit.workflows.figures.calibration_figure`).
    steering_cubic : fit a car's ``steering_cubic`` too (exact, from a trajectory or truth
        fixes; ``--fit-steering-cubic``).
    cubic_hint : the advice a car whose drive's halves disagree gets (default
        :data:`CUBIC_HINT`, the flag; a caller without it names its own way).
    window : str or WindowSpec, optional
        ``--window``: cut each run into consecutive windows of this length (``"60s"`` time,
        ``"20m"`` odometry travel; :func:`odomkit.windows.parse_window`), each fitted from its
        own start pose, the robot's parameters and the truth's clock offset shared
        (:func:`odomkit.calibrate.positions.calibrate_positions` ``window=``): a long drive
        whose dead-reckoned heading wanders biases a fit of the whole run. Exact only; with
        the logs' own ground truth (no ``truth``) their positions are compared as fixes on the
        log's own clock (no clock offset fitted; their heading compared only with
        ``--heading-weight``), so ``--from`` does not apply. JSON ``windows`` (length, fitted, left_out);
        ``std_errors_between_runs`` are then between windows, and a single run's halves are
        not calibrated alone (``halves`` absent).
    fixed : parameter names held at the robot file's values (``--fix``, exact only), in every
        fit: the runs' together, each run's and each half's alone, and from whichever start
        the fit takes (:func:`odomkit.calibrate.positions.calibrate_positions`,
        :func:`odomkit.calibrate.exact.calibrate_exact`). Their standard errors are 0 and
        the summary names them (``held``). A name the robot's calibration does not fit is an
        InputError naming those it does; so is holding every one. For a car whose drive
        hardly turns, ``["wheel_base"]``: the turning pins only tan(steer)/wheel_base, a
        steering ratio or understeer as much as the length.
    **exact_kwargs : passed to :func:`odomkit.calibrate.exact.calibrate_exact` (exact only).

    Returns
    -------
    dict with the calibration summary (JSON-ready), ``robot`` (the corrected parameters
    as in the robot file) and ``outputs`` (paths written).
    """
    from odomkit.workflows.results import paths_given, truths_per_log

    run_paths = paths_given(run_paths, "run")
    spec = parse_window(window) if isinstance(window, str) else window
    if truth is not None:
        truth = truths_per_log(truth, len(run_paths), "run")
    truth_paths = [t.path for t in truth or () if t.path is not None]
    check_outputs({"--out-robot": out_robot, "--ros-yaml": ros_yaml, "--plot": plot}, overwrite=overwrite,
                  inputs=[robot_path, *run_paths, *truth_paths])
    if plot is not None:
        from odomkit.plot import check_plot_file

        check_plot_file(plot)
        if spec is not None:
            # The figure draws each run from one start pose: not the fit of windows, each from
            # its own (a 600 s drive: 0.27 m RMS drawn for a 0.04 m fit).
            raise InputError("--plot draws whole runs, each from one start pose, not a calibration in "
                             "--window windows; leave out one of them")
    if truth is not None:
        _refuse_trajectory_flags(method, source, exact_kwargs)
    if method not in ("exact", "umbmark"):
        raise ModelError(f"--method must be 'exact' or 'umbmark', got {method!r}")
    if method == "umbmark":
        stray = [_EXACT_FLAGS.get(k, k) for k, v in exact_kwargs.items() if v is not None]
        if source is not None:
            stray.insert(0, "--from")
        if steering_cubic:
            stray.append("--fit-steering-cubic")
        if spec is not None:
            stray.append("--window")
        if fixed:
            stray.append("--fix")
        if stray:
            raise InputError(f"{', '.join(stray)} applies to --method exact only, not to umbmark")
        if side is None:
            raise InputError("--method umbmark needs --side (the square side in metres)")
    exact_kwargs = {k: v for k, v in exact_kwargs.items() if v is not None}
    if wheel_radius is not None and ros_yaml is None:
        raise InputError("--wheel-radius applies to --ros-yaml only (the controller's nominal radius)")
    robot, noise = read_robot(robot_path)
    fixed = _check_fixed(fixed, robot, steering_cubic, robot_path) if method == "exact" else ()
    if ros_yaml is not None:
        if not isinstance(robot, DiffDrive | Tricycle):
            raise InputError(f"--ros-yaml writes diff_drive_controller or tricycle_controller parameters; "
                             f"the robot file describes a {robot.type_name!r} robot (--twist-speed "
                             "without --ros-yaml gives any robot's twist covariance)", source=str(robot_path))
        wheel_radius = _controller_radius(robot_path, wheel_radius)
    if twist_speed is not None or controller_period is not None:
        _check_twist(twist_speed, controller_period, noise, robot_path)
    if method == "umbmark" and not isinstance(robot, DiffDrive):
        raise InputError("UMBmark needs a differential-drive robot (type = \"diff\")",
                         source=str(robot_path))
    runs = [load_log(p, robot, log_options or LogOptions()) for p in run_paths]
    own_columns = False  # the logs' own gt_* columns compared as fixes (--window without --truth)
    if truth is None and method == "exact" and any(isinstance(log.meta.get("truth"), Truth) for log in runs):
        # A bag's GPS topic (--truth-topic): position-only fixes on their own clock, compared
        # one by one as --truth files are.
        _refuse_trajectory_flags(method, source, exact_kwargs)
        truth = [own_truth or TruthOptions()] * len(runs)
    elif truth is None and method == "exact" and spec is not None:
        # Windows each start from a pose of their own, fitted as calibrate_positions fits a
        # run's: the logs' own truth is compared as fixes, on the log's clock (nothing to fit;
        # --truth-time-offset still moves it).
        _refuse_trajectory_flags(method, source, exact_kwargs, why="--window")
        own = own_truth or TruthOptions()
        truth = [replace(own, time_offset=own.time_offset or 0.0)] * len(runs)
        own_columns = True
    truth_table = read_truth_table(robot_path)  # kept in --out-robot; its offset refitted with --truth
    turning: Callable[[], tuple[float, float]] | None = None  # the drive's turning gain, with a truth
    with numeric_guard("the calibration"):
        if method == "umbmark":
            assert side is not None and isinstance(robot, DiffDrive)
            um = umbmark_from_runs(runs, robot, side)
            summary = um.to_dict()
            new_robot: Any = um.robot
        elif truth is not None:
            if not isinstance(robot, CALIBRATED_ROBOTS):
                raise InputError("calibration from truth positions fits a diff, tricycle, car, unicycle or "
                                 f"gyro robot; the robot file describes a {robot.type_name!r} robot",
                                 source=str(robot_path))
            # The truth's clock offset is fitted unless --truth-time-offset gives it (then the
            # truths below are already on the log's clock). The fit starts from the robot file's
            # [truth] time_offset, what an earlier calibration fitted, and fits what is left
            # within its range: a truth 8328 s off the log (an F1TENTH car's motion capture) was
            # refused with "only 0 truth fixes" though the file named the offset (user study).
            given = truth[0].time_offset
            base = (float(truth_table.get("time_offset", 0.0)) if given is None and not own_columns
                    and all(o.path is not None for o in truth) else 0.0)
            truths = []
            for log, options in zip(runs, truth, strict=True):
                found = load_truth(replace(options, time_offset=base) if base else options, log)
                if found is None:
                    raise InputError("no truth: give --truth or a log with gt_* columns", source=log.source)
                truths.append(found)
            gaps = [o.max_gap for o in truth]
            heading_weight = float(exact_kwargs.get("heading_weight", 0.0))  # the truth's heading compared

            def held(start: Any) -> Any:
                """``start`` with the --fix parameters at the robot file's values (a start the
                travel and turning suggest may have moved them)."""
                return replace(start, **{name: getattr(robot, name) for name in fixed}) if fixed else start

            def fit_from(start: Any) -> ExactCalibration:
                return calibrate_positions(runs, truths, held(start), fit_time_offset=given is None,
                                           steering_cubic=steering_cubic, window=spec,
                                           heading_weight=heading_weight, fixed=fixed)

            try:
                first = _fit_said(fit_from, robot)
            except ModelError as exc:
                first, failed = None, exc
            chosen = _better_start(first, runs, truths, robot, gaps, fit_from)
            if chosen is None:
                from odomkit.calibrate.check_ratios import follows_note

                # A truth that is not the log's explains every failure after it: said first.
                notes = [f"{log.source}: {n}" for log, found, gap in zip(runs, truths, gaps, strict=True)
                         if (n := follows_note(log, robot, found, gap))]
                if notes:
                    raise ModelError("; ".join(notes) + f" (so the fit failed: {failed})") from failed
                raise ModelError(str(failed) + _why_off(runs, truths, robot, gaps)) from failed
            cal, start, said = chosen
            # The drive's own turning, on the truth's clock as fitted (a Husky's 1.42 s moved its
            # turning gain from 0.97 ± 0.08 to 1.07 ± 0.06).
            fitted = cal.time_offset or 0.0 if given is None else 0.0
            shifted = [replace(t, t=t.t - fitted) for t in truths] if fitted else truths
            turning = partial(_turning_gain, runs, shifted, robot, gaps)
            for w in said:  # what the fit kept had to say
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
            # A unit read wrong can also land in a local minimum inside the range (mph read as
            # m/s on a simulated car: c_scale 0.71, wheel base 1.65 m, 65 m residuals).
            if off := _why_off(runs, truths, robot, gaps, only_failures=True):
                warnings.warn("the calibration may be bent by a unit or robot-file error" + off, UserWarning,
                              stacklevel=2)
            summary = cal.to_dict()
            if len(runs) > 1:
                # Each run alone (each half) from the start the joint fit came from.
                summary["per_run"] = _each_run_alone(cal, runs, lambda i: calibrate_positions(
                    [runs[i]], [truths[i]], held(start), fit_time_offset=given is None,
                    steering_cubic=steering_cubic, window=spec, heading_weight=heading_weight, fixed=fixed))
            elif spec is None:  # windows: their spread is the between-window standard errors
                summary["halves"] = _each_half_alone(cal, runs[0], truths[0], held(start), given is None,
                                                     steering_cubic, cubic_hint, nominal=robot,
                                                     heading_weight=heading_weight, fixed=fixed)
            new_robot = cal.robot
            if own_columns and given:  # a --truth-time-offset moved the gt_* columns: said
                summary["truth_time_offset"] = {"value": given, "std_error": 0.0, "fitted": False}
            elif not own_columns:  # the gt_* columns are on the log's clock: no offset to report
                if given is not None:
                    summary["truth_time_offset"] = {"value": given, "std_error": 0.0, "fitted": False}
                else:
                    fitted_clock = summary["truth_time_offset"]
                    total = base + float(fitted_clock["value"])
                    summary["truth_time_offset"] = {**fitted_clock, "value": total, "fitted": True,
                                                    **({"fitted_about": base} if base else {})}
                truth_table["time_offset"] = float(summary["truth_time_offset"]["value"])
                truth = [replace(o, time_offset=truth_table["time_offset"]) for o in truth]
        else:
            # A single trajectory's residuals are held against the truth's stated noise.
            stated = own_truth.sigma if own_truth is not None else None
            cal = calibrate_exact(runs, robot, source or "endpoints",  # type: ignore[arg-type]
                                  steering_cubic=steering_cubic, truth_sigma=stated, fixed=fixed,
                                  **exact_kwargs)
            summary = cal.to_dict()
            new_robot = cal.robot
            if len(runs) > 1 and source == "trajectory":
                # Endpoints have no run alone to compare (one end pose: 2 numbers for 3
                # parameters); their between-run standard errors need none.
                summary["per_run"] = _each_run_alone(cal, runs, lambda i: calibrate_exact(
                    [runs[i]], robot, "trajectory", steering_cubic=steering_cubic,  # type: ignore[arg-type]
                    truth_sigma=stated, fixed=fixed, **exact_kwargs))
            if side is not None and isinstance(robot, DiffDrive):
                summary["e_max_syst_before"] = e_max_syst_of_runs(runs, robot)
                summary["e_max_syst_after"] = e_max_syst_of_runs(runs, new_robot)
    _warn_far_from_file(robot, new_robot, turning)
    robot_fields = robot_to_dict(new_robot)["robot"]
    check_result("the calibration", {
        "the parameters": [v for v in robot_fields.values() if not isinstance(v, str)],
        **{k: summary.get(k) for k in ("E_d", "E_b", "wheel_base", "e_max_syst_before",
                                       "e_max_syst_after")},
    })
    outputs: dict[str, str] = {}
    if out_robot is not None:
        outputs["robot"] = str(write_robot(out_robot, new_robot, noise, overwrite=overwrite,
                                           truth=truth_table, name=read_robot_name(robot_path)))
    twist = None
    if twist_speed is not None:
        # robot_localization's twist covariance, for any robot: in the controller's YAML
        # where there is one (--ros-yaml), in the summary always.
        assert controller_period is not None
        twist = twist_covariance(new_robot, noise, twist_speed, controller_period, window=velocity_window)
        zero = [name for name, var in (("v", twist.var_speed), ("ω", twist.var_yaw_rate)) if var <= 0]
        if zero and twist.speed > 0:
            warnings.warn(f"the robot file's white noise gives {' and '.join(zero)} no variance at "
                          f"{twist.speed:g} m/s: an EKF (robot_localization) would trust it completely; "
                          "give that noise a value (fit-noise fitted it at zero? --fix keeps the file's)",
                          UserWarning, stacklevel=2)
        if turn := turn_noise_note(noise, controller_period, velocity_window):
            warnings.warn(turn, UserWarning, stacklevel=2)
        summary["twist_covariance"] = {"speed": twist.speed, "var_speed": twist.var_speed,
                                       "var_yaw_rate": twist.var_yaw_rate,
                                       "cov_speed_yaw_rate": twist.cov_speed_yaw_rate,
                                       "controller_period": twist.period, "velocity_window": twist.window}
    if ros_yaml is not None:
        assert wheel_radius is not None
        outputs["ros_yaml"] = str(write_ros2_yaml(ros_yaml, new_robot, wheel_radius,
                                                  overwrite=overwrite, twist=twist))
    if plot is not None:
        clock = summary.get("truth_time_offset", {})
        drawn = _calibration_plot(plot, runs, truth, robot, new_robot, side, bool(clock.get("fitted")),
                                  float(clock.get("fitted_about", 0.0)))
        if drawn is not None:  # else a warning has said why nothing was drawn
            outputs["plot"] = str(drawn)
    summary["method"] = method
    summary["robot"] = robot_fields
    summary["outputs"] = outputs
    return summary


#: A steered vehicle's calibrated length this far (relative) from the robot file's is named.
BENT_LENGTH = 0.1
#: A calibrated scale (a wheel's, a speed's, a gyro's) or a differential drive's wheel base
#: this far (relative) from the robot file's is no calibration error: tyres, loads and
#: temperature move a wheel's size by a few per cent, as check's travel ratio allows (15 %).
FAR_FROM_FILE = 0.15
_SCALES = {"diff": ("c_left", "c_right"), "tricycle": ("c_scale",), "car": ("c_scale",),
           "unicycle": ("c_scale", "yaw_rate_scale"), "gyro": ("m_per_tick", "gyro_scale")}


#: The scales that are a turning gain (:func:`_warn_far_from_file` holds them against the drive's).
_TURNING_SCALES = ("yaw_rate_scale", "gyro_scale")


def _turning_gain(runs: Sequence[OdometryLog], truths: Sequence[Truth], robot: Robot,
                  gaps: Sequence[float | None]) -> tuple[float, float]:
    """The drive's turning gain, odometry over truth with the robot file's values, and its
    standard error (:func:`odomkit.calibrate.check_ratios.motion_ratios`; the first run
    where it is measured; NaN where none is)."""
    from odomkit.calibrate.check_ratios import motion_ratios

    for log, truth, gap in zip(runs, truths, gaps, strict=True):
        r = motion_ratios(log, robot, truth, gap)
        if math.isfinite(r.turn) and math.isfinite(r.turn_se):
            return float(r.turn), float(r.turn_se)
    return math.nan, math.nan


#: Why a skid-steer or tracked base turns so differently from its geometry (ROS's
#: diff_drive_controller has a wheel_separation_multiplier for it; Clearpath ships 1.875 for its
#: Husky and 1.5 for its Jackal).
_SKID = ("its wheels slide sideways in every turn, so its effective wheel base is often 1.5-2x the "
         "geometric one: diff_drive_controller's wheel_separation_multiplier")


def _warn_far_from_file(robot: Robot, new_robot: Robot,
                        turning: Callable[[], tuple[float, float]] | None = None) -> None:
    """A calibrated parameter far from the robot file's: a scale or a differential drive's
    wheel base more than :data:`FAR_FROM_FILE` off, a steered vehicle's length more than
    :data:`BENT_LENGTH`. Either a unit or a robot-file entry is wrong, or the fit started so
    far off that it found a local minimum (a real diff robot whose file halved its wheel
    base: c_right 1.32, wheel base +25 %, and the held-out half worse than uncalibrated, with
    nothing said); check names which.

    ``turning`` gives, where there is a truth, the drive's own turning gain (odometry over
    truth) and its standard error (:func:`_turning_gain`): a yaw-rate scale far off while
    the drive turns as much as the truth does is no gain of the robot's but something else
    the fit absorbed (a Husky bag: yaw_rate_scale 1.21 on one half, its turning 0.97 ± 0.08)."""
    advice = ("odomkit check LOG --robot R --truth T (or --truth-topic) compares the odometry's travel and "
              "turning with the truth's and names the entry")
    for name in _SCALES.get(robot.type_name, ()):
        before, after = float(getattr(robot, name)), float(getattr(new_robot, name))
        if before > 0 and abs(off := after / before - 1) > FAR_FROM_FILE:
            gain, se = turning() if turning is not None and name in _TURNING_SCALES else (math.nan, math.nan)
            if abs(gain - 1) <= COVERS_ONE * se:
                warnings.warn(f"the calibrated {name} {after:.4g} is {100 * off:+.0f} % from the robot "
                              f"file's {before:.4g}, but the drive turns {gain:.3g} ± {se:.2g} x as much as "
                              "the truth does with the file's: no turning gain of the robot's, but something "
                              "else the fit absorbed (a yaw-rate bias, the truth's clock, a start heading); "
                              "a calibration from another part of the drive will differ, so check it on one "
                              "(--span)", UserWarning, stacklevel=3)
                continue
            # A unicycle's yaw rate is often a base controller's twist, computed from its wheels
            # with a nominal track width (a skid-steer base's turns slip by tens of per cent), or
            # from a car's commanded steering (an F1TENTH's VESC odometry: 0.57, a user study).
            why = (f"no gyro is that far off, but a yaw rate that is computed, not measured, is: a "
                   f"skid-steer or tracked base's odometry twist ({_SKID}), or a car's twist from its "
                   "commanded steering angle (an RC car's VESC odometry turned 1.8x its motion capture); "
                   "otherwise a unit" if name == "yaw_rate_scale" else
                   "no wheel or gyro is that far off its own; a unit")
            warnings.warn(f"the calibrated {name} {after:.4g} is {100 * off:+.0f} % from the "
                          f"robot file's {before:.4g}: {why} or a robot-file entry is wrong, or the fit "
                          f"started too far off and found a local minimum; {advice}", UserWarning,
                          stacklevel=3)
    if isinstance(robot, DiffDrive) and isinstance(new_robot, DiffDrive):
        before, after = robot.effective_wheel_base, new_robot.effective_wheel_base
        if before > 0 and abs(off := after / before - 1) > FAR_FROM_FILE:
            warnings.warn(f"the calibrated wheel base {after:.4g} m is {100 * off:+.0f} % from "
                          f"the robot file's {before:.4g} m: a two-wheeled base's wheels slip in turns by a "
                          f"few per cent, not so much, though a skid-steer or tracked base's do ({_SKID}); "
                          "otherwise the file's wheel_base is wrong, or the fit started too far off and "
                          f"found a local minimum; {advice}", UserWarning, stacklevel=3)
        return
    if isinstance(robot, Car):
        name, law, gains = "wheel_base", "tan(steer)", "steering_ratio, the road wheels' gain, understeer"
    elif isinstance(robot, Tricycle):
        name, law, gains = "wheel_to_axle", "sin(steer)", "the steering angle's gain"
    else:
        return
    # The turning per metre is tan α / L, so the fitted L stands in for every gain on the
    # steering, not only for the length: on the real BMW drive the halves gave 2.39 to 3.28 m
    # for a 2.69 m car with nothing said.
    before, after = float(getattr(robot, name)), float(getattr(new_robot, name))
    if before > 0 and abs(after / before - 1) > BENT_LENGTH:
        warnings.warn(f"the calibrated {name} {after:.4g} m is {100 * (after / before - 1):+.0f} % from the "
                      f"robot file's {before:.4g} m: the turning per metre is {law}/{name}, so it stands in "
                      f"for every gain on the steering ({gains}) as well as the length; if the length is "
                      "known, check the steering's unit and ratio (odomkit check --truth compares turning), "
                      f"or hold it: calibrate --fix {name} keeps the robot file's value and fits the rest",
                      UserWarning, stacklevel=3)


#: A calibration from a start the travel and turning ratios suggest replaces the robot
#: file's when its residual variance is below this share of the file's start's.
RESTART_GAIN = 0.5


def _ratio_start(runs: Sequence[OdometryLog], truths: Sequence[Truth], robot: Robot,
                 max_gaps: Sequence[float | None]) -> tuple[Any, str] | None:
    """A start for the calibration from the odometry's travel and turning against the truth
    (:func:`odomkit.calibrate.check_ratios.motion_ratios`, the median over the runs) where
    either is off beyond check's warning, and what it changed; None where both are within
    it (or cannot be measured)."""
    from odomkit.calibrate.check_ratios import TRAVEL_WARN, TURN_WARN, motion_ratios, unit_mixup
    from odomkit.robot import GyroOdometry, Unicycle

    ratios = [motion_ratios(log, robot, truth, gap) for log, truth, gap in
              zip(runs, truths, max_gaps, strict=True)]
    travel = float(np.nanmedian([r.travel for r in ratios])) if any(
        np.isfinite(r.travel) for r in ratios) else math.nan
    turn = float(np.nanmedian([r.turn for r in ratios])) if any(
        np.isfinite(r.turn) for r in ratios) else math.nan
    travel_off = math.isfinite(travel) and travel > 0 and abs(math.log(travel)) > math.log(TRAVEL_WARN)
    # A wheeled base turns by the distance it rolls: its wheel base or steering speaks in the
    # turning per metre (check_ratios._turn_finding); a gyro's turning is its own.
    wheeled = isinstance(robot, DiffDrive | Car | Tricycle)
    gain = turn / travel if wheeled and math.isfinite(travel) and travel > 0 else turn
    turn_off = math.isfinite(gain) and gain > 0 and abs(math.log(gain)) > math.log(TURN_WARN)
    if not (travel_off or turn_off) or unit_mixup(travel, gain) is not None:
        return None  # a unit read wrong is named (check_ratios), not calibrated away
    changes: dict[str, float] = {}
    scale = 1 / travel if travel_off else 1.0
    if isinstance(robot, DiffDrive):
        if travel_off:
            changes.update(c_left=robot.c_left * scale, c_right=robot.c_right * scale)
        if turn_off:  # the correction, as calibrate fits it (the file's wheel_base stays)
            changes["c_wheel_base"] = robot.c_wheel_base * gain
    elif isinstance(robot, Car | Tricycle):
        if travel_off:
            changes["c_scale"] = robot.c_scale * scale
        if turn_off:
            length = "wheel_base" if isinstance(robot, Car) else "wheel_to_axle"
            changes[length] = float(getattr(robot, length)) * gain
    elif isinstance(robot, Unicycle):
        if travel_off:
            changes["c_scale"] = robot.c_scale * scale
        if turn_off:
            changes["yaw_rate_scale"] = robot.yaw_rate_scale / gain
    elif isinstance(robot, GyroOdometry):
        if travel_off:
            changes["m_per_tick"] = robot.m_per_tick * scale
        if turn_off:
            changes["gyro_scale"] = robot.gyro_scale / gain
    if not changes:
        return None
    started: Any = robot  # every vehicle's fields named above are its own
    start = replace(started, **changes)
    said = ", ".join(f"wheel base {start.effective_wheel_base:.4g} m (c_wheel_base {v:.4g})"
                     if k == "c_wheel_base" else f"{k} {v:.4g}" for k, v in changes.items())
    return start, said


Fitted = tuple[ExactCalibration, Any, list[warnings.WarningMessage]]


def _fit_said(fit_from: Callable[[Any], ExactCalibration], start: Any) -> Fitted:
    """``fit_from(start)``, the start, and the warnings the fit gave, held back: only the fit
    kept says what it has to say."""
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        cal = fit_from(start)
    return cal, start, list(said)


def _better_start(first: Fitted | None, runs: Sequence[OdometryLog], truths: Sequence[Truth],
                  robot: Robot, max_gaps: Sequence[float | None],
                  fit_from: Callable[[Any], ExactCalibration]) -> Fitted | None:
    """The calibration from the robot file's values (``first``), or from the start the travel
    and turning ratios suggest (:func:`_ratio_start`) where that fits clearly better
    (:data:`RESTART_GAIN`) or the file's start failed (``first`` None). A fit from values
    far off finds a local minimum: a real diff robot whose file halved its wheel base
    calibrated to c_right 1.32 and a wheel base +25 % (residuals 0.18 m), where the start
    the turning suggested, 0.166 m, fitted to 0.02 m."""
    suggested = _ratio_start(runs, truths, robot, max_gaps)
    if suggested is None:
        return first
    try:
        other = _fit_said(fit_from, suggested[0])
    except ModelError:
        return first
    if first is not None and not other[0].residual_variance < RESTART_GAIN * first[0].residual_variance:
        return first
    before = (f"residual RMS {math.sqrt(other[0].residual_variance):.3g} against "
              f"{math.sqrt(first[0].residual_variance):.3g} from the robot file's values"
              if first is not None else "the robot file's values gave no fit")
    warnings.warn(f"the calibration started again from the values the odometry's travel and turning "
                  f"against the truth suggest ({suggested[1]}): {before}; the robot file is far off "
                  "(odomkit check names the entry)", UserWarning, stacklevel=3)
    return other


def _why_off(runs: Sequence[OdometryLog], truths: Sequence[Truth], robot: Robot,
             max_gaps: Sequence[float | None], only_failures: bool = False) -> str:
    """What ``odomkit check`` finds wrong with the odometry's travel or turning against the
    truth (its warnings and failures, or only its failures: off by more than 2×), for a
    calibration: a unit read wrong or a steering ratio left out runs a fit to the edge of
    its range or into a local minimum, and the check names it where the fit cannot."""
    from odomkit.calibrate.check_ratios import motion_problems

    said = [line for log, found, gap in zip(runs, truths, max_gaps, strict=True)
            for line in motion_problems(log, robot, found, gap, warnings=not only_failures)]
    return "".join(f"; odomkit check finds {s}" for s in dict.fromkeys(said))


def _each_run_alone(joint: ExactCalibration, runs: list[OdometryLog],
                    fit_alone: Callable[[int], ExactCalibration]) -> list[dict[str, Any]]:
    """Each run calibrated alone (``fit_alone(i)``: from its truth positions, or its own
    trajectory; JSON ``per_run``: ``log``, ``parameters``, ``std_errors``, or ``error`` where
    it cannot be fitted alone), and a warning where the joint fit is no compromise of them
    (:func:`runs_disagree`). N more fits, each of one run: together about as long as the
    joint fit (each run is integrated once per iteration either way)."""
    alone: list[ExactCalibration | None] = []
    rows: list[dict[str, Any]] = []
    for i, log in enumerate(runs):
        try:
            with warnings.catch_warnings():  # the joint fit has said what they would say
                warnings.simplefilter("ignore")
                one = fit_alone(i)
        except (InputError, ModelError) as exc:
            alone.append(None)
            rows.append({"log": log.source, "error": str(exc)})
            continue
        if not one.determined:  # its values lie anywhere along a ridge: nothing to compare
            alone.append(None)
            rows.append({"log": log.source, "error": "the run alone does not determine every parameter"})
            continue
        alone.append(one)
        summary = one.to_dict()
        rows.append({"log": log.source, "parameters": summary["parameters"],
                     "std_errors": summary["std_errors"]})
    said = runs_disagree(joint, alone, [log.source for log in runs])
    if said:
        warnings.warn(said, UserWarning, stacklevel=2)
    return rows


def _each_half_alone(joint: ExactCalibration, log: OdometryLog, truth: Truth, robot: Any,
                     clock_fitted: bool, steering_cubic: bool = False, cubic_hint: str = CUBIC_HINT, *,
                     nominal: Robot | None = None, heading_weight: float = 0.0, fixed: Sequence[str] = ()
                     ) -> list[dict[str, Any]] | None:
    """One drive's halves calibrated alone from ``robot`` and tried on each other, beside the
    ``nominal`` robot (the robot file's; JSON ``halves``), and a warning where the calibration
    does not hold along the drive (:func:`odomkit.calibrate.stability.halves_disagree`). None
    where a half cannot be fitted alone, with a warning that says why: a half whose fit fails
    (runs to the edge of a range) is itself a sign that the calibration does not hold (a
    Husky's ``--span :50%`` said nothing, and its calibration made the rest of the drive 4.7×
    worse than the robot file)."""
    from odomkit.calibrate.stability import calibrate_halves, halves_disagree, weakly_pinned

    if clock_fitted and joint.time_offset is not None:  # the fixes on the log's clock
        truth = replace(truth, t=truth.t - joint.time_offset)
    try:
        halves = calibrate_halves(log, truth, robot, steering_cubic=steering_cubic, nominal=nominal,
                                  heading_weight=heading_weight, fixed=fixed)
    except ModelError as exc:
        weak = weakly_pinned(joint, robot)
        # Where the whole drive pins a parameter near the edge of its range, a half may reach
        # that edge by chance: said, but not taken for evidence.
        what = (f"the whole drive pins {', '.join(weak)} too weakly for a half to be calibrated alone, so "
                "whether this calibration holds along the drive is not checked; drive more, turning both "
                "ways" if weak else
                "a half that cannot be fitted alone, where the whole drive pins every parameter, is itself a "
                "sign that this calibration may not hold on another drive; try it on a part it was not "
                "fitted to (--span)")
        warnings.warn(f"the drive's halves could not be calibrated alone ({exc}): {what}", UserWarning,
                      stacklevel=2)
        return None
    except InputError as exc:
        warnings.warn(f"the drive's halves were not calibrated alone ({exc}), so whether this calibration "
                      "holds along the drive is not checked", UserWarning, stacklevel=2)
        return None
    said = halves_disagree(halves)
    if said and isinstance(robot, Car) and not steering_cubic and robot.steering_cubic == 0:
        # What the real car's disagreement was (docs/results/honesty.md): a variable-ratio rack.
        said += f"; for a car that turns hard in one part of the drive and not in another, {cubic_hint}"
    if said:
        warnings.warn(said, UserWarning, stacklevel=2)
    return [half.to_dict() for half in halves]


def _check_fixed(fixed: Sequence[str], robot: Robot, steering_cubic: bool, robot_path: str | Path
                 ) -> tuple[str, ...]:
    """The ``--fix`` names, each once, checked against the parameters the robot's
    calibration fits (:func:`odomkit.calibrate.residuals.calibration_model`): one line naming
    those where a name is not one of them, or where every one is held."""
    from odomkit.calibrate.residuals import calibration_model

    names = tuple(dict.fromkeys(fixed))
    if not names or not isinstance(robot, CALIBRATED_ROBOTS):
        return names  # a robot calibrate does not fit is refused where it is calibrated
    valid = calibration_model(robot, [], steering_cubic=steering_cubic).names
    unknown = [name for name in names if name not in valid]
    if unknown:
        raise InputError(f"--fix {', '.join(unknown)}: not a parameter calibrate fits for a "
                         f"{robot.type_name!r} robot; give one of {', '.join(valid)}", source=str(robot_path))
    if set(valid) <= set(names):
        raise InputError(f"--fix holds every parameter ({', '.join(valid)}): nothing is left to calibrate; "
                         "hold fewer", source=str(robot_path))
    return names


def _refuse_trajectory_flags(method: str, source: str | None, exact_kwargs: Mapping[str, Any],
                             why: str = "--truth") -> None:
    """Calibration from truth fixes (``--truth``, a bag's GPS topic, or ``--window``: ``why``)
    takes none of the trajectory fit's flags but ``--heading-weight`` (which compares the
    truth's heading too): one line naming the ones given."""
    if method != "exact":
        raise InputError(f"{why} applies to --method exact")
    stray = (["--from"] if source is not None else []) + [
        _EXACT_FLAGS.get(k, k) for k, v in exact_kwargs.items() if v is not None and k not in _FIX_FLAGS]
    if stray:
        each = "window's" if why == "--window" else "run's"
        raise InputError(f"{', '.join(stray)} does not apply with {why}: every truth fix is compared "
                         f"as a position (and with --heading-weight a heading), and each {each} start pose "
                         "is fitted")


def _calibration_plot(plot: str | Path, runs: Sequence[OdometryLog], truth: Sequence[TruthOptions] | None,
                      robot: Robot, new_robot: Robot, side: float | None, clock_fitted: bool = False,
                      clock_base: float = 0.0) -> Path | None:
    """The runs against their truth, and with square runs of a differential drive UMBmark's
    return errors before and after; None, with a warning saying why, when there is nothing
    to draw. The log's own truth starts each run at its first pose; ``--truth`` fixes (on
    the log's clock by the offset calibrated) are the ones the calibration compared (inside
    the log's span; with ``clock_fitted``, their own stamps the clock offset's range inside
    it, :func:`odomkit.calibrate.positions.clock_range`), each run started from the pose
    fitted to them as the calibration fits it
    (:func:`odomkit.workflows.figures.calibration_figure`): position-only truth (GPS) has no
    start heading to take."""
    import numpy as np

    from odomkit.calibrate.positions import clock_range, compared_fixes
    from odomkit.calibrate.realdata import return_errors_from_runs
    from odomkit.workflows.figures import calibration_figure

    shown, paths, starts, times, left_out = [], [], [], [], []
    for i, log in enumerate(runs):
        if truth is not None:
            found = load_truth(truth[i], log)
            assert found is not None  # the calibration found it
            # the fixes calibrate_positions compared: with the clock fitted, those whose own
            # stamps lie the clock's range inside the log (the same ones at every offset tried)
            # (their stamps moved by the robot file's offset the fit started from, ``clock_base``)
            margin, own = ((clock_range(runs), found.t + (truth[i].time_offset or 0.0) - clock_base)
                           if clock_fitted
                           else (0.0, found.t))
            inside = compared_fixes(log.t, own, margin) & np.all(np.isfinite(found.xy), axis=1)
            if np.count_nonzero(inside) < 2:
                left_out.append(f"{log.source}: fewer than 2 truth fixes inside the log's time span")
                continue
            times.append(np.asarray(found.t[inside], dtype=float))
            paths.append(np.asarray(found.xy[inside], dtype=float))
        else:
            assert log.ground_truth is not None  # the calibration needs it
            if not np.all(np.isfinite(log.ground_truth[0])):
                left_out.append(f"{log.source}: no ground-truth pose at the log's first row to start from")
                continue
            starts.append(np.asarray(log.ground_truth[0], dtype=float))
            paths.append(np.asarray(log.ground_truth[:, :2], dtype=float))
        shown.append(log)
    umbmark = None
    if side is not None and isinstance(robot, DiffDrive) and isinstance(new_robot, DiffDrive):
        try:
            cw, ccw = return_errors_from_runs(runs, robot)
            after = return_errors_from_runs(runs, new_robot)
        except InputError:  # not square runs after all: no UMBmark panel
            cw = ccw = np.empty((0, 2))
        if len(cw) and len(ccw):
            umbmark = (cw, ccw, *after)
    if not shown and umbmark is None:
        warnings.warn(f"--plot {plot} not written: no run can be drawn against its truth ("
                      f"{'; '.join(left_out)})", UserWarning, stacklevel=3)
        return None
    if left_out:
        warnings.warn(f"left out of --plot: {'; '.join(left_out)}", UserWarning, stacklevel=3)
    return calibration_figure(plot, shown, paths, None if truth is not None else starts, robot, new_robot,
                              umbmark=umbmark, fix_times=times if truth is not None else None)


# The CLI flag of each keyword argument of calibrate_exact, for messages.
_EXACT_FLAGS = {"heading_weight": "--heading-weight"}
# Those that a calibration from truth fixes takes too (calibrate_positions' heading_weight).
_FIX_FLAGS = ("heading_weight",)


def _check_twist(speed: float | None, period: float | None, noise: Sequence[object],
                 robot_path: str | Path) -> None:
    """The twist-covariance flags come together, are positive, and the file has white noise."""
    if speed is None or period is None:
        raise InputError("--twist-speed and --controller-period go together: the twist covariance holds at "
                         "one speed and depends on how often the controller measures")
    if not (speed >= 0 and period > 0):
        raise InputError(f"--twist-speed must be >= 0 m/s and --controller-period > 0 s, got {speed!r}, "
                         f"{period!r}")
    if not any(getattr(m, "kind", None) == "white" for m in noise):
        raise InputError("--twist-speed needs a white [noise] model in the robot file (odomkit fit-noise "
                         "writes one)", source=str(robot_path))


def _controller_radius(robot_path: str | Path, given: float | None) -> float:
    """The nominal wheel radius for the ROS controller: ``given`` (``--wheel-radius``) or the
    robot file's own (mean of the two wheels), and an error when the two disagree, since the
    multipliers are computed against the file's nominal wheels
    (:func:`odomkit.calibrate.export.controller_radius`, which report's snippet shares)."""
    from odomkit.calibrate.export import controller_radius

    radius = controller_radius(given, file_wheel_radius(robot_path), str(robot_path))
    if radius is None:
        raise InputError("--ros-yaml needs --wheel-radius (the controller's nominal radius, m): "
                         "the robot file gives metres per tick, not a wheel size", source=str(robot_path))
    return radius


def file_wheel_radius(robot_path: str | Path) -> float | None:
    """The mean nominal wheel radius [m] a diff robot file gives through ``wheel_radius`` or
    ``wheel_diameter`` (plain or ``_left``/``_right``), or None when it gives metres per tick
    (:func:`odomkit.io.robotfile.read_robot` has already checked the file)."""
    import tomllib

    table = tomllib.loads(Path(robot_path).read_text(encoding="utf-8")).get("robot", {})
    radii = []
    sides = ("front",) if table.get("type") == "tricycle" else ("left", "right")
    for side in sides:
        for key, factor in ((f"wheel_radius_{side}", 1.0), ("wheel_radius", 1.0),
                            (f"wheel_diameter_{side}", 0.5), ("wheel_diameter", 0.5)):
            if key in table:
                radii.append(factor * float(table[key]))
                break
    return sum(radii) / len(radii) if len(radii) == len(sides) else None


def noise_files(
    run_paths: str | Path | Sequence[str | Path], robot_path: str | Path, *,
    log_options: LogOptions | None = None, plot: str | Path | None = None,
    overwrite: bool = False, progress: Progress = NO_PROGRESS, **kwargs: Any,
) -> dict[str, Any]:
    """Read repeated runs and a robot file and fit k_L, k_R
    (:func:`odomkit.calibrate.noise_fit.fit_wheel_noise_from_runs`); JSON-ready dict.
    With ``plot``, also draw the runs' errors with the fitted and empirical 95 % ellipses
    (needs matplotlib). The fit's ``warnings`` (k's the data cannot identify, runs beyond
    the first-order regime) are also issued as :class:`UserWarning`\\ s. ``progress``
    (:mod:`odomkit.progress`) sees two stages: ``"runs"``, a unit per run read, then
    ``"fitting"``."""
    from odomkit.workflows.results import paths_given

    run_paths = paths_given(run_paths, "run")
    check_outputs({"--plot": plot}, overwrite=overwrite, inputs=[robot_path, *run_paths])
    if plot is not None:
        from odomkit.plot import check_plot_file

        check_plot_file(plot)
    robot, _ = read_robot(robot_path)
    if not isinstance(robot, DiffDrive):
        raise InputError(f"calibrate-noise fits the wheel noise k_L, k_R of a differential drive; "
                         f"the robot file describes a {robot.type_name!r} robot", source=str(robot_path))
    runs = []
    with stage(progress, len(run_paths), "runs"):
        for path in run_paths:
            runs.append(load_log(path, robot, log_options or LogOptions()))
            progress.advance()
    with numeric_guard("the noise fit"), stage(progress, None, "fitting"):
        fit = fit_wheel_noise_from_runs(runs, robot, **kwargs)
    # An interval open above is a finding (see warnings), not an overflow.
    check_result("the noise fit", {"k_left": fit.k_left, "k_right": fit.k_right,
                                   "the lower interval ends": [fit.ci_left[0], fit.ci_right[0]],
                                   "the mean error": fit.mean, "the log-likelihood": fit.loglik},
                 {"the fitted covariance": fit.cov_fitted})
    for text in fit.warnings:
        warnings.warn(text, stacklevel=2)
    out = fit.to_dict()
    if plot is not None:
        from odomkit.plot import plot_noise_fit

        out["plot"] = str(plot_noise_fit(fit, plot))
    return out


def optiodom_square_table(data_dir: str | Path, **exact_kwargs: Any) -> list[SquareRow]:
    """:func:`odomkit.calibrate.realdata.square_table` of every OptiOdom ``diff/square``
    experiment under ``data_dir`` (the folder holding ``optiodom/``, or ``optiodom/``)."""
    root = Path(data_dir)
    folder = root / "optiodom" / "diff" / "square"
    if not folder.is_dir():
        folder = root / "diff" / "square"
    if not folder.is_dir():
        raise InputError("no optiodom/diff/square folder here", source=str(root))
    experiments = [read_experiment(p) for p in sorted(folder.iterdir()) if p.is_dir()]
    return square_table(experiments, **exact_kwargs)
