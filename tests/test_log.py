"""odomkit.log: the in-memory log, its checks and its decimation."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from odomkit.errors import InputError
from odomkit.log import (
    ABSOLUTE_CHANNELS,
    INCREMENT_CHANNELS,
    KNOWN_CHANNELS,
    RATE_CHANNELS,
    OdometryLog,
)


def test_channel_families_partition_the_known_channels():
    assert INCREMENT_CHANNELS | RATE_CHANNELS | ABSOLUTE_CHANNELS == KNOWN_CHANNELS
    assert not INCREMENT_CHANNELS & RATE_CHANNELS
    assert not INCREMENT_CHANNELS & ABSOLUTE_CHANNELS
    assert not RATE_CHANNELS & ABSOLUTE_CHANNELS


def test_a_log_holds_its_rows_and_is_frozen():
    log = OdometryLog(np.arange(4.0), {"speed": np.ones(4)}, np.zeros((4, 3)), "run.csv")
    assert len(log) == 4
    assert log.channel("speed").tolist() == [1.0] * 4
    with pytest.raises(dataclasses.FrozenInstanceError):
        log.source = "other"  # type: ignore[misc]


@pytest.mark.parametrize("kwargs, message", [
    (dict(t=np.zeros((3, 1))), r"^run\.csv: time must have shape \(N,\), got \(3, 1\)"),
    (dict(channels={"speed": np.ones(2)}), r"^run\.csv: channel 'speed' must have shape \(3,\), got \(2,\)"),
    (dict(channels={"velocity": np.ones(3)}), r"^run\.csv: unknown channel 'velocity'; expected one of"),
    (dict(ground_truth=np.zeros((3, 2))), r"^run\.csv: ground truth must have shape \(3, 3\), got \(3, 2\)"),
    (dict(ground_truth=np.zeros((2, 3))), r"ground truth must have shape \(3, 3\), got \(2, 3\)"),
])
def test_malformed_logs_are_rejected_naming_source_and_field(kwargs, message):
    args = dict(t=np.arange(3.0), channels={"speed": np.ones(3)}, ground_truth=None, source="run.csv")
    args.update(kwargs)
    with pytest.raises(InputError, match=message):
        OdometryLog(**args)


def _with(values, row, value):
    out = np.array(values, dtype=float)
    out[row] = value
    return out


@pytest.mark.parametrize("t, channels, message", [
    # a clock that jumps back 3 s at row 50: dead-reckoned, it ran silently backwards
    (_with(np.arange(0, 10, 0.1), slice(50, None), np.arange(5.0, 10.0, 0.1) - 3.0),
     {"speed": np.full(100, 0.5)},
     r"^run\.csv: time goes backwards at row 50 \(rows count from 0\): 2 s after 4\.9 s"),
    (_with(np.arange(100.0), 7, np.nan), {"speed": np.ones(100)}, r"^run\.csv: time is nan at row 7 \(rows"),
    (np.arange(100.0), {"speed": np.ones(100), "yaw_rate": _with(np.zeros(100), [50, 60], np.nan)},
     r"^run\.csv: channel 'yaw_rate' is nan at row 50 \(rows count from 0; 1 more row\)"),
    (np.arange(100.0), {"ticks_left": _with(np.ones(100), 0, np.inf), "ticks_right": np.ones(100)},
     r"^run\.csv: channel 'ticks_left' is inf at row 0 \(rows count from 0\)"),
])
def test_time_going_back_and_values_that_are_not_numbers_are_refused(t, channels, message):
    """API user study, M5: a log built in Python was not checked as the readers check theirs:
    time going backwards was dead-reckoned silently, a NaN failed later as ``dd[50] is nan``."""
    with pytest.raises(InputError, match=message) as info:
        OdometryLog(t, channels, source="run.csv")
    assert "\n" not in str(info.value)


def test_repeated_times_are_zero_length_steps_as_the_readers_keep_them():
    t = np.array([0.0, 0.1, 0.1, 0.2])
    log = OdometryLog(t, {"dist": np.array([0.0, 0.1, 0.0, 0.1]), "steer": np.zeros(4)})
    assert len(log) == 4


def test_missing_channel_names_what_the_log_has():
    log = OdometryLog(np.arange(3.0), {"speed": np.ones(3), "steer": np.zeros(3)}, source="s.txt")
    expected = r"^s\.txt: log has no channel 'yaw_rate' \(it has \['speed', 'steer'\]\)"
    with pytest.raises(InputError, match=expected):
        log.channel("yaw_rate")


def test_decimate_sums_increments_and_samples_the_rest():
    """Reading a counter every 3rd row sees the counts of the rows in between; a rate or an
    angle is simply read less often. Row 0 (motion before the log) stays as it was."""
    t = np.arange(8.0)
    ticks = np.array([99.0, 1, 2, 3, 4, 5, 6, 7])
    speed = 10.0 + t
    truth = np.column_stack((t, 2 * t, 3 * t))
    log = OdometryLog(t, {"ticks_left": ticks, "speed": speed, "steer": -t}, truth, "a", {"k": 1})
    dec = log.decimate(3)
    assert dec.t.tolist() == [0.0, 3.0, 6.0]
    # rows 1-3 -> 1+2+3, rows 4-6 -> 4+5+6 (row 7 is past the last kept row)
    assert dec.channel("ticks_left").tolist() == [99.0, 6.0, 15.0]
    assert dec.channel("speed").tolist() == [10.0, 13.0, 16.0]
    assert dec.channel("steer").tolist() == [0.0, -3.0, -6.0]
    assert dec.ground_truth.tolist() == truth[[0, 3, 6]].tolist()
    assert dec.meta == {"k": 1, "decimation": 3} and dec.source == "a"
    assert log.decimate(1) is log


@given(st.lists(st.integers(-1000, 1000), min_size=2, max_size=60), st.integers(1, 10))
def test_decimation_keeps_the_total_count_up_to_the_last_kept_row(counts, every):
    n = len(counts)
    log = OdometryLog(np.arange(float(n)), {"dist": np.array(counts, dtype=float)})
    dec = log.decimate(every)
    last = (n - 1) // every * every
    assert dec.channel("dist")[1:].sum() == pytest.approx(sum(counts[1:last + 1]))


@pytest.mark.parametrize("every", [0, -2, 2.0, True, None])
def test_decimation_must_be_a_positive_integer(every):
    log = OdometryLog(np.arange(3.0), {"speed": np.ones(3)}, source="run.csv")
    with pytest.raises(InputError, match=r"^run\.csv: decimation must be a positive integer, got "):
        log.decimate(every)


def test_from_row_keeps_every_channel_and_the_truth_from_that_row():
    """OdometryLog.from_row: the rows from ``row`` on, channels and ground truth alike; a
    track dead-reckoned from it equals the whole log's track from that row on, moved to start there."""
    from odomkit.robot import DiffDrive
    from odomkit.track import dead_reckon_log

    t = np.arange(0.0, 5.0, 0.1)
    log = OdometryLog(t, {"dist_left": 0.01 + 0.002 * np.sin(t), "dist_right": 0.01 + 0 * t},
                      np.column_stack((t, 0 * t, 0 * t)), "x.csv")
    part = log.from_row(20)
    assert part.t.tolist() == t[20:].tolist() and part.source == "x.csv"
    assert part.ground_truth.tolist() == log.ground_truth[20:].tolist()
    robot = DiffDrive(0.3)
    whole = dead_reckon_log(log, robot).poses
    late = dead_reckon_log(part, robot, pose0=tuple(whole[20])).poses
    np.testing.assert_allclose(late, whole[20:], atol=1e-12)
