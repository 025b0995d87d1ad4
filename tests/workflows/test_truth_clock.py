"""The truth's clock offset through the CLI: ``--truth-time-offset`` and the robot file's
``[truth] time_offset`` (a fix stamped t is the pose at log time t − offset).

A car (rear-axle bicycle, L = 2.7 m, speed scale 1.015, steering offset 0.01 rad) drives
5 min at 5–13 m/s with smooth random turns; its log is written at 20 Hz and its true path
is odomkit's own dead reckoning of that log with the true car, so the only errors are the
ones put in: a 5 Hz GPS of 5 cm noise whose clock runs ``delta`` late (the fix stamped s
is the true position at log time s − delta). Each test checks a command's output against
that simulation or against the GPS file interpolated directly in numpy.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from odomkit.robot import Car, Unicycle
from odomkit.track import dead_reckon_log
from odomkit.workflows.logs import LogOptions, load_log

COLUMNS = "t=t,speed=speed,steer=steer"
TRUE_CAR = Car(2.7, 0.0, "rear", steering_offset=0.01, c_scale=1.015)
GPS_SIGMA = 0.05
NOMINAL = '[robot]\ntype = "car"\nwheel_base = 2.7\n'
#: The true car with a white noise table (for fit-noise and evaluate).
TRUE_WITH_NOISE = ('[robot]\ntype = "car"\nwheel_base = 2.7\nsteering_offset = 0.01\nc_scale = 1.015\n\n'
                   '[noise]\nsigma_speed = 0.05\nsigma_steer = 0.002\n')


def drive(folder: Path, delta: float, seed: int = 3, minutes: float = 5.0) -> dict[str, Path]:
    """Write ``drive.csv`` (t, speed, steer at 20 Hz) and ``gps.csv`` (t, x, y at 5 Hz, on a
    clock ``delta`` s late, stamps off the log's rows) into ``folder``."""
    rng = np.random.default_rng(seed)
    dt = 0.05
    t = np.round(np.arange(int(minutes * 60 / dt)) * dt, 6)
    speed = 8.0 + 3.0 * np.sin(t / 23.0) + 2.0 * np.sin(t / 7.0 + 1.0)
    knots = rng.uniform(-0.15, 0.15, int(t[-1] / 8.0) + 2)
    steer = np.interp(t, np.arange(knots.size) * 8.0, knots)
    log = folder / "drive.csv"
    np.savetxt(log, np.column_stack([t, speed, steer]), delimiter=",", header="t,speed,steer",
               comments="", fmt="%.9g")
    # The true path from the log as odomkit reads it back, so the file's rounding is in it.
    read = load_log(log, TRUE_CAR, LogOptions(columns=COLUMNS))
    poses = dead_reckon_log(read, TRUE_CAR, pose0=(20.0, -10.0, 0.4)).poses
    stamps = np.arange(0.013, t[-1], 0.2)
    # Fixes only while the car is logged: np.interp would hold the path's ends still, and a
    # fix held still while the car drives at 8 m/s is a spike no vehicle can make.
    stamps = stamps[(stamps - delta >= 0.0) & (stamps - delta <= t[-1])]
    xy = np.column_stack([np.interp(stamps - delta, read.t, poses[:, i]) for i in (0, 1)])
    gps = folder / "gps.csv"
    np.savetxt(gps, np.column_stack([stamps, xy + rng.normal(0.0, GPS_SIGMA, xy.shape)]), delimiter=",",
               header="t,x,y", comments="", fmt="%.9g")
    return {"log": log, "gps": gps}


def robot_file(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


def ok_json(run_cli, *args) -> dict:
    code, out, err = run_cli(*args, "--columns", COLUMNS, "--json")
    assert code == 0, err
    return json.loads(out)


def truth_table(path: Path) -> dict:
    return tomllib.loads(path.read_text()).get("truth", {})


def test_calibrate_fits_the_clock_offset_and_writes_it_beside_the_input_truth_table(run_cli, tmp_path):
    """GPS 0.3 s late: the fitted offset is within 4 of its standard errors of 0.3 s (the
    model is exact, the fixes' noise independent, so its interval is honest; it is about
    0.3 ms here). --out-robot keeps the input's [truth] sigma and adds that offset; given
    --truth-time-offset, nothing is fitted and the given value is reported and written."""
    files = drive(tmp_path, 0.3)
    robot = robot_file(tmp_path, "car.toml", NOMINAL + "\n[truth]\nsigma = 0.5\n")
    cal = ok_json(run_cli, "calibrate", files["log"], "--robot", robot, "--truth", files["gps"],
                  "--out-robot", tmp_path / "cal.toml")
    offset = cal["truth_time_offset"]
    assert offset["fitted"] is True
    assert 0 < offset["std_error"] < 0.002
    assert abs(offset["value"] - 0.3) < 4 * offset["std_error"], offset
    # the car too, now that the clock is right (5 cm fixes on an exact model)
    assert cal["parameters"]["c_scale"] == pytest.approx(1.015, abs=1e-3)
    assert cal["parameters"]["steering_offset"] == pytest.approx(0.01, abs=1e-4)
    written = truth_table(tmp_path / "cal.toml")
    assert written == {"sigma": 0.5, "time_offset": offset["value"]}

    given = ok_json(run_cli, "calibrate", files["log"], "--robot", robot, "--truth", files["gps"],
                    "--truth-time-offset", "0.2", "--out-robot", tmp_path / "given.toml")
    assert given["truth_time_offset"] == {"value": 0.2, "std_error": 0.0, "fitted": False}
    assert truth_table(tmp_path / "given.toml") == {"sigma": 0.5, "time_offset": 0.2}


def _gt_columns(path: Path) -> tuple[np.ndarray, np.ndarray]:
    table = np.genfromtxt(path, delimiter=",", names=True)
    return table["t"], np.column_stack([table["gt_x"], table["gt_y"]])


def _gps_at(gps: Path, times: np.ndarray) -> np.ndarray:
    """The GPS file interpolated at ``times`` on its own clock, NaN outside its span."""
    fixes = np.loadtxt(gps, delimiter=",", skiprows=1)
    inside = (times >= fixes[0, 0]) & (times <= fixes[-1, 0])
    out = np.column_stack([np.interp(times, fixes[:, 0], fixes[:, i]) for i in (1, 2)])
    out[~inside] = np.nan
    return out


@pytest.mark.parametrize("offset", [0.3, -0.3])
def test_track_applies_the_robot_files_offset_unless_the_flag_overrides_it(run_cli, tmp_path, offset):
    """track's gt_x, gt_y at log time t are the GPS at its stamp t + offset (a negative
    offset is a truth clock running early, accepted), and --truth-time-offset 0 gives the
    GPS at t; the rows the shifted GPS does not cover are empty."""
    files = drive(tmp_path, offset, minutes=1.0)
    robot = robot_file(tmp_path, "car.toml", TRUE_WITH_NOISE + f"\n[truth]\ntime_offset = {offset}\n")
    for name, extra, shift in (("file.csv", (), offset), ("zero.csv", ("--truth-time-offset", "0"), 0.0)):
        ok_json(run_cli, "track", files["log"], "--robot", robot, "--truth", files["gps"], "--no-covariance",
                "--initial-pose", "0,0,0", "--out", tmp_path / name, *extra)
        t, gt = _gt_columns(tmp_path / name)
        expected = _gps_at(files["gps"], t + shift)
        assert np.array_equal(np.isnan(gt), np.isnan(expected))
        assert np.isnan(gt).any(axis=1).sum() >= 1  # the ends the shifted GPS misses are left empty
        np.testing.assert_allclose(gt, expected, rtol=0, atol=1e-9)


def test_fit_noise_applies_the_robot_files_offset_and_writes_it_on(run_cli, tmp_path):
    """GPS 0.4 s late on a car at 5–13 m/s with perfect odometry. With the robot file's
    offset (0.4 s) fit-noise finds no clock noise in the truth and writes the offset into
    --out's [truth]; told 0 instead, the 0.4 s shows up as the truth's clock noise (a
    constant error of 0.4 s has an RMS of 0.4 s) and no offset is written."""
    files = drive(tmp_path, 0.4, seed=5)
    robot = robot_file(tmp_path, "car.toml", TRUE_WITH_NOISE + "\n[truth]\ntime_offset = 0.4\n")
    common = ("fit-noise", "--log", files["log"], "--robot", robot, "--truth", files["gps"],
              "--window", "30s")
    applied = ok_json(run_cli, *common, "--out", tmp_path / "fit.toml")
    assert applied["truth_noise"]["truth_time_sigma"] < 0.05
    assert truth_table(tmp_path / "fit.toml")["time_offset"] == 0.4
    blind = ok_json(run_cli, *common, "--truth-time-offset", "0", "--out", tmp_path / "blind.toml")
    assert 0.3 < blind["truth_noise"]["truth_time_sigma"] < 0.5
    assert truth_table(tmp_path / "blind.toml").get("time_offset", 0.0) == 0.0


def test_evaluate_applies_the_robot_files_offset(run_cli, tmp_path):
    """The true car against a GPS 0.4 s late (3.2 m along track at 8 m/s): with the robot
    file's offset the windows' NEES is honest (mean ≤ 2, the χ²₂ mean, with a 5 cm truth and
    perfect odometry it is lower); told 0 instead, the 0.4 s is an error of metres against
    a covariance of centimetres. The file's offset gives exactly what the flag gives."""
    files = drive(tmp_path, 0.4, seed=5)
    robot = robot_file(tmp_path, "car.toml",
                       TRUE_WITH_NOISE + f"\n[truth]\nsigma = {GPS_SIGMA}\ntime_offset = 0.4\n")
    common = ("evaluate", files["log"], "--robot", robot, "--truth", files["gps"], "--window", "30s")
    from_file = ok_json(run_cli, *common)
    flag = ok_json(run_cli, *common, "--truth-time-offset", "0.4")
    blind = ok_json(run_cli, *common, "--truth-time-offset", "0")
    assert from_file["windows"] >= 8
    assert from_file["nees_position_mean"] < 2.0 and from_file["inside_95_fraction"] >= 0.8
    assert blind["nees_position_mean"] > 20 * from_file["nees_position_mean"]
    assert blind["ate_rmse"] > 5 * from_file["ate_rmse"]
    for key in ("nees_position_mean", "ate_rmse", "final_position_error", "windows"):
        assert from_file[key] == flag[key], key


def _error_line(run_cli, *args) -> str:
    code, out, err = run_cli(*args)
    assert code == 2, (code, out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("odomkit: error:"), err
    return lines[0]


def test_bad_offsets_and_truth_tables_are_one_line_errors(run_cli, tmp_path):
    files = drive(tmp_path, 0.0, minutes=0.5)
    robot = robot_file(tmp_path, "car.toml", NOMINAL)
    track = ("track", files["log"], "--robot", robot, "--truth", files["gps"], "--columns", COLUMNS)
    for bad in ("nan", "inf"):
        line = _error_line(run_cli, *track, "--truth-time-offset", bad)
        assert "--truth-time-offset" in line
    negative = robot_file(tmp_path, "negative.toml", NOMINAL + "\n[truth]\nsigma = -1\n")
    line = _error_line(run_cli, "track", files["log"], "--robot", negative, "--truth", files["gps"],
                       "--columns", COLUMNS)
    assert "[truth] sigma" in line and "negative.toml" in line


def test_a_non_finite_offset_in_the_robot_file_is_named(run_cli, tmp_path):
    files = drive(tmp_path, 0.0, minutes=0.5)
    robot = robot_file(tmp_path, "car.toml", NOMINAL + "\n[truth]\ntime_offset = nan\n")
    line = _error_line(run_cli, "track", files["log"], "--robot", robot, "--truth", files["gps"],
                       "--columns", COLUMNS)
    assert "[truth] time_offset" in line and "car.toml" in line


def test_fit_amcl_applies_the_robot_files_offset(run_cli, tmp_path):
    """A unicycle's log against a motion capture with heading at 20 Hz, 0.4 s late: the
    robot file's offset gives the same fit as --truth-time-offset 0.4."""
    t = np.round(np.arange(3000) * 0.05, 6)
    log = tmp_path / "log.csv"
    np.savetxt(log, np.column_stack([t, 1.0 + 0.3 * np.sin(t / 7.0), 0.3 * np.sin(t / 11.0)]), delimiter=",",
               header="t,speed,yaw_rate", comments="", fmt="%.9g")
    columns = "t=t,speed=speed,yaw_rate=yaw_rate"
    unicycle = Unicycle()
    poses = dead_reckon_log(load_log(log, unicycle, LogOptions(columns=columns)), unicycle,
                            pose0=(0.0, 0.0, 0.0)).poses
    stamps = np.arange(0.013, t[-1], 0.05)
    mocap = tmp_path / "mocap.csv"
    np.savetxt(mocap, np.column_stack([stamps, *(np.interp(stamps - 0.4, t, poses[:, i]) for i in range(3))]),
               delimiter=",", header="t,x,y,theta", comments="", fmt="%.9g")
    robot = robot_file(tmp_path, "unicycle.toml",
                       '[robot]\ntype = "unicycle"\n\n[truth]\ntime_offset = 0.4\n')

    def fit(*extra):
        code, out, err = run_cli("fit-amcl", log, "--robot", robot, "--truth", mocap, "--columns", columns,
                                 "--json", *extra)
        assert code == 0, err
        return json.loads(out)

    from_file, flag = fit(), fit("--truth-time-offset", "0.4")
    assert from_file["log_likelihood"] == flag["log_likelihood"]
    assert from_file["alpha"] == flag["alpha"]


def test_calibrate_prints_the_fitted_clock_offset_in_its_text(run_cli, tmp_path):
    """The text output shows the fitted offset with its standard error, equal to the JSON's,
    and a given one as given: a GPS user reads it without --json."""
    files = drive(tmp_path, 0.3)
    robot = robot_file(tmp_path, "car.toml", NOMINAL)
    args = ("calibrate", files["log"], "--robot", robot, "--truth", files["gps"], "--columns", COLUMNS)
    code, text, err = run_cli(*args)
    assert code == 0, err
    fitted = ok_json(run_cli, "calibrate", files["log"], "--robot", robot, "--truth", files["gps"])
    offset = fitted["truth_time_offset"]
    line = next(x for x in text.splitlines() if "truth clock" in x)
    assert f"{offset['value']:+.6f} s ± {offset['std_error']:.2g}" in line
    assert abs(offset["value"] - 0.3) < 0.01
    assert f"(the truth's fixes lag the log by {abs(offset['value']):.3g} s)" in line
    code, text, _ = run_cli(*args, "--truth-time-offset", "0.25")
    assert code == 0 and "+0.250000 s (given)" in text
    # an early truth clock leads: a negative lag read oddly
    code, text, _ = run_cli(*args, "--truth-time-offset", "-0.25")
    assert code == 0 and "-0.250000 s (given)  (the truth's fixes lead the log by 0.25 s)" in text


def test_the_report_shows_the_clock_offset_it_fitted(run_cli, tmp_path):
    """The report calibrates against a GPS 0.3 s late and fits its clock with the robot, and
    every later figure uses it; its calibration table showed the robot's parameters only.
    The offset and its standard error are shown, keyed, equal to calibrate's JSON."""
    import re

    files = drive(tmp_path, 0.3, minutes=2.0)
    robot = robot_file(tmp_path, "car.toml", TRUE_WITH_NOISE)
    cal = ok_json(run_cli, "calibrate", files["log"], "--robot", robot, "--truth", files["gps"])
    page = tmp_path / "report.html"
    code, _, err = run_cli("report", files["log"], "--robot", robot, "--truth", files["gps"], "--columns",
                           COLUMNS, "--out", page)
    assert code == 0, err
    shown = {m.group(1): float(m.group(2)) for m in re.finditer(
        r'data-key="calibration\.((?:std_error\.)?truth_time_offset)" data-value="([^"]+)"',
        page.read_text(encoding="utf-8"))}
    offset = cal["truth_time_offset"]
    assert shown["truth_time_offset"] == pytest.approx(offset["value"], rel=1e-9)
    assert shown["std_error.truth_time_offset"] == pytest.approx(offset["std_error"], rel=1e-9)
    assert abs(offset["value"] - 0.3) < 4 * offset["std_error"] + 0.01
