"""Pitfalls a user study met on real robots' bags (a Clearpath Husky's and a Jackal's), each
reproduced with a synthetic bag: the odometry topic given as its own truth; an IMU mounted on
its side, and a gyro that disagrees grossly with the odometry whose yaw rate it replaces; a
gzip-compressed bag or a bag without its ``.bag`` name; other topics left unnamed."""

from __future__ import annotations

import gzip
import re
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")

from odomkit.io.bag import is_bag, read_bag  # noqa: E402
from odomkit.workflows.logs import detect_format  # noqa: E402

T0 = 1_432_235_497 * 10**9
ODOM, IMU, FIX = "nav_msgs/msg/Odometry", "sensor_msgs/msg/Imu", "sensor_msgs/msg/NavSatFix"
NO_ORIENTATION = [-1.0] + [0.0] * 8
UNICYCLE = """[robot]
type = "unicycle"
c_scale = 1.0
yaw_rate_bias = 0.0
yaw_rate_scale = 1.0
"""


def no_warnings(call):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return call()


def odom(stamp, times, speed, rate, topic="/odom"):
    """Odometry messages at ``times`` [s] from T0 with twist ``speed`` [m/s], ``rate`` [rad/s]
    (scalars or arrays), the pose the integrated unicycle (so that it can serve as truth)."""
    speed, rate = np.broadcast_to(speed, times.shape), np.broadcast_to(rate, times.shape)
    out, x, th = [], 0.0, 0.0
    for k, t in enumerate(times):
        ns = T0 + round(t * 1e9)
        if k:
            dt = t - times[k - 1]
            x, th = x + speed[k] * dt, th + rate[k] * dt
        pose = {"pose": {"position": {"x": x}, "orientation": {"z": np.sin(th / 2), "w": np.cos(th / 2)}}}
        twist = {"twist": {"linear": {"x": float(speed[k])}, "angular": {"z": float(rate[k])}}}
        out.append((topic, ODOM, ns, {"header": stamp(ns), "pose": pose, "twist": twist}))
    return out


def imu(stamp, times, rate, accel=(0.0, 0.0, 9.81), topic="/imu", axis="z", others=0.0):
    """Imu messages (no orientation) at ``times`` [s] from T0: gyro ``rate`` [rad/s] about
    ``axis`` (``others`` about the other two), linear acceleration ``accel`` [m/s²] (x, y, z)."""
    rate = np.broadcast_to(rate, times.shape)
    a = dict(zip("xyz", map(float, accel), strict=True))
    return [(topic, IMU, T0 + round(t * 1e9),
             {"header": stamp(T0 + round(t * 1e9)),
              "angular_velocity": {k: float(w) if k == axis else others for k in "xyz"},
              "linear_acceleration": a, "orientation_covariance": NO_ORIENTATION})
            for t, w in zip(times, rate, strict=True)]


# --- 1. the odometry topic as its own truth ------------------------------------------------

def test_a_truth_topic_that_is_one_of_the_log_topics_is_refused(tmp_path, bag_writer, stamp, run_cli, errors):
    times = np.arange(0.0, 5.0, 0.1)
    path = bag_writer(tmp_path / "self", "ros1", odom(stamp, times, 1.0, 0.2))
    for wanted, truth in ((["/odom"], "/odom"), (["odom"], "odom"), (["/odom"], "odom")):
        text = errors(lambda w=wanted, t=truth: read_bag(path, w, truth_topic=t))
        assert "/odom" in text and "against itself" in text
    # No --topic: the bag's only readable topic is the truth topic; say so, not "needs --topic".
    text = errors(lambda: read_bag(path, truth_topic="/odom"))
    assert "/odom" in text and "--truth-topic" in text and "against itself" in text
    robot = tmp_path / "husky.toml"
    robot.write_text(UNICYCLE)
    code, out, err = run_cli("track", path, "--robot", robot, "--topic", "/odom", "--truth-topic", "/odom")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("odomkit: error: ") and "/odom" in err


