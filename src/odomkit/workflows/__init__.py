"""Side-effecting workflows behind the CLI: load files, run the core, write outputs.

Each CLI command calls exactly one function here (or one core function), so the
commands stay thin and everything they do is also available from Python.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from odomkit.errors import InputError
from odomkit.evaluate import evaluate_track, wrap
from odomkit.io.csvlog import parse_column_map, read_csv_log
from odomkit.io.files import refuse_overwrite
from odomkit.io.halmstad import read_khepera, read_snowhite
from odomkit.io.optiodom import read_run
from odomkit.io.robotfile import read_robot
from odomkit.io.trackio import write_track_csv, write_tum
from odomkit.kinematics import Method
from odomkit.log import OdometryLog
from odomkit.propagate.ros import ros_pose_covariance
from odomkit.robot import DiffDrive, Robot
from odomkit.track import Track, dead_reckon_log

LOG_FORMATS = ("auto", "csv", "khepera", "snowhite", "optiodom")


def detect_format(path: Path) -> str:
    """Guess a log format from its file name."""
    name = path.name.lower()
    if name.startswith("snowhite"):
        return "snowhite"
    if name.startswith("khepera"):
        return "khepera"
    if re.search(r"_run-\d+\.csv$", name):
        return "optiodom"
    return "csv"


@dataclass(frozen=True)
class LogOptions:
    """How to read a log (see ``odomkit track --help``)."""

    format: str = "auto"
    columns: str | None = None
    cumulative: bool = False
    wrap_bits: int | None = None
    period: float | None = None
    time_scale: float = 1.0


def load_log(path: str | Path, robot: Robot, options: LogOptions = LogOptions()) -> OdometryLog:
    """Read a log in any supported format."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such file", source=str(path))
    fmt = detect_format(path) if options.format == "auto" else options.format
    if fmt not in LOG_FORMATS:
        raise InputError(f"unknown log format {fmt!r}; expected one of {', '.join(LOG_FORMATS)}")
    if fmt == "khepera":
        return read_khepera(path, period=options.period or 1.0, wrap_bits=options.wrap_bits)
    if fmt == "snowhite":
        return read_snowhite(path, **({"period": options.period} if options.period else {}))
    if fmt == "optiodom":
        return read_run(path, "diff" if isinstance(robot, DiffDrive) else "tricyc")
    if not options.columns:
        raise InputError("a CSV log needs --columns, e.g. t=time,ticks_left=L,ticks_right=R",
                         source=str(path))
    return read_csv_log(path, parse_column_map(options.columns), cumulative=options.cumulative,
                        wrap_bits=options.wrap_bits, time_scale=options.time_scale)


@dataclass(frozen=True)
class TrackRun:
    """What ``odomkit track`` computed and wrote."""

    track: Track
    log: OdometryLog
    outputs: dict[str, str] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        """The ``--json`` object: final pose and covariance, path length, duration, and
        the final error against ground truth when the log has it."""
        final = self.track.poses[-1]
        out: dict[str, Any] = {
            "samples": int(self.track.poses.shape[0]),
            "pose": [float(final[0]), float(final[1]), float(wrap(final[2]))],
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
    log_options: LogOptions = LogOptions(),
    decimate: int = 1,
    pose0: tuple[float, float, float] | None = None,
    with_covariance: bool = True,
    engine: str = "recursion",
    out: str | Path | None = None,
    tum: str | Path | None = None,
    overwrite: bool = False,
) -> TrackRun:
    """Read a robot file and a log, dead-reckon, write the requested outputs."""
    robot, noise = read_robot(robot_path)
    refuse_overwrite(out, tum, overwrite=overwrite)
    log = load_log(log_path, robot, log_options).decimate(decimate)
    use_noise = (noise if len(noise) > 1 else noise[0]) if (noise and with_covariance) else None
    track = dead_reckon_log(log, robot, method, pose0, noise=use_noise, engine=engine)
    outputs = {}
    if out is not None:
        outputs["track_csv"] = str(write_track_csv(out, track, overwrite))
    if tum is not None:
        outputs["tum"] = str(write_tum(tum, track, overwrite))
    return TrackRun(track, log, outputs)


def builtin_data_path(name: str) -> Path:
    """Path of a file shipped in ``odomkit/data``."""
    return Path(str(resources.files("odomkit.data").joinpath(name)))

