"""``odomkit track``: read a robot file and a log, dead-reckon, write the track."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from odomkit.angles import wrap_angle
from odomkit.evaluate import evaluate_track
from odomkit.io.files import refuse_overwrite
from odomkit.io.robotfile import read_robot
from odomkit.io.ros import ros_pose_covariance
from odomkit.io.trackio import write_track_csv, write_tum
from odomkit.kinematics import Method
from odomkit.log import OdometryLog
from odomkit.track import Track, dead_reckon_log
from odomkit.workflows.logs import LogOptions, load_log

__all__ = ["TrackRun", "run_track"]


@dataclass(frozen=True)
class TrackRun:
    """What ``odomkit track`` computed and wrote."""

    track: Track
    log: OdometryLog
    outputs: dict[str, str] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        """The ``--json`` object: final pose and covariance (also in ROS's 6×6 layout,
        :func:`odomkit.io.ros.ros_pose_covariance`), path length, duration, and the final
        error against ground truth when the log has it."""
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
            out["ground_truth"] = evaluate_track(self.track.poses, self.log.ground_truth,
                                                 self.track.cov).to_dict()
        out["outputs"] = self.outputs
        return out


def run_track(
    log_path: str | Path,
    robot_path: str | Path,
    *,
    method: Method = "exact",
    log_options: LogOptions | None = None,
    decimate: int = 1,
    pose0: tuple[float, float, float] | None = None,
    with_covariance: bool = True,
    engine: str = "recursion",
    out: str | Path | None = None,
    tum: str | Path | None = None,
    overwrite: bool = False,
) -> TrackRun:
    """Read a robot file and a log, dead-reckon, write the requested outputs.

    ``log_options`` (:class:`~odomkit.workflows.logs.LogOptions`, default: format guessed
    from the file name) says how to read the log; ``out``/``tum`` are written only when
    new, or when ``overwrite``.
    """
    robot, noise = read_robot(robot_path)
    refuse_overwrite(out, tum, overwrite=overwrite)
    log = load_log(log_path, robot, log_options or LogOptions()).decimate(decimate)
    use_noise = (noise if len(noise) > 1 else noise[0]) if (noise and with_covariance) else None
    track = dead_reckon_log(log, robot, method, pose0, noise=use_noise, engine=engine)
    outputs = {}
    if out is not None:
        outputs["track_csv"] = str(write_track_csv(out, track, overwrite))
    if tum is not None:
        outputs["tum"] = str(write_tum(tum, track, overwrite))
    return TrackRun(track, log, outputs)