def test_a_truth_topic_of_its_own_is_still_read(tmp_path, bag_writer, stamp):
    times = np.arange(0.0, 5.0, 0.1)
    msgs = odom(stamp, times, 1.0, 0.2) + odom(stamp, times, 1.0, 0.2, topic="/mocap")
    path = bag_writer(tmp_path / "two", "mcap", msgs)
    for wanted in (["/odom"], []):  # named, or the one readable topic left once /mocap is truth
        log = read_bag(path, wanted, truth_topic="/mocap")
        assert log.meta["topics"] == ["/odom"] and log.ground_truth is not None


# --- 2a. an IMU not mounted level ----------------------------------------------------------

@pytest.mark.parametrize("accel, axis", [((-0.22, 9.79, 0.08), "+y"), ((-9.8, 0.3, 1.0), "-x")])
def test_an_imu_with_gravity_off_its_z_axis_warns(tmp_path, bag_writer, stamp, accel, axis):
    times = np.arange(0.0, 2.0, 0.02)
    path = bag_writer(tmp_path / "side", "ros1", imu(stamp, times, 0.1, accel))
    with pytest.warns(UserWarning, match=rf"/imu: gravity is along its {re.escape(axis)} axis.*"
                                         r"angular_velocity.z is not the robot's yaw rate.*"
                                         rf"--imu-up {re.escape(axis)} reads the rate"):
        read_bag(path, ["/imu"])


@pytest.mark.parametrize("up", ["+y", "-x"])
def test_imu_up_reads_the_yaw_rate_about_the_axis_that_points_up(tmp_path, bag_writer, stamp, run_cli, up):
    """An IMU on its side (gravity along ``up``) whose rate about that axis is the yaw rate
    0.3 + 0.1 t and about the others a wobble: --imu-up reads the first, sign included, and
    the IMU is level as read, so nothing warns (a Husky bag: 9.5 m from its GPS at the end,
    368 m reading angular_velocity.z)."""
    times = np.arange(0.0, 4.0, 0.02)
    sign, axis = (1.0 if up[0] == "+" else -1.0), up[1]
    gravity = tuple(sign * 9.8 if k == axis else 0.1 for k in "xyz")
    true = 0.3 + 0.1 * times
    path = bag_writer(tmp_path / "side_up", "mcap", imu(stamp, times, sign * true, gravity, axis=axis,
                                                        others=0.05))
    log = no_warnings(lambda: read_bag(path, ["/imu"], imu_up=up))
    # A rate is resampled at the rows as its mean over each step (trapezoid): exact for a line.
    np.testing.assert_allclose(log.channels["yaw_rate"][:-1], 0.3 + 0.1 * (times[:-1] + 0.01), atol=1e-12)
    robot = tmp_path / "g.toml"
    robot.write_text('[robot]\ntype = "unicycle"\n')
    code, _, err = run_cli("track", path, "--robot", robot, "--topic", "/imu", "--imu-up", "q")
    assert code == 2 and "--imu-up must be one of +x, -x, +y, -y, +z, -z" in err and "'q'" in err


@pytest.mark.parametrize("accel", [(0.0, 0.0, 9.81), (0.0, 0.0, 0.0), (0.5, -0.4, 9.7), (0.0, 0.0, -9.81)])
def test_a_level_imu_or_one_without_acceleration_does_not_warn(tmp_path, bag_writer, stamp, accel):
    """Level (a little tilt too), not filled in (zeros), or a driver that reports gravity as
    −9.81 on z (a sign convention some drivers use): all read as before, without a warning."""
    times = np.arange(0.0, 2.0, 0.02)
    path = bag_writer(tmp_path / "level", "mcap", imu(stamp, times, 0.1, accel))
    log = no_warnings(lambda: read_bag(path, ["/imu"]))
    assert np.allclose(log.channels["yaw_rate"], 0.1)


# --- 2b. a gyro that grossly disagrees with the odometry's yaw rate it replaces ------------

