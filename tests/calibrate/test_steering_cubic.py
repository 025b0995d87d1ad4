"""A car whose steering ratio varies with the angle, calibrated from a 1 Hz GPS
(``calibrate --truth --fit-steering-cubic``).

The car turns its road wheels s + 40·s³ for s the steering-wheel angle over 15 (a
variable-ratio rack; a real BMW's log fitted k = 39–40, docs/results/honesty.md). Its first
half turns hard at junctions, its second half cruises, as that drive did. Calibrated on
the first half with a constant ratio, the steering offset and wheel base absorb the cubic
and the second half is driven worse than with the robot file; with the cubic fitted, k is
recovered and the second half's error falls well below the robot file's.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from odomkit.io.robotfile import read_robot
from odomkit.log import OdometryLog
from odomkit.robot import Car
from odomkit.track import dead_reckon_log

pytestmark = pytest.mark.slow

RATIO, CUBIC, L = 15.0, 40.0, 2.7
TRUE = Car(L, steering_offset=0.0, c_scale=0.98, steering_ratio=RATIO, steering_cubic=CUBIC)


def drive(folder, seed=5, dt=0.05):
    """Turns at junctions (steering wheel to ±110°) for 5 min, then 5 min of cruising."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 600.0, dt)
    junctions = np.radians(110.0) * np.sin(2 * np.pi * t / 40.0) ** 9 * np.sign(np.sin(2 * np.pi * t / 173.0))
    cruising = np.radians(12.0) * np.sin(t / 13.0)
    wheel = np.where(t < 300.0, junctions, cruising)
    speed = np.where(t < 300.0, 8.0 - 4.0 * np.abs(np.sin(2 * np.pi * t / 40.0)) ** 9, 20.0)
    measured = OdometryLog(t, {"speed": speed / TRUE.c_scale, "steer": wheel})
    true = dead_reckon_log(measured, TRUE).poses
    np.savetxt(folder / "car.csv", np.column_stack((t, speed / TRUE.c_scale, wheel)), delimiter=",",
               header="t,speed,steer", comments="", fmt="%.6f")
    fixes = np.arange(0.3, t[-1], 1.0)
    xy = np.column_stack([np.interp(fixes, t, true[:, k]) for k in (0, 1)])
    xy += rng.normal(0, 0.5, (fixes.size, 2))
    np.savetxt(folder / "gps.csv", np.column_stack((fixes, xy)), delimiter=",", header="t,x,y", comments="",
               fmt="%.4f")
    (folder / "car.toml").write_text(f'[robot]\ntype = "car"\nwheel_base = {L}\nsteering_ratio = {RATIO}\n')
    return t, true


def second_half_rms(folder, robot_path, t, true):
    robot, _ = read_robot(robot_path)
    half = int(np.searchsorted(t, 300.0))
    data = np.loadtxt(folder / "car.csv", delimiter=",", skiprows=1)
    log = OdometryLog(data[half:, 0], {"speed": data[half:, 1], "steer": data[half:, 2]})
    poses = dead_reckon_log(log, robot, pose0=true[half]).poses
    return float(np.sqrt(np.mean(np.sum((poses[:, :2] - true[half:, :2]) ** 2, axis=1))))


def test_the_cubic_is_recovered_and_carries_the_calibration_to_the_other_half(run_cli, tmp_path):
    t, true = drive(tmp_path)
    args = ("calibrate", tmp_path / "car.csv", "--robot", tmp_path / "car.toml", "--truth",
            tmp_path / "gps.csv", "--truth-sigma", "0.5", "--truth-time-offset", "0", "--span", ":50%",
            "--json")
    code, out, err = run_cli(*args, "--fit-steering-cubic", "--out-robot", tmp_path / "cubic.toml")
    assert code == 0, err
    fitted = json.loads(out)
    assert set(fitted["parameters"]) == {"c_scale", "steering_offset", "wheel_base", "steering_cubic"}
    assert fitted["parameters"]["steering_cubic"] == pytest.approx(CUBIC, rel=0.1)
    assert fitted["parameters"]["c_scale"] == pytest.approx(0.98, abs=0.005)
    code, out, err = run_cli(*args, "--out-robot", tmp_path / "linear.toml")
    assert code == 0, err
    nominal = second_half_rms(tmp_path, tmp_path / "car.toml", t, true)
    linear = second_half_rms(tmp_path, tmp_path / "linear.toml", t, true)
    cubic = second_half_rms(tmp_path, tmp_path / "cubic.toml", t, true)
    assert cubic < nominal / 2 and cubic < linear / 2, (nominal, linear, cubic)


def test_the_flag_is_refused_where_it_does_not_apply(run_cli, tmp_path):
    drive(tmp_path)
    (tmp_path / "uni.toml").write_text('[robot]\ntype = "unicycle"\n')
    code, _, err = run_cli("calibrate", tmp_path / "car.csv", "--robot", tmp_path / "uni.toml", "--truth",
                           tmp_path / "gps.csv", "--columns", "t=t,speed=speed,yaw_rate=steer",
                           "--fit-steering-cubic")
    assert code == 2 and "steering_cubic is a car's" in err
    code, _, err = run_cli("calibrate", tmp_path / "car.csv", "--robot", tmp_path / "car.toml", "--method",
                           "umbmark", "--side", "2", "--fit-steering-cubic")
    assert code == 2 and "--fit-steering-cubic applies to --method exact only" in err
