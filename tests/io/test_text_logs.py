"""Text logs as they are (issue 12 item 1; DESIGN.md "Text logs and truth files").

The independent truth is a log made in memory: written out in every delimiter, header,
comment, gzip, line-ending and time-unit combination, and read back through
:func:`odomkit.workflows.logs.load_log` by both parsers (polars and numpy), it must give the
identical track, bit for bit (times are dyadic, so every spelling of them is exact).
"""

from __future__ import annotations

import gzip
import re
import tempfile
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import odomkit.io.table as table
from odomkit.errors import InputError
from odomkit.io.csvlog import parse_columns, read_csv_log
from odomkit.io.text import sniff_layout
from odomkit.io.truth import read_truth
from odomkit.log import OdometryLog
from odomkit.robot import Unicycle
from odomkit.track import dead_reckon_log
from odomkit.workflows.logs import LogOptions, load_log

ROBOT = Unicycle()
UNITS = {"s": 1, "ms": 1000, "us": 10**6, "ns": 10**9}
NAMES = {"t": "time", "speed": "v_mps", "yaw_rate": "w_radps", "_": "temp_C"}
DELIMITERS = [",", ";", "\t", " ", "   ", ", ", " ; ", " \t"]


def exact_decimal(value: Fraction) -> str:
    """The exact decimal spelling of a dyadic fraction with denominator up to 2**6."""
    scaled = value * 10**6
    assert scaled.denominator == 1
    sign, digits = ("-" if scaled < 0 else ""), f"{abs(scaled.numerator):07d}"
    whole, frac = digits[:-6], digits[-6:].rstrip("0")
    return f"{sign}{whole}.{frac}" if frac else f"{sign}{whole}"


@st.composite
def logs(draw):
    n = draw(st.integers(2, 30))
    start = Fraction(draw(st.integers(0, 2**20)), 64)
    steps = draw(st.lists(st.integers(0, 8), min_size=n - 1, max_size=n - 1))  # 0: a repeated time
    t = [start]
    for k in steps:
        t.append(t[-1] + Fraction(k, 64))
    floats = st.floats(-5, 5, allow_nan=False, allow_subnormal=False)
    speed = draw(st.lists(floats, min_size=n, max_size=n))
    yaw = draw(st.lists(floats, min_size=n, max_size=n))
    temp = draw(st.lists(floats, min_size=n, max_size=n))
    return t, speed, yaw, temp


@st.composite
def layouts(draw):
    return {
        "delimiter": draw(st.sampled_from(DELIMITERS)),
        "order": draw(st.permutations(["t", "speed", "yaw_rate", "_"])),
        "header": draw(st.booleans()),
        "leading_comments": draw(st.integers(0, 3)),
        "comment_every": draw(st.sampled_from([0, 2, 5])),
        "inline_comment": draw(st.booleans()),
        "blank_lines": draw(st.booleans()),
        "gzip": draw(st.booleans()),
        "crlf": draw(st.booleans()),
        "bom": draw(st.booleans()),
        "unit": draw(st.sampled_from(list(UNITS))),
    }


def render(log, layout) -> tuple[bytes, str]:
    """The file's bytes and the --columns text."""
    t, speed, yaw, temp = log
    d = layout["delimiter"]
    cells = {"t": [exact_decimal(x * UNITS[layout["unit"]]) for x in t],
             "speed": [repr(v) for v in speed], "yaw_rate": [repr(v) for v in yaw],
             "_": [repr(v) for v in temp]}
    lines = [f"# logger v{i}: {d!r}-separated, # marks a comment" for i in range(layout["leading_comments"])]
    if layout["header"]:
        lines.append(d.join(NAMES[c] for c in layout["order"]))
        columns = ",".join(f"{c}={NAMES[c]}" for c in layout["order"] if c != "_")
    else:
        columns = ",".join(layout["order"])
    for i in range(len(t)):
        row = d.join(cells[c][i] for c in layout["order"])
        if layout["inline_comment"] and i % 3 == 1:
            row += " # wheel slipped?"
        lines.append(row)
        if layout["comment_every"] and i % layout["comment_every"] == 0:
            lines.append("   # a comment between rows")
        if layout["blank_lines"] and i % 4 == 2:
            lines.append("")
    text = ("\r\n" if layout["crlf"] else "\n").join(lines) + "\n"
    data = ("\ufeff" if layout["bom"] else "").encode() + text.encode()
    return (gzip.compress(data) if layout["gzip"] else data), columns


