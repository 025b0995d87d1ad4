"""``--record``/``--truth-record`` drop the tag, so the columns count from the field after it.
A user who counts the tag all the same (``--record M --columns _,t,ticks_left,...``, a user
study on Claus Brenner's LEGO robot log, ``M t left ... right ...``) had the left wheel's
tick counter read as the time, and ``track`` printed "278 poses over 22.094 s" without a
word: a counter that never decreases passes as a clock, and the columns were fewer than the
fields, so the count did not give it away.

Refused, in one line naming the flag and the columns to give:

* a leading ``_`` with a WORD that leads every line of the file: there the flag changes
  nothing but the count, and leaving it out keeps the ``_`` for the tag;
* in a file of several types, a leading ``_`` whose skipped field advances at every row
  over a stretch of four rows where the named time stands still (a tick counter at rest
  while the clock runs), unless that field is a message counter (steps of 1).

The files are synthetic, in the datasets' layouts. The independent truth for the reads that
must work is the file read without the flag, the tag counted as a column of text (or the
file grepped by hand)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.io.csvlog import read_csv_log
from odomkit.io.truth import read_truth

RNG = np.random.default_rng(20251125)


def _write(path: Path, lines: list[str]) -> Path:
    path.write_text("\n".join(lines) + "\n")
    return path


def _grep(path: Path, word: str, out: Path) -> Path:
    return _write(out, [line for line in path.read_text().split("\n") if re.match(rf"{word} ", line)])


def lego(n: int = 80, still: int = 12) -> list[str]:
    """Brenner's ``M t[ms] left left2 3000 power right right2 3000 power 0 0 6000 0``: the robot
    stands for ``still`` rows, then drives; now and then a line is written twice."""
    lines, t, left, right = [], 204, 20795, 16067
    for k in range(n):
        moving = k >= still
        if k:
            t += int(RNG.integers(200, 321))
        if moving:
            left += int(RNG.integers(100, 132))
            right += int(RNG.integers(100, 132))
        power = 500 if moving else 0
        line = f"M {t} {left} {left - 1} 3000 {power} {right} {right - 1} 3000 {power} 0 0 6000 0"
        lines += [line, line] if k % 9 == 4 else [line]
    return lines


def mixed_ticks(n: int = 60, still: int = 8) -> list[str]:
    """``odo t left right flags`` (cumulative ticks, the robot standing for ``still`` rows)
    among ``scan t r1 .. r5`` lines."""
    lines, left, right = [], 1000, 2000
    for k in range(n):
        if k >= still:
            left += int(RNG.integers(20, 40))
            right += int(RNG.integers(20, 40))
        lines.append(f"odo {0.05 * k:.2f} {left} {right} 0")
        if k % 5 == 2:
            lines.append("scan " + " ".join(f"{v:.3f}" for v in RNG.uniform(0.5, 8, 6)))
    return lines


# --- a file of one record type ------------------------------------------------------------

def test_a_leading_skip_with_the_only_record_type_is_refused(tmp_path):
    path = _write(tmp_path / "robot4_motors.txt", lego())
    with pytest.raises(InputError) as info:
        read_csv_log(path, "_,t,ticks_left,_,_,_,ticks_right", cumulative=True, time_unit="ms", record="M")
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith(f"{path}: --record M drops the tag: --columns counts from the field after it")
    assert "skips field 1 (204, " in text
    assert "give --columns t,ticks_left,_,_,_,ticks_right" in text
    assert "or leave out --record (every line is led by M) and keep the _ for the tag" in text


def test_the_columns_it_names_read_as_the_tag_counted_without_the_flag(tmp_path):
    path = _write(tmp_path / "robot4_motors.txt", lego())
    log = read_csv_log(path, "t,ticks_left,_,_,_,ticks_right", cumulative=True, time_unit="ms", record="M")
    counted = read_csv_log(path, "_,t,ticks_left,_,_,_,ticks_right", cumulative=True, time_unit="ms")
    assert np.array_equal(log.t, counted.t) and log.channels.keys() == counted.channels.keys()
    for key in log.channels:
        assert np.array_equal(log.channels[key], counted.channels[key])
    assert log.t[0] == 0.204  # the time, not the tick counter (20.795 s)


def test_truth_a_leading_skip_with_the_only_record_type_is_refused(tmp_path):
    """``P t x y theta``, the robot driving along +x: ``_,t,x,y`` read x as the time, silently."""
    lines = [f"P {0.1 * k:.1f} {0.05 * k:.3f} 0.0 0.0" for k in range(40)]
    path = _write(tmp_path / "ref.txt", lines)
    with pytest.raises(InputError, match=r"--truth-record P drops the tag: --truth-columns counts from the "
                                         r"field after it; .*give --truth-columns t,x,y, or leave out "
                                         r"--truth-record \(every line is led by P\)"):
        read_truth(path, columns="_,t,x,y", record="P")
    truth = read_truth(path, columns="t,x,y", record="P")
    same = read_truth(path, columns="_,t,x,y")
    assert np.array_equal(truth.t, same.t) and np.array_equal(truth.xy, same.xy)


# --- a file of several record types -------------------------------------------------------

def test_mixed_records_a_counter_read_as_the_time_is_refused(tmp_path):
    path = _write(tmp_path / "robot.log", mixed_ticks())
    with pytest.raises(InputError) as info:
        read_csv_log(path, "_,t,ticks_left,ticks_right", cumulative=True, record="odo")
    text = str(info.value)
    assert "\n" not in text
    assert "--record odo drops the tag: --columns counts from the field after it" in text
    assert "its leading _ skips field 1, which advances (0.00, 0.05, 0.10, 0.15, ...)" in text
    assert "where t (field 2) stands still at 1000" in text
    assert "leave out the leading _ (t,ticks_left,ticks_right)" in text
    log = read_csv_log(path, "t,ticks_left,ticks_right", cumulative=True, record="odo")
    grepped = read_csv_log(_grep(path, "odo", tmp_path / "g.txt"), "_,t,ticks_left,ticks_right",
                           cumulative=True)
    assert np.array_equal(log.t, grepped.t) and len(log) == 60
    for key in log.channels:
        assert np.array_equal(log.channels[key], grepped.channels[key])


def test_truth_mixed_records_a_position_read_as_the_time_is_refused(tmp_path):
    """``pos t x y z`` among ``ang t heading 0``: the robot stands for 6 fixes, then drives along +x."""
    lines = []
    for k in range(40):
        lines.append(f"pos {0.2 * k:.1f} {max(0, k - 5) * 0.1:.2f} 0.0 0.0")
        lines.append(f"ang {0.2 * k:.1f} 0.0 0")
    path = _write(tmp_path / "gt.txt", lines)
    with pytest.raises(InputError, match=r"--truth-record pos drops the tag: --truth-columns counts from "
                                         r"the field after it; its leading _ skips field 1, which advances "
                                         r"\(0\.0, 0\.2, 0\.4, 0\.6, \.\.\.\) over lines 1-11, "
                                         r"where t \(field 2\) stands still at 0\.00: a counter, not the "
                                         r"time"):
        read_truth(path, columns="_,t,x,y", record="pos")


def test_mixed_records_a_message_counter_before_a_coarse_clock_reads(tmp_path):
    """``odom seq t speed yaw_rate``, the clock in whole seconds at 5 Hz (it stands for five
    rows while the message counter runs): a leading _ that skips a counter is meant."""
    lines = []
    for k in range(50):
        lines.append(f"odom {100 + k} {k // 5} 1.0 0.1")
        if k % 4 == 1:
            lines.append(f"loop {k // 5} 0 0.9")
    path = _write(tmp_path / "s.txt", lines)
    log = read_csv_log(path, "_,t,speed,yaw_rate", record="odom")
    grepped = read_csv_log(_grep(path, "odom", tmp_path / "g.txt"), "_,_,t,speed,yaw_rate")
    assert np.array_equal(log.t, grepped.t) and len(log) == 50


def test_cli_track_says_it_in_one_line(run_cli, tmp_path):
    path = _write(tmp_path / "robot4_motors.txt", lego())
    robot = _write(tmp_path / "lego.toml", ["[robot]", 'type = "diff"', "m_per_tick = 0.000349",
                                           "wheel_base = 0.173"])
    code, out, err = run_cli("track", path, "--robot", robot, "--record", "M", "--columns",
                             "_,t,ticks_left,_,_,_,ticks_right", "--cumulative", "--time-unit", "ms")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith(f"odomkit: error: {path}: --record M drops the tag")
