"""``odomkit track`` and ``odomkit demo`` end to end, including bad input (exit 2)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from odomkit.data import builtin_data_path

ROBOT = builtin_data_path("optiodom_diff.toml")
RUN = builtin_data_path("230620202042_run-01.csv")


def test_track_json_and_outputs(run_cli, tmp_path):
    out, tum = tmp_path / "t.csv", tmp_path / "t.tum"
    code, stdout, _ = run_cli("track", RUN, "--robot", ROBOT, "--no-covariance",
                              "--out", out, "--tum", tum, "--json")
    assert code == 0
    summary = json.loads(stdout)
    table = np.genfromtxt(out, delimiter=",", names=True)
    assert table.shape[0] == summary["samples"]
    assert np.isnan(table["cov_xx"]).all()  # empty until a noise model is given
    assert summary["pose"][0] == pytest.approx(table["x"][-1], abs=1e-9)
    # TUM quaternion encodes the heading: θ = 2·atan2(qz, qw)
    tum_rows = np.loadtxt(tum)
    assert np.all(tum_rows[:, 7] >= 0)  # the hemisphere with q_w >= 0, as evo expects
    assert np.allclose(2 * np.arctan2(tum_rows[:, 6], tum_rows[:, 7]),
                       np.angle(np.exp(1j * table["theta"])), atol=1e-8)
    # a second run must not overwrite without --force
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--out", out, "--no-covariance")
    assert code == 2 and "exists already" in err


@pytest.mark.parametrize(("args", "message"), [
    (["track", "missing.csv", "--robot", str(ROBOT)], "missing.csv: no such file"),
    (["track", str(RUN), "--robot", "nothere.toml"], "nothere.toml: no such robot file"),
    (["track", str(RUN), "--robot", str(ROBOT), "--method", "rk4"], "unknown integration method"),
    (["track", str(RUN), "--robot", str(ROBOT), "--initial-pose", "1,2"], "three numbers"),
])
def test_bad_input_exits_2_with_one_line(run_cli, args, message):
    code, _, err = run_cli(*args)
    assert code == 2
    assert message in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_bad_log_file_names_the_line(run_cli, tmp_path):
    bad = tmp_path / "x_run-01.csv"
    bad.write_text("0,0,0,0,0,0\n0.05,0,0,0,1\n")
    code, _, err = run_cli("track", bad, "--robot", ROBOT)
    assert code == 2 and "line 2: expected 6 columns, found 5" in err


@pytest.mark.slow
def test_demo_runs_on_builtin_data_and_calibration_helps(run_cli, tmp_path):
    code, stdout, err = run_cli("demo", "--out", tmp_path)
    assert code == 0, err
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert len(summary["runs"]) == 6
    cal = summary["calibration"]
    # Ground truth (OptiTrack) judges the calibration: systematic error drops 5x at least.
    assert cal["exact"]["e_max_syst_after"] < cal["e_max_syst_before"] / 5
    assert cal["umbmark"]["e_max_syst_after"] < cal["e_max_syst_before"] / 5
    for stem in summary["runs"]:
        assert (tmp_path / f"{stem}_track.csv").is_file() and (tmp_path / f"{stem}.tum").is_file()
    assert "calibrated_robot.toml" in stdout
    # a second run without --force refuses to overwrite
    code, _, err = run_cli("demo", "--out", tmp_path)
    assert code == 2 and "exists already" in err


def test_track_with_noise_fills_covariance_and_ros_export(run_cli, tmp_path):
    out = tmp_path / "t.csv"
    code, stdout, err = run_cli("track", RUN, "--robot", ROBOT, "--out", out, "--json")
    assert code == 0, err
    summary = json.loads(stdout)
    table = np.genfromtxt(out, delimiter=",", names=True)
    cov = np.array(summary["cov"])
    assert cov == pytest.approx(np.array([[table["cov_xx"][-1], table["cov_xy"][-1], table["cov_xtheta"][-1]],
                                          [table["cov_xy"][-1], table["cov_yy"][-1], table["cov_ytheta"][-1]],
                                          [table["cov_xtheta"][-1], table["cov_ytheta"][-1],
                                           table["cov_thetatheta"][-1]]]), rel=1e-8)
    assert np.all(np.diff(table["cov_thetatheta"]) >= 0)  # heading variance never shrinks
    ros = np.array(summary["ros_pose_covariance"]).reshape(6, 6)
    assert ros[np.ix_([0, 1, 5], [0, 1, 5])] == pytest.approx(cov)
    assert ros[2, 2] == ros[3, 3] == ros[4, 4] > 1e3  # z, roll, pitch: unobserved


@pytest.mark.parametrize(("body", "message"), [
    ('[robot]\ntype = "diff"\nwheel_base = -0.2\nm_per_tick = 1e-4\n', "wheel_base must be a positive"),
    ('[robot]\ntype = "diff"\nm_per_tick = 1e-4\n', "needs 'wheel_base'"),
])
def test_bad_robot_file_exits_2(run_cli, tmp_path, body, message):
    robot = tmp_path / "r.toml"
    robot.write_text(body)
    code, _, err = run_cli("track", RUN, "--robot", robot)
    assert code == 2 and message in err and str(robot) in err


def test_both_covariance_engines_agree_through_the_cli(run_cli):
    results = {}
    for engine in ("recursion", "transition"):
        code, stdout, err = run_cli("track", RUN, "--robot", ROBOT, "--engine", engine, "--json")
        assert code == 0, err
        results[engine] = np.array(json.loads(stdout)["cov"])
    # Kelly's transition solution equals the recursion exactly in exact arithmetic.
    assert results["transition"] == pytest.approx(results["recursion"], rel=1e-9)
    code, _, err = run_cli("track", RUN, "--robot", ROBOT, "--engine", "kalman")
    assert code == 2 and "engine" in err


@pytest.mark.parametrize("cov", [True, False])
def test_track_csv_is_the_same_with_either_writer(tmp_path, monkeypatch, cov):
    pytest.importorskip("polars")
    import odomkit.io.table as table
    from odomkit.io.optiodom import read_run
    from odomkit.io.robotfile import read_robot
    from odomkit.io.trackio import write_track_csv
    from odomkit.track import dead_reckon_log

    robot, noise = read_robot(ROBOT)
    track = dead_reckon_log(read_run(RUN), robot, noise=noise[0] if cov else None)
    write_track_csv(tmp_path / "fast.csv", track)
    monkeypatch.setattr(table, "polars_module", lambda: None)
    import odomkit.io.trackio as trackio

    monkeypatch.setattr(trackio, "polars_module", lambda: None)
    write_track_csv(tmp_path / "slow.csv", track)
    fast = np.genfromtxt(tmp_path / "fast.csv", delimiter=",", names=True)
    slow = np.genfromtxt(tmp_path / "slow.csv", delimiter=",", names=True)
    assert fast.dtype.names == slow.dtype.names == tuple(
        "t,x,y,theta,cov_xx,cov_xy,cov_xtheta,cov_yy,cov_ytheta,cov_thetatheta".split(","))
    for name in fast.dtype.names:  # both round-trip every double exactly
        assert np.array_equal(fast[name], slow[name], equal_nan=True)
    assert np.array_equal(fast["x"], track.poses[:, 0])
    assert np.isnan(fast["cov_xx"]).all() != cov


def test_track_text_says_nothing_of_a_nees_it_does_not_show(run_cli):
    """The README's first track command: its text shows no NEES, so the note on rows whose
    singular covariance makes the NEES (given with --json, where the NEES is) is not said;
    it opened every OptiOdom run's text with a warning."""
    from odomkit.data import builtin_data_path

    run = builtin_data_path("230620202042_run-01.csv")
    robot = builtin_data_path("optiodom_diff.toml")
    code, _, err = run_cli("track", run, "--robot", robot)
    assert code == 0 and err == "", err
    code, _, err = run_cli("track", run, "--robot", robot, "--json")
    assert code == 0 and "singular covariance" in err


