"""Tagged-record files: every line led by a word naming its type, several types in one file
(libRSF's ``odom3``/``pseudorange3``, ``odom2``/``loop``, ``point2``/``angle``, ``point3``;
CARMEN's ``ODOM``/``FLASER``/``TRUEPOS``), read with ``--record`` / ``--truth-record``.

The files are synthetic, written here in each dataset's layout (trailing blanks, comment
and ``PARAM`` lines, a text host column). The independent truth is the same file grepped
by hand: its lines of one type, tag kept, read without the flag as a table whose first
column is skipped (``_``), which the readers did before the flag existed.
"""

from __future__ import annotations

import gzip
import json
import re
from pathlib import Path

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.io.csvlog import read_csv_log
from odomkit.io.text import mixed_records_at, read_text, record_counts, select_record
from odomkit.io.truth import read_truth

RNG = np.random.default_rng(20240611)


def _num(x: float) -> str:
    return repr(float(x))


def _write(path: Path, lines: list[str], gz: bool = False) -> Path:
    text = "\n".join(lines) + "\n"
    if gz:
        path.write_bytes(gzip.compress(text.encode()))
    else:
        path.write_text(text)
    return path


def _grep(path: Path, word: str, out: Path) -> Path:
    """The lines of ``path`` whose first field is ``word``, tag kept (``grep '^word '``)."""
    text = gzip.decompress(path.read_bytes()).decode() if path.suffix == ".gz" else path.read_text()
    kept = [line for line in text.split("\n") if re.match(rf"{word}[ ,]", line)]
    return _write(out, kept)


def smartloc(n_odom: int = 100, head: int = 80, per: int = 3) -> list[str]:
    """``odom3 t vx vy vz wx wy wz cov(6)`` (14 fields) and ``pseudorange3 t pr x y z 0 0 0 σ id``
    (11 fields): the first ``head`` odom3 lines alone, then ``per`` pseudorange3 lines after each."""
    lines = []
    for k in range(n_odom):
        t = 0.1 * k
        lines.append(f"odom3 {_num(t)} {_num(5 + RNG.normal())} 0 0 0 0 {_num(0.02 * RNG.normal())} "
                     "0.0025 0.0009 0.0009 4e-06 4e-06 4e-06                 ")
        if k >= head:
            for sat in range(per):
                xyz = " ".join(_num(v) for v in 1e7 * RNG.normal(size=3))
                lines.append(f"pseudorange3 {_num(t)} {_num(2.2e7 + 1e5 * RNG.normal())} {xyz} "
                             f"0 0 0 {_num(abs(RNG.normal()) + 1)} {sat + 3}")
    return lines


def slam_input(n: int = 60) -> list[str]:
    """``odom2 t vx vy yaw_rate cov cov cov`` (8 fields) mixed with ``loop t1 t2 score`` (4)."""
    lines = []
    for k in range(n):
        lines.append(f"odom2 {_num(0.1 * k)} {_num(RNG.uniform(0, 1))} 0 {_num(RNG.normal(0, 0.1))} "
                     "0.0025 0.0025 0.0001                       ")
        if k % 7 == 3:
            lines.append(f"loop {_num(0.1 * k)} {_num(0.1 * (k // 2))} {_num(RNG.uniform())}")
    return lines


def slam_truth(n: int = 60) -> list[str]:
    """``point2 t x y 0 0 0 0`` (8 fields) mixed with ``angle t heading 0`` (4)."""
    lines = []
    for k in range(n):
        t = _num(0.2 * k)
        lines.append(f"point2 {t} {_num(k * 0.05 + RNG.normal(0, 0.01))} {_num(RNG.normal(0, 0.01))} 0 0 0 0")
        lines.append(f"angle {t} {_num(RNG.normal(0, 0.1))} 0")
    return lines


