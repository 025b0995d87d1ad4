"""``odomkit check`` and ``calibrate`` on a Husky-like ROS bag (a user study's real bag,
reproduced synthetically): wheel odometry, an IMU mounted on its side, and a 2.5 Hz GPS
(``NavSatFix``) whose error wanders (σ 0.8 m per axis, correlated over 12 s) and that states
its covariance (0.8 m).

The odometry is exact, so its true travel and turning ratios are 1; the IMU's gyro z is a
pitch wobble, so the turning it gives is about 0. Before: the ratios judged at the fixes'
0.13 m scatter failed the odometry's turning as a unit mixup, the IMU's turning stopped both
commands with "the numerics failed (math domain error)", and ``check`` without ``--topic``
was a finding (exit 1), not the one-line error ``track`` gives.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.log import OdometryLog
from odomkit.robot import Unicycle
from odomkit.track import dead_reckon_log

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")
pm = pytest.importorskip("pymap3d", reason="the gps extra (pymap3d) is not installed")

T0 = 1_432_235_497 * 10**9
ORIGIN = (43.6, -79.4, 100.0)
SIGMA = 0.8
UNICYCLE = '[robot]\ntype = "unicycle"\n'
GYRO = '[robot]\ntype = "gyro"\n'


def _drive(seed=3, duration=400.0, dt=0.1):
    """A base at about 0.9 m/s turning gently (tests/calibrate/test_check_ratios_gps.py)."""
    rng = np.random.default_rng(seed)
    t = dt * np.arange(int(duration / dt))
    knots = rng.uniform(-0.25, 0.25, t.size // 100 + 2) * (rng.random(t.size // 100 + 2) < 0.3)
    speed = 0.9 + 0.2 * np.sin(t / 23.0)
    rate = np.interp(t, np.arange(knots.size) * 10.0, knots)
    poses = dead_reckon_log(OdometryLog(t, {"speed": speed, "yaw_rate": rate}), Unicycle(),
                            pose0=(5.0, -3.0, 0.4)).poses
    return t, speed, rate, poses


@pytest.fixture(scope="module")
def husky(tmp_path_factory, bag_writer, stamp):
    d = tmp_path_factory.mktemp("husky")
    t, speed, rate, poses = _drive()
    rng = np.random.default_rng(11)
    msgs = []
    for k, tk in enumerate(t):
        ns = T0 + round(tk * 1e9)
        x, y, th = poses[k]
        pose = {"pose": {"position": {"x": x, "y": y},
                         "orientation": {"z": math.sin(th / 2), "w": math.cos(th / 2)}}}
        twist = {"twist": {"linear": {"x": float(speed[k])}, "angular": {"z": float(rate[k])}}}
        msgs.append(("/odom", "nav_msgs/msg/Odometry", ns,
                     {"header": stamp(ns), "pose": pose, "twist": twist}))
        # The IMU on its side: gravity along +y, its gyro z a pitch wobble, not the yaw rate.
        wobble = 0.003 * math.sin(tk / 1.7) + rng.normal(0.0, 0.002)
        msgs.append(("/imu", "sensor_msgs/msg/Imu", ns + 1000,
                     {"header": stamp(ns + 1000), "angular_velocity": {"z": wobble},
                      "linear_acceleration": {"x": -0.22, "y": 9.79, "z": 0.08},
                      "orientation_covariance": [-1.0] + [0.0] * 8}))
    fix_t = np.arange(0.13, t[-1], 0.4)
    xy = np.column_stack([np.interp(fix_t, t, poses[:, k]) for k in (0, 1)])
    keep = math.exp(-0.4 / 12.0)
    error = np.zeros_like(xy)
    error[0] = rng.normal(0.0, SIGMA, 2)
    for i in range(1, fix_t.size):
        error[i] = keep * error[i - 1] + math.sqrt(1 - keep**2) * rng.normal(0.0, SIGMA, 2)
    xy = xy + error + rng.normal(0.0, 0.05, xy.shape)
    lat, lon, alt = pm.enu2geodetic(xy[:, 0], xy[:, 1], np.zeros(fix_t.size), *ORIGIN)
    for k, tk in enumerate(fix_t):
        ns = T0 + round(tk * 1e9)
        msgs.append(("/fix", "sensor_msgs/msg/NavSatFix", ns + 2000,
                     {"header": stamp(ns), "latitude": lat[k], "longitude": lon[k], "altitude": alt[k],
                      "position_covariance": [SIGMA**2, 0, 0, 0, SIGMA**2, 0, 0, 0, 4.0],
                      "position_covariance_type": 2}))
    (d / "husky.toml").write_text(UNICYCLE)
    (d / "gyro.toml").write_text(GYRO)
    return {"bag": bag_writer(d / "test1", "ros1", msgs), "dir": d}


def _findings(out):
    return {f["check"]: f for f in json.loads(out)["findings"]}


def test_the_odometrys_turning_is_judged_at_the_sigma_the_fixes_state(run_cli, husky):
    """No --truth-sigma: ok, as with --truth-sigma 0.8, and the findings say whose σ judged them
    (before: turn_ratio FAIL about 0.3, "check the yaw rate's unit")."""
    args = (husky["bag"], "--robot", husky["dir"] / "husky.toml", "--topic", "/odom", "--truth-topic", "/fix",
            "--json")
    code, out, err = run_cli("check", *args)
    assert code == 0, out
    found = _findings(out)
    for check in ("travel_ratio", "turn_ratio"):
        assert found[check]["status"] == "ok", found[check]["message"]
        assert "0.8 m sigma the fixes state" in found[check]["message"]
    assert abs(found["turn_ratio"]["value"] - 1) < 0.15
    code, given, _ = run_cli("check", *args, "--truth-sigma", "0.8")
    assert code == 0
    assert _findings(given)["turn_ratio"]["value"] == pytest.approx(found["turn_ratio"]["value"], rel=1e-12)
    assert "fixes state" not in _findings(given)["turn_ratio"]["message"]
    # calibrate no longer says it may be bent by a unit, and fits as before (the stated σ
    # judges, it does not weigh the fit: the parameters are those of a truth without it).
    code, out, err = run_cli("calibrate", *args)
    assert code == 0, err
    assert "unit or robot-file error" not in err


@pytest.mark.parametrize("robot", ["gyro.toml", "husky.toml"])
def test_an_imu_on_its_side_is_a_finding_not_a_math_domain_error(run_cli, husky, robot):
    args = (husky["bag"], "--robot", husky["dir"] / robot, "--topic", "/odom", "--topic", "/imu",
            "--truth-topic", "/fix", "--truth-sigma", "0.8")
    code, out, err = run_cli("check", *args, "--json")
    assert code == 1, err
    turn = _findings(out)["turn_ratio"]
    assert turn["status"] == "fail" and "hardly turns" in turn["message"]
    assert "not mounted level" in turn["advice"]
    code, out, err = run_cli("calibrate", *args)
    assert "math domain error" not in err and "numerics failed" not in err
    assert "hardly turns" in err


def test_check_without_topic_on_a_bag_of_several_is_one_line_exit_2(run_cli, husky):
    code, out, err = run_cli("check", husky["bag"], "--robot", husky["dir"] / "husky.toml")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("odomkit: error: ") and "a bag log needs --topic; topics odomkit reads:" in err
    code, out, err = run_cli("check", husky["bag"], "--robot", husky["dir"] / "husky.toml", "--topic",
                             "/nope")
    assert code == 2 and "no topic /nope in the bag" in err
