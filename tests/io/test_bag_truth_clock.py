"""A bag's truth topic stamped on another clock than its odometry topic (user study: an
F1TENTH car's ``/vesc/odom`` on the car's clock, its motion capture on another, 8328 s
apart, in one bag): the error says both spans, how far apart they start and what mends it,
and ``--truth-time-offset`` moves the truth topic's stamps before they are interpolated at
the log's rows.

The independent truth is the motion capture's poses as written (the exact arc of a
unicycle driving 1 m/s at 0.2 rad/s), interpolated by hand (``np.interp``) at the
odometry's times on the truth's clock moved by the offset."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")

from odomkit.io.bag import read_bag  # noqa: E402
from odomkit.log import clock_text  # noqa: E402
from odomkit.workflows.logs import LogOptions, load_log  # noqa: E402
from odomkit.workflows.truth import TruthOptions, load_truth  # noqa: E402

T0 = 1_675_278_471 * 10**9  # the odometry's clock (the car's)
AHEAD = 1000.25  # the motion capture's clock runs this far ahead [s]
BAG = 1_675_000_000 * 10**9  # the clock the bag received both by
V, W = 1.0, 0.2
ODOM_TIMES = np.arange(100) * 0.1  # 0 .. 9.9 s
MOCAP_TIMES = np.arange(334) * 0.03  # 0 .. 9.99 s: other instants than the odometry's
ROBOT = '[robot]\ntype = "unicycle"\n'


def _stamp(ns: int) -> dict:
    return {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": ""}


def _arc(t: np.ndarray) -> np.ndarray:
    """The unicycle's exact poses (N, 3) at times ``t`` [s] from its start."""
    return np.column_stack([V / W * np.sin(W * t), V / W * (1 - np.cos(W * t)), W * t])


def _messages() -> list:
    out = []
    for t in ODOM_TIMES:
        twist = {"twist": {"linear": {"x": V}, "angular": {"z": W}}}
        out.append(("/odom", "nav_msgs/msg/Odometry", BAG + round(t * 1e9),
                    {"header": _stamp(T0 + round(t * 1e9)), "twist": twist}))
    for t, (x, y, th) in zip(MOCAP_TIMES, _arc(MOCAP_TIMES), strict=True):
        pose = {"position": {"x": x, "y": y}, "orientation": {"z": np.sin(th / 2), "w": np.cos(th / 2)}}
        out.append(("/mocap", "geometry_msgs/msg/PoseStamped", BAG + round(t * 1e9),
                    {"header": _stamp(T0 + round((t + AHEAD) * 1e9)), "pose": pose}))
    return out


@pytest.fixture(scope="module")
def two_clocks(tmp_path_factory, bag_writer):
    return bag_writer(tmp_path_factory.mktemp("clock") / "car", "db3", _messages())


@pytest.fixture
def robot(tmp_path):
    path = tmp_path / "uni.toml"
    path.write_text(ROBOT)
    return path


def _expected(rows: np.ndarray, offset: float) -> np.ndarray:
    """The motion capture's poses interpolated by hand at ``rows`` [s, the log's clock]."""
    own = MOCAP_TIMES + AHEAD - offset  # each fix's time on the log's clock
    poses = _arc(MOCAP_TIMES)
    return np.column_stack([np.interp(rows, own, poses[:, k]) for k in range(3)])


def test_topics_on_two_clocks_say_both_spans_how_far_apart_and_what_mends_it(two_clocks, errors):
    text = errors(lambda: read_bag(two_clocks, ["/odom"], truth_topic="/mocap"))
    start = T0 / 1e9
    assert f"/odom ({clock_text(start)}..{clock_text(start + 9.9)} s)" in text
    assert f"/mocap ({clock_text(start + AHEAD)}..{clock_text(start + AHEAD + 9.99)} s)" in text
    assert "do not overlap in time" in text
    assert "/mocap starts 1000.250 s after /odom" in text
    assert "--bag-time" in text
    assert "--truth-time-offset 1000.250" in text


