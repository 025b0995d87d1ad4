"""A differential drive read from its wheel speeds, ``speed_left``/``speed_right`` [m/s]
(ROS ``JointState`` velocities times the wheel radius, datasets such as TUC's "Labyrinth"
``odom2diff`` records). User study: ``--columns _,t,speed_right,speed_left`` said ``unknown
target 'speed_right'``, and the user integrated v·Δt by hand, choosing forward or backward
himself.

The second method throughout is the same drive written as metre increments by hand: a
speed at row k is held over step k (row k -> k+1, zero-order hold, as every rate in
:mod:`odomkit.log`), so ``dist[k + 1] = speed[k]·(t[k+1] − t[k])``; and, for constant wheel
speeds, the closed-form circle.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.calibrate.check import check_stuck
from odomkit.calibrate.check_channels import check_channels
from odomkit.calibrate.exact import calibrate_exact
from odomkit.errors import InputError
from odomkit.log import OdometryLog, wheel_channels
from odomkit.robot import DiffDrive
from odomkit.track import dead_reckon_log
from odomkit.truth import Truth

B = 0.4


def drive(seed=0, n=1501):
    """Irregular times (20–60 ms steps) and smooth wheel speeds that turn both ways [m/s]."""
    rng = np.random.default_rng(seed)
    t = 12.5 + np.concatenate(([0.0], np.cumsum(rng.uniform(0.02, 0.06, n - 1))))
    v = 0.4 + 0.1 * np.sin(0.3 * t)
    w = 0.8 * np.sin(0.21 * t + seed) + 0.3 * np.sin(0.57 * t)
    return t, v - 0.5 * B * w, v + 0.5 * B * w


def speed_log(t, left, right, gt=None):
    return OdometryLog(t, {"speed_left": left, "speed_right": right}, gt, "speeds.csv")


def dist_log(t, left, right, gt=None):
    """The same drive as metre increments, integrated by hand: step k's travel is row k's
    speed times the step's length, and is logged at row k+1 (increments count up to their row)."""
    dt = np.diff(t)
    channels = {"dist_left": np.r_[0.0, left[:-1] * dt], "dist_right": np.r_[0.0, right[:-1] * dt]}
    return OdometryLog(t, channels, gt, "dists.csv")


def test_wheel_speeds_track_as_the_same_drive_in_metres():
    t, left, right = drive()
    robot = DiffDrive(B, 1e-4, 2e-4, c_left=1.02, c_right=0.97, c_wheel_base=1.01)
    by_speed = dead_reckon_log(speed_log(t, left, right), robot).poses
    by_dist = dead_reckon_log(dist_log(t, left, right), robot).poses
    np.testing.assert_allclose(by_speed, by_dist, rtol=0, atol=1e-12)
    # m_per_tick does not apply (metres per second are metres already) ...
    plain = dead_reckon_log(speed_log(t, left, right), DiffDrive(B, c_left=1.02, c_right=0.97,
                                                                  c_wheel_base=1.01)).poses
    np.testing.assert_allclose(by_speed, plain, rtol=0, atol=1e-12)
    # ... and c_left, c_right do: the nominal robot on speeds scaled by hand.
    nominal = DiffDrive(B, c_wheel_base=1.01)
    scaled = dead_reckon_log(dist_log(t, 1.02 * left, 0.97 * right), nominal).poses
    np.testing.assert_allclose(by_speed, scaled, rtol=0, atol=1e-12)


def test_constant_wheel_speeds_give_the_exact_circle_at_irregular_times():
    t, _, _ = drive(seed=1, n=400)
    vl, vr = 0.3, 0.5
    log = speed_log(t, np.full(t.size, vl), np.full(t.size, vr))
    poses = dead_reckon_log(log, DiffDrive(B)).poses
    theta = (vr - vl) / B * (t - t[0])
    radius = 0.5 * B * (vr + vl) / (vr - vl)
    expected = np.column_stack([radius * np.sin(theta), radius * (1 - np.cos(theta)), theta])
    np.testing.assert_allclose(poses, expected, rtol=0, atol=1e-10)


def test_calibration_from_wheel_speeds_recovers_the_wheels_and_base():
    true = DiffDrive(B, c_left=1.012, c_right=0.985, c_wheel_base=1.04)
    nominal = DiffDrive(B)
    runs = {"speed": [], "dist": []}
    for seed in (2, 3):
        t, left, right = drive(seed, n=1200)
        gt = dead_reckon_log(speed_log(t, left, right), true).poses
        runs["speed"].append(speed_log(t, left, right, gt))
        runs["dist"].append(dist_log(t, left, right, gt))
    by_speed = calibrate_exact(runs["speed"], nominal, "trajectory")
    by_dist = calibrate_exact(runs["dist"], nominal, "trajectory")
    np.testing.assert_allclose(by_speed.values, [1.012, 0.985, 1.04], rtol=0, atol=1e-9)
    np.testing.assert_allclose(by_speed.values, by_dist.values, rtol=0, atol=1e-12)


