"""The shared truth options: a truth file, or the log's own ground truth, one per log."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.log import OdometryLog
from odomkit.workflows.truth import TruthOptions, load_truth, truth_options_per_log


def test_a_file_wins_over_the_log_and_sigma_reaches_the_truth(tmp_path):
    path = tmp_path / "gt.csv"
    path.write_text("t,x,y\n0,0,0\n1,1,0\n")
    log = OdometryLog(np.array([0.0, 1.0]), {"dist": np.zeros(2)}, np.zeros((2, 3)), "log.csv")
    from_file = load_truth(TruthOptions(path, sigma=0.01), log)
    assert from_file.source == str(path) and from_file.theta is None and from_file.sigma == 0.01
    from_log = load_truth(TruthOptions(sigma=0.02), log)
    assert from_log.source == "log.csv" and from_log.sigma == 0.02 and from_log.theta is not None
    assert load_truth(TruthOptions(), OdometryLog(np.zeros(1), {"dist": np.zeros(1)})) is None
    assert load_truth(TruthOptions()) is None


def test_one_truth_per_log():
    base = TruthOptions(format="tum", sigma=0.1)
    assert truth_options_per_log(base, [], 3) == [base] * 3
    got = truth_options_per_log(base, [Path("a.tum"), Path("b.tum")], 2)
    assert [o.path for o in got] == [Path("a.tum"), Path("b.tum")] and got[1].sigma == 0.1
    with pytest.raises(InputError, match="one --truth per log"):
        truth_options_per_log(base, [Path("a.tum")], 2)


def test_track_starts_a_reversing_robot_facing_its_body_heading_from_position_only_truth(tmp_path):
    """``track --truth`` with position-only truth: the start heading aligns the odometry's own
    path to the fixes (odomkit.truth.start_pose with the odometry), so a robot that backs up
    from the first row starts facing its body's way (the fixes only show the direction of
    travel, π away). Before, the start faced the direction of travel and the track ran off
    the other way: the final error was the path's length twice over."""
    from odomkit.workflows.track import run_track

    t = np.arange(0.0, 20.0, 0.05)
    speed, yaw_rate = -0.5 * np.ones_like(t), 0.05 * np.ones_like(t)
    log = tmp_path / "log.csv"
    # the log starts at 2 s; the fixes (5 Hz) from 0 s, so that some lie before its start
    np.savetxt(log, np.column_stack((t, speed, yaw_rate))[40:], delimiter=",", header="t,speed,yaw_rate",
               comments="")
    robot = tmp_path / "robot.toml"
    robot.write_text('[robot]\ntype = "unicycle"\n')
    # the true body heading is 1.0 rad at 0 s (1.1 at the log's start); it reverses on an arc
    theta = 1.0 + 0.05 * t
    x = np.cumsum(np.r_[0.0, (-0.5 * np.cos(theta[:-1] + 0.025 * 0.05)) * 0.05])
    y = np.cumsum(np.r_[0.0, (-0.5 * np.sin(theta[:-1] + 0.025 * 0.05)) * 0.05])
    fixes = tmp_path / "xy.csv"
    np.savetxt(fixes, np.column_stack((t[::4], x[::4], y[::4])), delimiter=",", header="t,x,y", comments="")
    from odomkit.workflows.logs import LogOptions

    run = run_track(log, robot, truth=TruthOptions(fixes, sigma=0.001), with_covariance=False,
                    log_options=LogOptions(columns="t=t,speed=speed,yaw_rate=yaw_rate"))
    assert run.track.poses[0, 2] == pytest.approx(1.1, abs=0.01)
    assert np.hypot(*(run.track.poses[-1, :2] - [x[-1], y[-1]])) < 0.02


def test_a_robot_files_clock_offset_applies_to_truth_files_not_to_a_logs_own_columns(tmp_path):
    """``[truth] time_offset`` is the clock of the truth files a robot was calibrated against:
    a log's own gt_* columns share the log's clock by construction and keep it, while
    ``--truth-time-offset`` (the user's word) moves either."""
    from odomkit.workflows.truth import clock_from_robot, resolved_truth

    robot = tmp_path / "r.toml"
    robot.write_text('[robot]\ntype = "unicycle"\n\n[truth]\ntime_offset = 0.3\n')
    t = np.arange(0.0, 5.0, 0.1)
    log = OdometryLog(t, {"speed": np.ones_like(t), "yaw_rate": np.zeros_like(t)},
                      np.column_stack((t, 0 * t, 0 * t)))
    truth_file = tmp_path / "gt.csv"
    np.savetxt(truth_file, np.column_stack((t, t, 0 * t)), delimiter=",", header="t,x,y", comments="")
    for fill in (clock_from_robot, resolved_truth):
        own, from_file = fill(robot, [TruthOptions(), TruthOptions(truth_file)])
        assert own.time_offset == 0.0 and from_file.time_offset == 0.3
        np.testing.assert_allclose(load_truth(own, log).t, t)
        np.testing.assert_allclose(load_truth(from_file, log).t, t - 0.3)
        (flagged,) = fill(robot, [TruthOptions(time_offset=0.1)])
        np.testing.assert_allclose(load_truth(flagged, log).t, t - 0.1)


