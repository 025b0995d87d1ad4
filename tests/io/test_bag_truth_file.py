"""Ground truth recorded in a bag of its own (``--truth BAG --truth-topic /mocap``): a motion
capture's or a GPS's bag beside the robot's log. The independent reference is the text
reader on the same poses: a TUM file (quaternions) for a pose topic, a latitude/longitude
file for NavSatFix fixes, each read by :func:`odomkit.io.truth.read_truth`.

The log is the built-in OptiOdom run 01 (its own OptiTrack columns are overridden by
``--truth``); the truth is its OptiTrack poses, every other row, 10 ms late, on their own
clock (epoch seconds, as a real bag has them).
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from odomkit.data import builtin_data_path
from odomkit.io.optiodom import read_run
from odomkit.io.truth import read_truth

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")

from odomkit.io.bag import read_bag_truth  # noqa: E402
from odomkit.workflows.truth import TruthOptions, load_truth  # noqa: E402

RUN = builtin_data_path("230620202042_run-01.csv")
ROBOT = builtin_data_path("optiodom_diff.toml")
LATE = 0.01  # [s] the truth's clock against the log's


def _seconds(ns: int) -> float:
    return ns // 10**9 + (ns % 10**9) / 1e9


@pytest.fixture(scope="module")
def truth_bags(tmp_path_factory, bag_writer, stamp):
    """Truth bags in every format (a PoseStamped topic /mocap, the odometry's own Odometry
    topic /odom as a decoy, and a repeated stamp), and the same poses as a TUM file."""
    d = tmp_path_factory.mktemp("truth_bag")
    log = read_run(RUN)
    gt, t = log.ground_truth[::2], log.t[::2] + LATE
    ns = np.round(t * 1e9).astype(np.int64)
    msgs, rows = [], []
    for k in range(len(t)):
        x, y, th = (float(v) for v in gt[k])
        q = {"z": math.sin(th / 2), "w": math.cos(th / 2)}
        pose = {"position": {"x": x, "y": y}, "orientation": q}
        msgs.append(("/mocap", "geometry_msgs/msg/PoseStamped", int(ns[k]) + 1_000_000,
                     {"header": stamp(int(ns[k]), "world"), "pose": pose}))
        msgs.append(("/odom", "nav_msgs/msg/Odometry", int(ns[k]) + 2_000_000,
                     {"header": stamp(int(ns[k]), "odom"), "pose": {"pose": pose}}))
        rows.append(f"{_seconds(int(ns[k]))!r} {x!r} {y!r} 0 0 0 {q['z']!r} {q['w']!r}\n")
    # The motion capture sent one pose twice: the second is dropped, with a warning.
    k = 5
    msgs.append(("/mocap", "geometry_msgs/msg/PoseStamped", int(ns[k]) + 1_500_000,
                 {"header": stamp(int(ns[k]), "world"),
                  "pose": {"position": {"x": 99.0, "y": 99.0}, "orientation": {"w": 1.0}}}))
    tum = d / "mocap.tum"
    tum.write_text("".join(rows))
    bags = {fmt: bag_writer(d / f"mocap_{fmt}", fmt, msgs) for fmt in ("ros1", "db3", "mcap")}
    return {"dir": d, "tum": tum, "bags": bags, "poses": len(t)}


@pytest.mark.parametrize("fmt", ["ros1", "db3", "mcap"])
def test_a_truth_bag_reads_as_the_tum_file_of_the_same_poses(truth_bags, fmt):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        truth, stated = read_bag_truth(truth_bags["bags"][fmt], "/mocap")
    assert [str(w.message) for w in caught] == [
        f"{truth_bags['bags'][fmt]}: /mocap: 1 fixes repeat an earlier stamp and were dropped "
        "(the first fix at each time is kept)"]
    text = read_truth(truth_bags["tum"])
    assert stated is None and len(truth) == truth_bags["poses"]
    assert truth.t.tolist() == text.t.tolist()  # kept at its own stamps, not resampled
    np.testing.assert_allclose(truth.xy, text.xy, rtol=0, atol=1e-12)
    np.testing.assert_allclose(truth.theta, text.theta, rtol=0, atol=1e-12)


def test_the_truth_topic_must_be_named_where_the_bag_has_several(truth_bags):
    from odomkit.errors import InputError

    with pytest.raises(InputError, match=r"name the topic with --truth-topic; truth topics: "
                                         r"/mocap \(PoseStamped\), /odom \(Odometry\)"):
        read_bag_truth(truth_bags["bags"]["mcap"])
    with pytest.raises(InputError, match=r"no topic /vicon in the bag; truth topics: /mocap"):
        read_bag_truth(truth_bags["bags"]["mcap"], "/vicon")


def _evaluate(run_cli, *args):
    code, out, err = run_cli("evaluate", RUN, "--robot", ROBOT, "--window", "10s", *args, "--json")
    assert code == 0, err
    result = json.loads(out)
    result.pop("warnings", None)
    return result


def test_evaluate_against_a_truth_bag_equals_the_tum_file(run_cli, truth_bags):
    from_bag = _evaluate(run_cli, "--truth", truth_bags["bags"]["ros1"], "--truth-topic", "/mocap")
    from_text = _evaluate(run_cli, "--truth", truth_bags["tum"])
    assert from_bag == from_text
    # And it is that truth, not the log's own OptiTrack columns, that was scored.
    assert from_bag != _evaluate(run_cli)


def test_track_and_calibrate_take_a_truth_bag(run_cli, truth_bags):
    def run(command, *args):
        code, out, err = run_cli(command, RUN, "--robot", ROBOT, *args, "--json")
        assert code == 0, err
        result = json.loads(out)
        result.pop("warnings", None)
        return result

    for command in ("track", "calibrate"):
        bag = run(command, "--truth", truth_bags["bags"]["db3"], "--truth-topic", "mocap")
        text = run(command, "--truth", truth_bags["tum"])
        assert bag == text, command


@pytest.fixture(scope="module")
def gps_only_bag(tmp_path_factory, bag_writer, stamp):
    """A GPS's own bag (NavSatFix only) and the same fixes as a latitude/longitude file."""
    pm = pytest.importorskip("pymap3d", reason="the gps extra (pymap3d) is not installed")
    d = tmp_path_factory.mktemp("gps_bag")
    log = read_run(RUN)
    xy = log.ground_truth[::4, :2] - log.ground_truth[0, :2]
    lat, lon, h = pm.enu2geodetic(xy[:, 0], xy[:, 1], np.zeros(len(xy)), 48.137, 11.575, 520.0)
    ns = np.round((log.t[::4] + LATE) * 1e9).astype(np.int64)
    msgs, rows = [], []
    for k in range(len(ns)):
        msgs.append(("/gps/fix", "sensor_msgs/msg/NavSatFix", int(ns[k]),
                     {"header": stamp(int(ns[k]), "gps"), "status": {"status": 0},
                      "latitude": lat[k], "longitude": lon[k], "altitude": h[k],
                      "position_covariance": [4e-6, 0, 0, 0, 4e-6, 0, 0, 0, 1e-4],
                      "position_covariance_type": 2}))
        rows.append(",".join(repr(float(v)) for v in (_seconds(int(ns[k])), lat[k], lon[k], h[k])) + "\n")
    text = d / "fixes.csv"
    text.write_text("t,lat,lon,alt\n" + "".join(rows))
    return {"bag": bag_writer(d / "gps", "ros1", msgs), "text": text}