def carmen(n: int = 50) -> list[str]:
    """A CARMEN log: comments, ``PARAM`` lines, then ``ODOM x y theta tv rv accel timestamp host
    logger_timestamp``, ``FLASER n r1..rn x y theta odom_x odom_y odom_theta timestamp host
    logger_timestamp`` and ``TRUEPOS x y theta odom_x odom_y odom_theta timestamp host logger_timestamp``."""
    lines = ["# CARMEN Logfile", "# file format is one of:", "# ODOM x y theta tv rv accel",
             "PARAM robot_width 0.5 nohost 0", "PARAM robot_length 0.6 nohost 0",
             "PARAM robot_use_laser on nohost 0"]
    for k in range(n):
        ts = _num(1e9 + 0.1 * k)
        x, y, th = (_num(v) for v in RNG.normal(0, 1, 3))
        lines.append(f"ODOM {x} {y} {th} {_num(RNG.uniform(0, 1))} {_num(RNG.normal(0, 0.2))} 0 {ts} robot1 "
                     f"{_num(1e9 + 0.1 * k + 0.01)}")
        ranges = " ".join(_num(v) for v in RNG.uniform(0.5, 8, 5))
        lines.append(f"FLASER 5 {ranges} {x} {y} {th} {x} {y} {th} {ts} robot1 {_num(1e9 + 0.1 * k + 0.02)}")
        lines.append(f"TRUEPOS {_num(0.1 * k)} {_num(0.01 * k)} {_num(0.001 * k)} {x} {y} {th} {ts} robot1 "
                     f"{_num(1e9 + 0.1 * k + 0.03)}")
    return lines


def _same_log(a, b):
    assert np.array_equal(a.t, b.t)
    assert a.channels.keys() == b.channels.keys()
    for key in a.channels:
        assert np.array_equal(a.channels[key], b.channels[key]), key


def _same_truth(a, b):
    assert np.array_equal(a.t, b.t)
    assert np.array_equal(a.xy, b.xy)
    assert (a.theta is None) == (b.theta is None)
    if a.theta is not None:
        assert np.array_equal(a.theta, b.theta)


# --- each dataset's format, read with the flag == grepped by hand --------------------------

@pytest.mark.usefixtures("parser")
def test_smartloc_odom3_equals_its_lines_grepped(tmp_path):
    path = _write(tmp_path / "smartLoc_Input.txt", smartloc())
    log = read_csv_log(path, ["t", "speed", "_", "_", "_", "_", "yaw_rate"], record="odom3")
    grepped = read_csv_log(_grep(path, "odom3", tmp_path / "g.txt"),
                           ["_", "t", "speed", "_", "_", "_", "_", "yaw_rate"])
    assert len(log) == 100
    _same_log(log, grepped)


@pytest.mark.usefixtures("parser")
@pytest.mark.parametrize("gz", [False, True])
def test_slam_odom2_equals_its_lines_grepped_also_gzip_with_comments(tmp_path, gz):
    lines = slam_input()
    lines = ["# libRSF SLAM input", *lines[:5], "   # a comment line", "", *lines[5:]]
    lines[3] += "   # a trailing comment"
    path = _write(tmp_path / ("SLAM_Input.txt" + (".gz" if gz else "")), lines, gz=gz)
    log = read_csv_log(path, ["t", "speed", "_", "yaw_rate"], record="odom2")
    grepped = read_csv_log(_grep(path, "odom2", tmp_path / "g.txt"), ["_", "t", "speed", "_", "yaw_rate"])
    assert len(log) == 60
    _same_log(log, grepped)


@pytest.mark.usefixtures("parser")
def test_slam_truth_point2_equals_its_lines_grepped(tmp_path):
    path = _write(tmp_path / "SLAM_GT.txt", slam_truth())
    truth = read_truth(path, columns="t,x,y", record="point2")
    grepped = read_truth(_grep(path, "point2", tmp_path / "g.txt"), columns="_,t,x,y")
    assert len(truth.t) == 60 and truth.theta is None
    _same_truth(truth, grepped)


def test_smartloc_truth_point3(tmp_path):
    """A file of one record type (``point3 t X Y Z ...``) reads with the flag as grepped."""
    lines = [f"point3 {_num(0.3 * k)} {_num(10 * k + RNG.normal())} {_num(RNG.normal())} "
             f"{_num(RNG.normal())} " + "0 " * 9 + "                " for k in range(40)]
    path = _write(tmp_path / "smartLoc_GT.txt", lines)
    truth = read_truth(path, columns="t,x,y", record="point3")
    _same_truth(truth, read_truth(path, columns="_,t,x,y"))


