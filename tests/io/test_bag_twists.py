"""Twists in a bag: wheel odometry published as ``geometry_msgs/TwistWithCovarianceStamped``
(its twist a measurement, read as an Odometry's: the independent reference is an Odometry
topic of the same twists, and the channels worked out by hand), and a twist that moves
sideways (linear.y), which odomkit's vehicles cannot follow: a holonomic base's track would
be wrong without a word, so it warns."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")

from odomkit.io.bag import read_bag  # noqa: E402

FORMATS = ("ros1", "db3", "mcap")
T0 = 1_700_000_000 * 10**9
ODOM, TWIST, TWIST_S, TWIST_COV = ("nav_msgs/msg/Odometry", "geometry_msgs/msg/Twist",
                                   "geometry_msgs/msg/TwistStamped",
                                   "geometry_msgs/msg/TwistWithCovarianceStamped")
UNICYCLE = '[robot]\ntype = "unicycle"\n'


def twist_fields(msgtype, stamp, ns, vx, wz, vy=0.0):
    """The fields of a ``msgtype`` message carrying the twist (vx, vy, wz)."""
    twist = {"linear": {"x": float(vx), "y": float(vy)}, "angular": {"z": float(wz)}}
    if msgtype == TWIST:
        return twist
    if msgtype == TWIST_S:
        return {"header": stamp(ns), "twist": twist}
    covariance = np.diag([1e-4, 1e-4, 1e6, 1e6, 1e6, 4e-4]).ravel()  # as a base reports it
    if msgtype == ODOM:
        return {"header": stamp(ns, "odom"), "child_frame_id": "base_link",
                "twist": {"twist": twist, "covariance": covariance}}
    return {"header": stamp(ns, "base_link"), "twist": {"twist": twist, "covariance": covariance}}


def messages(topic, msgtype, stamp, vx, wz, vy=None, dt_ns=50_000_000):
    vy = np.zeros_like(vx) if vy is None else vy
    return [(topic, msgtype, T0 + k * dt_ns + 1000,
             twist_fields(msgtype, stamp, T0 + k * dt_ns, vx[k], wz[k], vy[k])) for k in range(len(vx))]


@pytest.mark.parametrize("fmt", FORMATS)
def test_twist_with_covariance_reads_as_the_odometry_of_the_same_twists(tmp_path, bag_writer, stamp, run_cli,
                                                                       fmt):
    """Wheel odometry as a twist with covariance: speed = twist.twist.linear.x, yaw_rate =
    twist.twist.angular.z, each a measurement over the interval ending at its stamp (step k
    uses message k+1, as an Odometry's twist does): the channels by hand, and a track equal
    to the Odometry topic's of the same twists."""
    rng = np.random.default_rng(7)
    vx, wz = 0.4 + rng.uniform(-0.1, 0.1, 200), 0.3 * np.sin(np.arange(200) / 15.0)
    msgs = messages("/wheel/twist", TWIST_COV, stamp, vx, wz) + messages("/odom", ODOM, stamp, vx, wz)
    path = bag_writer(tmp_path / "twcov", fmt, msgs)
    log = read_bag(path, ["/wheel/twist"])
    assert log.channels["speed"].tolist() == [*vx[1:], vx[-1]]
    assert log.channels["yaw_rate"].tolist() == [*wz[1:], wz[-1]]
    assert log.t.tolist() == read_bag(path, ["/odom"]).t.tolist()  # header stamps
    robot = tmp_path / "u.toml"
    robot.write_text(UNICYCLE)
    tracks = []
    for topic in ("/wheel/twist", "/odom"):
        code, out, err = run_cli("track", path, "--robot", robot, "--topic", topic, "--json")
        assert code == 0 and err == "", err
        tracks.append(json.loads(out))
    assert tracks[0]["pose"] == tracks[1]["pose"] and tracks[0]["path_length"] == tracks[1]["path_length"]


# --- a twist that moves sideways ------------------------------------------------------------

def sideways(msgtype, stamp, vy_of):
    """20 messages standing, then 80 at vx = 0.5 m/s turning at 0.2 rad/s, with vy = vy_of(vx)."""
    vx = np.r_[np.zeros(20), np.full(80, 0.5)]
    wz = np.r_[np.zeros(20), np.full(80, 0.2)]
    vy = np.r_[np.zeros(20), vy_of(vx[20:])]
    return messages("/base/odom", msgtype, stamp, vx, wz, vy)


@pytest.mark.parametrize("msgtype", [ODOM, TWIST, TWIST_S, TWIST_COV])
def test_a_twist_that_moves_sideways_warns(tmp_path, bag_writer, stamp, msgtype):
    """vy = 0.3·vx on a mecanum base: over the 80 messages that move (the 20 standing ones,
    zero twist, are no motion), RMS 0.15 m/s sideways against 0.5 m/s ahead (by hand)."""
    path = bag_writer(tmp_path / "holonomic", "mcap", sideways(msgtype, stamp, lambda vx: 0.3 * vx))
    with pytest.warns(UserWarning) as seen:
        read_bag(path, ["/base/odom"])
    [text] = [str(w.message) for w in seen]
    assert re.fullmatch(
        re.escape(f"{path}: /base/odom: the twist moves sideways: linear.y has RMS 0.15 m/s against "
                  "linear.x's 0.5 m/s over the 80 messages that move; odomkit's vehicles have no sideways "
                  "velocity (a holonomic base, mecanum or omni, is not modelled), so the track ignores "
                  "linear.y"), text)


@pytest.mark.parametrize("vy_of", [
    lambda vx: 0.0 * vx,  # a diff drive: linear.y 0
    lambda vx: np.random.default_rng(3).normal(0.0, 0.005, vx.size),  # a filtered twist's noise
    lambda vx: 0.08 * vx,  # a skid-steer's slip in turns: under 10 %
])
def test_a_twist_without_material_sideways_motion_does_not_warn(tmp_path, bag_writer, stamp, vy_of):
    path = bag_writer(tmp_path / "diff", "db3", sideways(ODOM, stamp, vy_of))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        log = read_bag(path, ["/base/odom"])
    assert len(log) == 100


def test_a_slow_robots_sideways_noise_under_the_floor_does_not_warn(tmp_path, bag_writer, stamp):
    """vx 0.05 m/s with vy noise of RMS 0.015 m/s: 30 % of vx, but under 0.02 m/s."""
    rng = np.random.default_rng(5)
    vy = rng.normal(0.0, 1.0, 100)
    vy *= 0.015 / np.sqrt(np.mean(vy**2))
    path = bag_writer(tmp_path / "slow", "ros1", messages("/odom", ODOM, stamp, np.full(100, 0.05),
                                                          np.zeros(100), vy))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_bag(path, ["/odom"])


def test_the_sideways_warning_reaches_the_json_warnings(tmp_path, bag_writer, stamp, run_cli):
    path = bag_writer(tmp_path / "omni", "ros1", sideways(TWIST_COV, stamp, lambda vx: 0.3 * vx))
    robot = tmp_path / "u.toml"
    robot.write_text(UNICYCLE)
    code, out, err = run_cli("track", path, "--robot", robot, "--json")
    assert code == 0
    said = [w for w in json.loads(out)["warnings"] if "moves sideways" in w]
    assert len(said) == 1 and "RMS 0.15 m/s against linear.x's 0.5 m/s" in said[0]
    assert "odomkit: warning: " in err and "the track ignores linear.y" in err
    assert Path(path).exists()