def reference_track(log):
    t, speed, yaw, _ = log
    memory = OdometryLog(np.array([float(x) for x in t]),
                         {"speed": np.array(speed), "yaw_rate": np.array(yaw)})
    return dead_reckon_log(memory, ROBOT)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(log=logs(), layout=layouts())
def test_every_spelling_of_a_log_gives_the_identical_track(log, layout):
    data, columns = render(log, layout)
    expected = reference_track(log)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / ("log.txt.gz" if layout["gzip"] else "log.txt")
        path.write_bytes(data)
        options = LogOptions(columns=columns, time_unit=layout["unit"])
        for numpy_only in (False, True):
            with pytest.MonkeyPatch.context() as mp:
                if numpy_only:
                    mp.setattr(table, "polars_module", lambda: None)
                read = load_log(path, ROBOT, options)
            got = dead_reckon_log(read, ROBOT)
            assert np.array_equal(read.t, expected.t)
            assert np.array_equal(got.poses, expected.poses), (layout, numpy_only)


# --- the layout, found from the first data lines -----------------------------------------

@pytest.mark.parametrize("text, delimiter, header", [
    ("t,a,b\n0,1,2\n", ",", ("t", "a", "b")),
    ("# c\n# d\nt;a;b\n0;1;2\n1;2;3\n", ";", ("t", "a", "b")),
    ("0\t1\t2\n1\t-2e-3\tnan\n", "\t", None),
    ("  0   1 2\n1 2\t 3  # note\n", None, None),
    ('"time","left ticks"\n0,1\n', ",", ("time", "left ticks")),
    ("0, 1, 2\r\n1, 2, 3\r\n", ",", None),
    ("t x y\n", None, ("t", "x", "y")),  # a header alone: the table reader says 'no data rows'
])
def test_the_layout_is_sniffed(text, delimiter, header):
    layout = sniff_layout(text, "f")
    assert (layout.delimiter, layout.header) == (delimiter, header)


@pytest.mark.parametrize("text, message", [
    ("t;v\n0;1,5\n1;2,25\n", "line 2: '1,5' has a decimal comma"),
    ("0,5\t1,25\n", "line 1: '0,5' has a decimal comma"),
    ("1,5 2,5\n", "tr ',' '.' for this whitespace-separated one"),
    ("# only\n\n", "the file is empty"),
    ("0\n1\n2\n", "line 1: one column only"),
    ("t x y\n1,2,3\n", "line 1: the header has 1 name(s) but the next line has 3 comma-separated fields"),
])
def test_layouts_that_cannot_be_read_are_named(text, message):
    with pytest.raises(InputError, match=re.escape(message)):
        sniff_layout(text, "f")


