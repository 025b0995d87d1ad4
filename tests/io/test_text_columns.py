"""Columns that ``--columns`` / ``--truth-columns`` do not name may hold anything: a car's CAN
log has a wall-clock date, a gear letter, empty fields. Only the columns named are read as
numbers; a named column that is not a number is still refused with its file, line and column.

The independent truth is the same file written without its text columns (every number spelt
identically), and the numbers as written, parsed by Python's float().
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import odomkit.io.table as table
from odomkit.errors import InputError
from odomkit.io.csvlog import parse_columns, read_csv_log
from odomkit.io.truth import read_truth

CAR_ROBOT = Path(__file__).parents[2] / "examples" / "car.toml"
HEADER = ["Time", "Seconds", "Latitude / Y Position (Degrees)", "Longitude / X Position (Degrees)",
          "Speed (MPH)", "Steering Angle", "Gear"]
TEXT = (0, 6)  # Time and Gear
LOG_MAP = {"t": "Seconds", "speed_mph": "Speed (MPH)", "steer_deg": "Steering Angle"}
GEO_MAP = "t=Seconds,lat=Latitude / Y Position (Degrees),lon=Longitude / X Position (Degrees)"



def car_rows(n: int = 40, delimiter: str = ",") -> list[list[str]]:
    """Rows of a CAN log as a car writes it: a date, seconds, a fix, speed [mph], steering [deg],
    and a gear that is sometimes not logged (an empty field; a letter where the separator is
    blank: whitespace cannot hold an empty field, and a line's surrounding tabs are stripped
    as blanks)."""
    rng = np.random.default_rng(7)
    rows = []
    for k in range(n):
        date = f"2018-04-08{'T' if delimiter == ' ' else ' '}10:31:{37 + k // 10:02d}.{k % 10}05628"
        gear = "D" if k % 3 else ("N" if delimiter in " \t" else "")
        rows.append([date, f"{694.308316 + 0.1 * k:.6f}", f"{30.327356 + 2e-6 * k:.9f}",
                     f"{-97.755968 + 1e-6 * k:.9f}", f"{60 + rng.uniform():.3f}",
                     f"{rng.uniform(-5, 5):.2f}", gear])
    return rows


def name(header_name: str, delimiter: str) -> str:
    """A header name as a file of this separator can hold it (no blanks where they separate)."""
    return header_name.replace(" ", "_") if delimiter == " " else header_name


def write(path: Path, rows: list[list[str]], delimiter: str = ",", header: bool = True,
          keep=lambda i: True) -> Path:
    lines = ([delimiter.join(name(h, delimiter) for i, h in enumerate(HEADER) if keep(i))] if header else [])
    lines += [delimiter.join(f for i, f in enumerate(row) if keep(i)) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def numeric_only(i: int) -> bool:
    return i not in TEXT


def assert_same_log(a, b) -> None:
    np.testing.assert_array_equal(a.t, b.t)
    assert set(a.channels) == set(b.channels) == {"speed", "steer"}
    for name in a.channels:
        np.testing.assert_array_equal(a.channels[name], b.channels[name])


@pytest.mark.parametrize("delimiter", [",", ";", "\t", " "])
def test_a_log_with_text_columns_reads_as_the_same_log_without_them(tmp_path, parser, monkeypatch, delimiter):
    """By header names and in order (headerless, the date first), a log with a date and a gear
    column gives exactly the channels of the same file without them; polars reads such a file
    itself (its fast path is kept), numpy where polars cannot (whitespace)."""
    rows = car_rows(delimiter=delimiter)
    if parser == "polars" and delimiter != " ":
        monkeypatch.setattr(table, "_read_with_numpy", lambda *a: pytest.fail("polars refused the file"))
    text_log = write(tmp_path / "car.csv", rows, delimiter)
    plain_log = write(tmp_path / "plain.csv", rows, delimiter, keep=numeric_only)
    mapping = {key: name(column, delimiter) for key, column in LOG_MAP.items()}
    by_name = read_csv_log(text_log, mapping)
    assert_same_log(by_name, read_csv_log(plain_log, mapping))
    np.testing.assert_array_equal(by_name.t, [float(r[1]) for r in rows])
    np.testing.assert_array_equal(by_name.channels["speed"], [float(r[4]) * 0.44704 for r in rows])

    text_bare = write(tmp_path / "car_bare.csv", rows, delimiter, header=False)
    plain_bare = write(tmp_path / "plain_bare.csv", rows, delimiter, header=False, keep=numeric_only)
    in_order = read_csv_log(text_bare, parse_columns("_,t,_,_,speed_mph,steer_deg"))  # the gear: ignored
    assert_same_log(in_order, read_csv_log(plain_bare, parse_columns("t,_,_,speed_mph,steer_deg")))
    assert_same_log(in_order, by_name)


def test_the_users_can_log_is_tracked_through_the_cli(tmp_path, run_cli):
    log = write(tmp_path / "car.csv", car_rows())
    plain = write(tmp_path / "plain.csv", car_rows(), keep=numeric_only)
    columns = "t=Seconds,speed_mph=Speed (MPH),steer_deg=Steering Angle"
    code, out, err = run_cli("track", log, "--robot", CAR_ROBOT, "--columns", columns)
    assert code == 0, err
    assert out == run_cli("track", plain, "--robot", CAR_ROBOT, "--columns", columns)[1]


@pytest.mark.parametrize("delimiter", [",", "\t"])
def test_a_truth_file_with_text_columns_reads_as_the_same_truth_without_them(tmp_path, delimiter):
    """x, y truth by header names, in order (headerless, the date first) and by the header's
    own names gives the truth of the same file without its text columns."""
    rows = [[r[0], r[1], r[4], r[5], r[6]] for r in car_rows(delimiter=delimiter)]  # date, t, x, y, gear
    names = ["Date", "t", "x", "y", "Gear"]

    def save(name: str, header: bool, keep=lambda i: True) -> Path:
        lines = ([delimiter.join(n for i, n in enumerate(names) if keep(i))] if header else [])
        lines += [delimiter.join(f for i, f in enumerate(row) if keep(i)) for row in rows]
        (tmp_path / name).write_text("\n".join(lines) + "\n")
        return tmp_path / name

    def plain_cols(i: int) -> bool:
        return i in (1, 2, 3)

    reference = read_truth(save("plain.csv", True, plain_cols))
    np.testing.assert_array_equal(reference.t, [float(r[1]) for r in rows])
    for truth in (read_truth(save("mapped.csv", True), columns="t=t,x=x,y=y"),
                  read_truth(save("own_names.csv", True)),
                  read_truth(save("bare.csv", False), columns="_,t,x,y")):
        np.testing.assert_array_equal(truth.t, reference.t)
        np.testing.assert_array_equal(truth.xy, reference.xy)
        assert truth.theta is None


def test_a_gps_truth_with_a_date_column_reads_as_without_it(tmp_path):
    pytest.importorskip("pymap3d", reason="the gps extra (pymap3d) is not installed")
    rows = car_rows()
    truth = read_truth(write(tmp_path / "car.csv", rows), columns=GEO_MAP)
    plain = read_truth(write(tmp_path / "plain.csv", rows, keep=numeric_only), columns=GEO_MAP)
    bare = read_truth(write(tmp_path / "bare.csv", rows, header=False), columns="_,t,lat,lon")
    for other in (plain, bare):
        np.testing.assert_array_equal(truth.t, other.t)
        np.testing.assert_array_equal(truth.xy, other.xy)


def test_a_named_column_with_text_is_still_refused_with_its_line_and_column(tmp_path, parser, run_cli):
    """Line 7's speed is 'n/a': that is the error (not the date on line 2, which is not read)."""
    rows = car_rows()
    rows[5][4] = "n/a"
    log = write(tmp_path / "car.csv", rows)
    with pytest.raises(InputError, match=re.escape(f"{log}, line 7: column 5: 'n/a' is not a number")):
        read_csv_log(log, LOG_MAP)
    code, _, err = run_cli("track", log, "--robot", CAR_ROBOT, "--columns",
                           "t=Seconds,speed_mph=Speed (MPH),steer_deg=Steering Angle")
    assert code == 2 and "line 7: column 5: 'n/a' is not a number" in err
    bare = write(tmp_path / "bare.csv", rows, header=False)
    with pytest.raises(InputError, match=re.escape(f"{bare}, line 6: column 5: 'n/a' is not a number")):
        read_csv_log(bare, parse_columns("_,t,_,_,speed_mph,steer_deg"))

    rows = car_rows()
    rows[3][3] = "lost"
    truth = write(tmp_path / "gps.csv", rows)
    with pytest.raises(InputError, match=re.escape(f"{truth}, line 5: column 4: 'lost' is not a number")):
        read_truth(truth, columns="t=Seconds,x=Latitude / Y Position (Degrees),"
                                  "y=Longitude / X Position (Degrees)")


