"""``odomkit fit-amcl``: nav2 AMCL's motion-model α's from odometry and ground truth.

The odometry is a pose track (``odomkit track --out`` CSV, TUM, or headerless
``t,x,y,theta`` text), a ROS bag's ``nav_msgs/Odometry`` topic (``--topic``, or the bag's
only one; its own truth from ``--truth-topic``), or, with a robot file, a raw log
dead-reckoned here. AMCL's updates
are taken where AMCL would take them (its ``update_min_d``/``update_min_a`` thresholds on
the odometry, :func:`odomkit.calibrate.amcl.amcl_update_rows`); the truth, on its own
clock, is interpolated at the update times; the fit is
:func:`odomkit.calibrate.amcl.fit_amcl` pooled over every log.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from odomkit.errors import InputError

if TYPE_CHECKING:
    from odomkit.calibrate.amcl import AmclData
    from odomkit.robot import Robot
    from odomkit.truth import Truth
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.truth import TruthOptions

__all__ = ["fit_amcl_files", "OdometryPoses"]


@dataclass(frozen=True)
class OdometryPoses:
    """An odometry pose track and the truth it carries itself (None if it carries none).

    ``t`` (N,) [s]; ``poses`` (N, 3) [m, m, rad].
    """

    t: NDArray[np.float64]
    poses: NDArray[np.float64]
    own_truth: Truth | None
    source: str


def _track_poses(path: Path) -> OdometryPoses:
    """A track CSV (found by its header ``t,x,y,theta``) or any pose file the truth reader
    takes (TUM, headerless ``t,x,y,theta``), which must have a heading."""
    from odomkit.io.trackio import read_pose_file
    from odomkit.truth import Truth

    track = read_pose_file(path, "odometry")
    own = None
    if track.truth is not None:
        ok = np.all(np.isfinite(track.truth), axis=1)
        if ok.sum() >= 2:
            own = Truth(track.t[ok], track.truth[ok, :2].copy(), track.truth[ok, 2].copy(),
                        source=str(path))
    return OdometryPoses(track.t, track.poses, own, str(path))


# The log options a bag's Odometry topic uses without a robot file.
_BAG_FLAGS = {"--topic", "--bag-time", "--truth-topic", "--truth-frame", "--truth-time-offset"}


def _bag_poses(path: Path, options: LogOptions) -> OdometryPoses:
    """A bag's ``nav_msgs/Odometry`` poses, and its truth topic (``--truth-topic``, ``--truth-frame``)
    if named."""
    from odomkit.io.bag import bag_topics, read_bag, read_bag_odometry
    from odomkit.truth import truth_from_log

    topic = options.topic[0] if options.topic else None
    if len(options.topic) > 1:
        raise InputError("fit-amcl reads one Odometry topic: give one --topic", source=str(path))
    odom = read_bag_odometry(path, topic, options.bag_time)
    own = None
    if options.truth_topic is not None:
        if topic is None:
            topic = next(n for n, t in bag_topics(path).items() if t == "nav_msgs/msg/Odometry")
        own = truth_from_log(read_bag(path, (topic,), (), options.bag_time, options.truth_topic,
                                      truth_frame=options.truth_frame,
                                      truth_time_offset=options.truth_time_offset))
    return OdometryPoses(odom.t, odom.poses, own, str(path))


def _log_poses(path: Path, robot: Robot, options: LogOptions, truth_options: TruthOptions,
               method: str) -> OdometryPoses:
    """A raw log dead-reckoned from the origin (AMCL's increments do not depend on where the
    odom frame starts)."""
    from odomkit.track import dead_reckon_log
    from odomkit.workflows.logs import load_log
    from odomkit.workflows.truth import load_truth

    log = load_log(path, robot, options)
    track = dead_reckon_log(log, robot, method, np.zeros(3))  # type: ignore[arg-type]
    own = load_truth(truth_options, log) if truth_options.path is None else None
    return OdometryPoses(log.t, track.poses, own, str(path))


def _updates(odom: OdometryPoses, truth: Truth, opts: TruthOptions, model: str, update_min_d: float,
             update_min_a: float) -> tuple[AmclData, int, int]:
    """One log's AMCL data, its update count and the updates left out (no truth there)."""
    from odomkit.calibrate.amcl import amcl_data, amcl_update_rows
    from odomkit.truth import truth_at

    if not truth.has_heading:
        raise InputError("fit-amcl needs truth with a heading (AMCL's model compares turns): "
                         "the truth has positions only", source=truth.source)
    rows = amcl_update_rows(odom.poses, update_min_d, update_min_a)
    samples = truth_at(truth, odom.t[rows], opts.max_gap)
    ok = samples.valid[:-1] & samples.valid[1:]
    start, end = rows[:-1][ok], rows[1:][ok]
    data = amcl_data(odom.poses[start], odom.poses[end], samples.poses[:-1][ok], samples.poses[1:][ok],
                     model, opts.sigma or 0.0)
    return data, int(rows.size - 1), int(np.count_nonzero(~ok))


