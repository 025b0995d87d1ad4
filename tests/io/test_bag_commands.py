"""Commands on ROS bags (issue 12 items 4, 5): the real OptiOdom runs (encoder ticks with
OptiTrack truth) recorded as ``sensor_msgs/JointState`` wheel angles plus a
``geometry_msgs/PoseStamped`` truth topic must give what the same runs give as text logs
(the independent reference: the text reader and the robot file in ticks), and a track
written as a bag must read back as the CSV track. Bad input is one line, exit 2."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.data import builtin_data_path
from odomkit.io.optiodom import read_run
from odomkit.io.trackio import read_track_csv

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")

from odomkit.io.bag import read_bag_odometry  # noqa: E402

ROBOT = builtin_data_path("optiodom_diff.toml")
RUNS = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in range(1, 7)]
T0 = 1_687_000_000 * 10**9  # the runs' times, moved to an epoch time [ns]


def run_bag(bag_writer, stamp, wheel_angles, run, path, fmt="mcap"):
    log = read_run(run)
    left, right = wheel_angles(log)
    msgs = []
    for k, t in enumerate(log.t):
        ns = T0 + round(t * 1e9)
        x, y, th = log.ground_truth[k]
        msgs.append(("/joint_states", "sensor_msgs/msg/JointState", ns + 2_000_000,
                     {"header": stamp(ns), "name": ["wheel_left_joint", "wheel_right_joint"],
                      "position": [left[k], right[k]]}))
        msgs.append(("/mocap", "geometry_msgs/msg/PoseStamped", ns + 1_000_000,
                     {"header": stamp(ns, "world"), "pose": {"position": {"x": x, "y": y},
                                                             "orientation": {"z": math.sin(th / 2),
                                                                             "w": math.cos(th / 2)}}}))
    return bag_writer(path, fmt, msgs)


@pytest.fixture(scope="module")
def bags(tmp_path_factory, bag_writer, stamp, wheel_angles, rad_robot):
    d = tmp_path_factory.mktemp("bags")
    (d / "rad.toml").write_text(rad_robot)
    (d / "gyro.toml").write_text('[robot]\ntype = "gyro"\n')
    made = {fmt: run_bag(bag_writer, stamp, wheel_angles, RUNS[0], d / f"run1_{fmt}", fmt)
            for fmt in ("ros1", "db3", "mcap")}
    made["runs"] = [made["mcap"]] + [run_bag(bag_writer, stamp, wheel_angles, r, d / f"run{i + 2}")
                                     for i, r in enumerate(RUNS[1:])]
    made["dir"] = d
    return made


def run_json(run_cli, *args):
    code, out, err = run_cli(*args, "--json")
    assert code == 0, err
    return json.loads(out)


def close(a, b, rel=1e-9, abs_=1e-12, skip=("outputs", "warnings", "duration", "source", "sources", "files")):
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a.keys() - set(skip):
            close(a[key], b[key], rel, abs_, skip)
    elif isinstance(a, list):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            close(x, y, rel, abs_, skip)
    elif isinstance(a, float):
        assert a == pytest.approx(b, rel=rel, abs=abs_)
    elif not isinstance(a, str):
        assert a == b


@pytest.mark.parametrize("fmt", ["ros1", "db3", "mcap"])
def test_track_on_a_joint_state_bag_equals_the_text_log(run_cli, bags, fmt):
    bag = run_json(run_cli, "track", bags[fmt], "--robot", bags["dir"] / "rad.toml",
                   "--topic", "/joint_states", "--joints", "wheel_left_joint,wheel_right_joint")
    text = run_json(run_cli, "track", RUNS[0], "--robot", ROBOT, "--no-covariance")
    text_cov = run_json(run_cli, "track", RUNS[0], "--robot", ROBOT)
    keys = ("pose", "path_length", "samples")
    close({k: bag[k] for k in keys}, {k: text[k] for k in keys})
    close(bag["cov"], text_cov["cov"])
    assert bag["duration"] == pytest.approx(text["duration"], abs=1e-6)  # epoch seconds: 0.24 µs steps


def test_a_track_written_as_a_bag_reads_back_as_the_csv_track(run_cli, bags, tmp_path):
    for fmt, name in (("ros1", "t.bag"), ("db3", "t_db3"), ("mcap", "t_mcap")):
        out, bag = tmp_path / f"{fmt}.csv", tmp_path / name
        run_json(run_cli, "track", RUNS[0], "--robot", ROBOT, "--out", out, "--bag-out", bag,
                 "--bag-format", fmt, "--frame-id", "map", "--child-frame-id", "base_footprint")
        csv, odo = read_track_csv(out), read_bag_odometry(bag)
        assert np.abs(odo.t - csv.t).max() <= 0.5e-9  # stamps hold nanoseconds
        assert odo.poses[:, :2].tolist() == csv.poses[:, :2].tolist()
        assert np.abs(odo.poses[:, 2] - csv.poses[:, 2]).max() < 1e-14
        upper = np.triu_indices(3)
        assert odo.cov[:, upper[0], upper[1]].tolist() == csv.cov[:, upper[0], upper[1]].tolist()
        assert (odo.frame_id, odo.child_frame_id) == ("map", "base_footprint")
    # The twists are the steps: read back as speed and yaw rate (a gyro robot), they give
    # the same track again.
    again = run_json(run_cli, "track", tmp_path / "t_mcap", "--robot", bags["dir"] / "gyro.toml")
    final = read_track_csv(tmp_path / "mcap.csv").poses[-1]
    assert again["pose"][:2] == pytest.approx(final[:2].tolist(), abs=1e-12)
    assert again["theta_unwrapped"] == pytest.approx(final[2], abs=1e-12)


# Windows of 29.98 s: the runs' rows fall every 50 ms, and a 30 s boundary would land on a
# row, where the text log's times (29.999999999999996) and the bag's (30 s to the nanosecond)
# would end the window one row apart.


def test_evaluate_on_a_bag_with_a_truth_topic_equals_the_text_log(run_cli, bags):
    bag = run_json(run_cli, "evaluate", bags["mcap"], "--robot", bags["dir"] / "rad.toml",
                   "--truth-topic", "/mocap", "--window", "29.98s")
    text = run_json(run_cli, "evaluate", RUNS[0], "--robot", ROBOT, "--window", "29.98s")
    # The window ends' times are each log's own: the bag's epoch seconds, the text's from 0.
    for got, want in zip(bag["per_log"][0]["window_ends"], text["per_log"][0]["window_ends"], strict=True):
        assert got["end"] - got["start"] == pytest.approx(want["end"] - want["start"], abs=1e-6)
    close(bag, text, rel=1e-8, abs_=1e-10,
          skip=("outputs", "warnings", "duration", "source", "sources", "files", "start", "end",
                "start_time"))
    if bag["start_time"] is not None:  # the start of the scored run, on each log's own clock
        assert bag["start_time"] - bag["per_log"][0]["window_ends"][0]["start"] == pytest.approx(
            text["start_time"] - text["per_log"][0]["window_ends"][0]["start"], abs=1e-6)


def test_calibrate_on_bags_equals_the_text_logs(run_cli, bags):
    bag = run_json(run_cli, "calibrate", *bags["runs"], "--robot", bags["dir"] / "rad.toml",
                   "--truth-topic", "mocap")
    text = run_json(run_cli, "calibrate", *RUNS, "--robot", ROBOT)
    for key in ("c_left", "c_right", "c_wheel_base"):
        assert bag["robot"][key] == pytest.approx(text["robot"][key], rel=1e-9), key


def test_fit_noise_on_bags_equals_the_text_logs(run_cli, bags, tmp_path):
    logs = [a for p in bags["runs"][:3] for a in ("--log", p)]
    bag = run_json(run_cli, "fit-noise", "--robot", bags["dir"] / "rad.toml", *logs,
                   "--truth-topic", "/mocap", "--out", tmp_path / "a.toml", "--window", "29.98s")
    text = run_json(run_cli, "fit-noise", "--robot", ROBOT, *[a for p in RUNS[:3] for a in ("--log", p)],
                    "--out", tmp_path / "b.toml", "--window", "29.98s")
    # Equal to the optimiser's precision (it stops at a relative change of 1e-6 in scaled
    # units; the bag's nanosecond stamps move the inputs in the last digits): with the
    # truth's own noise fitted too, 8 parameters on 9 windows, that is ~1e-7, not 1e-12.
    close(bag["parameters"], text["parameters"], rel=1e-5, abs_=1e-12)
    assert bag["log_likelihood"] == pytest.approx(text["log_likelihood"], rel=1e-9)
    assert bag["windows"] == text["windows"] == 9


def one_line_error(run_cli, *args):
    code, out, err = run_cli(*args)
    assert code == 2 and out == ""
    assert err.startswith("odomkit: error: ") and err.count("\n") == 1 and "Traceback" not in err
    return err


def test_bad_bags_are_one_line_exit_2(run_cli, bags, bag_writer, stamp, tmp_path):
    robot = bags["dir"] / "rad.toml"
    err = one_line_error(run_cli, "track", bags["mcap"], "--robot", robot, "--topic", "/odom")
    assert ("no topic /odom in the bag; topics odomkit reads: /joint_states (JointState); other topics: "
            "/mocap (geometry_msgs/msg/PoseStamped)" in err)
    err = one_line_error(run_cli, "track", bags["ros1"], "--robot", robot, "--joints", "left,right")
    assert "no joint named 'left'; its joints are wheel_left_joint, wheel_right_joint" in err
    back = [("/js", "sensor_msgs/msg/JointState", T0 + k * 10**8,
             {"header": stamp(T0 + (1 - k) * 10**8), "name": ["l", "r"], "position": [k, k]})
            for k in range(2)]
    err = one_line_error(run_cli, "track", bag_writer(tmp_path / "back", "db3", back), "--robot", robot)
    assert "header stamps go backwards at message 2" in err
    err = one_line_error(run_cli, "track", bags["mcap"], "--robot", robot, "--truth-topic", "/joint_states")
    assert ("odomkit reads Odometry, PoseStamped, PoseWithCovarianceStamped, NavSatFix, TransformStamped, "
            "TFMessage, Pose2D (truth topics: /mocap" in err)
    err = one_line_error(run_cli, "track", bags["mcap"], "--robot", robot, "--joints", "a,b,c")
    assert "--joints takes LEFT,RIGHT or one joint name, got 'a,b,c'" in err
    err = one_line_error(run_cli, "track", RUNS[0], "--robot", ROBOT, "--topic", "/odom")
    assert "--topic does not apply to a optiodom log" in err
    err = one_line_error(run_cli, "track", RUNS[0], "--robot", ROBOT, "--bag-out", tmp_path / "a.bag",
                         "--bag-format", "mcap")
    assert "a .bag path is a ROS 1 bag" in err
    err = one_line_error(run_cli, "track", bags["mcap"], "--robot", robot, "--bag-out", bags["mcap"],
                         "--force")
    assert "would replace an input" in err


def test_check_reads_a_ros2_bag_folder(run_cli, bags):
    """A ROS 2 bag is a folder: check refused it as "no such file" before (it tested for a
    file itself); it reads it as every command does, its mocap topic the truth."""
    code, out, err = run_cli("check", bags["mcap"], "--robot", bags["dir"] / "rad.toml", "--topic",
                             "/joint_states", "--joints", "wheel_left_joint,wheel_right_joint",
                             "--truth-topic", "/mocap", "--json")
    assert code in (0, 1), err
    report = json.loads(out)
    assert any(f["check"] == "travel_ratio" for f in report["findings"])