def test_carmen_odom_and_truepos(tmp_path):
    path = _write(tmp_path / "robot.log", carmen())
    log = read_csv_log(path, ["_", "_", "_", "speed", "yaw_rate", "_", "t"], record="ODOM")
    grepped = read_csv_log(_grep(path, "ODOM", tmp_path / "g.txt"),
                           ["_", "_", "_", "_", "speed", "yaw_rate", "_", "t"])
    assert len(log) == 50
    _same_log(log, grepped)
    truth = read_truth(path, columns="x,y,theta,_,_,_,t", record="TRUEPOS")
    _same_truth(truth, read_truth(_grep(path, "TRUEPOS", tmp_path / "h.txt"), columns="_,x,y,theta,_,_,_,t"))
    assert truth.t[0] == 1e9


def test_comma_separated_records(tmp_path):
    lines = [line.replace(" ", ",") for line in (s.strip() for s in slam_input(20))]
    path = _write(tmp_path / "c.csv", lines)
    log = read_csv_log(path, ["t", "speed", "_", "yaw_rate"], record="odom2")
    grepped = read_csv_log(_grep(path, "odom2", tmp_path / "g.csv"), ["_", "t", "speed", "_", "yaw_rate"])
    _same_log(log, grepped)


# --- line numbers stay the file's own ------------------------------------------------------

@pytest.mark.usefixtures("parser")
def test_a_nan_is_named_by_its_line_in_the_file(tmp_path):
    lines = slam_input()
    bad = 30  # 0-based index: a line after several loop lines
    assert lines[bad].startswith("odom2")
    fields = lines[bad].split()
    fields[4] = "nan"  # yaw_rate
    lines[bad] = " ".join(fields)
    path = _write(tmp_path / "s.txt", ["# header comment", *lines])
    with pytest.raises(InputError, match=rf"line {bad + 2}: column 4 is nan") as info:
        read_csv_log(path, ["t", "speed", "_", "yaw_rate"], record="odom2")
    assert "--record odom2 drops the tag" in str(info.value)


def test_a_time_going_back_is_named_by_its_line_in_the_file(tmp_path):
    lines = slam_input(12)  # a loop line after odom2 at k = 3 and k = 10
    assert lines[9].startswith("odom2 0.8")
    lines[9] = "odom2 0.1" + lines[9][len("odom2 0.8"):]
    path = _write(tmp_path / "s.txt", lines)
    with pytest.raises(InputError, match=r"line 10: time 0.1 is earlier than 0.7000000000000001 on line 9"):
        read_csv_log(path, ["t", "speed", "_", "yaw_rate"], record="odom2")


def test_truth_error_names_the_files_line(tmp_path):
    lines = slam_truth(10)
    lines[6] = "point2 0.6 1 oops 0 0 0 0"
    path = _write(tmp_path / "gt.txt", lines)
    with pytest.raises(InputError, match=r"line 7: column 3: 'oops' is not a number"):
        read_truth(path, columns="t,x,y", record="point2")


# --- without the flag: a mix of types is named ---------------------------------------------

@pytest.mark.parametrize("columns", [None, ["_", "t", "speed", "_", "_", "_", "_", "yaw_rate"]])
def test_a_mix_without_the_flag_names_the_types(tmp_path, columns):
    path = _write(tmp_path / "smartLoc_Input.txt", smartloc(n_odom=100, head=80, per=3))
    with pytest.raises(InputError) as info:
        read_csv_log(path, columns)
    assert str(info.value) == (
        f"{path}: its lines are tagged records of 2 types (odom3: 100 lines, pseudorange3: 60 lines): keep "
        "one with --record odom3 (its tag is dropped: the columns count from the field after it)")