def _spinning_log(folder, psd_gyro):
    """100 s at 0.5 m/s on a circle of 5 m (0.1 rad/s), every 0.1 s, and a unicycle whose
    only noise is the gyro's: the heading variance is psd_gyro·t exactly (no cov0)."""
    t = np.round(0.1 * np.arange(1001), 10)
    log = folder / "spin.csv"
    np.savetxt(log, np.column_stack((t, np.full(t.size, 0.5), np.full(t.size, 0.1))), delimiter=",",
               header="t,speed,yaw_rate", comments="")
    robot = folder / f"spin{psd_gyro:g}.toml"
    robot.write_text(f'[robot]\ntype = "unicycle"\n\n[noise]\npsd_gyro = {psd_gyro!r}\n')
    return t, log, robot


def test_a_heading_past_the_first_order_limit_is_warned_of_once(run_cli, tmp_path):
    """User study s25 (MRCLAM, 887 s): track's final σθ of 2.73 rad and a ROS yaw variance of
    7 rad², beyond a heading spread uniformly round the circle (π²/3), came without a word.
    With gyro noise of 0.045 rad²/s the heading variance is 0.045·t (by hand): σθ passes
    FIRST_ORDER_SIGMA_THETA (0.2 rad) at the first row past t = 0.04/0.045 = 0.889 s, i.e.
    0.9 s, and ends at √4.5 rad with a variance beyond π²/3 in --json's ros_pose_covariance.
    One warning, in the JSON's warnings and on stderr alike; none at 0.0003 rad²/s (σθ 0.173
    rad at the end)."""
    from odomkit.calibrate.fit_noise import FIRST_ORDER_SIGMA_THETA

    t, log, robot = _spinning_log(tmp_path, 0.045)
    var = 0.045 * t
    first = t[np.argmax(np.sqrt(var) > FIRST_ORDER_SIGMA_THETA)]
    assert first == pytest.approx(0.9)
    code, out, err = run_cli("track", log, "--robot", robot, "--json")
    assert code == 0, err
    summary = json.loads(out)
    assert summary["ros_pose_covariance"][35] == pytest.approx(var[-1], rel=1e-9)  # numbers unchanged
    said = [w for w in summary.get("warnings", []) if "first-order limit" in w]
    assert len(said) == 1 and len(summary["warnings"]) == 1, summary.get("warnings")
    note = said[0]
    assert f"from {first:.4g} s into the log on" in note and f"reaches {np.sqrt(var[-1]):.3g} rad" in note
    assert "too small along the arc" in note and "windowed" in note
    assert f"{var[-1]:.4g} rad²" in note and "π²/3" in note and "robot_localization" in note
    code, _, err = run_cli("track", log, "--robot", robot)
    assert code == 0 and err.count("first-order limit") == 1, err
    _, log, quiet = _spinning_log(tmp_path, 0.0003)
    code, out, err = run_cli("track", log, "--robot", quiet, "--json")
    assert code == 0 and "warnings" not in json.loads(out), err


