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