def test_a_truth_mix_names_the_truth_flag(tmp_path):
    path = _write(tmp_path / "gt.txt", slam_truth())
    with pytest.raises(InputError, match=r"\(point2: 60 lines, angle: 60 lines\): keep one with "
                                         r"--truth-record point2 "):
        read_truth(path, columns="_,t,x,y")
    with pytest.raises(InputError, match=r"--truth-record TRUEPOS"):
        read_truth(_write(tmp_path / "c.log", carmen(5)), columns="_,x,y")


def test_carmen_without_the_flag_suggests_odom(tmp_path):
    path = _write(tmp_path / "c.log", carmen(5))
    with pytest.raises(InputError, match=r"4 types \(PARAM: 3 lines, ODOM: 5 lines, FLASER: 5 lines, "
                                         r"TRUEPOS: 5 lines\): keep one with --record ODOM "):
        read_csv_log(path, ["_", "_", "_", "_", "speed", "yaw_rate", "_", "t"])


def test_a_type_change_after_a_header_is_named_where_the_read_fails(tmp_path):
    """A header exempts the first column from the early look (it is a named column), but a
    line of another type with another column count is still named as a mix."""
    lines = ["kind t speed yaw_rate"] + [f"odom {0.1 * k:.1f} 1 0" for k in range(100)] + ["loop 1 2"]
    path = _write(tmp_path / "h.txt", lines)
    with pytest.raises(InputError, match=r"tagged records of 2 types \(odom: 100 lines, loop: 1 line\): keep "
                                         "one with --record odom"):
        read_csv_log(path, ["_", "t", "speed", "yaw_rate"])
    assert mixed_records_at(read_text(path), str(path), 102) is not None
    assert mixed_records_at(read_text(path), str(path), 50) is None


def test_one_leading_word_reads_as_before(tmp_path):
    """Every line led by the same word: the tag is a column of text, read as before."""
    path = _write(tmp_path / "one.txt", [s for s in slam_input() if s.startswith("odom2")])
    log = read_csv_log(path, ["_", "t", "speed", "_", "yaw_rate"])
    assert len(log) == 60


def test_a_named_text_column_that_varies_is_no_record_type(tmp_path):
    """A header names the first column: its words (a mode) are text, not record types."""
    lines = ["mode,t,speed,yaw_rate"] + [f"{'MOVING' if k % 3 else 'STOP'},{0.1 * k:.1f},1,0"
                                         for k in range(80)]
    log = read_csv_log(_write(tmp_path / "m.csv", lines), ["_", "t", "speed", "yaw_rate"])
    assert len(log) == 80


# --- a type that is not there, and the column count ----------------------------------------

def test_a_type_not_found_names_the_types_present(tmp_path):
    path = _write(tmp_path / "s.txt", slam_input(20))
    with pytest.raises(InputError, match=r"no line is a 'odom' record \(--record odom\); its lines start "
                                         r"with odom2: 20 lines, loop: 3 lines$"):
        read_csv_log(path, ["t", "speed"], record="odom")
    with pytest.raises(InputError, match=r"did you mean ODOM\?"):
        read_csv_log(_write(tmp_path / "c.log", carmen(3)), ["t", "speed"], record="odom")
    with pytest.raises(InputError, match=r"no line is a 'angle' record \(--truth-record angle\)"):
        read_truth(_write(tmp_path / "p.txt", [f"point2 {k} 0 0" for k in range(4)]), record="angle")
    with pytest.raises(InputError, match=r"the lines start with numbers"):
        read_csv_log(_write(tmp_path / "n.txt", ["0 1 0", "0.1 1 0"]), ["t", "speed"], record="odom")


def test_a_leading_skip_for_the_dropped_tag_is_explained(tmp_path):
    path = _write(tmp_path / "s.txt", slam_input(20))
    with pytest.raises(InputError, match=r"--record odom2 drops the tag: --columns counts from the field "
                                         r"after it; leave out the leading _ \(t,speed,_,yaw_rate\)"):
        read_csv_log(path, ["_", "t", "speed", "_", "yaw_rate", "_", "_", "_"], record="odom2")
    with pytest.raises(InputError, match=r"--truth-record point2 drops the tag: --truth-columns counts from"):
        read_truth(_write(tmp_path / "g.txt", slam_truth(5)), columns="_,t,x,y,_,_,_,_", record="point2")