def test_a_bag_whose_yaw_variance_passes_the_uniform_circles_says_from_when(run_cli, tmp_path):
    """--bag-out writes every pose's covariance: the warning names the first message whose yaw
    variance passes π²/3 (0.045·t > 3.29 from t = 73.2 s on, by hand) and how many do, and
    that bag's messages read back through rosbags say the same (the numbers are unchanged)."""
    pytest.importorskip("rosbags", reason="the ros extra (rosbags) is not installed")
    from odomkit.io.bag import read_bag_odometry

    t, log, robot = _spinning_log(tmp_path, 0.045)
    beyond = 0.045 * t > np.pi**2 / 3
    first = t[np.argmax(beyond)]
    assert first == pytest.approx(73.2)
    bag = tmp_path / "spin.bag"
    code, out, err = run_cli("track", log, "--robot", robot, "--bag-out", bag, "--json")
    assert code == 0, err
    [note] = [w for w in json.loads(out).get("warnings", []) if "first-order limit" in w]
    assert f"--bag-out messages from {first:.4g} s into the log on, {int(beyond.sum())} of {t.size}" in note
    back = read_bag_odometry(bag)
    yaw = np.array(back.pose_covariance)[:, 35]
    assert back.t[np.argmax(yaw > np.pi**2 / 3)] - back.t[0] == pytest.approx(first)
    assert int((yaw > np.pi**2 / 3).sum()) == int(beyond.sum())


@pytest.mark.parametrize(("scale", "unit"), [(1e3, "ms"), (1e6, "us")])
def test_a_log_whose_time_is_in_another_unit_is_said_without_a_truth(run_cli, tmp_path, scale, unit):
    """A car's 20 Hz log with its time in ms (or µs), read as seconds and tracked without a
    truth: the track ran 1000× too long, exit 0, without a word. Now one warning names the
    flag; given it, the log reads as the one in seconds does, without the warning."""
    t = np.arange(0.0, 60.0, 0.05)
    rows = np.column_stack((t, np.full(t.size, 5.0), 0.05 * np.sin(t / 5.0)))
    robot = tmp_path / "car.toml"
    robot.write_text('[robot]\ntype = "car"\nwheel_base = 2.7\n')
    for name, times in (("s.csv", t), ("scaled.csv", t * scale)):
        np.savetxt(tmp_path / name, np.column_stack((times, rows[:, 1:])), delimiter=",",
                   header="t,speed,steer", comments="", fmt="%.9g")
    code, out, err = run_cli("track", tmp_path / "scaled.csv", "--robot", robot, "--json")
    assert code == 0 and f"slower than any odometry logger (1 s at most): is its time in {unit}? " \
        f"(--time-unit {unit})" in err, err
    code, given, err = run_cli("track", tmp_path / "scaled.csv", "--robot", robot, "--time-unit", unit,
                               "--json")
    assert code == 0 and "slower than any" not in err, err
    _, plain, _ = run_cli("track", tmp_path / "s.csv", "--robot", robot, "--json")
    assert json.loads(given)["pose"] == pytest.approx(json.loads(plain)["pose"], abs=1e-6)
