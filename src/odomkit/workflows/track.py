"""``odomkit track``: read a robot file and a log, dead-reckon, write the track."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from odomkit.angles import wrap_angle
from odomkit.errors import InputError
from odomkit.evaluate import evaluate_track
from odomkit.io.bag_writer import check_bag_out, write_track_bag
from odomkit.io.files import check_outputs
from odomkit.io.robotfile import read_robot
from odomkit.io.ros import ros_pose_covariance
from odomkit.io.trackio import kitti_times_path, write_kitti, write_track_csv, write_tum
from odomkit.kinematics import Method
from odomkit.log import OdometryLog
from odomkit.progress import NO_PROGRESS, Progress, stage
from odomkit.robot import Robot
from odomkit.track import Track, dead_reckon_log
from odomkit.truth import Truth, no_overlap, truth_at
from odomkit.workflows.logs import LogOptions, load_log
from odomkit.workflows.results import check_result, numeric_guard
from odomkit.workflows.truth import TruthOptions, applied_clock, clock_from_robot, load_truth

__all__ = ["first_order_warning", "TrackRun", "run_track"]


@dataclass(frozen=True)
class TrackRun:
    """What ``odomkit track`` computed and wrote."""

    track: Track
    log: OdometryLog
    outputs: dict[str, str] = field(default_factory=dict)
    truth: NDArray[np.float64] | None = None  # (N, 3) truth at the log rows, NaN outside it

    def summary(self, note_nees: bool = True) -> dict[str, Any]:
        """The ``--json`` object: final pose and covariance (also in ROS's 6×6 layout,
        :func:`odomkit.io.ros.ros_pose_covariance`), path length, duration, and the final
        error against ground truth when the log has it (``ground_truth``), and, with any
        truth (``--truth`` or the log's), ``final_position_error`` at the last row inside
        the truth and ``max_position_error`` over the rows inside it. ``note_nees`` False
        leaves out the warning on rows whose singular covariance makes the NEES
        (:func:`odomkit.evaluate.singular_nees_note`), for a caller that shows no NEES."""
        final = self.track.poses[-1]
        out: dict[str, Any] = {
            "samples": int(self.track.poses.shape[0]),
            "pose": [float(final[0]), float(final[1]), float(wrap_angle(final[2]))],
            "theta_unwrapped": float(final[2]),
            "cov": None if self.track.cov is None else self.track.cov[-1],
            "ros_pose_covariance": (None if self.track.cov is None
                                    else ros_pose_covariance(self.track.cov[-1])),
            "path_length": self.track.path_length,
            "duration": self.track.duration,
        }
        if self.log.ground_truth is not None:
            with numeric_guard("the comparison with ground truth"):
                truth = evaluate_track(self.track.poses, self.log.ground_truth, self.track.cov,
                                       note_nees=note_nees)
            # Errors of 1e199 m overflow the RMSE's squares to inf (JSON null): one line instead.
            # drift_per_distance is nan by definition when the truth does not move, and the NEES
            # None when no row has a regular covariance; neither is checked then.
            check_result("the comparison with ground truth", {
                "final_position_error": truth.final_position_error,
                "max_position_error": truth.max_position_error,
                "final_heading_error": truth.final_heading_error,
                "ate_rmse": truth.ate_rmse,
                "true_path_length": truth.true_path_length,
                "drift_per_distance": truth.drift_per_distance if truth.true_path_length > 0 else None,
                "nees_position_mean": truth.nees_position_mean,
                "inside_95_fraction": truth.inside_95_fraction})
            out["ground_truth"] = truth.to_dict()
        if self.truth is not None:
            inside = np.isfinite(self.truth[:, 0])
            err = np.hypot(*(self.track.poses[inside, :2] - self.truth[inside, :2]).T)
            out["final_position_error"] = float(err[-1])
            out["max_position_error"] = float(err.max())
        out["outputs"] = self.outputs
        return out


def run_track(
    log_path: str | Path,
    robot_path: str | Path,
    *,
    method: Method = "exact",
    log_options: LogOptions | None = None,
    pose0: tuple[float, float, float] | None = None,
    cov0: list[list[float]] | None = None,
    truth: TruthOptions | None = None,
    with_covariance: bool = True,
    engine: str | None = None,
    out: str | Path | None = None,
    tum: str | Path | None = None,
    kitti: str | Path | None = None,
    overwrite: bool = False,
    bag_out: str | Path | None = None,
    bag_format: str | None = None,
    frame_id: str = "odom",
    child_frame_id: str = "base_link",
    progress: Progress = NO_PROGRESS,
    plot: str | Path | None = None,
    note_first_order: bool = True,
) -> TrackRun:
    """Read a robot file and a log, dead-reckon, write the requested outputs.

    ``log_options`` (:class:`~odomkit.workflows.logs.LogOptions`, default: format guessed
    from the file name) says how to read (and decimate) the log; ``out``/``tum``/``kitti`` (KITTI
    poses and, beside them, their times: :func:`odomkit.io.trackio.write_kitti`) are written only
    when new, or when ``overwrite``. ``truth`` (:class:`~odomkit.workflows.truth.TruthOptions`)
    names a truth file; without one the log's own ground truth is used, if it has any.
    With truth the track starts at the truth pose at the first log time unless ``pose0``
    is given, and ``cov0`` defaults to that pose's uncertainty (``--truth-sigma``, and the
    variance of a heading fitted to position-only truth); the CSV gets ``gt_*`` columns.
    Where the truth starts after the log's first row, or (position-only) gives no heading
    there, the track starts at the first row where it gives a pose and heading, as
    ``odomkit evaluate``'s whole run does (:func:`odomkit.windows.run_start`): the rows before
    it are left out of the track and its outputs, with a warning that counts them.
    ``bag_out`` writes ``nav_msgs/Odometry`` (:mod:`odomkit.io.bag_writer`; ``bag_format``
    ros1, db3 or mcap, default from the path) with ``frame_id``/``child_frame_id``.
    ``engine`` (default ``"recursion"``) and ``cov0`` apply to the covariance only: given
    without one (``with_covariance`` false, or a robot file without ``[noise]``) they are
    refused. ``progress`` (:mod:`odomkit.progress`) sees the stages: reading the log, dead
    reckoning, the covariance chunk by chunk, writing the outputs. ``plot`` (.png, .svg or
    .pdf) draws :func:`odomkit.workflows.figures.track_figure`.
    A covariance whose σθ passes the first-order limit is warned of, once
    (:func:`first_order_warning`); ``note_first_order`` False leaves that to the caller (the
    report, which says it of what its page shows).
    """
    options = truth or TruthOptions()
    inputs = [p for p in (log_path, robot_path, options.path) if p is not None]
    if bag_out is not None and not (frame_id and child_frame_id):
        raise InputError("--frame-id and --child-frame-id must not be empty")
    bag = None if bag_out is None else check_bag_out(bag_out, bag_format, overwrite=overwrite, inputs=inputs)
    check_outputs({"--out": out, "--tum": tum, "--kitti": kitti,
                   "--kitti (its times)": None if kitti is None else kitti_times_path(kitti),
                   "--bag-out": None if bag is None else bag.file_check, "--plot": plot},
                  overwrite=overwrite, inputs=inputs)
    if plot is not None:
        from odomkit.plot import check_plot_file

        check_plot_file(plot)
    robot, noise = read_robot(robot_path)
    flagged = options.time_offset is not None  # --truth-time-offset, else the robot file's
    options = clock_from_robot(robot_path, [options])[0]  # the robot file's [truth] time_offset
    _refuse_covariance_flags(engine, cov0, with_covariance, bool(noise), robot_path)
    log = load_log(log_path, robot, log_options or LogOptions(), progress=progress)
    found = load_truth(options, log)
    truth_rows = None
    if found is not None:
        samples = truth_at(found, log.t, options.max_gap)
        if not samples.valid.any():
            raise InputError(no_overlap(found, log.t, log.meta.get("time")), source=found.source)
        truth_rows = samples.poses
        if pose0 is None:
            from odomkit.windows import late_start_note, run_start

            own = _own_path(log, robot, method, found)
            first, start, start_cov = run_start(log.t, found, samples.valid, own, options.max_gap,
                                                hint="give --initial-pose")
            if first > 0:
                note = late_start_note(log.source, "the track", log.t, first, int(np.argmax(samples.valid)))
                why = _lead_within_a_period(log.t, found, first, applied_clock(options, log), flagged)
                warnings.warn(f"{note} of the track and its outputs{why}; give --initial-pose to start at "
                              "the first row", stacklevel=2)
                log, truth_rows = log.from_row(first), truth_rows[first:]
            pose0 = (float(start[0]), float(start[1]), float(start[2]))
            if cov0 is None and start_cov.any():
                cov0 = start_cov.tolist()
    use_noise = (noise if len(noise) > 1 else noise[0]) if (noise and with_covariance) else None
    with numeric_guard("the track"):
        track = dead_reckon_log(log, robot, method, pose0, noise=use_noise, cov0=cov0,
                                engine=engine or "recursion", progress=progress)
    check_result("the track", {"the poses": track.poses, "the path length": track.path_length},
                 {"the covariance": track.cov})
    outputs = {}
    with stage(progress, sum(p is not None for p in (bag, out, tum, kitti)), "writing"):
        # The bag first: its writer still checks the content (ROS stamps), and a refusal there
        # must leave nothing half-written; the text writers can fail only on the file system.
        if bag is not None:
            outputs["bag"] = str(write_track_bag(bag, track, use_noise, frame_id=frame_id,
                                                 child_frame_id=child_frame_id))
            progress.advance()
        if out is not None:
            outputs["track_csv"] = str(write_track_csv(out, track, overwrite, truth=truth_rows))
            progress.advance()
        if tum is not None:
            outputs["tum"] = str(write_tum(tum, track, overwrite))
            progress.advance()
        if kitti is not None:
            poses, times = write_kitti(kitti, track, overwrite)
            outputs["kitti"], outputs["kitti_times"] = str(poses), str(times)
            progress.advance()
    run = TrackRun(track, log, outputs, truth_rows)
    linearised = first_order_warning(track, bag=bag is not None) if note_first_order else None
    if linearised is not None:
        warnings.warn(linearised, stacklevel=2)
    if plot is not None:
        from odomkit.workflows.figures import track_figure

        outputs["plot"] = str(track_figure(plot, run, robot))
    return run


def first_order_warning(track: Track, bag: bool = False) -> str | None:
    """The warning that ``track``'s covariance has passed the first-order limit
    (:func:`odomkit.calibrate.fit_noise.first_order_track_note`), or None (also without a
    covariance); where the ROS pose covariance it exports (--json's
    ``ros_pose_covariance`` at the end, and with ``bag`` every --bag-out message) has a yaw
    variance beyond π²/3, it says so too (:func:`odomkit.io.ros.yaw_variance_note`): one
    warning, since the second follows from the first."""
    from odomkit.calibrate.fit_noise import first_order_track_note
    from odomkit.io.ros import UNIFORM_HEADING_VARIANCE, yaw_variance_note

    if track.cov is None:
        return None
    var = track.cov[:, 2, 2]
    note = first_order_track_note(track.t, var)
    if note is None:
        return None
    beyond = var > UNIFORM_HEADING_VARIANCE
    json_key = "--json's ros_pose_covariance at the end"
    if bag and beyond.any():
        first = int(np.argmax(beyond))
        since = track.t[first] - track.t[0]
        where = (f"ROS's pose covariance (the --bag-out messages from {since:.4g} s into the log on, "
                 f"{int(beyond.sum())} of {var.size}" + (f"; {json_key})" if beyond[-1] else ")"))
        yaw = yaw_variance_note(float(var.max()), where)
    else:
        yaw = yaw_variance_note(float(var[-1]), f"ROS's pose covariance ({json_key})")
    return note if yaw is None else f"{note}; {yaw}"


def _lead_within_a_period(t: NDArray[np.float64], truth: Truth, first: int, offset: float,
                          flagged: bool) -> str:
    """Why rows before ``first`` have no truth when the truth's first fix comes less than one
    log period (the median step) after the log's first row: the rows are left out all the
    same (an interpolation cannot reach before the first fix), but a lead that small looks
    like a bug where log and truth come from one file, and is most often the clock offset
    (``--truth-time-offset``, ``flagged``, or the robot file's ``[truth] time_offset``,
    which calibrate fits) moving the fixes later. "" otherwise."""
    if first == 0 or t.size < 2 or first != int(np.searchsorted(t, truth.t[0])):
        return ""  # no rows left out, or left out for want of a heading: late_start_note says
    lead, period = float(truth.t[0] - t[0]), float(np.median(np.diff(t)))
    if not 0 < lead < period:
        return ""
    said = (f": the truth's first fix comes {lead:.4g} s after the log's first row, less than one log period "
            f"({period:.4g} s)")
    if offset and truth.t[0] + offset <= t[0]:  # on its own clock the truth covers the first row
        source = "--truth-time-offset" if flagged else "the robot file's [truth] time_offset"
        said += f", because {source} ({offset:.4g} s) moves the truth's clock"
    return said


def _own_path(log: OdometryLog, robot: Robot, method: Method, truth: Truth) -> NDArray[np.float64] | None:
    """The odometry's own path (N, 3), dead-reckoned from the origin over the whole log, which
    :func:`odomkit.windows.run_start` aligns to position-only truth wherever it looks for a
    start heading (as evaluate's whole run does); None with truth heading."""
    if truth.has_heading:
        return None
    from odomkit.integrate import dead_reckon
    from odomkit.kinematics import body_steps

    steps = body_steps(robot, log)
    return dead_reckon(steps.dd, steps.dtheta, np.zeros(3), method)



def _refuse_covariance_flags(engine: str | None, cov0: object, with_covariance: bool, has_noise: bool,
                             robot_path: str | Path) -> None:
    """``--engine`` and ``--initial-cov`` shape the covariance: without one they would be
    ignored silently, so they are refused (as a log option that the log's format does not use)."""
    stray = [flag for flag, value in (("--engine", engine), ("--initial-cov", cov0)) if value is not None]
    if not stray or (with_covariance and has_noise):
        return
    flags = " and ".join(stray)
    verb = "apply" if len(stray) > 1 else "applies"
    if not with_covariance:
        raise InputError(f"{flags} {verb} to the covariance, which --no-covariance turns off")
    raise InputError(f"{flags} {verb} to the covariance, and the robot file has no [noise] table to "
                     "propagate", source=str(robot_path))
