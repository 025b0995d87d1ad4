"""Without the ``ros`` extra a bag is one line saying what to install (exit 2), and nothing
else needs rosbags."""

from __future__ import annotations

import sys

import pytest

from odomkit.data import builtin_data_path

ROBOT = builtin_data_path("optiodom_diff.toml")
RUN = builtin_data_path("230620202042_run-01.csv")


@pytest.fixture
def no_rosbags(monkeypatch):
    for name in [m for m in sys.modules if m == "rosbags" or m.startswith("rosbags.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "rosbags", None)  # import rosbags -> ImportError


def test_reading_a_bag_without_rosbags_says_what_to_install(run_cli, no_rosbags, tmp_path):
    bag = tmp_path / "run.bag"
    bag.write_bytes(b"#ROSBAG V2.0\n")
    code, out, err = run_cli("track", bag, "--robot", ROBOT)
    assert code == 2 and out == ""
    assert err == "odomkit: error: ROS bags need the rosbags package: pip install 'odomkit[ros]'\n"


def test_bag_out_without_rosbags_fails_before_any_work(run_cli, no_rosbags, tmp_path):
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--out", tmp_path / "t.csv", "--bag-out",
                           tmp_path / "t.bag")
    assert code == 2 and "pip install 'odomkit[ros]'" in err
    assert list(tmp_path.iterdir()) == []  # checked before the track was computed or written
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--out", tmp_path / "t.csv")
    assert code == 0, err  # text logs and CSV tracks need no rosbags
