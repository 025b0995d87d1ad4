"""OptiOdom run files: which platform a run is (API user study, M8).

A run file has no header: columns 5 and 6 are the right and left wheels' ticks per cycle
(diff) or the traction wheel's ticks and the steering angle [rad] (tricycle). ``read_run``
defaulted to diff and read a tricycle's steering angle as left-wheel ticks; the robot
type's word ``tricycle`` was refused. The columns tell the platforms apart (ticks are whole
numbers, tens per cycle; a steering angle is fractional and within ±π/2): a run is read as
what its columns say, and a platform they contradict is refused.
"""

from __future__ import annotations

import glob

import numpy as np
import pytest

from odomkit.data import builtin_data_path
from odomkit.errors import InputError
from odomkit.io.optiodom import read_run

DIFF_RUN = builtin_data_path("230620202042_run-01.csv")


def _tricycle_run(data_dir):
    runs = sorted(glob.glob(str(data_dir / "optiodom" / "tricyc" / "square" / "*" / "*_run-01.csv")))
    if not runs:
        pytest.skip(f"no OptiOdom tricycle runs under {data_dir}")
    return runs[0]


def test_a_tricycle_run_reads_as_a_tricycle_by_default(data_dir):
    from odomkit.robot import Tricycle
    from odomkit.track import dead_reckon_log

    path = _tricycle_run(data_dir)
    raw = np.loadtxt(path, delimiter=",")
    log = read_run(path)
    assert sorted(log.channels) == ["steer", "ticks"]
    np.testing.assert_array_equal(log.channel("ticks"), raw[:, 4])
    np.testing.assert_array_equal(log.channel("steer"), raw[:, 5])
    # Read so, the nominal tricycle (SOURCE.md: L 0.15 m, one tick π·0.065/1600 m) turns as
    # the motion capture does, within 5 % (data/optiodom/SOURCE.md checked it so).
    track = dead_reckon_log(log, Tricycle(0.15, m_per_tick=np.pi * 0.065 / 1600))
    turned, true_turn = track.poses[-1, 2], log.ground_truth[-1, 2]
    assert abs(true_turn) > 5.0
    assert turned == pytest.approx(true_turn, rel=0.05)


def test_the_robot_types_word_tricycle_is_the_datasets_tricyc(data_dir):
    path = _tricycle_run(data_dir)
    one, other = read_run(path, platform="tricycle"), read_run(path, platform="tricyc")
    assert one.channels.keys() == other.channels.keys() == {"ticks", "steer"}
    np.testing.assert_array_equal(one.channel("steer"), other.channel("steer"))


def test_a_tricycle_run_read_as_diff_is_refused_naming_its_steering_column(data_dir):
    path = _tricycle_run(data_dir)
    with pytest.raises(InputError, match=r"column 6 .*steering angle.*platform='tricycle'") as info:
        read_run(path, platform="diff")
    assert "\n" not in str(info.value)


def test_a_diff_run_reads_as_diff_and_is_refused_as_a_tricycle():
    raw = np.loadtxt(DIFF_RUN, delimiter=",")
    log = read_run(DIFF_RUN)
    # Column 5 is the RIGHT wheel (data/optiodom/SOURCE.md)
    np.testing.assert_array_equal(log.channel("ticks_right"), raw[:, 4])
    np.testing.assert_array_equal(log.channel("ticks_left"), raw[:, 5])
    with pytest.raises(InputError, match=r"column 6 .*no steering angle.*platform='diff'"):
        read_run(DIFF_RUN, platform="tricycle")


def test_a_run_whose_columns_cannot_tell_needs_its_platform(tmp_path):
    """Column 6 all zero: a left wheel that never turns, or a steering held straight."""
    path = tmp_path / "exp_run-01.csv"
    t = np.arange(20) * 0.05
    np.savetxt(path, np.column_stack((t, t * 0.1, 0 * t, 0 * t, np.full(20, 30.0), 0 * t)), delimiter=",")
    with pytest.raises(InputError, match=r"platform='diff' or platform='tricycle'"):
        read_run(path)
    assert sorted(read_run(path, "tricycle").channels) == ["steer", "ticks"]
    assert sorted(read_run(path, "diff").channels) == ["ticks_left", "ticks_right"]


def test_an_unknown_platform_names_the_words_taken():
    with pytest.raises(InputError, match=r"platform must be diff or tricycle \(or tricyc\), got 'car'"):
        read_run(DIFF_RUN, platform="car")


def test_the_command_line_refuses_a_tricycle_run_with_a_diff_robot_in_one_line(data_dir, run_cli):
    """``--format optiodom`` takes the platform from the robot file: a diff robot on a
    tricycle run read its steering angle as left-wheel ticks and drew a track."""
    path = _tricycle_run(data_dir)
    robot = builtin_data_path("optiodom_diff.toml")
    code, out, err = run_cli("track", path, "--format", "optiodom", "--robot", robot, "--json")
    assert code == 2 and not out, (code, out)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("odomkit: error: "), err
    assert "column 6" in lines[0] and "a tricycle robot file" in lines[0]