def test_a_replaced_yaw_rate_that_disagrees_by_more_than_a_factor_two_warns(tmp_path, bag_writer, stamp):
    # /odom turns at 1 rad/s for 10 s, the IMU at 0.2 rad/s: 10 rad against 2 rad (by hand).
    rows, gyro = np.arange(0.0, 10.001, 0.1), np.arange(0.0, 10.001, 0.02)
    msgs = odom(stamp, rows, 1.0, 1.0) + imu(stamp, gyro, 0.2)
    path = bag_writer(tmp_path / "skew", "db3", msgs)
    with pytest.warns(UserWarning) as seen:
        log = read_bag(path, ["/odom", "/imu"])
    text = " ".join(str(w.message) for w in seen)
    assert "yaw_rate" in text and "/odom" in text and "/imu" in text
    assert "/odom turns 10 rad" in text and "/imu 2 rad" in text
    assert np.allclose(log.channels["yaw_rate"], 0.2)  # the documented rule still holds: /imu's is used
    # Named the other way round the odometry's rate is used, and the same pair warns alike.
    with pytest.warns(UserWarning, match=r"/imu turns 2 rad.*/odom 10 rad"):
        read_bag(path, ["/imu", "/odom"])


def test_a_gyro_turning_the_other_way_warns(tmp_path, bag_writer, stamp, run_cli):
    """A gyro mounted upside down: the same turning, the opposite sign (Σ|Δθ| alike, so only
    the signs tell). Turns of ±0.5 rad/s for 20 s, switching every 2 s: the odometry's
    twist turns 10 rad in all; the gyro's samples, averaged over each 0.02 s step, lose
    0.01 rad at each sample that closes a 2 s interval (0, 2, ..., 18 s; the one at 0 s
    closes one before the start): 10 − 10·0.01 = 9.9 rad."""
    rows, gyro = np.arange(0.0, 20.001, 0.1), np.arange(0.0, 20.001, 0.02)

    def rate(t):  # a switch at 2 s belongs to the 2 s before it: an Odometry twist ends its step
        return np.where(np.floor((t - 1e-6) / 2.0) % 2 == 0, 0.5, -0.5)

    path = bag_writer(tmp_path / "flip", "ros1", odom(stamp, rows, 1.0, rate(rows))
                      + imu(stamp, gyro, -rate(gyro)))
    with pytest.warns(UserWarning, match=r"yaw_rate from /imu replaces /odom's.*opposite ways.*"
                                         r"/odom turns 10 rad.*/imu 9.9 rad"):
        read_bag(path, ["/odom", "/imu"])
    robot = tmp_path / "gyro.toml"
    robot.write_text(UNICYCLE)
    code, _, err = run_cli("track", path, "--robot", robot, "--topic", "/odom", "--topic", "/imu")
    assert code == 0 and "odomkit: warning: " in err and "opposite ways" in err


def test_an_honest_gyro_and_odometry_pair_does_not_warn(tmp_path, bag_writer, stamp):
    """A skid-steer base whose odometry overstates its turning by 20 %, a gyro with a bias of
    0.005 rad/s and white noise of 0.02 rad/s (a cheap MEMS gyro), 100 s of turning to and
    fro and then 100 s straight ahead: a factor 1.2 and a bias, never a factor 2."""
    rng = np.random.default_rng(1)
    rows, gyro = np.arange(0.0, 200.0, 0.1), np.arange(0.0, 200.0, 0.01)

    def true_rate(t):
        return np.where(t < 100.0, 0.5 * np.sin(2 * np.pi * t / 20.0), 0.0)

    msgs = odom(stamp, rows, 1.0, 1.2 * true_rate(rows))
    msgs += imu(stamp, gyro, true_rate(gyro) + 0.005 + 0.02 * rng.standard_normal(gyro.size))
    path = bag_writer(tmp_path / "honest", "ros1", msgs)
    log = no_warnings(lambda: read_bag(path, ["/odom", "/imu"]))
    assert log.channels["yaw_rate"].size == rows.size
    # Straight ahead only (the odometry's rate exactly 0): the gyro's bias and noise alone.
    straight = bag_writer(tmp_path / "straight", "ros1",
                          odom(stamp, rows, 1.0, 0.0)
                          + imu(stamp, gyro, 0.005 + 0.02 * rng.standard_normal(gyro.size)))
    no_warnings(lambda: read_bag(straight, ["/odom", "/imu"]))