def test_an_offset_that_falls_short_is_said_with_the_whole_offset_to_give(two_clocks, errors):
    text = errors(lambda: read_bag(two_clocks, ["/odom"], truth_topic="/mocap", truth_time_offset=0.25))
    assert "moved by --truth-time-offset 0.25" in text and "--truth-time-offset 1000.250" in text


def test_truth_time_offset_moves_the_truth_topic_before_it_is_interpolated(two_clocks):
    log = read_bag(two_clocks, ["/odom"], truth_topic="/mocap", truth_time_offset=AHEAD)
    assert log.ground_truth is not None and len(log.t) == 100
    assert np.allclose(log.t - T0 / 1e9, ODOM_TIMES, atol=1e-6)  # epoch seconds: good to 0.24 µs
    rows = ODOM_TIMES  # as stamped, to the nanosecond
    assert np.allclose(log.ground_truth, _expected(rows, AHEAD), atol=1e-9, rtol=0)
    # ... and the fixes are where the robot was: linear interpolation of the arc, within v·w·dt²/8
    assert np.abs(log.ground_truth[:, :2] - _arc(rows)[:, :2]).max() < V * W * 0.03**2 / 8 + 1e-9


def test_bag_time_reads_both_topics_on_the_bags_clock(two_clocks):
    log = read_bag(two_clocks, ["/odom"], receive_time=True, truth_topic="/mocap")
    assert log.ground_truth is not None and len(log.t) == 100


def test_the_offset_moves_the_truth_once_not_again_as_the_logs_own_truth(two_clocks, robot):
    from odomkit.robot import Unicycle

    log = load_log(two_clocks, Unicycle(), LogOptions(topic=("/odom",), truth_topic="/mocap",
                                                       truth_time_offset=AHEAD))
    truth = load_truth(TruthOptions(time_offset=AHEAD), log)
    assert truth is not None and np.array_equal(truth.t, log.t)


def test_cli_same_bag_truth_on_another_clock(two_clocks, robot, run_cli):
    args = ("track", two_clocks, "--robot", robot, "--topic", "/odom", "--truth-topic", "/mocap")
    code, out, err = run_cli(*args)
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("odomkit: error: ") and "--truth-time-offset 1000.250" in err
    code, out, err = run_cli(*args, "--truth-time-offset", str(AHEAD), "--json")
    assert code == 0, err
    found = json.loads(out)
    # Perfect odometry against its own motion capture: the track ends where the truth does
    # (dead reckoning's arcs are exact for constant v, w: only the fixes' interpolation is off).
    assert found["samples"] == 100
    assert found["ground_truth"]["final_position_error"] < 1e-4


def test_gps_fixes_of_the_same_bag_are_moved_once(tmp_path, bag_writer):
    """A NavSatFix truth topic is kept at its own fixes (not interpolated): moved by the offset
    when read, and not again as the log's own truth."""
    pytest.importorskip("pymap3d", reason="the gps extra (pymap3d) is not installed")
    fixes = np.arange(10) * 1.0
    msgs = [m for m in _messages() if m[0] == "/odom"]
    for t in fixes:
        msgs.append(("/fix", "sensor_msgs/msg/NavSatFix", BAG + round(t * 1e9),
                     {"header": _stamp(T0 + round((t + AHEAD) * 1e9)), "status": {"status": 0},
                      "latitude": 48.2 + 1e-5 * t, "longitude": 16.37}))
    path = bag_writer(tmp_path / "gps", "mcap", msgs)
    from odomkit.robot import Unicycle

    log = load_log(path, Unicycle(), LogOptions(topic=("/odom",), truth_topic="/fix",
                                                truth_time_offset=AHEAD))
    truth = load_truth(TruthOptions(time_offset=AHEAD), log)
    assert truth is not None and np.allclose(truth.t - T0 / 1e9, fixes, atol=1e-6)
