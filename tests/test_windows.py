"""Windows over a log with truth (odomkit.windows): their length and where they are cut.

Independent truth: window rows counted by hand. The errors and covariances at the window
ends (odomkit.window_errors) are tested in test_window_errors.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.windows import Window, WindowSpec, parse_window, split_windows


def test_parse_window_reads_time_and_travel():
    assert parse_window("30s") == WindowSpec(30.0, "s")
    assert parse_window(" 2.5 min ") == WindowSpec(150.0, "s")
    assert parse_window("1h") == WindowSpec(3600.0, "s")
    assert parse_window("5m") == WindowSpec(5.0, "m")
    assert parse_window("1e1s") == WindowSpec(10.0, "s")


@pytest.mark.parametrize("text", ["", "30", "s", "-5s", "0s", "5 km", "thirty s"])
def test_parse_window_refuses_bad_text_naming_the_flag(text):
    with pytest.raises(InputError, match="--window"):
        parse_window(text)


def test_split_windows_by_time_counted_by_hand():
    t = np.arange(0.0, 10.01, 0.5)  # 21 rows
    windows, skipped = split_windows(t, t, WindowSpec(3.0, "s"))
    assert [(w.start, w.end) for w in windows] == [(0, 6), (6, 12), (12, 18)]
    assert skipped == 0
    assert windows[0] == Window(0, 6, 3.0, 3.0)


def test_split_windows_by_travel_and_stationary_windows_are_counted():
    t = np.arange(0.0, 20.01, 1.0)  # 21 rows
    # Moves 1 m/s for 10 s, stands still for 10 s.
    travel = np.minimum(t, 10.0)
    windows, skipped = split_windows(t, travel, WindowSpec(4.0, "s"))
    # Rows 12..16 and 16..20 travel nothing; 8..12 travels 2 m and is kept.
    assert [(w.start, w.end) for w in windows] == [(0, 4), (4, 8), (8, 12)]
    assert skipped == 2
    windows, _ = split_windows(t, travel, WindowSpec(4.0, "s"), min_travel=0.0)
    assert len(windows) == 5
    by_travel, skipped = split_windows(t, travel, WindowSpec(3.0, "m"))
    assert [(w.start, w.end) for w in by_travel] == [(0, 3), (3, 6), (6, 9)]
    assert skipped == 0


def test_split_windows_restart_after_a_truth_gap_and_one_window_without_spec():
    t = np.arange(0.0, 20.01, 1.0)
    valid = np.ones(t.size, bool)
    valid[7:9] = False  # rows 0..6 and 9..20 have truth
    windows, _ = split_windows(t, t, WindowSpec(3.0, "s"), valid=valid)
    assert [(w.start, w.end) for w in windows] == [(0, 3), (3, 6), (9, 12), (12, 15), (15, 18)]
    whole, _ = split_windows(t, t, None, valid=valid)
    assert [(w.start, w.end) for w in whole] == [(0, 20)]


def test_windows_span_a_truth_gap_shorter_than_a_window():
    """A window needs truth at its two ends only: a 1 s dropout (row 6) inside 3 s windows
    costs none; a window whose end would fall in it ends at the next row with truth (7);
    a gap as long as a window (rows 7, 8: 6 s to 9 s) still restarts the windows after it
    (test_split_windows_restart_after_a_truth_gap_and_one_window_without_spec)."""
    t = np.arange(0.0, 20.01, 1.0)
    valid = np.ones(t.size, bool)
    valid[6] = False
    windows, _ = split_windows(t, t, WindowSpec(3.0, "s"), valid=valid)
    assert [(w.start, w.end) for w in windows] == [(0, 3), (3, 7), (7, 10), (10, 13), (13, 16), (16, 19)]


def test_a_window_longer_than_the_log_gives_none():
    t = np.arange(0.0, 5.01, 0.5)
    assert split_windows(t, t, WindowSpec(30.0, "s")) == ([], 0)


def test_windows_against_a_sparse_truth_end_at_its_fixes_not_on_its_chords(run_cli, tmp_path):
    """A unicycle turning 90° in 2.5 s every 5 s, logged at 10 Hz without error, against a
    noise-free truth with heading given only every 2.2 s (as a reference interpolated between
    keyframes, thinned to them): window ends at rows between fixes would score the chord
    between two fixes (centimetres to decimetres off the arc) as odometry error; at the rows
    of the fixes the odometry is exact, so every window end's error is its rounding."""
    import json

    from odomkit.log import OdometryLog
    from odomkit.robot import Unicycle
    from odomkit.track import dead_reckon_log
    from odomkit.windows import rows_at_fixes

    t = np.round(np.arange(0.0, 120.0, 0.1), 10)
    speed = np.full(t.size, 0.6)
    yaw_rate = np.where((t % 5.0) < 2.5, 0.6283185307179586, 0.0)
    log = OdometryLog(t, {"speed": speed, "yaw_rate": yaw_rate})
    poses = dead_reckon_log(log, Unicycle(), pose0=np.zeros(3)).poses
    keys = np.flatnonzero(np.isclose(np.round(t / 2.2) * 2.2, t, atol=1e-9))
    log_path, truth_path, robot_path = tmp_path / "log.csv", tmp_path / "gt.csv", tmp_path / "u.toml"
    np.savetxt(log_path, np.column_stack((t, speed, yaw_rate)), delimiter=",", header="t,speed,yaw_rate",
               comments="", fmt="%.17g")
    np.savetxt(truth_path, np.column_stack((t[keys], poses[keys])), delimiter=",", header="t,x,y,theta",
               comments="", fmt="%.17g")
    robot_path.write_text('[robot]\ntype = "unicycle"\n[noise]\nalpha_ss = 1e-4\npsd_gyro = 1e-5\n')
    valid = np.ones(t.size, dtype=bool)
    assert np.flatnonzero(rows_at_fixes(t, t[keys], valid)).tolist() == keys.tolist()
    assert rows_at_fixes(t, t, valid).all()  # a truth as dense as the log: every row
    code, out, err = run_cli("evaluate", log_path, "--robot", robot_path, "--truth", truth_path,
                             "--window", "10s", "--json")
    assert code == 0, err
    ends = json.loads(out)["per_log"][0]["window_ends"]
    assert len(ends) >= 8
    assert max(np.hypot(*e["error"]) for e in ends) < 1e-9
    # The same windows ended at every row: the chords' error (the test above would fail).
    chord = []
    for end in (e["end"] + 0.1 for e in ends):
        row = int(round(end / 0.1))
        if row < t.size:
            truth_xy = [np.interp(t[row], t[keys], poses[keys, k]) for k in (0, 1)]
            chord.append(np.hypot(*(poses[row, :2] - truth_xy)))
    assert max(chord) > 0.01