def test_a_gps_bag_is_the_truth_its_text_file_gives(run_cli, gps_only_bag):
    # Its only truth topic is taken without --truth-topic; the σ it states is said, not used.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        truth = load_truth(TruthOptions(path=gps_only_bag["bag"]))
    assert any("median horizontal sigma 0.002 m per axis" in str(w.message) for w in caught)
    text = read_truth(gps_only_bag["text"])
    assert truth is not None and truth.theta is None
    assert truth.t.tolist() == text.t.tolist()
    np.testing.assert_allclose(truth.xy, text.xy, rtol=0, atol=1e-9)
    assert (_evaluate(run_cli, "--truth", gps_only_bag["bag"])
            == _evaluate(run_cli, "--truth", gps_only_bag["text"]))


@pytest.mark.parametrize(("args", "said"), [
    (("--truth-topic", "/mocap"), "--truth-topic names a topic of a ROS bag; the --truth file"),
    (("--truth-columns", "t,x,y"), "--truth-columns applies to a text truth file;"),
    (("--truth-record", "point2"), "--truth-record applies to a text truth file;"),
])
def test_options_of_the_other_kind_of_truth_are_refused(run_cli, truth_bags, args, said):
    truth = truth_bags["tum"] if args[0] == "--truth-topic" else truth_bags["bags"]["mcap"]
    code, out, err = run_cli("evaluate", RUN, "--robot", ROBOT, "--window", "10s", "--truth", truth, *args)
    assert code == 2 and out == ""
    assert said in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_the_log_bag_named_again_as_truth_with_its_own_topic_is_refused(run_cli, truth_bags):
    """--truth THE_LOG.bag --truth-topic /odom, where /odom is the log's own topic: the
    odometry would be scored against itself (a Husky bag said "final position error 0.16 m")."""
    bag = truth_bags["bags"]["ros1"]
    robot = Path(__file__).parents[2] / "examples" / "unicycle.toml"
    args = ("track", bag, "--robot", robot, "--topic", "/odom", "--truth", bag)
    code, out, err = run_cli(*args, "--truth-topic", "/odom")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert "is the log's own topic /odom: the odometry would be scored against itself" in err
    code, _, err = run_cli(*args, "--truth-topic", "/mocap")  # another topic of the same bag is truth
    assert code == 0, err


