"""Readers: odd-but-valid data handled on purpose, bad input named precisely."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.io.csvlog import read_csv_log
from odomkit.io.halmstad import read_khepera, read_snowhite
from odomkit.io.robotfile import read_robot, write_robot
from odomkit.io.table import unwrap_counter
from odomkit.kinematics import body_steps
from odomkit.noise import ParameterUncertainty, WheelNoise
from odomkit.robot import DiffDrive, Tricycle
from odomkit.track import dead_reckon_log


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize("bits", [16, 32])
def test_counter_wraparound_is_undone_in_both_directions(bits, tmp_path):
    true_counts = np.array([0, 30000, 60000, 90000, 70000, 40000, 15000, 10]) + 2**bits - 40000
    raw = np.mod(true_counts, 2**bits)
    lines = "\n".join(f"{t * 0.1},{r},{r}" for t, r in enumerate(raw))
    path = write(tmp_path, "log.csv", "time,L,R\n" + lines + "\n")
    log = read_csv_log(path, {"t": "time", "ticks_left": "L", "ticks_right": "R"},
                       cumulative=True, wrap_bits=bits)
    assert np.array_equal(log.channels["ticks_left"][1:], np.diff(true_counts))
    assert np.array_equal(unwrap_counter(raw.astype(float), bits) - raw[0], true_counts - true_counts[0])


def test_decreasing_timestamps_are_refused_with_their_line(tmp_path):
    """Issue 12 item 1: a clock that jumps back (or rows written out of order) is refused,
    naming the line, rather than sorted: sorting would hide either."""
    text = "# logger\ntime,L,R\n0,0,0\n0.2,20,20\n0.1,10,10\n0.3,30,30\n"
    path = write(tmp_path, "log.csv", text)
    with pytest.raises(InputError, match=r"log.csv, line 5: time 0.1 is earlier than 0.2 on line 4"):
        read_csv_log(path, {"t": "time", "ticks_left": "L", "ticks_right": "R"}, cumulative=True)


def test_repeated_timestamps_give_zero_length_steps(tmp_path):
    text = "time,L,R\n0,0,0\n0.1,10,10\n0.2,20,20\n0.2,20,20\n0.3,30,30\n"
    path = write(tmp_path, "log.csv", text)
    log = read_csv_log(path, {"t": "time", "ticks_left": "L", "ticks_right": "R"}, cumulative=True)
    assert np.array_equal(log.t, [0, 0.1, 0.2, 0.2, 0.3])
    assert np.array_equal(log.channels["ticks_left"], [0, 10, 10, 0, 10])
    track = dead_reckon_log(log, DiffDrive(0.2))
    assert track.poses[-1, 0] == pytest.approx(30.0)


def test_speed_channel_with_repeated_timestamp_moves_nothing(tmp_path):
    text = "t,v,a\n0,1,0\n1,1,0\n1,1,0\n2,1,0\n"
    path = write(tmp_path, "s.csv", text)
    log = read_csv_log(path, {"t": "t", "speed": "v", "steer": "a"})
    steps = body_steps(Tricycle(1.0), log)
    assert np.array_equal(steps.dd, [1, 0, 1])


def test_decimation_sums_increments_and_samples_rates(tmp_path):
    counts = np.cumsum(np.arange(10))
    path = write(tmp_path, "k.txt", "\n".join(f"{c} {2 * c}" for c in counts))
    log = read_khepera(path)
    dec = log.decimate(3)
    assert np.array_equal(dec.t, [0, 3, 6, 9])
    assert np.array_equal(np.cumsum(dec.channels["ticks_left"]), counts[[0, 3, 6, 9]])
    robot = DiffDrive(0.05, 1e-4, 1e-4)
    full = dead_reckon_log(log, robot, "euler").poses[-1]
    coarse = dead_reckon_log(dec, robot, "euler").poses[-1]
    assert full[2] == pytest.approx(coarse[2], rel=1e-12)  # heading only needs the totals


@pytest.mark.parametrize(("text", "message"), [
    ("1 2\n3 4 5\n", "line 2: expected 2 columns, found 3"),
    ("1 2\n3 abc\n", "line 2: column 2: 'abc' is not a number"),
    ("1 2\n\n# note\n3 nan\n", "line 4: column 2 is nan"),
    ("", "empty"),
])
def test_bad_khepera_files_name_line_and_problem(tmp_path, text, message):
    path = write(tmp_path, "k.txt", text)
    with pytest.raises(InputError, match=message.replace("(", r"\(")):
        read_khepera(path)


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_snowhite(tmp_path / "nope.txt")


def test_csv_mapping_to_a_missing_column_is_named(tmp_path):
    path = write(tmp_path, "log.csv", "time,L,R\n0,0,0\n")
    with pytest.raises(InputError, match="no column named 'right'"):
        read_csv_log(path, {"t": "time", "ticks_left": "L", "ticks_right": "right"})


ROBOT = """[robot]
type = "diff"
wheel_base = {b}
wheel_diameter = 0.0153
encoder_resolution = 600
"""


def test_robot_file_round_trip_and_refusal_to_overwrite(tmp_path):
    path = write(tmp_path, "r.toml", ROBOT.format(b=0.053) + "[noise]\nk_left = 0.001\nk_right = 0.002\n")
    robot, noise = read_robot(path)
    assert robot.m_per_tick_left == pytest.approx(np.pi * 0.0153 / 600)
    assert noise == (WheelNoise(0.001, 0.002),)
    out = tmp_path / "copy.toml"
    write_robot(out, robot, noise + (ParameterUncertainty(sigma_wheel_base=0.001),))
    again, noise2 = read_robot(out)
    assert again == robot and noise2[0] == noise[0] and noise2[1].sigma_wheel_base == 0.001
    with pytest.raises(InputError, match="exists already"):
        write_robot(out, robot)


@pytest.mark.parametrize(("body", "message"), [
    (ROBOT.format(b=-0.05), "wheel_base must be a positive"),
    ('[robot]\ntype = "diff"\nwheel_diameter = 0.1\n', "needs 'wheel_base'"),
    ('[robot]\ntype = "diff"\nwheel_base = 0.1\n', "needs the wheel size"),
    ('[robot]\ntype = "boat"\n', "type must be one of"),
    (ROBOT.format(b=0.05) + "wheelbase = 3\n", "unknown field"),
    (ROBOT.format(b=0.05) + "[noise]\nk_left = 0.1\n", "also needs k_right"),
    (ROBOT.format(b=0.05) + "[noise]\nk_left = -0.1\nk_right = 0.1\n", "non-negative"),
    ("[robot\n", "not valid TOML"),
])
def test_bad_robot_files(tmp_path, body, message):
    path = write(tmp_path, "r.toml", body)
    with pytest.raises(InputError, match=message) as info:
        read_robot(path)
    assert str(path) in str(info.value)



@pytest.mark.parametrize(("text", "message"), [
    ("t,L,R\n0,0,0\n1,2,3,4\n", "line 3: expected 3 columns, found 4"),
    ("t,L,R\n0,0,0\n1,2\n", "line 3: expected 3 columns, found 2"),
    ("t,L,R\n0,0,0\n1,x,3\n", "line 3: column 2: 'x' is not a number"),
    ("t,L,R\n0,0,0\n1,,3\n", "line 3: column 2: '' is not a number"),
    ("t,L,R\n0,0,0\n# pause\n\n1,nan,3\n", "line 5: column 2 is nan"),
    ("t,L,R\n", "empty"),
])
def test_csv_errors_are_the_same_with_either_parser(tmp_path, parser, text, message):
    path = write(tmp_path, "log.csv", text)
    with pytest.raises(InputError, match=message):
        read_csv_log(path, {"t": "t", "ticks_left": "L", "ticks_right": "R"})


def test_both_parsers_read_the_same_numbers(tmp_path, monkeypatch):
    pytest.importorskip("polars")
    import odomkit.io.table as table

    rng = np.random.default_rng(4)
    values = rng.normal(size=(500, 3)) * 10.0 ** rng.integers(-9, 9, size=(500, 3))
    path = tmp_path / "v.csv"
    np.savetxt(path, values, delimiter=",", fmt="%.17g")
    fast = table.read_numeric(path, 3, delimiter=",")
    monkeypatch.setattr(table, "polars_module", lambda: None)
    slow = table.read_numeric(path, 3, delimiter=",")
    assert np.array_equal(fast, slow) and np.array_equal(fast, values)  # correctly rounded