def _circle_files(tmp_path, write_truth):
    """A unicycle's log on a circle (0.3 m/s, 0.2 rad/s, 60 s at 10 Hz) and its truth, written
    by ``write_truth(path, t, x, y, theta)``."""
    t = np.arange(0.0, 60.0, 0.1)
    theta = 0.2 * t
    x, y = 1.5 * np.sin(theta), 1.5 * (1 - np.cos(theta))
    log = tmp_path / "log.csv"
    log.write_text("t,speed,yaw_rate\n" + "".join(f"{ti:.1f},0.3,0.2\n" for ti in t))
    robot = tmp_path / "robot.toml"
    robot.write_text('[robot]\ntype = "unicycle"\n[noise]\nalpha_ss = 0.001\npsd_gyro = 1e-5\n')
    truth = tmp_path / "truth.txt"
    write_truth(truth, t, x, y, theta)
    return log, robot, truth


def _tum(quaternion):
    def write(path, t, x, y, theta):
        rows = [(ti, xi, yi, 0.0, *quaternion(th)) for ti, xi, yi, th in zip(t, x, y, theta, strict=True)]
        path.write_text("".join(" ".join(f"{v:.9g}" for v in row) + "\n" for row in rows))
    return write


@pytest.mark.parametrize("case", ["degrees", "quaternion w first", "right"])
def test_a_truth_heading_that_does_not_follow_its_motion_is_warned_about(tmp_path, run_cli, case):
    """A heading in degrees read as radians, or a TUM quaternion written w first (yaw 0
    throughout), scored every window from a heading that is not the robot's, silently
    (heading NEES 243 and 18.5 on this circle, final error 0 m); now evaluate says so and
    names the likely causes. The right TUM file says nothing."""
    writers = {
        "degrees": lambda p, t, x, y, th: p.write_text(
            "t,x,y,theta\n" + "".join(f"{a:.2f},{b:.6f},{c:.6f},{np.degrees(d):.4f}\n"
                                      for a, b, c, d in zip(t, x, y, th, strict=True))),
        "quaternion w first": _tum(lambda th: (np.cos(th / 2), 0.0, 0.0, np.sin(th / 2))),
        "right": _tum(lambda th: (0.0, 0.0, np.sin(th / 2), np.cos(th / 2))),
    }
    log, robot, truth = _circle_files(tmp_path, writers[case])
    code, out, err = run_cli("evaluate", log, "--robot", robot, "--truth", truth, "--json")
    assert code == 0, err
    import json

    said = [w for w in json.loads(out)["warnings"] if "does not follow the direction" in w]
    if case == "right":
        assert said == []
    else:
        [text] = said
        assert str(truth) in text and "theta_deg" in text and "qx qy qz qw" in text
        assert "does not follow the direction" in err


@pytest.mark.parametrize("case", ["millimetres", "milliseconds"])
def test_a_truth_in_another_unit_is_named(tmp_path, run_cli, case):
    """Positions in mm read as metres (a Vicon export) scored ATE 2166 m with nothing said;
    times in ms read as seconds overlapped the log in its first 60 ms and evaluate stopped at
    "no window travels --min-travel". Both now name the unit and its flag."""
    scale_xy, scale_t = (1000.0, 1.0) if case == "millimetres" else (1.0, 1000.0)
    log, robot, truth = _circle_files(tmp_path, lambda p, t, x, y, th: p.write_text(
        "t,x,y,theta\n" + "".join(f"{scale_t * a:.3f},{scale_xy * b:.6f},{scale_xy * c:.6f},{d:.6f}\n"
                                  for a, b, c, d in zip(t, x, y, th, strict=True))))
    code, out, err = run_cli("evaluate", log, "--robot", robot, "--truth", truth)
    if case == "millimetres":
        assert code == 0 and "move at 300 m/s" in err and "x_mm, y_mm" in err
    else:
        assert "the truth's time is likely in ms read as seconds (--truth-time-unit ms)" in err
    code, out, err = run_cli("evaluate", log, "--robot", robot, "--truth", truth, "--truth-time-unit",
                             "ms" if case == "milliseconds" else "s", *(
                                 ["--truth-columns", "t,x_mm,y_mm,theta"] if case == "millimetres" else []))
    assert code == 0 and "m/s" not in err and "read as seconds" not in err, err