def test_windows_shorter_than_a_sparse_truths_spacing_run_from_fix_to_fix():
    """A 10 Hz log against a 1 Hz truth and 0.5 s windows: each window starts and ends at
    the row next to a fix, so it runs from one fix to the next (1 s), and none is refused
    as longer than a stretch of truth (the gap between two fixes is no gap in the truth).
    A real gap of 5 s still ends a stretch."""
    from odomkit.windows import WindowSpec, rows_at_fixes, split_windows

    t = np.round(np.arange(0.0, 20.0, 0.1), 10)
    fixes = np.r_[np.arange(0.0, 10.0, 1.0), np.arange(15.0, 20.0, 1.0)]
    valid = (t <= 9.0) | (t >= 15.0)  # truth_at's valid rows: no truth across the 6 s gap
    ends = rows_at_fixes(t, fixes, valid)
    windows, skipped = split_windows(t, t, WindowSpec(0.5, "s"), 0.0, valid=valid, ends=ends)
    assert skipped == 0
    assert [(t[w.start], t[w.end]) for w in windows] == [(float(a), float(a + 1)) for a in
                                                          [*range(0, 9), *range(15, 19)]]


def test_a_late_start_note_is_known_by_its_words():
    """The report shows the track's late start once and drops the scorings' own (which say
    the same of "the whole-run track"): it knows them by the words late_start_note uses."""
    from odomkit.windows import is_late_start_note, late_start_note

    t = np.arange(10.0)
    for first_valid in (3, 1):
        note = late_start_note("a.csv", "the whole-run track", t, 3, first_valid)
        assert is_late_start_note(note), note
    assert not is_late_start_note("a.csv: the whole run starts from a heading fitted to the fixes")
    assert not is_late_start_note("a.csv: no RPE over 1 m (the truth has no heading)")