def fit_amcl_files(
    odometry: str | Path | Sequence[str | Path],
    truth: TruthOptions | Sequence[TruthOptions] | None = None,
    *,
    robot_path: str | Path | None = None,
    log_options: LogOptions | None = None,
    model: str = "diff",
    update_min_d: float = 0.25,
    update_min_a: float = 0.2,
    level: float = 0.95,
    method: str = "exact",
    yaml_out: str | Path | None = None,
    overwrite: bool = False,
    plot: str | Path | None = None,
) -> dict[str, Any]:
    """Fit AMCL's α's to odometry files with ground truth; write the nav2 snippet if asked.

    Parameters
    ----------
    odometry : pose tracks, or logs when ``robot_path`` is given (or one)
    truth : one :class:`~odomkit.workflows.truth.TruthOptions` per file, or one for every
        file (``path`` None: the file's own truth, ``gt_*`` columns or an OptiOdom log's);
        None: each file's own
    robot_path : robot file: the files are raw logs, dead-reckoned with it
    log_options : how to read the logs (with ``robot_path`` only)
    model : {"diff", "omni"}
    update_min_d, update_min_a : AMCL's update thresholds [m], [rad]
    level : confidence level of the intervals
    method : dead-reckoning method for logs
    yaml_out : write the nav2 snippet here (never over a file unless ``overwrite``)
    plot : draw each α's profile likelihood with its interval into this .png, .svg or .pdf
        file (:func:`odomkit.workflows.figures.profiles_figure`)

    Returns
    -------
    dict
        ``model``, ``alpha``, ``interval95``, ``updates``, ``updates_skipped``,
        ``update_min_d``, ``update_min_a``, ``log_likelihood``, ``per_log``, ``warnings``,
        ``outputs``.
    """
    from odomkit.calibrate.amcl import AMCL_MODELS, fit_amcl
    from odomkit.io.files import check_outputs
    from odomkit.io.ros import nav2_amcl_yaml
    from odomkit.workflows.logs import LogOptions
    from odomkit.workflows.results import check_result, numeric_guard, paths_given, truths_per_log
    from odomkit.workflows.truth import load_truth

    odometry = paths_given(odometry, "file")
    truth = truths_per_log(truth, len(odometry), "file")
    if model not in AMCL_MODELS:
        raise InputError(f"--model must be one of {', '.join(AMCL_MODELS)}, got {model!r}")
    for flag, value in (("--update-min-d", update_min_d), ("--update-min-a", update_min_a)):
        if not (np.isfinite(value) and value > 0):
            raise InputError(f"{flag} must be a positive number, got {value!r}")
    truth_files = [t.path for t in truth if t.path is not None]
    check_outputs({"--yaml-out": yaml_out, "--plot": plot}, overwrite=overwrite,
                  inputs=[*odometry, *truth_files, *([robot_path] if robot_path else [])])
    if plot is not None:
        from odomkit.plot import check_plot_file

        check_plot_file(plot)
    robot = None
    if robot_path is not None:
        from odomkit.io.robotfile import read_robot
        from odomkit.workflows.truth import clock_from_robot

        robot = read_robot(robot_path)[0]
        truth = clock_from_robot(robot_path, truth)  # the [truth] time_offset calibrate fitted
    elif log_options is not None and set(log_options.given()) - _BAG_FLAGS:
        stray = sorted(set(log_options.given()) - _BAG_FLAGS)
        raise InputError(f"{', '.join(stray)} reads logs, so it needs --robot")
    from odomkit.io.bag import is_bag

    parts, per_log, skipped = [], [], 0
    for path, opts in zip(odometry, truth, strict=True):
        path = Path(path)
        if robot is not None:
            odom = _log_poses(path, robot, log_options or LogOptions(), opts, method)
        elif is_bag(path):
            odom = _bag_poses(path, log_options or LogOptions())
        else:
            if log_options is not None and log_options.given():
                raise InputError(f"{', '.join(log_options.given())} applies to a ROS bag; this is a "
                                 "pose track", source=str(path))
            odom = _track_poses(path)
        found = load_truth(opts) if opts.path is not None else odom.own_truth
        if found is None:
            raise InputError("no truth: give --truth (or --truth-topic for a bag's own), or odometry that "
                             "carries it (gt_* columns, an "
                             "OptiOdom log with --robot)", source=str(path))
        data, updates, left_out = _updates(odom, found, opts, model, update_min_d, update_min_a)
        parts.append(data)
        skipped += left_out
        per_log.append({"log": str(path), "updates": len(data), "updates_skipped": left_out})
        if updates == 0:
            warnings.warn(f"{path}: the odometry never passes AMCL's update thresholds "
                          f"({update_min_d:g} m, {update_min_a:g} rad): no update", stacklevel=2)
    with numeric_guard("the AMCL fit"):
        fit = fit_amcl(parts, level=level)
    check_result("the AMCL fit", {"the alphas": list(fit.alpha), "the log-likelihood": fit.log_likelihood})
    notes = list(fit.warnings)
    if skipped:
        notes.append(f"{skipped} update(s) left out: no truth at one of their ends (outside the truth "
                     "or inside a gap longer than --max-gap)")
    for text in notes:
        warnings.warn(text, stacklevel=2)
    out = fit.to_dict()
    out.update({"updates_skipped": skipped, "update_min_d": float(update_min_d),
                "update_min_a": float(update_min_a), "per_log": per_log, "warnings": notes})
    outputs: dict[str, str] = {}
    if yaml_out is not None:
        from odomkit.io.files import write_new_text

        text = nav2_amcl_yaml(out["alpha"], model, update_min_d=update_min_d, update_min_a=update_min_a,
                              notes=[f"fitted by odomkit fit-amcl on {fit.updates} updates"])
        outputs["yaml"] = str(write_new_text(yaml_out, text, overwrite))
    if plot is not None:
        from odomkit.calibrate.profile import amcl_profiles
        from odomkit.workflows.figures import profiles_figure

        units = {"diff": ("rad²/rad²", "rad²/m²", "m²/m²", "m²/rad²"),
                 "omni": ("rad²/rad²", "rad²/m²", "m²/m²", "m²/rad²", "m²/m²")}[fit.model]
        outputs["plot"] = str(profiles_figure(
            plot, amcl_profiles(parts, fit), units=dict(zip(fit.names, units, strict=True)),
            title=f"fit-amcl: profile likelihoods of AMCL's α ({fit.updates} updates, "
                  f"{100 * fit.level:g} % intervals)"))
    out["outputs"] = outputs
    return out
