"""odomkit.workflows.calibration: runs and a robot file in, corrected robot file and ROS
YAML out, never over an existing file unless asked."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from odomkit.errors import InputError, ModelError
from odomkit.integrate import dead_reckon
from odomkit.io.robotfile import read_robot, robot_to_dict
from odomkit.kinematics import diff_body_steps
from odomkit.noise import WheelNoise
from odomkit.robot import DiffDrive
from odomkit.workflows.calibration import calibrate_files
from odomkit.workflows.logs import LogOptions

# The true robot: its wheels roll 0.995 and 1.004 of what the odometry believes, and its
# effective wheel base is 0.51 m where the odometry assumes 0.5 m.
TRUE_LEFT, TRUE_RIGHT, TRUE_BASE, NOMINAL_BASE = 0.995, 1.004, 0.51, 0.5
COLUMNS = "t=t,dist_left=dl,dist_right=dr,gt_x=gx,gt_y=gy,gt_theta=gth"
ROBOT_TOML = f"""[robot]
type = "diff"
wheel_base = {NOMINAL_BASE}
m_per_tick = 1.0

[noise]
k_left = 0.001
k_right = 0.002
"""


def _write_run(path: Path, left: float, right: float, n: int = 200) -> Path:
    """A constant-curvature run: the odometry counts ``left``/``right`` metres per wheel;
    the ground truth is what the true robot does with them (exact arcs)."""
    dl, dr = np.full(n, left / n), np.full(n, right / n)
    truth = dead_reckon(*diff_body_steps(TRUE_LEFT * dl, TRUE_RIGHT * dr, TRUE_BASE))
    table = np.column_stack((np.arange(n + 1.0), np.r_[0.0, dl], np.r_[0.0, dr], truth))
    np.savetxt(path, table, delimiter=",", fmt="%.17g", header="t,dl,dr,gx,gy,gth", comments="")
    return path


@pytest.fixture()
def files(tmp_path):
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML, encoding="utf-8")
    runs = [_write_run(tmp_path / "left.csv", 2.0, 2.5), _write_run(tmp_path / "right.csv", 2.5, 2.0)]
    return tmp_path, runs, robot


def _calibrate(runs, robot, **kwargs):
    return calibrate_files(runs, robot, source="trajectory", log_options=LogOptions(columns=COLUMNS),
                           **kwargs)


def test_exact_calibration_recovers_the_true_robot_and_writes_both_files(files):
    tmp, runs, robot_path = files
    out_robot, ros_yaml = tmp / "calibrated.toml", tmp / "controller.yaml"
    summary = _calibrate(runs, robot_path, out_robot=out_robot, ros_yaml=ros_yaml, wheel_radius=0.04)
    assert summary["method"] == "exact"
    assert summary["outputs"] == {"robot": str(out_robot), "ros_yaml": str(ros_yaml)}

    # the robot file holds the true robot, and the noise of the input file
    robot, noise = read_robot(out_robot)
    assert isinstance(robot, DiffDrive)
    assert robot.scale_left == pytest.approx(TRUE_LEFT, rel=1e-6)
    assert robot.scale_right == pytest.approx(TRUE_RIGHT, rel=1e-6)
    assert robot.effective_wheel_base == pytest.approx(TRUE_BASE, rel=1e-6)
    assert robot.wheel_base == NOMINAL_BASE
    assert noise == (WheelNoise(0.001, 0.002),)
    assert summary["robot"] == robot_to_dict(robot)["robot"]

    # diff_drive_controller: wheel travel = radius·multiplier·angle and base =
    # separation·multiplier, so the multipliers are the true/believed wheel ratios
    doc = yaml.safe_load(ros_yaml.read_text(encoding="utf-8"))
    params = doc["diff_drive_controller"]["ros__parameters"]
    assert params["wheel_radius"] == 0.04
    assert params["wheel_separation"] * params["wheel_separation_multiplier"] == pytest.approx(
        TRUE_BASE, rel=1e-6)
    assert params["left_wheel_radius_multiplier"] == pytest.approx(TRUE_LEFT, rel=1e-6)
    assert params["right_wheel_radius_multiplier"] == pytest.approx(TRUE_RIGHT, rel=1e-6)


def test_the_robot_file_round_trips(files):
    """What is written reads back as the same robot, bit for bit."""
    tmp, runs, robot_path = files
    summary = _calibrate(runs, robot_path, out_robot=tmp / "a.toml")
    robot, _ = read_robot(tmp / "a.toml")
    fields = {k: v for k, v in summary["robot"].items() if k != "type"}
    assert robot == DiffDrive(**fields)
    # starting from the calibrated robot there is nothing left to correct
    again = _calibrate(runs, tmp / "a.toml", out_robot=tmp / "b.toml")
    assert again["outputs"] == {"robot": str(tmp / "b.toml")}
    twice, _ = read_robot(tmp / "b.toml")
    assert twice.scale_left == pytest.approx(robot.scale_left, rel=1e-9)
    assert twice.scale_right == pytest.approx(robot.scale_right, rel=1e-9)
    assert twice.effective_wheel_base == pytest.approx(robot.effective_wheel_base, rel=1e-9)


def test_existing_outputs_are_never_overwritten_without_force(files):
    tmp, runs, robot_path = files
    out_robot, ros_yaml = tmp / "calibrated.toml", tmp / "controller.yaml"
    ros_yaml.write_text("mine\n", encoding="utf-8")
    with pytest.raises(InputError, match="exists already; pass --force"):
        _calibrate(runs, robot_path, out_robot=out_robot, ros_yaml=ros_yaml, wheel_radius=0.04)
    # refused before anything was written: nothing half-done, nothing lost
    assert not out_robot.exists()
    assert ros_yaml.read_text(encoding="utf-8") == "mine\n"
    _calibrate(runs, robot_path, out_robot=out_robot, ros_yaml=ros_yaml, wheel_radius=0.04,
               overwrite=True)
    assert "diff_drive_controller" in ros_yaml.read_text(encoding="utf-8")
    assert read_robot(out_robot)[0].effective_wheel_base == pytest.approx(TRUE_BASE, rel=1e-6)


def test_bad_requests(files):
    tmp, runs, robot_path = files
    with pytest.raises(InputError, match="--wheel-radius"):
        _calibrate(runs, robot_path, ros_yaml=tmp / "c.yaml")
    assert not (tmp / "c.yaml").exists()
    with pytest.raises(InputError, match="--side"):
        calibrate_files(runs, robot_path, method="umbmark", log_options=LogOptions(columns=COLUMNS))
    with pytest.raises(ModelError, match="--method"):
        _calibrate(runs, robot_path, method="guess")
    with pytest.raises(InputError, match="no such file"):
        _calibrate([tmp / "missing.csv"], robot_path)
    with pytest.raises(InputError, match="no such robot file"):
        _calibrate(runs, tmp / "missing.toml")


# --- issue 10, item 8: flags that do not apply are refused, outputs checked up front ----


@pytest.mark.parametrize("kwargs, message", [
    ({"method": "umbmark", "side": 0.75, "source": "trajectory"}, "--from applies to --method exact"),
    ({"method": "umbmark", "side": 0.75, "heading_weight": 0.5},
     "--heading-weight applies to --method exact"),
    ({"wheel_radius": 0.04}, "--wheel-radius applies to --ros-yaml"),
])
def test_flags_that_do_not_apply_are_refused(files, kwargs, message):
    tmp, runs, robot_path = files
    with pytest.raises(InputError, match=message):
        calibrate_files(runs, robot_path, log_options=LogOptions(columns=COLUMNS), **kwargs)


def test_a_wheel_radius_that_conflicts_with_the_robot_file(files):
    tmp, runs, robot_path = files
    sized = tmp / "sized.toml"
    sized.write_text(ROBOT_TOML.replace("m_per_tick = 1.0", "wheel_diameter = 0.08"), encoding="utf-8")
    with pytest.raises(InputError, match="--wheel-radius 0.05 m conflicts with the robot file"):
        _calibrate(runs, sized, ros_yaml=tmp / "c.yaml", wheel_radius=0.05)
    assert not (tmp / "c.yaml").exists()
    # the robot file's own radius is the default, and agreeing with it is fine
    for radius in (None, 0.04):
        out = tmp / f"c{radius}.yaml"
        _calibrate(runs, sized, ros_yaml=out, wheel_radius=radius)
        params = yaml.safe_load(out.read_text(encoding="utf-8"))
        assert params["diff_drive_controller"]["ros__parameters"]["wheel_radius"] == pytest.approx(0.04)


def test_outputs_are_checked_before_the_runs_are_read(files):
    tmp, runs, robot_path = files
    # the runs do not exist: the output problem is reported first, nothing is computed
    with pytest.raises(InputError, match="--out-robot: no such folder"):
        _calibrate([tmp / "missing.csv"], robot_path, out_robot=tmp / "nodir" / "r.toml")


def test_calibrate_a_car_log_with_gps_truth_on_its_own_clock(tmp_path, run_cli):
    """Issue 12 item 3 through the CLI: a car's speed log (t, speed, steer) and a GPS file
    (t, x, y at 1 Hz, 0.37 s off the log's clock, σ = 3 m, a 40 s gap) recover the true
    speed scale, steering offset and wheel base within their intervals."""
    import json

    from odomkit.log import OdometryLog
    from odomkit.robot import Car
    from odomkit.track import dead_reckon_log

    rng = np.random.default_rng(5)
    n, dt = 6000, 0.1
    t = 1000.0 + dt * np.arange(n)
    knots = rng.uniform(-0.25, 0.25, n // 100 + 2)
    steer = np.interp(t - t[0], np.arange(knots.size) * 100 * dt, knots)
    speed = 8 + 2 * np.sin(t / 37.0)
    true = Car(2.75, 0.8, "rear", steering_offset=0.01, c_scale=1.02)
    poses = dead_reckon_log(OdometryLog(t, {"speed": speed, "steer": steer}), true, pose0=(10, 5, 0.3)).poses
    log = tmp_path / "car.csv"
    np.savetxt(log, np.column_stack([t, speed, steer]), delimiter=",", header="t,speed,steer",
               comments="", fmt="%.12g")
    tg = np.arange(t[0] + 0.37, t[-1], 1.0)
    tg = tg[(tg < t[0] + 200) | (tg > t[0] + 240)]
    xy = np.column_stack([np.interp(tg, t, poses[:, 0]), np.interp(tg, t, poses[:, 1])])
    gps = tmp_path / "gps.csv"
    np.savetxt(gps, np.column_stack([tg, xy + rng.normal(0, 3, xy.shape)]), delimiter=",",
               header="t,x,y", comments="", fmt="%.12g")
    robot = tmp_path / "car.toml"
    robot.write_text('[robot]\ntype = "car"\nwheel_base = 2.7\nencoder_offset = 0.8\n', encoding="utf-8")
    code, out, err = run_cli("calibrate", log, "--robot", robot, "--truth", gps, "--columns",
                             "t=t,speed=speed,steer=steer", "--out-robot", tmp_path / "new.toml", "--json")
    assert code == 0, err
    result = json.loads(out)
    assert result["source"] == "positions"
    for name, value in (("c_scale", 1.02), ("steering_offset", 0.01), ("wheel_base", 2.75)):
        assert abs(result["parameters"][name] - value) < 3 * result["std_errors"][name], name
    assert read_robot(tmp_path / "new.toml")[0].steering_offset == result["parameters"]["steering_offset"]
    # --from belongs to logs with their own ground truth
    code, _, err = run_cli("calibrate", log, "--robot", robot, "--truth", gps, "--columns",
                           "t=t,speed=speed,steer=steer", "--from", "trajectory")
    assert code == 2 and "--from does not apply with --truth" in err
    # Two runs: each is also calibrated alone (JSON per_run, the single-run fit's numbers),
    # and runs of one robot are no cause for the "runs disagree" warning.
    code, out, err = run_cli("calibrate", log, log, "--robot", robot, "--truth", gps, "--truth", gps,
                             "--columns", "t=t,speed=speed,steer=steer", "--json")
    assert code == 0, err
    both = json.loads(out)
    assert [row["log"] for row in both["per_run"]] == [str(log), str(log)]
    for row in both["per_run"]:
        for name, value in result["parameters"].items():
            assert row["parameters"][name] == pytest.approx(value, rel=1e-6, abs=1e-9), name
    assert not any("runs disagree" in w for w in both.get("warnings", [])) and "runs disagree" not in err


def test_a_yaw_rate_scale_far_off_names_a_twist_from_commanded_steering():
    """An F1TENTH car's VESC odometry computes its yaw rate from the commanded steering angle
    and turned 1.8x its motion capture (yaw_rate_scale 0.57, a user study); the warning named
    only a skid-steer base's twist or a unit."""
    import warnings

    from odomkit.robot import Unicycle
    from odomkit.workflows.calibration import _warn_far_from_file

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _warn_far_from_file(Unicycle(), Unicycle(yaw_rate_scale=0.57))
    (said,) = [str(w.message) for w in caught if "yaw_rate_scale" in str(w.message)]
    assert "-43 %" in said and "commanded steering" in said and "skid-steer" in said


def test_calibrate_fits_the_clock_about_the_robot_files_offset(tmp_path, run_cli, noisy_diff_log):
    """A truth stamped 1000.25 s late, the robot file's [truth] time_offset 1000 s (what an
    earlier calibration or fit-noise wrote): the clock's fit starts there and fits the rest,
    and the total comes back. An F1TENTH car's motion capture 8328 s off its odometry was
    refused with "only 0 truth fixes" although the file named the offset (user study)."""
    import json

    import numpy as np

    log, _, robot = noisy_diff_log(tmp_path, k_true=0.0, k_model=0.0, seconds=120.0, truth_noise=0.001)
    fixes = np.loadtxt(tmp_path / "xy.csv", delimiter=",", skiprows=1)
    fixes[:, 0] += 1000.25
    late = tmp_path / "late.csv"
    np.savetxt(late, fixes, delimiter=",", header="t,x,y", comments="")
    with_clock = tmp_path / "clocked.toml"
    with_clock.write_text(robot.read_text() + "[truth]\ntime_offset = 1000.0\n")
    code, out, err = run_cli("calibrate", log, "--robot", with_clock, "--columns",
                             "t=t,dist_left=L,dist_right=R", "--truth", late, "--json")
    assert code == 0, err
    clock = json.loads(out)["truth_time_offset"]
    assert clock["fitted"] and clock["fitted_about"] == 1000.0
    assert abs(clock["value"] - 1000.25) < max(3 * clock["std_error"], 0.01)