@pytest.mark.parametrize("command", ["fit-noise", "evaluate"])
def test_a_bag_log_without_truth_is_told_of_truth_topic(run_cli, truth_bags, tmp_path, command):
    """fit-noise and evaluate say the same where a log has no truth, naming --truth-topic for
    a bag (fit-noise named --truth FILE and gt_* columns only)."""
    bag = truth_bags["bags"]["ros1"]
    robot = tmp_path / "r.toml"
    robot.write_text((Path(__file__).parents[2] / "examples" / "unicycle.toml").read_text())
    args = (["fit-noise", "--robot", robot, "--log", bag, "--out", tmp_path / "f.toml"]
            if command == "fit-noise" else ["evaluate", bag, "--robot", robot])
    code, out, err = run_cli(*args, "--topic", "/odom", "--window", "10s")
    assert code == 2 and out == "" and "Traceback" not in err
    assert "no truth: give --truth FILE, or --truth-topic TOPIC for a bag's own" in err


@pytest.mark.parametrize("fmt", ["db3", "mcap"])
def test_a_ros2_bag_named_as_its_folder_and_as_its_storage_file_is_one_bag(run_cli, truth_bags, fmt,
                                                                          monkeypatch):
    """A ROS 2 bag is its folder; its storage file inside names the same bag. The log read from
    the folder and its own topic named again as truth through the file scored the odometry
    against itself ("final position error 0.0000 m", a review's finding), and the file opened
    through a link to the folder though no link is needed."""
    import odomkit.io.bag as bag_module

    folder = truth_bags["bags"][fmt]
    [storage] = folder.glob(f"*.{fmt}")

    def no_link(*args, **kwargs):
        raise AssertionError("a ROS 2 bag's storage file needs no link")

    monkeypatch.setattr(bag_module, "_named_as", no_link)
    robot = Path(__file__).parents[2] / "examples" / "unicycle.toml"
    for log, truth in ((folder, storage), (storage, folder)):
        code, _, err = run_cli("track", log, "--robot", robot, "--topic", "/odom", "--truth", truth,
                               "--truth-topic", "/odom")
        assert code == 2 and "the odometry would be scored against itself" in err, err


def test_the_robot_files_clock_for_a_logs_own_truth_survives_resolving_twice():
    """TruthOptions.resolved puts 0 in time_offset for a log's own truth (its gt_* columns are
    on its clock) and keeps the robot file's offset apart, for a GPS topic; resolving again
    must not lose it (a review's finding: the second pass saw the 0 as given)."""
    once = TruthOptions().resolved({"time_offset": 1.42})
    assert once.time_offset == 0.0 and once.file_clock == 1.42
    assert once.resolved({"time_offset": 1.42}).file_clock == 1.42
    given = TruthOptions(time_offset=0.2).resolved({"time_offset": 1.42})
    assert given.time_offset == 0.2 and given.file_clock == 0.0  # a flag wins, for either truth
