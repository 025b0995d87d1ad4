"""3-D poses onto the ground plane (odomkit.frames), against scipy's rotations."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from odomkit.frames import UP_AXES, ground_basis, likely_up, planar_poses, quaternion_matrices


def test_quaternion_matrices_are_scipys_rotations_times_the_squared_norm():
    q = Rotation.random(50, random_state=3).as_quat()  # x, y, z, w
    scale = np.linspace(0.5, 3.0, 50)[:, None]
    got = quaternion_matrices(q * scale)
    assert np.allclose(got / scale[:, :, None] ** 2, Rotation.from_quat(q).as_matrix(), atol=1e-12)


@pytest.mark.parametrize("up", UP_AXES)
def test_every_ground_basis_is_right_handed_with_up_third(up):
    basis = ground_basis(up)
    assert np.allclose(basis @ basis.T, np.eye(3)) and np.linalg.det(basis) == pytest.approx(1.0)
    assert basis[2, "xyz".index(up[1])] == (1.0 if up[0] == "+" else -1.0)


def test_z_up_yaw_is_the_zyx_yaw_of_any_rotation():
    rotations = Rotation.random(40, random_state=5)
    positions = np.random.default_rng(5).normal(size=(40, 3))
    xy, yaw = planar_poses(positions, quaternion_matrices(rotations.as_quat()))
    assert np.allclose(xy, positions[:, :2])
    assert np.allclose(yaw, rotations.as_euler("ZYX")[:, 0], atol=1e-12)


def _ground_track():
    t = np.linspace(0.0, 30.0, 301)
    heading = 0.3 * np.sin(0.2 * t) + 0.1 * t
    return np.column_stack((2.0 * np.cos(0.1 * t), 3.0 * np.sin(0.15 * t))), heading


def test_a_y_up_motion_capture_reads_back_the_ground_track():
    """A Y-up frame (x', y' up, z'): the ground's x is z' and its y is x' (right-handed about
    +y), and a turn by ψ about the ground's up is scipy's rotation by ψ about +y'."""
    xy, heading = _ground_track()
    height = 0.12 + 0.001 * np.sin(np.arange(xy.shape[0]))
    file_positions = np.column_stack((xy[:, 1], height, xy[:, 0]))
    file_rotations = Rotation.from_rotvec(np.outer(heading, [0.0, 1.0, 0.0]))
    got_xy, got_yaw = planar_poses(file_positions, quaternion_matrices(file_rotations.as_quat()), "+y")
    assert np.allclose(got_xy, xy)
    assert np.allclose(np.angle(np.exp(1j * (got_yaw - heading))), 0.0, atol=1e-12)
    # Read as z-up, the track is x' and the height, and the heading is no turn about +y'.
    assert likely_up(file_positions) == "+y"
    assert likely_up(np.column_stack((xy, height))) is None
    assert planar_poses(file_positions, None, "+y")[1] is None


def test_y_down_reads_a_camera_driving_along_its_z_axis():
    """KITTI's camera frame: x right, y down, z forward. A car drives along its camera's z:
    the ground's forward is z and its left is -x, and a left turn by ψ is a turn about -y
    (scipy's rotation by -ψ about +y), which takes z towards -x. Before, -y read the ground
    as (x, z) and the heading from the camera's x axis: 90° off the way the car drives."""
    xy, heading = _ground_track()
    file_positions = np.column_stack((-xy[:, 1], np.full(len(xy), 1.7), xy[:, 0]))
    rotations = Rotation.from_rotvec(np.outer(-heading, [0.0, 1.0, 0.0]))  # a turn about -y
    assert np.allclose(rotations.apply([0.0, 0.0, 1.0])[:, [2, 0]] * [1, -1],
                       np.column_stack((np.cos(heading), np.sin(heading))))  # z is forward
    got_xy, got_yaw = planar_poses(file_positions, rotations.as_matrix(), "-y")
    assert np.allclose(got_xy, xy)
    assert np.allclose(np.angle(np.exp(1j * (got_yaw - heading))), 0.0, atol=1e-12)