def test_a_delimiter_inside_a_text_field_is_refused_not_shifted(tmp_path, parser):
    """A gear 'D,3' would shift every number after it one column on: the row is refused by
    its field count, although the column it is in is not read. Quotes are plain characters
    (as to numpy): an unclosed quote does not swallow the lines after it."""
    rows = car_rows()
    rows[9][6] = "D,3"
    log = write(tmp_path / "car.csv", rows)
    with pytest.raises(InputError, match=re.escape(f"{log}, line 11: expected 7 columns, found 8")):
        read_csv_log(log, LOG_MAP)
    with pytest.raises(InputError, match=re.escape(f"{log}, line 11: expected 7 columns, found 8")):
        read_truth(log, columns=GEO_MAP.replace("lat=", "x=").replace("lon=", "y="))
    rows = car_rows()
    rows[2][6], rows[5][6] = '"D', 'N"'
    quoted = read_csv_log(write(tmp_path / "quoted.csv", rows), LOG_MAP)
    assert_same_log(quoted, read_csv_log(write(tmp_path / "plain.csv", rows, keep=numeric_only), LOG_MAP))


def test_a_text_column_with_spaces_does_not_change_the_delimiter(tmp_path):
    """A note with more words than the table has columns: the separator that splits every
    line into the header's number of fields is the table's, not whitespace."""
    log = tmp_path / "notes.csv"
    log.write_text("t,note,v,w\n0,left the parking lot at last,1,0\n0.5,still going on and on,1,0.5\n")
    read = read_csv_log(log, {"t": "t", "speed": "v", "yaw_rate": "w"})
    np.testing.assert_array_equal(read.channels["yaw_rate"], [0, 0.5])


def test_the_columns_error_names_every_header_and_each_time_column(tmp_path):
    """Without --columns the CAN log still asks for them, and the message names every column
    it does not read by its own names, and both of its times: 'Time' (odomkit's name for t,
    here a date) and 'Seconds'. Two of odomkit's time names are both named too."""
    log = write(tmp_path / "car.csv", car_rows())
    with pytest.raises(InputError, match="needs --columns") as raised:
        read_csv_log(log, None)
    message = str(raised.value)
    for name in HEADER[1:]:
        assert repr(name) in message
    assert "more than one time column, 'Time' (odomkit's name for t) and 'Seconds'" in message
    both = tmp_path / "both.csv"
    both.write_text("t,time,speed\n0,0,1\n1,1,1\n")
    with pytest.raises(InputError, match="it names 2 time columns, 't', 'time': map the one that holds "
                                         "the time as t=<header name>"):
        read_csv_log(both, None)
