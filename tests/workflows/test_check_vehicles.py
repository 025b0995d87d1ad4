"""``odomkit check LOG --robot R --truth GT --json`` judges the calibration parameters of the
vehicles beyond the differential drive and the tricycle (the example unicycle and car robot
files): the findings name each parameter, use the truth's σ, and say what to record."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from odomkit.io.robotfile import read_robot
from odomkit.log import OdometryLog
from odomkit.track import dead_reckon_log

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
PERIOD = 0.05


def _write(tmp_path, robot_file, channels, n):
    """The log's channels and its position truth, dead-reckoned with the robot file's robot."""
    robot, _ = read_robot(robot_file)
    t = PERIOD * np.arange(n)
    log = OdometryLog(t, channels)
    poses = dead_reckon_log(log, robot, pose0=np.zeros(3)).poses
    log_path, truth_path = tmp_path / "log.csv", tmp_path / "gt.csv"
    names = list(channels)
    np.savetxt(log_path, np.column_stack([t, *(channels[c] for c in names)]), delimiter=",",
               header=",".join(["t", *names]), comments="")
    np.savetxt(truth_path, np.column_stack((t, poses[:, 0], poses[:, 1])), delimiter=",", header="t,x,y",
               comments="")
    return log_path, truth_path, t


def _check(run_cli, robot_file, log_path, truth_path, sigma):
    code, out, err = run_cli("check", log_path, "--robot", robot_file, "--truth", truth_path,
                             "--truth-sigma", str(sigma), "--json")
    assert err == "", err
    report = json.loads(out)
    found = {f["message"].split(":")[0]: f for f in report["findings"] if f["check"] == "identifiable"}
    return code, report, found


def test_unicycle_straight_run_gives_the_bias_and_not_the_yaw_rate_scale(run_cli, tmp_path):
    """A minute straight at 0.5 m/s: the yaw-rate bias bends the track by −v·t²/2 per rad/s,
    so its standard error is σ/‖v·t_k²/2‖ over the positions once a second; the yaw-rate
    scale has nothing to act on."""
    n, v, sigma = 1201, 0.5, 0.002
    log_path, truth_path, t = _write(tmp_path, EXAMPLES / "unicycle.toml",
                                     {"speed": np.full(n, v), "yaw_rate": np.zeros(n)}, n)
    code, report, found = _check(run_cli, EXAMPLES / "unicycle.toml", log_path, truth_path, sigma)
    assert code == 1 and not report["ok"]
    assert list(found) == ["speed scale c_scale", "yaw-rate bias", "yaw-rate scale"]
    t_k = t[20::20]
    assert found["yaw-rate bias"]["status"] == "ok"
    expected = sigma / np.linalg.norm(0.5 * v * t_k**2)
    assert math.isclose(found["yaw-rate bias"]["value"], expected, rel_tol=1e-9)
    assert found["speed scale c_scale"]["status"] == "ok"
    assert found["yaw-rate scale"]["status"] == "fail" and found["yaw-rate scale"]["value"] is None
    assert "σ = 2 mm per axis" in found["yaw-rate scale"]["message"]
    assert any("turn more, both ways" in step for step in report["next"])


def test_unicycle_turning_both_ways_gives_every_parameter(run_cli, tmp_path):
    n = 2401
    t = PERIOD * np.arange(n)
    yaw_rate = np.where((t % 20) < 10, 0.0, 0.3 * np.sign(np.sin(2 * math.pi * t / 40)))
    log_path, truth_path, _ = _write(tmp_path, EXAMPLES / "unicycle.toml",
                                     {"speed": np.full(n, 0.5), "yaw_rate": yaw_rate}, n)
    code, report, found = _check(run_cli, EXAMPLES / "unicycle.toml", log_path, truth_path, 0.005)
    assert code == 0 and report["ok"], report["findings"]
    assert {k: f["status"] for k, f in found.items()} == {
        "speed scale c_scale": "ok", "yaw-rate bias": "ok", "yaw-rate scale": "ok"}


def test_car_driving_straight_cannot_give_the_wheel_base(run_cli, tmp_path):
    """A straight car run: the wheel base only scales the turning the steering makes, and
    there is none; the steering offset would bend the run, so the run pins it."""
    n = 1201
    log_path, truth_path, _ = _write(tmp_path, EXAMPLES / "car.toml",
                                     {"speed": np.full(n, 5.0), "steer": np.zeros(n)}, n)
    code, report, found = _check(run_cli, EXAMPLES / "car.toml", log_path, truth_path, 0.05)
    assert code == 1
    assert list(found) == ["wheel scale c_scale", "steering offset", "wheel base L"]
    assert found["wheel base L"]["status"] == "fail" and "tight curves" in found["wheel base L"]["advice"]
    assert found["steering offset"]["status"] == "ok" and found["wheel scale c_scale"]["status"] == "ok"
