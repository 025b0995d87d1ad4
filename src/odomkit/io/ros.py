"""ROS interface formats: the ``geometry_msgs/PoseWithCovariance`` covariance layout and the
ROS 2 ``diff_drive_controller`` parameter file (YAML).

**Pose covariance.** ROS stores a pose covariance as 36 numbers, a row-major 6×6 matrix
over (x, y, z, rotation about X, rotation about Y, rotation about Z) — REP 103 axes, with
the rotations as fixed-axis roll, pitch, yaw. A planar robot's θ is the yaw, so odomkit's
(x, y, θ) block lands on indices (0, 1, 5).

The three axes planar odometry does not observe (z, roll, pitch) get a large variance,
:data:`UNOBSERVED_VARIANCE` = 1e6 (m² or rad²), the value ROS's
``diff_drive_controller`` configurations use in ``pose_covariance_diagonal``
([0.001, 0.001, 1e6, 1e6, 1e6, 1e3]). A large variance rather than zero, because zero
would claim those axes are known exactly and an EKF (e.g. robot_localization) fusing
this message would then trust them over every other sensor; 1e6 is large enough to be
ignored, yet finite so the matrix stays invertible.

**Controller parameters.** The numbers (wheel separation, radius and their multipliers)
come from :func:`odomkit.calibrate.export.diff_drive_controller_parameters`; this module
only lays them out as the controller's YAML and writes the file.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from odomkit.calibrate.export import diff_drive_controller_parameters
from odomkit.errors import ModelError
from odomkit.io.files import write_new_text
from odomkit.robot import DiffDrive

__all__ = ["UNOBSERVED_VARIANCE", "ros2_diff_drive_yaml", "ros_pose_covariance", "write_ros2_yaml"]

UNOBSERVED_VARIANCE = 1e6
"""Variance given to z [m²], roll and pitch [rad²]."""

_ROS_INDEX = (0, 1, 5)  # x, y, yaw in ROS's (x, y, z, roll, pitch, yaw)


def ros_pose_covariance(
    cov3: ArrayLike, unobserved_variance: float = UNOBSERVED_VARIANCE
) -> list[float]:
    """The 36-element ROS pose covariance of a planar (x, y, θ) covariance.

    Parameters
    ----------
    cov3 : array_like, shape (3, 3)
        Covariance in the order x, y, θ [m², m·rad, rad²].
    unobserved_variance : float
        Diagonal entry for z, roll and pitch; their covariances with everything are 0.

    Returns
    -------
    list of float, length 36
        Row-major 6×6 over (x, y, z, roll, pitch, yaw).

    Examples
    --------
    >>> c = ros_pose_covariance([[1.0, 0.1, 0.2], [0.1, 2.0, 0.3], [0.2, 0.3, 3.0]])
    >>> c[0], c[1], c[5], c[7], c[11], c[35], c[14]
    (1.0, 0.1, 0.2, 2.0, 0.3, 3.0, 1000000.0)
    """
    cov = np.asarray(cov3, dtype=float)
    if cov.shape != (3, 3):
        raise ModelError(f"pose covariance must be 3x3 (x, y, theta), got shape {cov.shape}")
    if not (np.isfinite(unobserved_variance) and unobserved_variance > 0):
        raise ModelError(f"unobserved_variance must be positive, got {unobserved_variance!r}")
    out = np.zeros((6, 6))
    out[2, 2] = out[3, 3] = out[4, 4] = unobserved_variance
    out[np.ix_(_ROS_INDEX, _ROS_INDEX)] = cov
    return [float(v) for v in out.reshape(-1)]


def ros2_diff_drive_yaml(
    robot: DiffDrive,
    wheel_radius: float,
    *,
    controller_name: str = "diff_drive_controller",
    nominal_m_per_tick: float | None = None,
) -> str:
    """ROS 2 ``diff_drive_controller`` parameters for a calibrated robot (YAML text).

    Parameters
    ----------
    robot : DiffDrive
        Calibrated robot.
    wheel_radius : float
        Nominal wheel radius configured in the controller [m].
    controller_name : str
        Top-level key (the controller's node name).
    nominal_m_per_tick : float, optional
        Metres per tick that ``wheel_radius`` corresponds to (see
        :func:`odomkit.calibrate.export.diff_drive_controller_parameters`).

    Examples
    --------
    >>> print(ros2_diff_drive_yaml(DiffDrive(0.2, 1e-4, 1e-4, 0.999, 1.001, 1.006), 0.042))
    diff_drive_controller:
      ros__parameters:
        wheel_separation: 0.2
        wheel_radius: 0.042
        wheel_separation_multiplier: 1.006
        left_wheel_radius_multiplier: 0.999
        right_wheel_radius_multiplier: 1.001
    <BLANKLINE>
    """
    values = diff_drive_controller_parameters(robot, wheel_radius,
                                              nominal_m_per_tick=nominal_m_per_tick)
    if not controller_name or any(c in controller_name for c in ":#\n "):
        raise ModelError(f"controller_name must be a plain ROS node name, got {controller_name!r}")
    body = "".join(f"    {k}: {float(v)!r}\n" for k, v in values.items())
    return f"{controller_name}:\n  ros__parameters:\n{body}"


def write_ros2_yaml(path: str | Path, robot: DiffDrive, wheel_radius: float, *,
                    overwrite: bool = False, **kwargs: Any) -> Path:
    """Write :func:`ros2_diff_drive_yaml` to ``path`` (never over an existing file unless
    ``overwrite``); ``kwargs`` go to :func:`ros2_diff_drive_yaml`."""
    return write_new_text(path, ros2_diff_drive_yaml(robot, wheel_radius, **kwargs), overwrite)
