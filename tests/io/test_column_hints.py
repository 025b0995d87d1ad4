"""Column names and time columns as a CAN logger writes them (a real car's user study,
findings 13 and 15).

The file is the logger's layout: a wall-clock ``Time`` of date text, ``Seconds``, GPS and CAN
channels under names with capitals and spaces, and log and truth in the same file. A header
name given in another case or spacing is answered with the header's own spelling; an error
about a ``--truth-columns`` name says it is the truth file's; a time column of date text
says so and names the header's numeric time columns. Each is one line, exit 2.
"""

from __future__ import annotations

import pytest

from odomkit.errors import InputError
from odomkit.io.csvlog import read_csv_log
from odomkit.io.truth import read_truth

HEADER = "Time,Seconds,X (m),Y (m),Speed (MPH),Steering Angle,Engine RPM"
ROWS = ["2018-04-08 10:31:37.005628,694.308,0.0,0.0,10.0,1.5,900",
        "2018-04-08 10:31:37.091200,694.393,0.4,0.0,10.2,1.4,905",
        "2018-04-08 10:31:37.177000,694.479,0.9,0.0,10.4,1.2,910"]
LOG = {"t": "Seconds", "speed_mph": "Speed (MPH)", "steer_deg": "Steering Angle"}


@pytest.fixture()
def logger_csv(tmp_path):
    path = tmp_path / "dataset.csv"
    path.write_text("\n".join([HEADER, *ROWS]) + "\n")
    return path


def _error(read) -> str:
    with pytest.raises(InputError) as caught:
        read()
    return str(caught.value)


@pytest.mark.parametrize("given", ["Speed (mph)", "speed (MPH)", "Speed(MPH)", "Speed  (MPH)", "SPEED (MPH)"])
def test_a_log_column_in_another_case_or_spacing_gets_the_headers_spelling(logger_csv, given):
    said = _error(lambda: read_csv_log(logger_csv, {**LOG, "speed_mph": given}))
    assert "did you mean 'Speed (MPH)'" in said and f"no column named {given!r}" in said
    assert "--columns" in said and "--truth-columns" not in said


def test_a_misspelt_log_column_is_not_matched_to_another_name(logger_csv):
    said = _error(lambda: read_csv_log(logger_csv, {**LOG, "steer_deg": "Steering Angel"}))
    assert "no column named 'Steering Angel'" in said and "did you mean" not in said


def test_a_truth_column_error_says_it_is_the_truth_files(logger_csv):
    said = _error(lambda: read_truth(logger_csv, columns="t=Seconds,x=X (mm),y=Y (m)"))
    assert "--truth-columns" in said and "truth file" in said and "no column named 'X (mm)'" in said
    assert "did you mean" not in said
    said = _error(lambda: read_truth(logger_csv, columns="t=Seconds,x=x (M),y=Y (m)"))
    assert "--truth-columns" in said and "truth file" in said and "did you mean 'X (m)'" in said


def test_a_date_text_time_column_names_the_numeric_time_column(logger_csv):
    said = _error(lambda: read_csv_log(logger_csv, {**LOG, "t": "Time"}))
    assert "line 2" in said and "'2018-04-08 10:31:37.005628'" in said
    assert "date" in said and "'Seconds'" in said and "t=Seconds" in said
    assert "Engine RPM" not in said  # a numeric column, but no time
    said = _error(lambda: read_truth(logger_csv, columns="t=Time,x=X (m),y=Y (m)"))
    assert "date" in said and "t=Seconds" in said and "--truth-columns" in said


def test_a_truth_header_whose_time_column_is_date_text_names_the_numeric_one(tmp_path):
    """Without --truth-columns the truth's header names its columns: 'time' is taken for t."""
    path = tmp_path / "gps.csv"
    path.write_text("time,seconds,x,y\n2018-04-08 10:31:37,0.0,0,0\n2018-04-08 10:31:38,1.0,1,0\n")
    said = _error(lambda: read_truth(path))
    assert "date" in said and "'seconds'" in said and "--truth-columns t=seconds,x=x,y=y" in said


def test_a_clock_time_without_a_numeric_time_column_asks_for_seconds(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("clock,speed,steer\n10:31:37.005,1.0,0.0\n10:31:37.105,1.0,0.0\n")
    said = _error(lambda: read_csv_log(path, {"t": "clock", "speed": "speed", "steer": "steer"}))
    assert "line 2" in said and "'10:31:37.005'" in said and "time-of-day" in said
    assert "seconds" in said


def test_a_headerless_file_whose_time_is_clock_text_says_so_too(tmp_path):
    """The same time-of-day text in a file without a header (KITTI's OXTS timestamps beside
    their values: a date, then a clock): its first line was told "mixes names and numbers ...
    delete it if it is a header" (user study); it is told, as with a header, that the time
    column holds clock text."""
    path = tmp_path / "oxts.txt"
    path.write_text("2011-09-30 13:12:10.525 48.97 8.47 3.1\n2011-09-30 13:12:10.635 48.97 8.47 3.2\n")
    said = _error(lambda: read_csv_log(path, ["_", "t", "_", "_", "speed"]))
    assert "line 1" in said and "'13:12:10.525' is time-of-day text, not a number" in said
    assert "mixes names and numbers" not in said


def test_the_cli_says_it_in_one_line(run_cli, logger_csv, tmp_path):
    robot = tmp_path / "car.toml"
    robot.write_text('[robot]\ntype = "car"\nwheel_base = 2.69\nsteering_ratio = 15\n')
    columns = "t=Seconds,speed_mph=Speed (mph),steer_deg=Steering Angle"
    code, out, err = run_cli("track", logger_csv, "--robot", robot, "--columns", columns)
    assert code == 2 and out == "" and err.count("\n") == 1 and err.startswith("odomkit: error: ")
    assert "did you mean 'Speed (MPH)'" in err
    code, out, err = run_cli("track", logger_csv, "--robot", robot, "--columns",
                             "t=Time,speed_mph=Speed (MPH),steer_deg=Steering Angle")
    assert code == 2 and err.count("\n") == 1 and "t=Seconds" in err


def test_a_first_line_of_labelled_values_is_told_as_data_with_its_fields(tmp_path):
    """A course's tricycle log writes each value after its label (``time: T ticks: S D
    model_pose: x y θ``): its first line was taken for a header and the hint said "map it as
    t=time:", which then failed on the next line (user study). The line is data; the labels
    and the fields after each are named, and the columns given in order read it."""
    path = tmp_path / "dataset.txt"
    rows = [f"time: {100.0 + 0.05 * k:.3f} ticks: {290 + k} {1000 + 7 * k} model_pose: 0 0 0"
            for k in range(40)]
    path.write_text("#kinematic_model: traction_drive_wheel\n" + "\n".join(rows) + "\n")
    said = _error(lambda: read_csv_log(path, None))
    assert "its first line is data, each value after a label, not a header" in said
    assert "'time:' (field 2), 'ticks:' (fields 4-5), 'model_pose:' (fields 7-9) of 9" in said
    assert "map it as t=" not in said
    log = read_csv_log(path, ["_", "t", "_", "steer", "ticks"], cumulative=True)
    assert log.t[1] - log.t[0] == pytest.approx(0.05) and log.channels["ticks"][1] == 7
