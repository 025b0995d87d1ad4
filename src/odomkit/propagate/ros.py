"""Export a planar pose covariance in ROS form (``geometry_msgs/PoseWithCovariance``).

ROS stores a pose covariance as 36 numbers, a row-major 6×6 matrix over
(x, y, z, rotation about X, rotation about Y, rotation about Z) — REP 103 axes, with the
rotations as fixed-axis roll, pitch, yaw. A planar robot's θ is the yaw, so odomkit's
(x, y, θ) block lands on indices (0, 1, 5).

The three axes planar odometry does not observe (z, roll, pitch) get a large variance,
:data:`UNOBSERVED_VARIANCE` = 1e6 (m² or rad²), the value ROS's
``diff_drive_controller`` configurations use in ``pose_covariance_diagonal``
([0.001, 0.001, 1e6, 1e6, 1e6, 1e3]). A large variance rather than zero, because zero
would claim those axes are known exactly and an EKF (e.g. robot_localization) fusing
this message would then trust them over every other sensor; 1e6 is large enough to be
ignored, yet finite so the matrix stays invertible.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from odomkit.errors import ModelError

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
