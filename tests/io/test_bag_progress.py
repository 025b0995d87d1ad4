"""Reading a bag reports its messages as progress (:mod:`odomkit.progress`): one stage, as
many units as the messages written here, and the same log as without progress."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")

from odomkit.io.bag import read_bag  # noqa: E402
from odomkit.progress import RecordingProgress  # noqa: E402

T0 = 1_700_000_000 * 10**9
JS, POSE = "sensor_msgs/msg/JointState", "geometry_msgs/msg/PoseStamped"


@pytest.mark.parametrize("fmt", ["ros1", "mcap"])
def test_every_message_read_is_reported_once(tmp_path, bag_writer, stamp, fmt):
    n_joints, n_truth = 2345, 1200  # past the report interval (1000), and not a multiple of it
    msgs = []
    for k in range(n_joints):
        ns = T0 + k * 10_000_000
        msgs.append(("/joint_states", JS, ns, {"header": stamp(ns), "name": ["left", "right"],
                                               "position": [0.01 * k, 0.02 * k]}))
    for k in range(n_truth):
        ns = T0 + k * 20_000_000
        msgs.append(("/mocap", POSE, ns, {"header": stamp(ns), "pose": {"position": {"x": 0.01 * k},
                                                                          "orientation": {"w": 1.0}}}))
    path = bag_writer(tmp_path / "b", fmt, msgs)
    seen = RecordingProgress()
    log = read_bag(path, ["/joint_states"], truth_topic="/mocap", progress=seen)
    (reading,) = seen.stages
    assert reading.description == f"reading {path.name}" and reading.closed
    assert reading.total == reading.done == n_joints + n_truth
    assert reading.advances == 2 + 1 + 2  # 1000s, then each topic's remainder (345, 200)
    plain = read_bag(path, ["/joint_states"], truth_topic="/mocap")
    assert np.array_equal(log.t, plain.t) and np.array_equal(log.ground_truth, plain.ground_truth)
