"""ROS bags out: a track as ``nav_msgs/Odometry`` messages (``odomkit track --bag-out``).

A ``.bag`` path is a ROS 1 bag; any other path a ROS 2 bag folder, stored as MCAP or
SQLite (``--bag-format mcap|db3``; default mcap). Written through ``rosbags`` (the ``ros``
extra), imported only here.

**Each message** (one per track row, stamped with the row's time, also as the bag's time):

* ``pose``: x, y, z = 0, the orientation a rotation about z by θ (q = (0, 0, sin θ/2,
  cos θ/2), θ wrapped so q_w ≥ 0); its covariance the track's (x, y, θ) covariance in ROS's
  6×6 layout (:func:`odomkit.io.ros.ros_pose_covariance`), with z, roll and pitch
  :data:`~odomkit.io.ros.UNOBSERVED_VARIANCE` (large, not zero: zero would tell an EKF
  those axes are known exactly). A track without covariance gets that large variance on all
  six axes, "unknown" (an all-zero matrix would be read as exact by robot_localization).
* ``twist`` (in ``child_frame_id``, the body): the forward speed Δd/Δt and yaw rate Δθ/Δt
  of the step *ending* at the message, as ``diff_drive_controller`` reports it (and as
  :mod:`odomkit.io.bag` reads an Odometry twist back). Its covariance is that of the step's
  (Δd, Δθ) divided by Δt² (:func:`track_twist`); v_y, v_z, ω_x, ω_y get the large variance.
  The first message, and one after a zero-length step, has no step: zero twist, large
  variance on all six axes.

Times become stamps to the nearest nanosecond (``sec``, ``nanosec``): an epoch time (where
a float's spacing is 0.24 µs) reads back as exactly the same float
(:func:`odomkit.io.bag.read_bag_odometry`), a time near zero to within 0.5 ns.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from odomkit.angles import wrap_angle
from odomkit.errors import InputError
from odomkit.io.bag import require_rosbags
from odomkit.io.files import EXISTS_ALREADY
from odomkit.io.ros import UNOBSERVED_VARIANCE, ros_pose_covariance, ros_twist_covariance
from odomkit.noise import NoiseSet
from odomkit.track import Track

if TYPE_CHECKING:
    from odomkit.propagate.plan import NoiseArg

__all__ = ["BAG_FORMATS", "BagTarget", "check_bag_out", "track_twist", "write_odometry_bag",
           "write_track_bag"]

BAG_FORMATS = ("ros1", "db3", "mcap")
_ODOMETRY = "nav_msgs/msg/Odometry"


@dataclass(frozen=True)
class BagTarget:
    """Where and how ``--bag-out`` writes: ``path``, ``format`` (one of :data:`BAG_FORMATS`)."""

    path: Path
    format: str

    @property
    def file_check(self) -> Path | None:
        """The path for :func:`odomkit.io.files.check_outputs` (a new path or a ROS 1 file);
        None for an existing ROS 2 bag folder, which :func:`check_bag_out` checked itself."""
        return None if self.format != "ros1" and self.path.is_dir() else self.path


def check_bag_out(path: str | Path, fmt: str | None = None, *, overwrite: bool = False,
                  inputs: Iterable[str | Path] = ()) -> BagTarget:
    """The bag to write, checked before anything is computed.

    A ``.bag`` path is ROS 1 (``fmt`` None or "ros1"); any other path a ROS 2 bag folder
    (``fmt`` "mcap", the default, or "db3"). An existing ROS 2 bag folder is replaced only
    with ``overwrite`` and only if it holds a bag and nothing else (never a folder holding
    an input). Also checks that rosbags is installed.
    """
    path = Path(path)
    ros1 = path.suffix.lower() == ".bag"
    if fmt is None:
        fmt = "ros1" if ros1 else "mcap"
    if fmt not in BAG_FORMATS:
        raise InputError(f"--bag-format must be one of {', '.join(BAG_FORMATS)}, got {fmt!r}")
    if ros1 != (fmt == "ros1"):
        raise InputError("--bag-format ros1 writes a .bag file; give a .bag path" if fmt == "ros1" else
                         f"a .bag path is a ROS 1 bag; --bag-format {fmt} writes a ROS 2 bag folder: "
                         "give a path without .bag", source=str(path))
    require_rosbags()
    if fmt != "ros1" and path.exists():
        if not path.is_dir():
            raise InputError("--bag-out: a ROS 2 bag is a folder, and this is a file", source=str(path))
        if not _is_bag_folder(path):
            raise InputError("--bag-out: this folder is not a ROS 2 bag; odomkit replaces only a bag "
                             "folder (metadata.yaml and its storage files)", source=str(path))
        if not overwrite:
            raise InputError(EXISTS_ALREADY, source=str(path))
        here = path.resolve()
        for source in inputs:
            if here in (Path(source).resolve(), *Path(source).resolve().parents):
                raise InputError("--bag-out would replace an input of this command; write elsewhere",
                                 source=str(source))
        if not os.access(path.parent if str(path.parent) else ".", os.W_OK | os.X_OK):
            raise InputError("--bag-out: its folder is not writable", source=str(path))
    return BagTarget(path, fmt)


def _is_bag_folder(path: Path) -> bool:
    entries = list(path.iterdir())
    return (path / "metadata.yaml").is_file() and all(
        e.is_file() and (e.name == "metadata.yaml" or ".db3" in e.name or ".mcap" in e.name) for e in entries)


def track_twist(track: Track, noise: NoiseArg | None = None
                ) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """The body twist at each row and its covariance, for ``nav_msgs/Odometry``.

    Row k holds the step from row k−1 to row k: v = Δd/Δt [m/s], ω = Δθ/Δt [rad/s]; its
    covariance is Cov(Δd, Δθ)/Δt², where Cov(Δd, Δθ) is the noise models' white part
    (``NoiseSet.input_cov``) plus the bias part's spread J Σ_b Jᵀ (correlated between
    steps: a consumer that takes twists as independent counts it too little over time)
    plus, for measured heading, the two heading samples' variances.

    Returns
    -------
    twist : ndarray, shape (N, 2)
        NaN in row 0 and after a zero-length step (no step ends there).
    cov : ndarray, shape (N, 2, 2), or None without ``noise``
    """
    steps = track.steps
    n = track.poses.shape[0]
    dt = np.asarray(steps.dt, dtype=float)
    moving = dt > 0
    twist = np.full((n, 2), np.nan)
    safe = np.where(moving, dt, 1.0)
    twist[1:, 0] = np.where(moving, steps.dd / safe, np.nan)
    twist[1:, 1] = np.where(moving, steps.dtheta / safe, np.nan)
    if noise is None:
        return twist, None
    models = NoiseSet.of(noise)
    m = len(steps)
    q = models.input_cov(steps, 0, m)
    jac = models.bias_jacobian(steps, 0, m)
    q = q + np.einsum("...ik,k,...jk->...ij", jac, models.bias_variances(steps.robot), jac)
    heading = models.heading_variances(steps)
    if heading is not None:
        q[:, 1, 1] += heading[:-1] + heading[1:]
    cov = np.full((n, 2, 2), np.nan)
    cov[1:] = np.where(moving[:, None, None], q / (safe**2)[:, None, None], np.nan)
    return twist, cov


def _stamp(t: float) -> tuple[int, int]:
    """(sec, nanosec) of a time [s]: the nanosecond nearest to the float."""
    sec = math.floor(t)
    nsec = round((t - sec) * 1e9)  # t − sec is exact for a float t
    if nsec >= 1_000_000_000:
        sec, nsec = sec + 1, nsec - 1_000_000_000
    return sec, nsec


def write_odometry_bag(
    target: BagTarget,
    t: NDArray[np.float64],
    poses: NDArray[np.float64],
    cov: NDArray[np.float64] | None = None,
    twist: NDArray[np.float64] | None = None,
    twist_cov: NDArray[np.float64] | None = None,
    *,
    topic: str = "/odom",
    frame_id: str = "odom",
    child_frame_id: str = "base_link",
) -> Path:
    """Write ``nav_msgs/Odometry`` messages (module docstring) to ``target``.

    Parameters
    ----------
    target : BagTarget
        From :func:`check_bag_out`; an existing bag there is replaced once the new one is
        complete (it is written next to it first).
    t : ndarray, shape (N,)
        Non-negative, non-decreasing times [s].
    poses : ndarray, shape (N, 3)
        [m, m, rad].
    cov : ndarray, shape (N, 3, 3), optional
        Pose covariance over (x, y, θ).
    twist, twist_cov : ndarray, shapes (N, 2) and (N, 2, 2), optional
        (v, ω) and its covariance; NaN rows are written as "no twist" (zero, large variance).
    """
    rosbags = require_rosbags()
    t = np.asarray(t, dtype=float)
    if t.size and (not np.all(np.isfinite(t)) or t[0] < 0 or np.any(np.diff(t) < 0)):
        raise InputError("ROS stamps need finite, non-negative, non-decreasing times",
                         source=str(target.path))
    if not frame_id or not child_frame_id:
        raise InputError("--frame-id and --child-frame-id must not be empty")
    ros1 = target.format == "ros1"
    store = rosbags.typesys.get_typestore(
        rosbags.typesys.Stores.ROS1_NOETIC if ros1 else rosbags.typesys.Stores.ROS2_HUMBLE)
    parent = target.path.parent
    scratch = Path(tempfile.mkdtemp(prefix=f".{target.path.name}.", dir=parent))
    written = scratch / target.path.name
    try:
        if ros1:
            writer = rosbags.rosbag1.Writer(written)
        else:
            plugin = rosbags.rosbag2.StoragePlugin
            writer = rosbags.rosbag2.Writer(
                written, version=9, storage_plugin=plugin.MCAP if target.format == "mcap" else plugin.SQLITE3)
        serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
        with writer:
            conn = writer.add_connection(topic, _ODOMETRY, typestore=store)
            for k, message in enumerate(_messages(store, ros1, t, poses, cov, twist, twist_cov,
                                                  frame_id, child_frame_id)):
                sec, nsec = _stamp(float(t[k]))
                writer.write(conn, sec * 1_000_000_000 + nsec, serialize(message, _ODOMETRY))
        if target.path.is_dir():
            shutil.rmtree(target.path)
        os.replace(written, target.path)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return target.path


def _messages(store: Any, ros1: bool, t: NDArray[np.float64], poses: NDArray[np.float64],
              cov: NDArray[np.float64] | None, twist: NDArray[np.float64] | None,
              twist_cov: NDArray[np.float64] | None, frame_id: str, child_frame_id: str) -> Iterable[Any]:
    types = store.types
    header_cls, time_cls = types["std_msgs/msg/Header"], types["builtin_interfaces/msg/Time"]
    vector, point, quaternion = (types["geometry_msgs/msg/Vector3"], types["geometry_msgs/msg/Point"],
                                 types["geometry_msgs/msg/Quaternion"])
    unknown = np.diag(np.full(6, UNOBSERVED_VARIANCE)).reshape(-1)
    theta = wrap_angle(np.asarray(poses, dtype=float)[:, 2])
    for k in range(t.size):
        sec, nsec = _stamp(float(t[k]))
        extra = {"seq": k} if ros1 else {}
        header = header_cls(stamp=time_cls(sec=sec, nanosec=nsec), frame_id=frame_id, **extra)
        pose_cov = unknown if cov is None else np.array(ros_pose_covariance(cov[k]))
        pose = types["geometry_msgs/msg/PoseWithCovariance"](
            pose=types["geometry_msgs/msg/Pose"](
                position=point(x=float(poses[k, 0]), y=float(poses[k, 1]), z=0.0),
                orientation=quaternion(x=0.0, y=0.0, z=math.sin(theta[k] / 2), w=math.cos(theta[k] / 2))),
            covariance=pose_cov)
        v, w = (0.0, 0.0) if twist is None or np.isnan(twist[k]).any() else map(float, twist[k])
        if twist is None or np.isnan(twist[k]).any() or twist_cov is None:
            twist_c = unknown
        else:
            twist_c = np.array(ros_twist_covariance(twist_cov[k]))
        body = types["geometry_msgs/msg/TwistWithCovariance"](
            twist=types["geometry_msgs/msg/Twist"](linear=vector(x=v, y=0.0, z=0.0),
                                                   angular=vector(x=0.0, y=0.0, z=w)),
            covariance=twist_c)
        yield types[_ODOMETRY](header=header, child_frame_id=child_frame_id, pose=pose, twist=body)


def write_track_bag(target: BagTarget, track: Track, noise: NoiseArg | None = None, *,
                    topic: str = "/odom", frame_id: str = "odom", child_frame_id: str = "base_link") -> Path:
    """Write a track as ``nav_msgs/Odometry`` (:func:`write_odometry_bag`, twist from
    :func:`track_twist` with ``noise``, the noise the track's covariance was propagated with)."""
    twist, twist_cov = track_twist(track, noise if track.cov is not None else None)
    return write_odometry_bag(target, track.t, track.poses, track.cov, twist, twist_cov,
                              topic=topic, frame_id=frame_id, child_frame_id=child_frame_id)