def _truth(log, robot, rng, sigma=0.005):
    """The drive of ``robot`` as a 50 Hz truth with heading, σ per axis (the log's own rows)."""
    poses = dead_reckon_log(log, robot).poses
    return Truth(log.t, poses[:, :2] + rng.normal(0.0, sigma, (log.t.size, 2)),
                 poses[:, 2] + rng.normal(0.0, sigma, log.t.size))


@pytest.mark.parametrize(("spoil", "words"), [
    (lambda le, r: (r, le), "left and right swapped"),
    (lambda le, r: (-le, r), "the left channel's sign flipped"),
])
def test_check_tells_swapped_or_flipped_wheel_speeds(spoil, words):
    t, left, right = drive(seed=4, n=3000)
    log = speed_log(t, left, right)
    truth = _truth(log, DiffDrive(B * 1.02, c_left=1.01), np.random.default_rng(4))
    (given,) = [f for f in check_channels(log, DiffDrive(B), truth) if f.check == "channels"]
    assert given.status == "ok", given
    bad = speed_log(t, *spoil(left, right))
    (found,) = [f for f in check_channels(bad, DiffDrive(B), truth) if f.check == "channels"]
    assert found.status == "fail" and f"with {words}" in found.message, found


def test_check_finds_a_wheel_speed_stuck_at_zero():
    t = 0.02 * np.arange(500)
    left, right = np.full(t.size, 0.3), np.full(t.size, 0.3)
    left[200:300] = 0.0  # 2 s of a silent left wheel while the right one turns
    (found,) = check_stuck(speed_log(t, left, right), DiffDrive(B))
    assert found.status == "warn" and found.message.startswith("speed_left reads 0 from t = 4 s"), found


@pytest.mark.parametrize(("channels", "words"), [
    ({"ticks_left", "speed_right"}, "two forms (ticks_left, speed_right)"),
    ({"dist_left", "dist_right", "speed_left", "speed_right"}, "two forms"),
    ({"speed_left"}, "speed_left is given without speed_right"),
])
def test_mixed_or_lone_wheel_channels_are_refused(channels, words):
    t = np.arange(5.0)
    log = OdometryLog(t, {c: np.ones(5) for c in channels}, source="mixed.csv")
    with pytest.raises(InputError, match="mixed.csv: ") as err:
        dead_reckon_log(log, DiffDrive(B))
    assert words in str(err.value) and "speed_left/speed_right" in str(err.value)
    with pytest.raises(InputError):
        wheel_channels(channels)


def test_wheel_channels_names_the_one_pair():
    assert wheel_channels(["t", "speed_right", "speed_left"]) == ("speed_left", "speed_right")
    assert wheel_channels(["ticks_left", "ticks_right", "gt_x"]) == ("ticks_left", "ticks_right")
    assert wheel_channels(["speed", "yaw_rate"]) is None


# --- the command line ---------------------------------------------------------------------

ROBOT = """[robot]
type = "diff"
wheel_base = 0.4
wheel_radius = 0.05          # a JointState robot: ticks would be radians; speeds are m/s already
encoder_resolution = "rad"

[noise]
k_left = 0.002
k_right = 0.002
"""


def _files(tmp_path, seed=5, n=1500):
    """A TUC-style tagged file (``odom2diff t v_right v_left v_y wheel_distance``), the same
    drive as a header log ``t,speed_left,speed_right``, as metre increments, and its truth."""
    t, left, right = drive(seed, n)
    true = DiffDrive(B, c_left=1.01, c_right=0.99, c_wheel_base=1.03)
    poses = dead_reckon_log(speed_log(t, left, right), true).poses
    dists = dist_log(t, left, right)
    d_left, d_right = dists.channels["dist_left"].tolist(), dists.channels["dist_right"].tolist()
    t, left, right = t.tolist(), left.tolist(), right.tolist()  # repr: the shortest exact digits
    rng = np.random.default_rng(seed)
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT)
    tagged = tmp_path / "input.txt"
    tagged.write_text("".join(f"odom2diff {a!r} {r!r} {le!r} 0 0.0785 0.0001\n"
                              for a, r, le in zip(t, right, left, strict=True)))
    header = tmp_path / "speeds.csv"
    header.write_text("t,speed_left,speed_right\n" + "".join(
        f"{a!r},{le!r},{r!r}\n" for a, le, r in zip(t, left, right, strict=True)))
    metres = tmp_path / "dists.csv"
    metres.write_text("t,dist_left,dist_right\n" + "".join(
        f"{a!r},{le!r},{r!r}\n" for a, le, r in zip(t, d_left, d_right, strict=True)))
    truth = tmp_path / "gt.csv"
    noisy = poses + rng.normal(0.0, 0.003, poses.shape)
    truth.write_text("t,x,y,theta\n" + "".join(f"{a!r},{x!r},{y!r},{h!r}\n" for a, (x, y, h) in
                                               zip(t, noisy.tolist(), strict=True)))
    return robot, tagged, header, metres, truth