def test_header_names_do_not_go_with_a_record(tmp_path):
    path = _write(tmp_path / "s.txt", slam_input(20))
    with pytest.raises(InputError, match=r"--record keeps lines without a header: name the columns in order"):
        read_csv_log(path, {"t": "time", "speed": "v"}, record="odom2")
    with pytest.raises(InputError, match=r"--truth-record keeps lines without a header"):
        read_truth(_write(tmp_path / "g.txt", slam_truth(5)), columns="t=time,x=x,y=y", record="point2")


def test_selection_keeps_every_line_number():
    text = "# c\nodom2 0 1\nloop 1 2 3\n\nodom2\t0.1\t2\r\n  odom2, 0.2, 3\nodom20 5 5\n"
    out = select_record(text, "f", "odom2")
    assert out.split("\n") == ["# c", "0 1", "#", "", "0.1\t2\r", " 0.2, 3", "#", ""]
    assert record_counts(text) == {"odom2": 3, "loop": 1, "odom20": 1}


# --- the command line ---------------------------------------------------------------------

@pytest.fixture
def robot(tmp_path):
    return _write(tmp_path / "uni.toml", ["[robot]", 'type = "unicycle"'])


def test_cli_track_with_record_equals_the_grepped_log(run_cli, tmp_path, robot):
    path = _write(tmp_path / "smartLoc_Input.txt", smartloc())
    code, out, err = run_cli("track", path, "--robot", robot, "--record", "odom3",
                             "--columns", "t,speed,_,_,_,_,yaw_rate", "--json")
    assert code == 0, err
    code2, out2, err2 = run_cli("track", _grep(path, "odom3", tmp_path / "g.txt"), "--robot", robot,
                                "--columns", "_,t,speed,_,_,_,_,yaw_rate", "--json")
    assert code2 == 0, err2
    assert json.loads(out)["samples"] == 100
    assert json.loads(out) == json.loads(out2)


def test_cli_track_without_record_says_which_flag(run_cli, tmp_path, robot):
    path = _write(tmp_path / "smartLoc_Input.txt", smartloc())
    code, _, err = run_cli("track", path, "--robot", robot, "--columns", "_,t,speed,_,_,_,_,yaw_rate")
    assert code == 2
    assert err.strip() == (
        f"odomkit: error: {path}: its lines are tagged records of 2 types (odom3: 100 lines, pseudorange3: "
        "60 lines): keep one with --record odom3 (its tag is dropped: the columns count from the field "
        "after it)")


def test_cli_evaluate_with_truth_record(run_cli, tmp_path, robot):
    log = _write(tmp_path / "SLAM_Input.txt", slam_input())
    truth = _write(tmp_path / "SLAM_GT.txt", slam_truth(40))
    track = tmp_path / "track.csv"
    code, _, err = run_cli("track", log, "--robot", robot, "--record", "odom2",
                           "--columns", "t,speed,_,yaw_rate", "--out", track, "--no-covariance")
    assert code == 0, err
    code, out, err = run_cli("evaluate", track, "--truth", truth, "--truth-record", "point2",
                             "--truth-columns", "t,x,y", "--json")
    assert code == 0, err
    code2, out2, err2 = run_cli("evaluate", track, "--truth", _grep(truth, "point2", tmp_path / "g.txt"),
                                "--truth-columns", "_,t,x,y", "--json")
    assert code2 == 0, err2
    strip = re.compile(r'"[^"]*(SLAM_GT|g)\.txt[^"]*"')
    assert strip.sub('"F"', out) == strip.sub('"F"', out2)
    code, _, err = run_cli("evaluate", track, "--truth", truth, "--truth-columns", "_,t,x,y")
    assert code == 2 and "--truth-record point2" in err


def test_cli_record_does_not_apply_to_a_bag(run_cli, tmp_path, robot):
    code, _, err = run_cli("track", tmp_path / "x.bag", "--robot", robot, "--record", "odom")
    assert code == 2 and "--record does not apply to a bag log" in err
