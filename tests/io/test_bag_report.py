"""``odomkit report`` on a bag without truth: what the page offers fits the robot and the bag."""

from __future__ import annotations

import html
import json
import re

import pytest

pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")


def test_without_truth_a_unicycle_bag_is_told_its_own_calibration_and_truth_topic(
        run_cli, tmp_path, husky_drive, bag_writer, stamp):
    """A unicycle's bag without truth (a Jackal bag's user study): the page offered "the
    calibration of the wheel sizes and wheel base" and "--truth FILE" only."""
    log, _ = husky_drive(1, duration=30.0)
    t0 = 1_700_000_000 * 10**9
    msgs = [("/odom", "nav_msgs/msg/Odometry", t0 + round(t * 1e9),
             {"header": stamp(t0 + round(t * 1e9)), "twist": {"twist": {"linear": {"x": float(v)},
                                                                       "angular": {"z": float(w)}}}})
            for t, v, w in zip(log.t, log.channels["speed"], log.channels["yaw_rate"], strict=True)]
    bag = bag_writer(tmp_path / "jackal", "ros1", msgs)
    robot = tmp_path / "u.toml"
    robot.write_text('[robot]\ntype = "unicycle"\n[noise]\nalpha_ss = 0.001\npsd_gyro = 1e-5\n')
    out = tmp_path / "r.html"
    code, printed, err = run_cli("report", bag, "--robot", robot, "--out", out, "--json")
    assert code == 0, err
    assert json.loads(printed)["sections"] == ["summary", "track", "truth", "ros"]
    text = " ".join(html.unescape(re.sub(r"<[^>]+>", " ", out.read_text(encoding="utf-8"))).split())
    assert "the calibration of the speed scale and the yaw rate's bias and scale" in text
    assert "wheel sizes" not in text and "--truth-topic TOPIC" in text