def _json(run_cli, *args):
    code, out, err = run_cli(*args, "--json")
    assert code == 0, err
    return json.loads(out)


def test_cli_reads_wheel_speeds_in_order_and_by_header(run_cli, tmp_path):
    robot, tagged, header, metres, _ = _files(tmp_path)
    in_order = _json(run_cli, "track", tagged, "--robot", robot, "--columns", "_,t,speed_right,speed_left")
    by_header = _json(run_cli, "track", header, "--robot", robot)
    by_metres = _json(run_cli, "track", metres, "--robot", robot)
    for got in (in_order, by_header):
        assert got["pose"] == pytest.approx(by_metres["pose"], abs=1e-12)
        assert got["path_length"] == pytest.approx(by_metres["path_length"], rel=1e-12)
    assert math.hypot(*by_metres["pose"][:2]) > 1.0  # the drive went somewhere


@pytest.mark.parametrize("command", [
    ("calibrate",), ("fit-noise", "--window", "10s", "--kinds", "white"), ("evaluate", "--window", "10s"),
    ("check",),
])
def test_every_command_reads_wheel_speeds_as_metres(run_cli, tmp_path, command):
    robot, _, header, metres, truth = _files(tmp_path)
    name, *flags = command
    outs = []
    for i, log in enumerate((header, metres)):
        out = {"calibrate": ("--out-robot",), "fit-noise": ("--out",)}.get(name, ())
        out = (*out, tmp_path / f"out{i}.toml") if out else ()
        outs.append(_json(run_cli, name, log, "--robot", robot, "--truth", truth, *flags, *out))
    by_speed, by_metres = outs
    _close(by_speed, by_metres, skip={"seconds", "outputs"})


def _close(a, b, skip, where="") -> None:
    """Two JSON documents alike: numbers to 1e-9 relative, text equal but for file names."""
    if isinstance(a, dict):
        assert set(a) == set(b), where
        for k in a:
            if k not in skip:
                _close(a[k], b[k], skip, f"{where}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _close(x, y, skip, f"{where}[{i}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-12, nan_ok=True), where
    elif isinstance(a, str):
        assert a.replace("speeds.csv", "L").replace("speed_", "") == \
            b.replace("dists.csv", "L").replace("dist_", ""), where
    else:
        assert a == b, where


@pytest.mark.parametrize(("how", "words"), [
    (("--columns", "_,t,ticks_right,speed_left"), "--columns: the wheels are given in two forms"),
    (("--columns", "_,t,speed_right"), "--columns: speed_right is given without speed_left"),
])
def test_cli_refuses_mixed_wheel_forms_in_one_line(run_cli, tmp_path, how, words):
    robot, tagged, *_ = _files(tmp_path, n=50)
    code, out, err = run_cli("track", tagged, "--robot", robot, *how)
    lines = err.strip().splitlines()
    assert code == 2 and out == "" and len(lines) == 1, err
    assert lines[0].startswith(f"odomkit: error: {tagged}: {words}"), err


def test_a_text_log_of_wheel_speeds_in_kmh_is_warned_about(tmp_path):
    from odomkit.io.csvlog import read_csv_log

    path = tmp_path / "kmh.csv"
    rows = "".join(f"{i},{90 + i % 3},{0.5 + i % 2}\n" for i in range(50))  # the left one in km/h
    path.write_text("t,speed_left,speed_right\n" + rows)
    with pytest.warns(UserWarning, match=r"\(speed_left\) has a 99th percentile of 92 m/s.*km/h or mph\? "
                                         r"odomkit reads m/s; convert the wheel speeds to m/s"):
        log = read_csv_log(path, None)
    assert sorted(log.channels) == ["speed_left", "speed_right"]