# --- 3. bag names: gzip-compressed, no suffix, upper case ----------------------------------

def test_a_gzip_compressed_bag_says_to_decompress_it(tmp_path, bag_writer, stamp, run_cli, errors):
    bag = bag_writer(tmp_path / "t2", "ros1", odom(stamp, np.arange(0.0, 1.0, 0.1), 1.0, 0.0))
    robot = tmp_path / "husky.toml"
    robot.write_text(UNICYCLE)
    named = tmp_path / "t2.bag.gz"
    named.write_bytes(gzip.compress(bag.read_bytes()))
    unnamed = tmp_path / "run.gz"  # the bytes say it: gzip holding "#ROSBAG V2.0"
    shutil.copy(named, unnamed)
    for path in (named, unnamed):
        assert is_bag(path) and detect_format(path) == "bag"
        code, out, err = run_cli("track", path, "--robot", robot, "--topic", "/odom")
        assert code == 2 and out == "" and err.count("\n") == 1, err
        assert "gzip-compressed ROS bag" in err and "decompress" in err and "csv" not in err
        assert "gzip-compressed ROS bag" in errors(lambda p=path: read_bag(p, ["/odom"]))
    # A gzip-compressed text log is still a text log.
    log = tmp_path / "log.csv.gz"
    log.write_bytes(gzip.compress(b"t,speed,yaw_rate\n0,1,0\n1,1,0\n"))
    assert not is_bag(log) and detect_format(log) == "csv"


@pytest.mark.parametrize("name", ["run", "RUN.BAG", "run.dat"])
def test_a_ros1_bag_is_known_by_its_first_line_whatever_its_name(tmp_path, bag_writer, stamp, run_cli, name):
    times = np.arange(0.0, 2.0, 0.1)
    bag = bag_writer(tmp_path / "orig", "ros1", odom(stamp, times, 1.0, 0.3))
    assert bag.read_bytes().startswith(b"#ROSBAG V2.0\n")
    renamed = tmp_path / "other" / name
    renamed.parent.mkdir()
    shutil.copy(bag, renamed)
    assert is_bag(renamed) and detect_format(renamed) == "bag"
    expected = read_bag(bag, ["/odom"])
    got = read_bag(renamed, ["/odom"])
    assert got.t.tolist() == expected.t.tolist()
    assert got.channels["yaw_rate"].tolist() == expected.channels["yaw_rate"].tolist()
    robot = tmp_path / "husky.toml"
    robot.write_text(UNICYCLE)
    for extra in ((), ("--format", "bag")):
        code, out, err = run_cli("track", renamed, "--robot", robot, "--topic", "/odom", *extra)
        assert code == 0 and err == "", err
        assert f"{times.size} poses" in out


def test_an_mcap_file_is_known_by_its_magic_whatever_its_name(tmp_path, bag_writer, stamp):
    times = np.arange(0.0, 2.0, 0.1)
    folder = bag_writer(tmp_path / "ros2", "mcap", odom(stamp, times, 1.0, 0.3))
    (storage,) = folder.glob("*.mcap")
    assert storage.read_bytes().startswith(b"\x89MCAP0\r\n")
    renamed = tmp_path / "run.MCAP.bin"
    shutil.copy(storage, renamed)
    assert is_bag(renamed) and detect_format(renamed) == "bag"
    got = read_bag(renamed, ["/odom"])
    assert got.channels["yaw_rate"].tolist() == read_bag(folder, ["/odom"]).channels["yaw_rate"].tolist()


def test_a_text_file_is_not_taken_for_a_bag(tmp_path):
    text = tmp_path / "log"
    text.write_text("t,speed,yaw_rate\n0,1,0\n")
    assert not is_bag(text) and detect_format(text) == "csv"
    assert not is_bag(tmp_path / "missing") and is_bag(Path("missing.bag"))


