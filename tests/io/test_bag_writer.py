"""ROS bags out (issue 12 item 5): nav_msgs/Odometry in all three formats reads back to the
same numbers (through odomkit's reader and through rosbags' own), the 6×6 layouts hold
their entries where ROS puts them, and the twist covariance equals hand formulas."""

from __future__ import annotations

import math
import warnings
from fractions import Fraction

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.io.ros import UNOBSERVED_VARIANCE, ros_pose_covariance, ros_twist_covariance

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")

from odomkit.io.bag import read_bag_odometry  # noqa: E402
from odomkit.io.bag_writer import check_bag_out, write_odometry_bag  # noqa: E402

FORMATS = ("ros1", "db3", "mcap")
T0 = 1_700_000_000 * 10**9  # an epoch time [ns]


def seconds(ns: int) -> float:
    """The float nearest to ns·1e-9 (exact rational arithmetic)."""
    return float(Fraction(ns, 10**9))


def _track_arrays(n=7):
    rng = np.random.default_rng(5)
    t = np.array([seconds(T0) + 0.1 * k for k in range(n)])
    poses = np.column_stack((rng.normal(size=n), rng.normal(size=n), np.linspace(0, 9.0, n)))  # θ past 2π
    a = rng.normal(size=(n, 3, 3))
    cov = a @ a.transpose(0, 2, 1)
    twist = rng.normal(size=(n, 2))
    twist[0] = np.nan  # no step ends at the first row
    b = rng.normal(size=(n, 2, 2))
    return t, poses, cov, twist, b @ b.transpose(0, 2, 1)


@pytest.mark.parametrize("fmt", FORMATS)
def test_odometry_written_reads_back_the_same_numbers(tmp_path, fmt):
    t, poses, cov, twist, twist_cov = _track_arrays()
    target = check_bag_out(tmp_path / ("odo.bag" if fmt == "ros1" else "odo"), fmt)
    path = write_odometry_bag(target, t, poses, cov, twist, twist_cov, frame_id="map", child_frame_id="base")
    back = read_bag_odometry(path)
    assert back.t.tolist() == t.tolist()  # each float time to the nanosecond and back, exactly
    assert back.poses[:, :2].tolist() == poses[:, :2].tolist()
    assert np.abs(back.poses[:, 2] - poses[:, 2]).max() < 4e-15
    assert back.pose_covariance.tolist() == [ros_pose_covariance(c) for c in cov]
    assert np.array_equal(back.cov, cov)
    assert back.twist[1:].tolist() == twist[1:].tolist() and back.twist[0].tolist() == [0.0, 0.0]
    assert back.twist_covariance[1:].tolist() == [ros_twist_covariance(c) for c in twist_cov[1:]]
    assert back.twist_covariance[0].tolist() == np.diag([UNOBSERVED_VARIANCE] * 6).reshape(-1).tolist()
    assert (back.frame_id, back.child_frame_id) == ("map", "base")


def test_the_6x6_layout_seen_by_rosbags_itself(tmp_path):
    """Independent of odomkit's reader: the raw messages through rosbags' AnyReader."""
    from rosbags.highlevel import AnyReader

    t, poses, cov, twist, twist_cov = _track_arrays(3)
    path = write_odometry_bag(check_bag_out(tmp_path / "raw"), t, poses, cov, twist, twist_cov)
    with AnyReader([path]) as reader:
        msgs = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()]
    m = msgs[2]
    c6 = np.asarray(m.pose.covariance).reshape(6, 6)
    assert c6[0, 0] == cov[2, 0, 0] and c6[0, 5] == cov[2, 0, 2] and c6[5, 1] == cov[2, 2, 1]
    assert c6[5, 5] == cov[2, 2, 2] and [c6[i, i] for i in (2, 3, 4)] == [UNOBSERVED_VARIANCE] * 3
    assert np.count_nonzero(c6) == 9 + 3
    w6 = np.asarray(m.twist.covariance).reshape(6, 6)
    assert w6[0, 0] == twist_cov[2, 0, 0] and w6[0, 5] == twist_cov[2, 0, 1]
    assert w6[5, 5] == twist_cov[2, 1, 1]
    assert [w6[i, i] for i in (1, 2, 3, 4)] == [UNOBSERVED_VARIANCE] * 4
    assert m.twist.twist.linear.x == twist[2, 0] and m.twist.twist.angular.z == twist[2, 1]
    q = m.pose.pose.orientation
    assert (q.x, q.y) == (0.0, 0.0) and q.w >= 0
    assert math.atan2(q.z, q.w) * 2 == pytest.approx(poses[2, 2] - 2 * math.pi, abs=1e-15)


