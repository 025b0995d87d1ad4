"""ROS export of a planar pose covariance."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.io.ros import UNOBSERVED_VARIANCE, ros_pose_covariance


def test_layout_row_major_x_y_z_roll_pitch_yaw():
    cov3 = np.array([[1.0, 0.2, 0.3], [0.2, 2.0, 0.4], [0.3, 0.4, 3.0]])
    flat = ros_pose_covariance(cov3)
    assert len(flat) == 36 and all(isinstance(v, float) for v in flat)
    m = np.array(flat).reshape(6, 6)
    # row-major: element (i, j) at 6i + j; x = 0, y = 1, yaw = 5
    assert flat[0 * 6 + 0] == 1.0 and flat[1 * 6 + 1] == 2.0 and flat[5 * 6 + 5] == 3.0
    assert flat[0 * 6 + 1] == flat[1 * 6 + 0] == 0.2
    assert flat[0 * 6 + 5] == flat[5 * 6 + 0] == 0.3  # x–yaw
    assert flat[1 * 6 + 5] == flat[5 * 6 + 1] == 0.4  # y–yaw
    for k in (2, 3, 4):  # z, roll, pitch: large variance, uncorrelated
        assert m[k, k] == UNOBSERVED_VARIANCE == 1e6
        assert np.count_nonzero(m[k]) == 1 and np.count_nonzero(m[:, k]) == 1
    assert np.array_equal(m, m.T)
    assert np.min(np.linalg.eigvalsh(m)) > 0


def test_custom_unobserved_variance_and_bad_shape():
    assert ros_pose_covariance(np.eye(3), 50.0)[14] == 50.0
    with pytest.raises(ModelError, match="3x3"):
        ros_pose_covariance(np.eye(2))
    with pytest.raises(ModelError, match="unobserved"):
        ros_pose_covariance(np.eye(3), 0.0)