def test_a_truth_that_merely_runs_longer_is_no_unit(tmp_path):
    """A GPS logging for 17 hours around a 60 s drive spans 1000 times the log, on the same
    clock: it starts elsewhere, so no time unit is blamed."""
    import warnings

    t = np.arange(-30000.0, 30000.0, 1.0)
    path = tmp_path / "gps.csv"
    path.write_text("t,x,y\n" + "".join(f"{ti:.1f},{0.3 * ti:.3f},0\n" for ti in t))
    log = OdometryLog(np.arange(0.0, 60.0, 0.1), {"speed": np.full(600, 0.3)}, source="log.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load_truth(TruthOptions(path), log) is not None


def test_warnings_from_worker_processes_reach_the_json_once(tmp_path, run_cli):
    """fit-noise --workers 2 reads the logs in other processes: their warnings (here a truth
    heading in degrees) went to the workers' stderr in Python's raw form and were missing
    from the JSON; now they come back as the command's own, each once."""
    paths = []
    for k in (1, 2):
        folder = tmp_path / f"run{k}"
        folder.mkdir()
        log, robot, truth = _circle_files(folder, lambda p, t, x, y, th: p.write_text(
            "t,x,y,theta\n" + "".join(f"{a:.2f},{b:.6f},{c:.6f},{np.degrees(d):.4f}\n"
                                      for a, b, c, d in zip(t, x, y, th, strict=True))))
        paths += ["--log", log, "--truth", truth]
    code, out, err = run_cli("fit-noise", "--robot", robot, *paths, "--window", "10s", "--workers", "2",
                             "--out", tmp_path / "fitted.toml", "--json")
    # The fit itself fails on such windows (exit 2, one error line); the truth's warning,
    # raised in the workers, comes first as the command's own line, both files named in it.
    assert code == 2 and "UserWarning" not in err, err
    [said] = [line for line in err.splitlines() if "does not follow the direction" in line]
    assert said.startswith("odomkit: warning: 2 logs (") and "run1" in said and "run2" in said


def test_a_span_cut_from_a_long_log_is_no_time_unit(tmp_path, run_cli):
    """--span 0:2 of a 30 min log against its 30 min truth: the cut log spans 1.9 s, a
    factor 947 against the truth, which was blamed on the truth's time unit."""
    t = np.arange(0.0, 1800.0, 0.1)
    log = tmp_path / "log.csv"
    log.write_text("t,speed,yaw_rate\n" + "".join(f"{ti:.1f},0.5,0\n" for ti in t))
    truth = tmp_path / "truth.csv"
    truth.write_text("t,x,y,theta\n" + "".join(f"{ti:.1f},{0.5 * ti:.3f},0,0\n" for ti in t))
    robot = tmp_path / "robot.toml"
    robot.write_text('[robot]\ntype = "unicycle"\n[noise]\nalpha_ss = 0.001\npsd_gyro = 1e-5\n')
    code, _, err = run_cli("track", log, "--robot", robot, "--truth", truth, "--span", "0:2")
    assert code == 0 and "time is likely in" not in err, err


@pytest.mark.parametrize("flag", [("--truth-up", "+y"), ("--truth-time-unit", "ms"),
                                  ("--truth-columns", "t,x,y")])
def test_a_truth_file_flag_without_a_truth_file_is_refused(run_cli, flag):
    """--truth-up (or any flag that reads a truth file) with the log's own ground truth was
    ignored without a word: the user believed the truth turned, or its clock scaled."""
    from odomkit.data import builtin_data_path

    code, _, err = run_cli("evaluate", builtin_data_path("230620202042_run-01.csv"), "--robot",
                           builtin_data_path("optiodom_diff.toml"), *flag)
    assert code == 2 and f"{flag[0]} reads a --truth file, and none is given" in err, err
    assert len(err.strip().splitlines()) == 1


def test_check_says_a_heading_off_its_motion_once(tmp_path, run_cli):
    """check's truth_heading FAILs on a heading in degrees; reading the truth warned of the
    same beside it, so the user read it twice."""
    log, robot, truth = _circle_files(tmp_path, lambda p, t, x, y, th: p.write_text(
        "t,x,y,theta\n" + "".join(f"{a:.2f},{b:.6f},{c:.6f},{np.degrees(d):.4f}\n"
                                  for a, b, c, d in zip(t, x, y, th, strict=True))))
    code, out, err = run_cli("check", log, "--robot", robot, "--truth", truth)
    said = (out + err).count("does not follow the direction its positions move in")
    assert said == 1 and "FAIL truth_heading" in out, out + err