# --- 4. the other topics named --------------------------------------------------------------

def test_a_missing_topic_names_the_other_topics_with_their_types(tmp_path, bag_writer, stamp, errors):
    times = np.arange(0.0, 1.0, 0.1)
    msgs = odom(stamp, times, 1.0, 0.0)
    msgs.append(("/fix", FIX, T0, {"header": stamp(T0)}))
    msgs += [(f"/scan{k:02d}", "sensor_msgs/msg/LaserScan", T0 + k, {"header": stamp(T0 + k)})
             for k in range(11)]
    path = bag_writer(tmp_path / "many", "ros1", msgs)
    text = errors(lambda: read_bag(path, ["/husky/odom"]))
    assert "topics odomkit reads: /odom (Odometry)" in text
    assert "other topics: /fix (sensor_msgs/msg/NavSatFix), /scan00 (sensor_msgs/msg/LaserScan)" in text
    assert "/scan08 (sensor_msgs/msg/LaserScan) and 2 more" in text and "/scan09" not in text


def test_a_replaced_wheel_channel_is_said_in_metres_not_radians(tmp_path, bag_writer, stamp):
    """Only the yaw rate and the heading turn: a speed given by two topics that disagree is
    said in metres travelled (a review found every other channel said in "rad" and "turns")."""
    t0 = 1_700_000_000 * 10**9
    msgs = []
    for k in range(400):
        ns = t0 + k * 50_000_000
        msgs.append(("/odom", "nav_msgs/msg/Odometry", ns, {"header": stamp(ns),
                                                             "twist": {"twist": {"linear": {"x": 1.0}}}}))
        msgs.append(("/cmd", "geometry_msgs/msg/TwistStamped", ns + 1, {"header": stamp(ns + 1),
                                                                          "twist": {"linear": {"x": 3.0}}}))
    path = bag_writer(tmp_path / "two_speeds", "mcap", msgs)
    with pytest.warns(UserWarning, match=r"speed from /cmd replaces /odom's .* by a factor 3\.0: .* /odom "
                                         r"travels 19\.9 m in all"):
        read_bag(path, ["/odom", "/cmd"])


def test_a_bag_whose_header_stamps_run_on_the_robots_clock_is_told_of_bag_time(tmp_path, bag_writer,
                                                                              run_cli):
    """A Pioneer's odometry stamped by its own clock, 9.5 days behind the bag's, against a
    motion capture written out on the bag's clock (user study): the clocks do not overlap,
    and the line named --truth-time-unit and --truth-time-offset but not --bag-time, which
    mends it."""
    times = np.arange(0.0, 30.0, 0.1)
    behind = int(9.5 * 86400) * 10**9

    def robot_clock(ns, frame_id=""):
        ns -= behind
        return {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": frame_id}

    bag = bag_writer(tmp_path / "pioneer", "ros1", odom(robot_clock, times, 0.3, 0.1))
    truth = tmp_path / "mocap.csv"
    th = 0.1 * times
    xy = np.column_stack([np.cumsum(np.r_[0.0, 0.3 * 0.1 * np.cos(th[:-1])]),
                          np.cumsum(np.r_[0.0, 0.3 * 0.1 * np.sin(th[:-1])])])
    np.savetxt(truth, np.column_stack([T0 / 1e9 + times, xy]), delimiter=",", header="t,x,y", comments="",
               fmt="%.9f")
    robot = tmp_path / "u.toml"
    robot.write_text(UNICYCLE)
    code, out, err = run_cli("evaluate", bag, "--robot", robot, "--topic", "/odom", "--truth", truth)
    assert code == 2 and err.count("\n") == 1 and "do not overlap" in err and "--bag-time" in err
    code, out, err = run_cli("evaluate", bag, "--robot", robot, "--topic", "/odom", "--bag-time",
                             "--truth", truth)
    assert code == 0, err