def test_a_comma_file_with_one_bad_row_names_that_row_not_the_delimiter(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("t,v,w\n0,1,2\n1,2,3\n2,3;4\n3,4,5\n")
    with pytest.raises(InputError, match="line 4: expected 3 columns, found 2"):
        read_csv_log(path, {"t": "t", "speed": "v", "yaw_rate": "w"})


# --- --columns in order or as a header map -----------------------------------------------

def test_columns_in_order_skip_and_ignore_the_rest(tmp_path):
    path = tmp_path / "log.txt"
    path.write_text("# t temp v w extra\n0 20 1 0 9\n1 21 1 0.5 9\n2 22 1 0.5 9\n")
    log = read_csv_log(path, parse_columns("t,_,speed,yaw_rate"))
    assert np.array_equal(log.channels["speed"], [1, 1, 1])
    assert np.array_equal(log.channels["yaw_rate"], [0, 0.5, 0.5])


def test_columns_in_order_replace_a_header(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("stamp,vel,omega\n0,1,0\n1,1,0.5\n")
    log = read_csv_log(path, ["t", "speed", "yaw_rate"])
    assert np.array_equal(log.t, [0, 1]) and np.array_equal(log.channels["yaw_rate"], [0, 0.5])


def test_a_header_map_on_a_headerless_file_says_to_name_them_in_order(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("# no header\n0,1,0\n1,1,0.5\n")
    with pytest.raises(InputError, match=r"line 2: --columns maps header names, but the file has no header.*"
                                         r"--columns t,ticks_left,ticks_right"):
        read_csv_log(path, {"t": "time", "speed": "v", "yaw_rate": "w"})


def test_a_header_of_numbers_is_a_header_when_the_map_names_it(tmp_path):
    """pandas writes the header 0,1,2 for a frame without column names."""
    path = tmp_path / "log.csv"
    path.write_text("0,1,2\n0.0,1.0,0.0\n0.5,1.0,0.25\n")
    log = read_csv_log(path, {"t": "0", "speed": "1", "yaw_rate": "2"})
    assert np.array_equal(log.t, [0, 0.5])


def test_a_line_of_names_and_numbers_is_not_silently_skipped(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("0,,0\n0.5,1.0,0.25\n1,1,0.5\n")  # the logger had no speed yet
    with pytest.raises(InputError, match="line 1: this line mixes names and numbers"):
        read_csv_log(path, ["t", "speed", "yaw_rate"])


@pytest.mark.parametrize("text, message", [
    ("t,speed=v", "mixes the two forms"),
    ("t,speed,speed", "names speed more than once"),
    ("speed,yaw_rate", "needs the time column t"),
    ("t,velocity", "unknown target 'velocity'"),
    ("t,speed,yaw_rate,_,_", "--columns names 5 columns, the file has 3 (comma-separated)"),
])
def test_bad_columns_are_named(tmp_path, text, message):
    path = tmp_path / "log.csv"
    path.write_text("0,1,0\n1,1,0.5\n")
    with pytest.raises(InputError, match=re.escape(message)):
        read_csv_log(path, parse_columns(text))


# --- time ----------------------------------------------------------------------------------

@pytest.mark.parametrize("unit, text", [("ns", "1234567891"), ("us", "1234567.891"), ("ms", "1234.567891"),
                                        ("s", "1.234567891"), (1e-9, "1234567891")])
def test_time_units_read_the_same_double(tmp_path, unit, text):
    """Dividing by 10**9 (not multiplying by 1e-9) is correctly rounded: ns integers give the
    very double that the seconds spelling does."""
    path = tmp_path / "log.csv"
    path.write_text(f"0,1,0\n{text},1,0\n")
    log = read_csv_log(path, ["t", "speed", "yaw_rate"], time_unit=unit)
    assert log.t[1] == float("1.234567891")


def test_truth_files_are_sniffed_like_logs(tmp_path):
    comma = tmp_path / "gt.csv"
    comma.write_text("t,x,y\n0,0,0\n0.5,1,0.5\n1,2,1\n")
    semicolon = tmp_path / "gt2.csv"
    semicolon.write_text("# mocap export\nt;x;y\n0;0;0 # start\n0.5;1;0.5\n\n1;2;1\n")
    a, b = read_truth(comma), read_truth(semicolon)
    assert np.array_equal(a.t, b.t) and np.array_equal(a.xy, b.xy)


def test_a_header_in_odomkits_own_names_needs_no_columns(tmp_path):
    """A log whose header names every column as odomkit does (``t,speed,yaw_rate``, or
    ``time`` and ``gt_*``) is read without --columns, identically to the mapped form; a
    header with a name odomkit does not know, or no header, still asks for --columns and
    says why (a misspelt channel must not be dropped silently)."""
    t = np.arange(0.0, 5.0, 0.1)
    rows = np.column_stack((t, 0.3 + 0 * t, 0.1 * np.sin(t), t, 0 * t, 0 * t))
    own = tmp_path / "own.csv"
    np.savetxt(own, rows, delimiter=",", header="time,speed,yaw_rate,gt_x,gt_y,gt_theta", comments="")
    robot = Unicycle()
    plain = load_log(own, robot, LogOptions())
    mapped = load_log(own, robot, LogOptions(columns="t=time,speed=speed,yaw_rate=yaw_rate,gt_x=gt_x,"
                                                     "gt_y=gt_y,gt_theta=gt_theta"))
    np.testing.assert_array_equal(plain.t, mapped.t)
    for name in ("speed", "yaw_rate"):
        np.testing.assert_array_equal(plain.channels[name], mapped.channels[name])
    np.testing.assert_array_equal(plain.ground_truth, mapped.ground_truth)
    odd = tmp_path / "odd.csv"
    np.savetxt(odd, rows[:, :3], delimiter=",", header="t,speed,yawrate", comments="")
    with pytest.raises(InputError, match=r"needs --columns.*'yawrate', not odomkit's own names"):
        load_log(odd, robot, LogOptions())
    bare = tmp_path / "bare.csv"
    np.savetxt(bare, rows[:, :3], delimiter=",")
    with pytest.raises(InputError, match="needs --columns.*no header"):
        load_log(bare, robot, LogOptions())


def test_a_ros_twist_header_is_read_and_the_columns_hint_is_the_robots_own(tmp_path):
    """``stamp,linear_x,angular_z`` (a Twist as ROS tools export it) reads as speed and yaw
    rate, the same as the mapped form; where --columns is needed the example names the
    robot's own channels (a unicycle's speed and yaw rate, not a diff's ticks)."""
    from odomkit.robot import ROBOT_TYPES
    from odomkit.workflows.logs import COLUMN_EXAMPLES

    t = np.arange(0.0, 5.0, 0.1)
    rows = np.column_stack((t, 0.3 + 0 * t, 0.1 * np.sin(t)))
    ros = tmp_path / "ros.csv"
    np.savetxt(ros, rows, delimiter=",", header="stamp,linear_x,angular_z", comments="")
    robot = Unicycle()
    plain = load_log(ros, robot, LogOptions())
    mapped = load_log(ros, robot, LogOptions(columns="t=stamp,speed=linear_x,yaw_rate=angular_z"))
    for name in ("speed", "yaw_rate"):
        np.testing.assert_array_equal(plain.channels[name], mapped.channels[name])
    short = tmp_path / "vw.csv"
    np.savetxt(short, rows, delimiter=",", header="t,v,w", comments="")
    with pytest.raises(InputError, match=r"header names \(t=time,speed=V,yaw_rate=W\) or the columns in "
                                         r"order \(t,speed,yaw_rate\)"):
        load_log(short, robot, LogOptions())
    assert set(COLUMN_EXAMPLES) == set(ROBOT_TYPES)


def test_angles_in_degrees_read_as_radians_and_radians_that_look_like_degrees_are_warned_about(tmp_path):
    """A CAN steering angle or a gyro is often logged in degrees: ``steer_deg``,
    ``yaw_rate_deg`` and ``heading_deg`` (in --columns or in the header) read them as the
    radians of the same channel, exactly as ``np.radians`` of the numbers. Read as radians,
    a steering angle beyond ±(π/2 + 0.01) or a yaw rate beyond a revolution a second in 1 %
    of the rows is said to look like degrees; a tricycle at its ±π/2 lock is not."""
    import warnings as warnings_module

    from odomkit.robot import Car

    t = np.arange(0.0, 20.0, 0.05)
    steer_deg = 25.0 * np.sin(0.3 * t)
    rate_deg = 40.0 * np.cos(0.2 * t)
    rows = np.column_stack((t, 0.3 + 0 * t, steer_deg, rate_deg))
    path = tmp_path / "deg.csv"
    np.savetxt(path, rows, delimiter=",", header="t,speed,steer_deg,yaw_rate_deg", comments="")
    with warnings_module.catch_warnings():
        warnings_module.simplefilter("error")  # degree columns read so are no cause for a warning
        by_header = read_csv_log(path, None)
        in_order = read_csv_log(path, ["t", "speed", "steer_deg", "yaw_rate_deg"])
    for log in (by_header, in_order):
        np.testing.assert_array_equal(log.channels["steer"], np.radians(steer_deg))
        np.testing.assert_array_equal(log.channels["yaw_rate"], np.radians(rate_deg))
        assert "steer_deg" not in log.channels and "yaw_rate_deg" not in log.channels
    radians = tmp_path / "rad.csv"
    np.savetxt(radians, np.column_stack((t, 0.3 + 0 * t, np.radians(steer_deg))), delimiter=",",
               header="t,speed,steer", comments="")
    car = Car(wheel_base=2.7)
    track_deg = dead_reckon_log(load_log(path, car, LogOptions(columns="t,speed,steer_deg")), car)
    track_rad = dead_reckon_log(load_log(radians, car, LogOptions()), car)
    np.testing.assert_allclose(track_deg.poses, track_rad.poses, rtol=0, atol=1e-12)

    with pytest.warns(UserWarning, match=r"column 3 \(steer\) reaches 25 rad.*steer_deg"):
        read_csv_log(path, ["t", "speed", "steer", "yaw_rate_deg"])
    with pytest.warns(UserWarning, match=r"column 4 \(yaw_rate\) has a 99th percentile of 40 rad/s.*_deg"):
        read_csv_log(path, ["t", "speed", "steer_deg", "yaw_rate"])
    lock = tmp_path / "lock.csv"
    np.savetxt(lock, np.column_stack((t, 0.3 + 0 * t, np.full_like(t, np.pi / 2), np.full_like(t, 6.0))),
               delimiter=",")
    with warnings_module.catch_warnings():
        warnings_module.simplefilter("error")
        read_csv_log(lock, ["t", "speed", "steer", "yaw_rate"])
    with pytest.raises(InputError, match="give steer or steer_deg, not more than one"):
        read_csv_log(path, ["t", "speed", "steer", "steer_deg"])


def test_a_steering_encoders_raw_ticks_are_not_called_degrees(tmp_path):
    """A tricycle's 8192-per-turn steering encoder read as radians reached 8156 and was asked
    "is it in degrees?" (user study): no steering wheel turns 8156°. Beyond 1080° (three
    turns) the warning names raw ticks; a steering-wheel angle of 540° is still degrees."""
    t = np.arange(0.0, 20.0, 0.05)
    for peak, said in ((8156.0, r"reaches 8156, beyond any angle in degrees.*encoder's raw ticks"),
                       (540.0, r"reaches 540 rad.*is it in degrees")):
        path = tmp_path / f"steer{peak:g}.csv"
        np.savetxt(path, np.column_stack((t, 0.3 + 0 * t, peak * np.sin(0.3 * t) ** 2)), delimiter=",",
                   header="t,speed,steer", comments="")
        with pytest.warns(UserWarning, match=said) as caught:
            read_csv_log(path, None)
        assert len(caught) == 1


def test_speeds_in_kmh_and_mph_are_read_as_metres_per_second_and_kmh_read_as_ms_is_warned_about(tmp_path):
    """A car's CAN speed is km/h or mph: ``speed_kmh`` and ``speed_mph`` read it as the m/s
    of ``speed`` (1 km/h = 1/3.6 m/s; 1 mph = 1609.344 m / 3600 s, exact by definition), so
    the track is the one of the same speeds written in m/s. Read as m/s, a speed beyond
    60 m/s (216 km/h) in 1 % of the rows is said to look like km/h or mph; a 30 m/s car is not."""
    import warnings as warnings_module

    from odomkit.robot import Car

    t = np.arange(0.0, 60.0, 0.1)
    kmh = 50.0 + 40.0 * np.sin(0.05 * t)  # 10-90 km/h
    steer = 0.05 * np.sin(0.2 * t)
    mph = kmh / 1.609344
    path = tmp_path / "can.csv"
    np.savetxt(path, np.column_stack((t, kmh, mph, steer)), delimiter=",", header="t,speed_kmh,v_mph,steer",
               comments="")
    with warnings_module.catch_warnings():
        warnings_module.simplefilter("error")
        from_kmh = read_csv_log(path, {"t": "t", "speed_kmh": "speed_kmh", "steer": "steer"})
        from_mph = read_csv_log(path, ["t", "_", "speed_mph", "steer"])
    np.testing.assert_allclose(from_kmh.channels["speed"], kmh * 1000.0 / 3600.0, rtol=1e-15, atol=0)
    np.testing.assert_allclose(from_mph.channels["speed"], mph * 1609.344 / 3600.0, rtol=1e-15, atol=0)
    np.testing.assert_allclose(from_mph.channels["speed"], from_kmh.channels["speed"], rtol=1e-12)
    ms = tmp_path / "ms.csv"
    np.savetxt(ms, np.column_stack((t, kmh / 3.6, steer)), delimiter=",", header="t,speed,steer", comments="")
    car = Car(wheel_base=2.7)
    with warnings_module.catch_warnings():
        warnings_module.simplefilter("error")  # 25 m/s is a car's speed, no cause for a warning
        track_ms = dead_reckon_log(load_log(ms, car, LogOptions()), car)
    track_kmh = dead_reckon_log(load_log(path, car, LogOptions(columns="t,speed_kmh,_,steer")), car)
    np.testing.assert_allclose(track_kmh.poses, track_ms.poses, rtol=0, atol=1e-9)
    with pytest.warns(UserWarning, match=r"column 2 \(speed\) has a 99th percentile of 90 m/s.*km/h or mph"):
        read_csv_log(path, ["t", "speed", "_", "steer"])
    with pytest.raises(InputError, match="give speed or speed_kmh, not more than one"):
        read_csv_log(path, ["t", "speed", "speed_kmh", "steer"])
    with pytest.raises(InputError, match="speed_kmh, speed_mph"):
        read_csv_log(path, ["t", "speed_kph", "_", "steer"])


def test_a_header_written_as_a_comment_is_shown_in_the_columns_hint(tmp_path):
    """Public datasets often write their header as the last comment line (the UTIAS MRCLAM
    robots: ``# Time [s]    forward velocity [m/s]    angular velocity[rad/s]`` over
    tab-separated rows). It is not read as a header (a comment may say anything), but the
    --columns hint quotes it, and the columns in order then read the log."""
    rows = "\n".join(f"{1248272272.841 + 0.02 * k:.3f} \t  0.074 \t  {0.229 - 0.001 * k:.3f}"
                     for k in range(20))
    path = tmp_path / "Robot1_Odometry.dat"
    path.write_text("# A dataset\n# Odometry Data Format:\n"
                    "# Time [s]    forward velocity [m/s]    angular velocity[rad/s]\n" + rows + "\n")
    robot = Unicycle()
    with pytest.raises(InputError, match=r"its last comment line names its 3 columns 'Time \[s\]', "
                                         r"'forward velocity \[m/s\]', 'angular velocity\[rad/s\]'"):
        load_log(path, robot, LogOptions())
    log = load_log(path, robot, LogOptions(columns="t,speed,yaw_rate"))
    assert len(log) == 20 and log.channels["speed"][0] == 0.074
    other = tmp_path / "other.dat"
    other.write_text("# recorded on Tuesday\n" + rows + "\n")
    with pytest.raises(InputError, match=r"this log has no header$"):
        load_log(other, robot, LogOptions())


def test_read_csv_log_takes_the_columns_text_the_command_line_takes(tmp_path):
    """MRCLAM user study: read_csv_log(path, "t,speed,yaw_rate") was refused ("not a
    string") while read_truth and LogOptions take their columns as text. The text reads
    as the sequence or mapping it names: both in order and by header name, and the empty
    text is the command line's error."""
    path = tmp_path / "log.dat"
    path.write_text("# t v w\ntime v w\n0.0 0.5 0.25\n0.5 0.75 -0.5\n1.0 1.0 0.125\n")
    by_list = read_csv_log(path, ["t", "speed", "yaw_rate"])
    for text in ("t,speed,yaw_rate", " t, speed , yaw_rate ", "t=time,speed=v,yaw_rate=w"):
        got = read_csv_log(path, text)
        assert np.array_equal(got.t, [0.0, 0.5, 1.0]) and np.array_equal(got.t, by_list.t)
        assert np.array_equal(got.channels["speed"], [0.5, 0.75, 1.0])
        assert np.array_equal(got.channels["yaw_rate"], [0.25, -0.5, 0.125])
    swapped = read_csv_log(path, "t,yaw_rate,speed")
    assert np.array_equal(swapped.channels["speed"], by_list.channels["yaw_rate"])
    with pytest.raises(InputError, match="--columns is empty"):
        read_csv_log(path, " , ")
