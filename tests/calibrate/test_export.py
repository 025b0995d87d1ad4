"""Robot-file and ROS 2 outputs of a calibration, and the ``calibrate`` CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.errors import InputError, OdomkitError
from odomkit.io.robotfile import read_robot, write_robot
from odomkit.io.ros import ros2_diff_drive_yaml, write_ros2_yaml
from odomkit.robot import DiffDrive, Tricycle

ROBOT = DiffDrive(0.2, 9.4e-5, 9.6e-5, 0.999, 1.002, 1.0064)


def test_robot_file_round_trips_and_is_not_overwritten(tmp_path):
    path = tmp_path / "robot.toml"
    write_robot(path, ROBOT)
    assert read_robot(path)[0] == ROBOT
    before = path.read_text()
    with pytest.raises(InputError, match="exists"):
        write_robot(path, DiffDrive(0.3))
    assert path.read_text() == before
    write_robot(path, DiffDrive(0.3), overwrite=True)
    assert read_robot(path)[0] == DiffDrive(0.3)


def test_ros2_yaml_has_the_standard_nesting_and_reproduces_the_odometry():
    yaml = pytest.importorskip("yaml")
    doc = yaml.safe_load(ros2_diff_drive_yaml(ROBOT, 0.042, controller_name="base_controller"))
    params = doc["base_controller"]["ros__parameters"]
    # The controller's wheel travel is radius·multiplier·angle and its wheel base
    # separation·multiplier; with a joint angle of one tick at the nominal (mean) radius
    # this must equal the calibrated metres per tick and effective wheel base.
    mean_tick = 0.5 * (9.4e-5 + 9.6e-5)
    assert params["wheel_separation"] * params["wheel_separation_multiplier"] == pytest.approx(
        ROBOT.effective_wheel_base, rel=1e-15)
    assert mean_tick * params["left_wheel_radius_multiplier"] == pytest.approx(ROBOT.scale_left, rel=1e-15)
    assert mean_tick * params["right_wheel_radius_multiplier"] == pytest.approx(ROBOT.scale_right, rel=1e-15)
    assert params["wheel_radius"] == 0.042


def test_ros2_yaml_refuses_bad_input(tmp_path):
    with pytest.raises(OdomkitError, match="DiffDrive"):
        ros2_diff_drive_yaml(Tricycle(0.15), 0.03)  # type: ignore[arg-type]
    with pytest.raises(OdomkitError, match="wheel_radius"):
        ros2_diff_drive_yaml(ROBOT, 0.0)
    with pytest.raises(OdomkitError, match="controller_name"):
        ros2_diff_drive_yaml(ROBOT, 0.04, controller_name="a b")
    path = tmp_path / "p.yaml"
    path.write_text("keep me")
    with pytest.raises(InputError, match="exists"):
        write_ros2_yaml(path, ROBOT, 0.04)
    assert path.read_text() == "keep me"


def _experiment(data_dir, name="230620202042"):
    folder = data_dir / "optiodom" / "diff" / "square" / name
    if not folder.is_dir():
        pytest.skip(f"OptiOdom experiment {name} not found under {data_dir}")
    return folder


def _robot_file(tmp_path, folder):
    from odomkit.io.optiodom import read_metadata

    meta = read_metadata(next(folder.glob("*_metadata.csv")))
    path = tmp_path / "nominal.toml"
    write_robot(path, meta.robot())
    return path, meta


def test_cli_exact_and_umbmark_on_real_runs(tmp_path, data_dir, run_cli):
    folder = _experiment(data_dir)
    robot_path, meta = _robot_file(tmp_path, folder)
    runs = sorted(str(p) for p in folder.glob("*_run-*.csv"))
    code, out, err = run_cli("calibrate", *runs, "--robot", robot_path, "--side", meta.side,
                             "--out-robot", tmp_path / "new.toml", "--ros-yaml", tmp_path / "p.yaml",
                             "--wheel-radius", 0.042, "--json")
    assert code == 0, err
    res = json.loads(out)
    assert res["scale_fixed"] is True
    assert res["e_max_syst_after"] < 0.2 * res["e_max_syst_before"]
    new_robot = read_robot(tmp_path / "new.toml")[0]
    assert new_robot.c_wheel_base == pytest.approx(res["parameters"]["c_wheel_base"], rel=1e-12)
    # The same runs through UMBmark give nearly the same corrections (both are right to
    # first order; they differ by the small-angle terms and the noise weighting).
    code, out, err = run_cli("calibrate", *runs, "--robot", robot_path, "--side", meta.side,
                             "--method", "umbmark", "--json")
    assert code == 0, err
    um = json.loads(out)
    assert um["E_b"] == pytest.approx(res["E_b"], rel=1e-3)
    assert um["E_d"] == pytest.approx(res["E_d"], rel=1e-4)
    # Outputs are never overwritten without --force: exit 2, one line on stderr.
    code, out, err = run_cli("calibrate", *runs, "--robot", robot_path, "--out-robot",
                             tmp_path / "new.toml")
    assert code == 2 and "exists" in err and len(err.strip().splitlines()) == 1


def test_cli_errors_are_one_line(tmp_path, data_dir, run_cli):
    folder = _experiment(data_dir)
    robot_path, _ = _robot_file(tmp_path, folder)
    cw_runs = sorted(str(p) for p in folder.glob("*_run-0[123].csv"))  # WWWccc: CW first
    code, _, err = run_cli("calibrate", *cw_runs, "--robot", robot_path)
    assert code == 2 and "same way" in err
    code, _, err = run_cli("calibrate", *cw_runs, "--robot", robot_path, "--method", "umbmark")
    assert code == 2 and "--side" in err
    code, _, err = run_cli("calibrate", *cw_runs, "--robot", robot_path, "--method", "umbmark",
                           "--side", 0.75)
    assert code == 2 and "both directions" in err
    code, _, err = run_cli("calibrate", *cw_runs, "--robot", robot_path, "--method", "best")
    assert code == 2 and "--method" in err


def test_cli_noise_fit_runs_on_repeated_logs(tmp_path, data_dir, run_cli):
    # OptiOdom has no forward-and-back runs; the squares of one experiment are repeated
    # runs of one path per direction, so the CCW runs of the 10-run experiment serve.
    folder = _experiment(data_dir, "230620202317")
    robot_path, _ = _robot_file(tmp_path, folder)
    runs = sorted(str(p) for p in folder.glob("*_run-*.csv"))[5:]
    code, out, err = run_cli("calibrate-noise", *runs, "--robot", robot_path, "--json")
    assert code == 0, err
    res = json.loads(out)
    assert res["n_runs"] == 5
    for side in ("left", "right"):
        lo, hi = res[f"ci_{side}"]
        assert 0 <= lo <= res[f"k_{side}"] <= hi and math.isfinite(hi)
    assert np.all(np.linalg.eigvalsh(np.array(res["cov_fitted"])) > 0)


def test_umbmark_command_reads_runs_through_this_module(tmp_path, data_dir, run_cli):
    # `odomkit umbmark --runs` (the UMBmark command) calls workflows.umbmark.umbmark_from_files with file
    # paths; the E_max,syst it reports must equal the library's on the same logs.
    from odomkit.calibrate.realdata import umbmark_from_runs
    from odomkit.io.optiodom import read_experiment

    folder = _experiment(data_dir)
    robot_path, meta = _robot_file(tmp_path, folder)
    runs = sorted(str(p) for p in folder.glob("*_run-*.csv"))
    code, out, err = run_cli("umbmark", "--runs", *runs, "--robot", robot_path, "--side", meta.side,
                             "--json")
    assert code == 0, err
    res = json.loads(out)
    ex = read_experiment(folder)
    ref = umbmark_from_runs(ex.runs, meta.robot(), meta.side)
    assert res["e_max_syst"] == pytest.approx(ref.e_max_syst_before, rel=1e-12)
    assert res["e_max_syst_after"] == pytest.approx(ref.e_max_syst_after, rel=1e-12)


def test_calibrate_noise_plot_is_written_and_never_overwritten(run_cli, tmp_path):
    """The --plot figure of fitted vs empirical 95 % ellipses (matplotlib extra)."""
    import pytest

    pytest.importorskip("matplotlib")
    from odomkit.data import builtin_data_path

    runs = [builtin_data_path(f"230620202042_run-0{i}.csv") for i in (1, 2, 3)]
    out = tmp_path / "noise.png"
    code, stdout, err = run_cli("calibrate-noise", *runs, "--robot",
                                builtin_data_path("optiodom_diff.toml"), "--plot", out)
    assert code == 0, err
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, _, err = run_cli("calibrate-noise", *runs, "--robot",
                           builtin_data_path("optiodom_diff.toml"), "--plot", out)
    assert code == 2 and "exists already" in err


def test_twist_covariance_of_a_car_and_a_unicycle_matches_their_sensors_simulated():
    """The car's steady motion at (v, ω) and its speed/steering white noise, simulated
    sensor by sensor through the car's kinematics (W = 10 updates of T = 0.02 s, the
    published velocity the mean): the sample covariance matches within 5 standard
    errors. The unicycle's is Kelly's: var v = α_ss·v/(W T), var ω = σ_gg/(W T)."""
    import math

    from odomkit.calibrate.export import twist_covariance
    from odomkit.kinematics import car_body_steps, car_speed_factor
    from odomkit.noise import GyroNoise, SpeedNoise, TricycleNoise
    from odomkit.robot import Car, Unicycle

    car, noise = Car(2.7, 0.8, c_scale=1.02, steering_offset=0.01), TricycleNoise(0.05, 0.01)
    v, w, T, W = 5.0, 0.3, 0.02, 10
    got = twist_covariance(car, noise, v, T, window=W, yaw_rate=w)
    alpha = math.atan2(w * car.wheel_base, v)
    wheel = v / float(car_speed_factor(alpha, car.wheel_base, car.encoder_offset))  # measured speed
    rng = np.random.default_rng(4)
    n = 40000
    speed = wheel + noise.sigma_speed * rng.standard_normal((n, W))
    steer = alpha + noise.sigma_steer * rng.standard_normal((n, W))
    dd, dth = car_body_steps(speed * T, steer, car.wheel_base, car.encoder_offset)
    published = np.column_stack([dd.sum(axis=1), dth.sum(axis=1)]) / (W * T)
    assert np.allclose(published.mean(axis=0), [v, w], rtol=2e-3)
    emp = np.cov(published.T)
    want = np.array([[got.var_speed, got.cov_speed_yaw_rate], [got.cov_speed_yaw_rate, got.var_yaw_rate]])
    se = np.sqrt((np.outer(np.diag(want), np.diag(want)) + want**2) / n)
    assert np.all(np.abs(emp - want) <= 5 * se), (emp, want)
    # A steering-wheel angle over its ratio: the same road-wheel angle, the same noise on it.
    from dataclasses import replace

    geared = twist_covariance(replace(car, steering_ratio=15.0), noise, v, T, window=W, yaw_rate=w)
    assert (geared.var_speed, geared.var_yaw_rate, geared.cov_speed_yaw_rate) == pytest.approx(
        (got.var_speed, got.var_yaw_rate, got.cov_speed_yaw_rate), rel=1e-9)
    uni = twist_covariance(Unicycle(c_scale=1.1), (SpeedNoise(1e-3), GyroNoise(1e-4)), v, T, window=W,
                           yaw_rate=w)
    assert uni.var_speed == pytest.approx(1e-3 * v / (W * T), rel=1e-12)
    assert uni.var_yaw_rate == pytest.approx(1e-4 / (W * T), rel=1e-12)
