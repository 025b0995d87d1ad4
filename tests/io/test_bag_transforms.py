"""Ground truth from transforms: a ``geometry_msgs/TransformStamped`` topic (vicon_bridge's
``/vicon/<name>/<name>``) and the ``/tf`` transforms (``tf2_msgs/TFMessage``) of one frame pair
(``--truth-frame PARENT:CHILD``). The independent reference is a ``geometry_msgs/PoseStamped``
topic of the same poses at the same stamps (read by the reader's pose path, itself checked
against a TUM file in ``test_bag_truth_file.py``), and the poses as written, by hand."""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from odomkit.angles import unwrap_angle
from odomkit.data import builtin_data_path
from odomkit.io.optiodom import read_run

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")

from odomkit.io.bag import read_bag, read_bag_truth  # noqa: E402

FORMATS = ("ros1", "db3", "mcap")
T0 = 1_700_000_000 * 10**9
POSE, TRANSFORM, TF = ("geometry_msgs/msg/PoseStamped", "geometry_msgs/msg/TransformStamped",
                       "tf2_msgs/msg/TFMessage")
ODOM = "nav_msgs/msg/Odometry"
VICON = "/vicon/robot/robot"


def _quaternion(yaw):
    return {"z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}


def _transform(stamp, ns, parent, child, x, y, yaw):
    return {"header": stamp(ns, parent), "child_frame_id": child,
            "transform": {"translation": {"x": x, "y": y, "z": 0.3}, "rotation": _quaternion(yaw)}}


def poses(n=60):
    """A drive whose yaw passes ±π (the truth's heading is unwrapped): times [ns] from T0 and
    x, y [m], yaw [rad]."""
    k = np.arange(n)
    ns = T0 + k * 20_000_000 + (k % 3) * 7
    yaw = -2.5 - 0.05 * k  # from -2.5 rad through -π
    return ns, 0.01 * k * np.cos(0.1 * k), 0.02 * k, yaw


def truth_messages(stamp, ros1, extra_pairs=True, odom=True):
    """PoseStamped /mocap, TransformStamped /vicon/robot/robot and /tf (world→base_link, and
    with ``extra_pairs`` odom→base_link and base_link→laser in the same messages) of the same
    poses, each written at the same bag time (2 ms after the stamp); an Odometry log /odom."""
    ns, x, y, yaw = poses()
    slash = "/" if ros1 else ""  # ROS 1's tf wrote frame ids with a leading '/'
    msgs = []
    for k in range(ns.size):
        t, bag = int(ns[k]), int(ns[k]) + 2_000_000
        pose = {"position": {"x": float(x[k]), "y": float(y[k])}, "orientation": _quaternion(yaw[k])}
        msgs.append(("/mocap", POSE, bag, {"header": stamp(t, "world"), "pose": pose}))
        msgs.append((VICON, TRANSFORM, bag, _transform(stamp, t, "world", "vicon/robot/robot", float(x[k]),
                                                       float(y[k]), float(yaw[k]))))
        transforms = [_transform(stamp, t, f"{slash}world", f"{slash}base_link", float(x[k]), float(y[k]),
                                 float(yaw[k]))]
        if extra_pairs:
            transforms.insert(0, _transform(stamp, t - 1000, f"{slash}odom", f"{slash}base_link", 5.0, 6.0,
                                            0.1))
            if k % 2:
                transforms.append(_transform(stamp, t, f"{slash}base_link", f"{slash}laser", 0.2, 0.0, 0.0))
        msgs.append(("/tf", TF, bag, {"transforms": transforms}))
        if odom:
            msgs.append(("/odom", ODOM, bag, {"header": stamp(t, "odom"),
                                              "twist": {"twist": {"linear": {"x": 0.5}}}}))
    return msgs


@pytest.fixture(scope="module")
def bags(tmp_path_factory, bag_writer, stamp):
    d = tmp_path_factory.mktemp("tf_bags")
    return {fmt: bag_writer(d / f"tf_{fmt}", fmt, truth_messages(stamp, fmt == "ros1")) for fmt in FORMATS}


def same_truth(a, b):
    assert a[0].t.tolist() == b[0].t.tolist()
    assert a[0].xy.tolist() == b[0].xy.tolist()
    assert a[0].theta.tolist() == b[0].theta.tolist()
    assert a[1] is None and b[1] is None


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_transform_stamped_topic_is_the_truth_its_poses_give(bags, fmt):
    """vicon_bridge's TransformStamped: pose = translation x, y and the yaw of the rotation,
    at its header stamp (or, with --bag-time, the bag's time): the PoseStamped truth, exactly."""
    path = bags[fmt]
    vicon = read_bag_truth(path, VICON)
    same_truth(vicon, read_bag_truth(path, "/mocap"))
    same_truth(read_bag_truth(path, VICON, receive_time=True), read_bag_truth(path, "/mocap", True))
    ns, x, y, yaw = poses()
    assert vicon[0].t.tolist() == [int(v) // 10**9 + (int(v) % 10**9) / 1e9 for v in ns]
    np.testing.assert_allclose(vicon[0].xy, np.column_stack((x, y)), rtol=0, atol=1e-15)
    np.testing.assert_allclose(vicon[0].theta, yaw, rtol=0, atol=1e-12)  # unwrapped through -π
    assert vicon[0].source.endswith(f":{VICON}")
    # As a log bag's own truth (interpolated at the rows) too.
    log = read_bag(path, ["/odom"], truth_topic=VICON)
    assert log.ground_truth.tolist() == read_bag(path, ["/odom"], truth_topic="/mocap").ground_truth.tolist()


@pytest.mark.parametrize("fmt", FORMATS)
def test_the_tf_transforms_of_one_frame_pair_are_the_truth(bags, fmt):
    """/tf with --truth-frame world:base_link: only those transforms (the messages also carry
    odom→base_link and base_link→laser), a leading '/' ignored on either side (ROS 1's
    frames are /world, /base_link): the PoseStamped truth of the same poses, exactly."""
    path = bags[fmt]
    mocap = read_bag_truth(path, "/mocap")
    for frame in ("world:base_link", "/world:/base_link"):
        same_truth(read_bag_truth(path, "/tf", frame=frame), mocap)
    same_truth(read_bag_truth(path, "tf", True, "world:base_link"), read_bag_truth(path, "/mocap", True))
    log = read_bag(path, ["/odom"], truth_topic="/tf", truth_frame="world:base_link")
    assert log.ground_truth.tolist() == read_bag(path, ["/odom"], truth_topic="/mocap").ground_truth.tolist()


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_pose2d_topic_is_the_truth_its_poses_give_at_the_bags_times(tmp_path, bag_writer, stamp, fmt):
    """mocap_optitrack's ground_pose is a geometry_msgs/Pose2D (x, y, theta, no header; user
    study: refused, with the log's own odometry offered as a truth topic): the PoseStamped
    truth at the bag's times, exactly. Stamped when they arrived in bursts (a motion
    capture's buffer), the log bag's truth topic warns of it, as a truth file does."""
    msgs = [m for m in truth_messages(stamp, fmt == "ros1") if m[0] in ("/mocap", "/odom")]
    ns, x, y, yaw = poses()
    msgs += [("/ground_pose", "geometry_msgs/msg/Pose2D", int(ns[k]) + 2_000_000,
              {"x": float(x[k]), "y": float(y[k]), "theta": float(yaw[k])}) for k in range(ns.size)]
    path = bag_writer(tmp_path / f"pose2d_{fmt}", fmt, msgs)
    got, want = read_bag_truth(path, "/ground_pose"), read_bag_truth(path, "/mocap", receive_time=True)
    assert got[0].t.tolist() == want[0].t.tolist() and got[0].xy.tolist() == want[0].xy.tolist()
    np.testing.assert_allclose(got[0].theta, yaw, rtol=0, atol=0)  # as written: no quaternion between
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # steady stamps: no bursts
        log = read_bag(path, ["/odom"], truth_topic="/ground_pose", receive_time=True)
    np.testing.assert_allclose(log.ground_truth, read_bag(path, ["/odom"], truth_topic="/mocap",
                                                          receive_time=True).ground_truth, rtol=0, atol=1e-12)
    arrived = 50_000_000 * (np.arange(ns.size) // 5) + 200_000 * (np.arange(ns.size) % 5)  # 5 a burst
    bursty = [m for m in msgs if m[0] == "/odom"] + [
        ("/ground_pose", "geometry_msgs/msg/Pose2D", T0 + int(a), m[3])
        for a, m in zip(arrived, [m for m in msgs if m[0] == "/ground_pose"], strict=True)]
    path = bag_writer(tmp_path / f"bursts_{fmt}", fmt, bursty)
    with pytest.warns(UserWarning, match=r"/ground_pose: its fixes come in bursts: .* within 0\.2 ms"):
        read_bag(path, ["/odom"], truth_topic="/ground_pose", receive_time=True)


def test_a_tf_topic_of_one_frame_pair_needs_no_truth_frame(tmp_path, bag_writer, stamp):
    msgs = [m for m in truth_messages(stamp, False, extra_pairs=False, odom=False) if m[0] == "/tf"]
    # /tf_static does not move: never taken for the truth, so /tf is the bag's only truth topic.
    static = [_transform(stamp, T0, "base_link", "laser", 0.2, 0, 0)]
    msgs.append(("/tf_static", TF, T0, {"transforms": static}))
    path = bag_writer(tmp_path / "one_pair", "mcap", msgs)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        alone = read_bag_truth(path)
    ns, x, y, yaw = poses()
    assert alone[0].source.endswith(":/tf") and len(alone[0]) == ns.size
    np.testing.assert_allclose(alone[0].xy, np.column_stack((x, y)), rtol=0, atol=1e-15)
    np.testing.assert_allclose(alone[0].theta, unwrap_angle(yaw), rtol=0, atol=1e-12)


def test_which_frame_pair_is_asked_for_and_what_is_not_there_is_listed(bags, errors):
    path = bags["ros1"]
    text = errors(lambda: read_bag_truth(path, "/tf"))
    assert ("/tf carries transforms of 3 frame pairs; name the truth's with --truth-frame PARENT:CHILD: "
            "base_link:laser (30), odom:base_link (60), world:base_link (60)") in text
    text = errors(lambda: read_bag(path, ["/odom"], truth_topic="/tf"))
    assert "--truth-frame PARENT:CHILD" in text and "world:base_link (60)" in text
    text = errors(lambda: read_bag_truth(path, "/tf", frame="map:base_footprint"))
    assert ("/tf has no transform map:base_footprint (--truth-frame); its frame pairs: base_link:laser (30), "
            "odom:base_link (60), world:base_link (60)") in text
    for call in (lambda: read_bag_truth(path, "/mocap", frame="world:base_link"),
                 lambda: read_bag(path, ["/odom"], truth_topic=VICON, truth_frame="world:base_link")):
        assert "--truth-frame picks the transforms of a tf2_msgs/TFMessage truth topic (/tf)" in errors(call)
    assert "no --truth-topic is given" in errors(
        lambda: read_bag(path, ["/odom"], truth_frame="world:base_link"))
    for bad in ("world", "world:", ":base_link", "a:b:c"):
        assert "--truth-frame takes PARENT:CHILD" in errors(
            lambda b=bad: read_bag_truth(path, "/tf", frame=b))


def test_tf_static_is_no_truth(tmp_path, bag_writer, stamp, errors):
    msgs = [("/tf_static", TF, T0 + k,
             {"transforms": [_transform(stamp, T0 + k, "world", "base_link", 0, 0, 0)]}) for k in range(3)]
    path = bag_writer(tmp_path / "static", "db3", msgs)
    text = errors(lambda: read_bag_truth(path, "/tf_static", frame="world:base_link"))
    assert "topic /tf_static holds static transforms, which do not move: it is no ground truth" in text
    # Not offered as the bag's one truth topic either.
    assert "truth topics: none; other topics: /tf_static (tf2_msgs/msg/TFMessage)" in errors(
        lambda: read_bag_truth(path))


def test_a_truth_transform_from_the_odom_frame_warns(bags):
    """odom→base_link is, as a rule, the odometry's own transform: scored against itself."""
    with pytest.warns(UserWarning, match=r"/tf odom:base_link: a transform from the odom frame is, as a "
                                         r"rule, the odometry's own"):
        read_bag_truth(bags["mcap"], "/tf", frame="odom:base_link")


# --- the commands, end to end -------------------------------------------------------------

RUN = builtin_data_path("230620202042_run-01.csv")
ROBOT = builtin_data_path("optiodom_diff.toml")


@pytest.fixture(scope="module")
def run_bag(tmp_path_factory, bag_writer, stamp, wheel_angles, rad_robot):
    """The OptiOdom run 1 as JointState wheel angles, its OptiTrack poses as a PoseStamped
    /mocap, a TransformStamped /vicon/robot/robot and /tf world→base_link (beside odom→base_link)."""
    d = tmp_path_factory.mktemp("tf_run")
    log = read_run(RUN)
    left, right = wheel_angles(log)
    msgs = []
    for k, t in enumerate(log.t):
        ns = T0 + round(t * 1e9)
        x, y, th = (float(v) for v in log.ground_truth[k])
        msgs.append(("/joint_states", "sensor_msgs/msg/JointState", ns + 2_000_000,
                     {"header": stamp(ns), "name": ["wheel_left_joint", "wheel_right_joint"],
                      "position": [left[k], right[k]]}))
        pose = {"position": {"x": x, "y": y}, "orientation": _quaternion(th)}
        msgs.append(("/mocap", POSE, ns + 1_000_000, {"header": stamp(ns, "world"), "pose": pose}))
        msgs.append((VICON, TRANSFORM, ns + 1_000_000, _transform(stamp, ns, "world", "robot", x, y, th)))
        msgs.append(("/tf", TF, ns + 1_000_000, {"transforms": [
            _transform(stamp, ns, "odom", "base_link", 0.0, 0.0, 0.0),
            _transform(stamp, ns, "world", "base_link", x, y, th)]}))
    (d / "rad.toml").write_text(rad_robot)
    return {"bag": bag_writer(d / "run1", "mcap", msgs), "robot": d / "rad.toml", "dir": d}


def test_truth_topic_on_track_evaluate_calibrate_and_fit_noise(run_cli, run_bag):
    """--truth-topic VICON and --truth-topic /tf --truth-frame world:base_link give every
    truth-taking command the JSON that --truth-topic /mocap (PoseStamped) gives; with
    --truth BAG too (a text log scored against the bag's /tf); bad combinations are one line."""
    bag, robot, d = run_bag["bag"], run_bag["robot"], run_bag["dir"]
    tf = ("--truth-topic", "/tf", "--truth-frame", "world:base_link")

    def run(*args):
        code, out, err = run_cli(*args, "--json")
        assert code == 0, err
        result = json.loads(out)
        for key in ("warnings", "seconds"):  # the warnings name the topic; seconds: run time
            result.pop(key, None)
        return result

    commands = {
        "track": ("track", bag, "--robot", robot),
        "evaluate": ("evaluate", bag, "--robot", robot, "--window", "29.98s"),
        "calibrate": ("calibrate", bag, "--robot", robot, "--from", "trajectory"),
        "fit-noise": ("fit-noise", "--robot", robot, "--log", bag, "--window", "29.98s", "--truth-sigma",
                      "0.001", "--truth-heading-sigma", "0.01", "--truth-time-sigma", "0"),
    }
    for name, args in commands.items():
        out = ("--out", d / "fitted.toml", "--force") if name == "fit-noise" else ()
        reference = run(*args, "--truth-topic", "/mocap", *out)
        assert run(*args, "--truth-topic", VICON, *out) == reference, name
        assert run(*args, *tf, *out) == reference, name
    # --truth BAG: the truth-frame goes with the truth bag's topic.
    text = ("evaluate", RUN, "--robot", ROBOT, "--window", "29.98s", "--truth", bag, "--truth-time-offset",
            str(T0 // 10**9))  # the bag's epoch clock against the text log's from 0
    assert run(*text, *tf) == run(*text, "--truth-topic", "/mocap")

    def refused(*args):
        code, out, err = run_cli(*args)
        assert code == 2 and out == "" and err.startswith("odomkit: error: ") and err.count("\n") == 1, err
        return err

    assert "name the truth's with --truth-frame PARENT:CHILD: odom:base_link" in refused(
        "track", bag, "--robot", robot, "--truth-topic", "/tf")
    err = refused("evaluate", bag, "--robot", robot, "--truth-topic", "/mocap", *tf[2:])
    assert "--truth-frame picks the transforms of a tf2_msgs/TFMessage truth topic (/tf); /mocap is" in err
    tum = d / "truth.tum"
    tum.write_text("0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n")
    assert "--truth-frame picks transforms of a ROS bag's /tf topic; the --truth file" in refused(
        "evaluate", RUN, "--robot", ROBOT, "--truth", tum, "--truth-frame", "world:base_link")
    assert "--truth-frame takes PARENT:CHILD" in refused("track", bag, "--robot", robot, *tf[:3], "world")
    assert "--truth-frame does not apply to a optiodom log" in refused(
        "track", RUN, "--robot", ROBOT, "--truth-frame", "world:base_link")
    assert Path(bag).exists()