def test_bag_out_paths_are_checked(tmp_path):
    with pytest.raises(InputError, match="give a .bag path"):
        check_bag_out(tmp_path / "x", "ros1")
    with pytest.raises(InputError, match="a .bag path is a ROS 1 bag"):
        check_bag_out(tmp_path / "x.bag", "db3")
    with pytest.raises(InputError, match="--bag-format must be one of"):
        check_bag_out(tmp_path / "x", "ros3")
    other = tmp_path / "notes"
    other.mkdir()
    (other / "a.txt").write_text("keep me")
    with pytest.raises(InputError, match="not a ROS 2 bag"):
        check_bag_out(other, overwrite=True)
    t, poses, *_ = _track_arrays(2)
    bag = write_odometry_bag(check_bag_out(tmp_path / "b"), t, poses)
    with pytest.raises(InputError, match="exists already"):
        check_bag_out(bag)
    with pytest.raises(InputError, match="replace an input"):
        check_bag_out(bag, overwrite=True, inputs=[bag / "b.mcap"])
    again = write_odometry_bag(check_bag_out(bag, "db3", overwrite=True), t, poses + 1)
    assert sorted(p.name for p in again.iterdir()) == ["b.db3", "metadata.yaml"]
    assert read_bag_odometry(again).poses[:, 0].tolist() == (poses[:, 0] + 1).tolist()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        unknown = read_bag_odometry(again).pose_covariance  # no covariance: "unknown", large
    assert unknown[0].tolist() == np.diag([UNOBSERVED_VARIANCE] * 6).reshape(-1).tolist()


def test_twist_covariance_is_the_step_covariance_over_dt_squared():
    """Hand formula for a differential drive (Borenstein–Feng eq. 2.2–2.4, variance k²|d| per
    wheel): Δd = (d_L + d_R)/2, Δθ = (d_R − d_L)/b."""
    from odomkit.io.bag_writer import track_twist
    from odomkit.log import OdometryLog
    from odomkit.noise import WheelNoise
    from odomkit.robot import DiffDrive
    from odomkit.track import dead_reckon_log

    b, kl, kr = 0.4, 0.002, 0.003
    t = np.array([0.0, 0.1, 0.1, 0.35, 0.5])  # a repeated time: a zero-length step
    dl = np.array([0.0, 0.01, 0.0, -0.02, 0.03])
    dr = np.array([0.0, 0.02, 0.0, 0.01, 0.03])
    log = OdometryLog(t, {"dist_left": dl, "dist_right": dr})
    track = dead_reckon_log(log, DiffDrive(b), noise=WheelNoise(kl, kr))
    twist, cov = track_twist(track, WheelNoise(kl, kr))
    assert np.isnan(twist[[0, 2]]).all() and np.isnan(cov[[0, 2]]).all()
    for k in (1, 3, 4):
        dt = t[k] - t[k - 1]
        vl, vr = kl**2 * abs(dl[k]), kr**2 * abs(dr[k])
        assert twist[k] == pytest.approx([(dl[k] + dr[k]) / 2 / dt, (dr[k] - dl[k]) / b / dt], rel=1e-14)
        c = (vr - vl) / (2 * b)
        expected = np.array([[(vl + vr) / 4, c], [c, (vl + vr) / b**2]]) / dt**2
        assert cov[k] == pytest.approx(expected, rel=1e-12)
    assert track_twist(track)[1] is None


def test_twist_covariance_adds_the_spread_of_a_bias():
    """A left-wheel scale error s (σ_s) moves each step by s·d_L: J = (d_L/2, −d_L/b)."""
    from odomkit.io.bag_writer import track_twist
    from odomkit.log import OdometryLog
    from odomkit.noise import ParameterUncertainty, WheelNoise
    from odomkit.robot import DiffDrive
    from odomkit.track import dead_reckon_log

    b, k, s = 0.3, 0.001, 0.01
    t, dl, dr = np.array([0.0, 0.2, 0.5]), np.array([0.0, 0.04, -0.01]), np.array([0.0, 0.05, 0.02])
    noise = (WheelNoise(k, k), ParameterUncertainty(sigma_scale_left=s))
    track = dead_reckon_log(OdometryLog(t, {"dist_left": dl, "dist_right": dr}), DiffDrive(b), noise=noise)
    _, with_bias = track_twist(track, noise)
    _, white = track_twist(track, noise[0])
    for i in (1, 2):
        jac = np.array([dl[i] / 2, -dl[i] / b])
        assert with_bias[i] - white[i] == pytest.approx(s**2 * np.outer(jac, jac) / (t[i] - t[i - 1]) ** 2,
                                                        rel=1e-12)
