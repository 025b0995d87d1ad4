"""Parameters robots load (issue 12 item 6): the tricycle_controller and nav2 AMCL snippets,
and the twist covariance a fitted noise implies (what robot_localization fuses).

Every snippet is read back with a YAML parser (PyYAML, a test-only dependency) and checked
for the key names the ROS packages read; the twist covariance is checked against a Monte
Carlo of the wheels themselves and against its closed form.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from odomkit.calibrate.export import TwistCovariance, twist_covariance
from odomkit.errors import InputError, ModelError
from odomkit.io.ros import (
    UNOBSERVED_VARIANCE,
    nav2_amcl_yaml,
    ros2_diff_drive_yaml,
    ros2_tricycle_yaml,
    ros_twist_covariance_diagonal,
)
from odomkit.noise import ParameterUncertainty, TricycleNoise, WheelNoise
from odomkit.robot import DiffDrive, Tricycle

yaml = pytest.importorskip("yaml")

# nav2_amcl's parameter names (nav2_params.yaml of navigation2) and the tricycle
# controller's (ros2_controllers tricycle_controller_parameter.yaml).
NAV2_KEYS = {"alpha1", "alpha2", "alpha3", "alpha4", "robot_model_type", "update_min_d", "update_min_a"}
TRICYCLE_KEYS = {"wheelbase", "wheel_radius", "twist_covariance_diagonal"}


@pytest.mark.parametrize(("model", "plugin"), [("diff", "nav2_amcl::DifferentialMotionModel"),
                                               ("omni", "nav2_amcl::OmniMotionModel")])
def test_nav2_amcl_snippet_loads_with_nav2s_key_names(model, plugin):
    alpha = {"alpha1": 0.0123, "alpha2": 1.5e-4, "alpha3": 0.0, "alpha4": 2.0, "alpha5": 0.25}
    text = nav2_amcl_yaml(alpha, model, update_min_d=0.1, update_min_a=0.15, notes=["fitted # here"])
    params = yaml.safe_load(text)["amcl"]["ros__parameters"]
    wanted = NAV2_KEYS | ({"alpha5"} if model == "omni" else set())
    assert set(params) == wanted
    assert params["robot_model_type"] == plugin
    assert all(params[k] == alpha[k] for k in wanted if k.startswith("alpha"))
    assert (params["update_min_d"], params["update_min_a"]) == (0.1, 0.15)


def test_numbers_read_back_as_floats_in_yaml_1_1():
    """PyYAML (YAML 1.1) reads ``1e-05`` as a string: every number must come back a float."""
    alpha = {"alpha1": 1e-05, "alpha2": 3e-300, "alpha3": 1e20, "alpha4": 0.0}
    params = yaml.safe_load(nav2_amcl_yaml(alpha))["amcl"]["ros__parameters"]
    assert all(isinstance(params[k], float) and params[k] == v for k, v in alpha.items())


def test_nav2_amcl_snippet_refuses_what_nav2_would_misread():
    with pytest.raises(ModelError, match="alpha4"):
        nav2_amcl_yaml({"alpha1": 0.1, "alpha2": 0.1, "alpha3": 0.1})
    with pytest.raises(ModelError, match=">= 0"):
        nav2_amcl_yaml({"alpha1": -0.1, "alpha2": 0.1, "alpha3": 0.1, "alpha4": 0.1})
    with pytest.raises(ModelError, match="model"):
        nav2_amcl_yaml({"alpha1": 0.1}, "ackermann")


def test_tricycle_snippet_loads_and_reproduces_the_calibrated_odometry():
    robot = Tricycle(0.1580347, 1.2763e-4, -0.0200833, 0.99313)
    nominal_radius = 0.0325
    doc = yaml.safe_load(ros2_tricycle_yaml(robot, nominal_radius))
    params = doc["tricycle_controller"]["ros__parameters"]
    assert set(params) <= TRICYCLE_KEYS
    # The controller's traction travel is wheel_radius x joint angle; one tick turns the
    # wheel by m_per_tick / nominal radius, so one tick must travel the calibrated scale.
    assert params["wheel_radius"] * robot.m_per_tick / nominal_radius == pytest.approx(robot.scale, rel=1e-15)
    assert params["wheelbase"] == robot.wheel_to_axle
    # the steering offset has no controller parameter: it is a comment, not a key
    assert "-0.0200833" in ros2_tricycle_yaml(robot, nominal_radius)


def _mc_wheel_twist(k_left, k_right, b, speed, period, window, draws, rng):
    """Wheels drawn directly: each update each wheel travels v·T + N(0, k²·v·T)."""
    d = speed * period
    left = d + k_left * math.sqrt(d) * rng.standard_normal((draws, window))
    right = d + k_right * math.sqrt(d) * rng.standard_normal((draws, window))
    v = 0.5 * (left + right).sum(axis=1) / (window * period)
    w = (right - left).sum(axis=1) / b / (window * period)
    return np.cov(np.vstack((v, w)))


def test_twist_covariance_of_wheel_noise_matches_the_wheels_simulated():
    robot, noise = DiffDrive(0.4), WheelNoise(0.002, 0.001)
    got = twist_covariance(robot, noise, 0.5, 0.01, window=10)
    mc = _mc_wheel_twist(0.002, 0.001, 0.4, 0.5, 0.01, 10, 200_000, np.random.default_rng(1))
    # 200 000 draws: sampling error of a variance about 0.3 % (1σ)
    assert got.var_speed == pytest.approx(mc[0, 0], rel=0.015)
    assert got.var_yaw_rate == pytest.approx(mc[1, 1], rel=0.015)
    assert got.cov_speed_yaw_rate == pytest.approx(mc[0, 1], rel=0.03)
    # closed form: var v = (kL² + kR²) v / (4 W T), var ω = (kL² + kR²) v / (b² W T)
    k2 = 0.002**2 + 0.001**2
    assert got.var_speed == pytest.approx(k2 * 0.5 / (4 * 10 * 0.01), rel=1e-12)
    assert got.var_yaw_rate == pytest.approx(k2 * 0.5 / (0.16 * 10 * 0.01), rel=1e-12)


def test_twist_covariance_scales_with_speed_and_averaging_time():
    """What a fixed diagonal misses: the wheel model's twist variance is linear in speed and
    inverse in the averaging time; the tricycle's speed noise does not grow with speed."""
    robot, noise = DiffDrive(0.4), WheelNoise(0.001, 0.001)
    slow = twist_covariance(robot, noise, 0.2, 0.01, window=10)
    fast = twist_covariance(robot, noise, 0.8, 0.01, window=10)
    long = twist_covariance(robot, noise, 0.2, 0.01, window=40)
    assert fast.var_speed / slow.var_speed == pytest.approx(4.0, rel=1e-12)
    assert slow.var_speed / long.var_speed == pytest.approx(4.0, rel=1e-12)
    tri = twist_covariance(Tricycle(0.15), TricycleNoise(0.01, 0.005), 0.2, 0.02, window=10)
    assert tri.var_speed == pytest.approx(0.01**2 / 10, rel=1e-12)  # mean of 10 speed samples


def test_twist_covariance_needs_white_noise():
    with pytest.raises(ModelError, match="white"):
        twist_covariance(DiffDrive(0.4), ParameterUncertainty(sigma_wheel_base=0.01, mode="bias"), 0.5, 0.01)


def test_diff_drive_snippet_with_twist_covariance_loads():
    twist = TwistCovariance(1.5e-6, 7.5e-5, -5e-6, 0.3, 0.0, 0.02, 10)
    text = ros2_diff_drive_yaml(DiffDrive(0.2, 1e-4, 1e-4), 0.042, twist=twist)
    params = yaml.safe_load(text)["diff_drive_controller"]["ros__parameters"]
    assert params["twist_covariance_diagonal"] == ros_twist_covariance_diagonal(twist)
    assert params["twist_covariance_diagonal"] == [1.5e-6, 1.5e-6, UNOBSERVED_VARIANCE, UNOBSERVED_VARIANCE,
                                                   UNOBSERVED_VARIANCE, 7.5e-5]
    assert "0.3 m/s" in text  # the speed it holds at is said
    # Whose noise it is, not "fitted": a user study published a hand-set k = 0.01 under a
    # comment that called it fitted. And why no pose covariance diagonal is given.
    lines = [line.strip() for line in text.splitlines()]
    comments = " ".join(line.lstrip("# ") for line in lines if line.startswith("#"))
    assert "fitted white noise" not in comments and "robot file's white noise" in comments
    assert "pose_covariance_diagonal is left out" in comments
    assert "pose_covariance_diagonal" not in params


def _write_tricycle(tmp_path):
    """A tricycle log and its truth from a known robot, and a nominal robot file."""
    true = Tricycle(0.158, 1e-4, -0.02, 1.0)
    t = np.arange(0.0, 40.0, 0.05)
    steer = 0.3 * np.sin(2 * np.pi * t / 20.0)
    ticks = np.full(t.size, 100.0)
    from odomkit.kinematics import body_steps
    from odomkit.log import OdometryLog
    from odomkit.track import dead_reckon_log

    log = OdometryLog(t, {"ticks": ticks, "steer": steer})
    poses = dead_reckon_log(log, true, pose0=np.zeros(3)).poses
    assert len(body_steps(true, log)) == t.size - 1
    rows = zip(t.tolist(), ticks.tolist(), steer.tolist(), poses.tolist(), strict=True)
    lines = ["t,ticks,steer,gx,gy,gth"] + [f"{a!r},{b!r},{c!r},{x!r},{y!r},{h!r}"
                                            for a, b, c, (x, y, h) in rows]
    run = tmp_path / "run.csv"
    run.write_text("\n".join(lines) + "\n")
    robot = tmp_path / "tri.toml"
    robot.write_text('[robot]\ntype = "tricycle"\nwheel_to_axle = 0.15\nwheel_radius = 0.05\n'
                     'encoder_resolution = 3141.592653589793\n\n'
                     '[noise]\nsigma_speed = 0.01\nsigma_steer = 0.005\n')
    return run, robot


def test_calibrate_writes_a_tricycle_controller_snippet(tmp_path, run_cli):
    run, robot = _write_tricycle(tmp_path)
    out = tmp_path / "tricycle.yaml"
    code, stdout, err = run_cli("calibrate", run, "--robot", robot, "--from", "trajectory",
                                "--columns", "t=t,ticks=ticks,steer=steer,gt_x=gx,gt_y=gy,gt_theta=gth",
                                "--ros-yaml", out, "--twist-speed", "0.2", "--controller-period", "0.02",
                                "--json")
    assert code == 0, err
    params = yaml.safe_load(out.read_text())["tricycle_controller"]["ros__parameters"]
    assert params["wheelbase"] == pytest.approx(0.158, rel=1e-6)
    assert params["wheel_radius"] == pytest.approx(0.05, rel=1e-6)  # c_scale 1: the nominal radius
    assert "steering_offset -0.0" in out.read_text()
    twist = json.loads(stdout)["twist_covariance"]
    assert twist["var_speed"] == pytest.approx(0.01**2 / 10, rel=1e-9)
    assert params["twist_covariance_diagonal"][0] == twist["var_speed"]


def test_twist_flags_are_checked(tmp_path, run_cli):
    run, robot = _write_tricycle(tmp_path)
    cols = "t=t,ticks=ticks,steer=steer,gt_x=gx,gt_y=gy,gt_theta=gth"
    code, _, err = run_cli("calibrate", run, "--robot", robot, "--columns", cols, "--twist-speed", "0.2")
    assert code == 2 and "go together" in err
    code, _, err = run_cli("calibrate", run, "--robot", robot, "--columns", cols,
                           "--ros-yaml", tmp_path / "a.yaml", "--twist-speed", "0.2")
    assert code == 2 and "--controller-period" in err
    bare = tmp_path / "bare.toml"
    bare.write_text('[robot]\ntype = "tricycle"\nwheel_to_axle = 0.15\nwheel_radius = 0.05\n'
                    'encoder_resolution = 3141.592653589793\n')
    code, _, err = run_cli("calibrate", run, "--robot", bare, "--columns", cols,
                           "--ros-yaml", tmp_path / "b.yaml", "--twist-speed", "0.2",
                           "--controller-period", "0.02")
    assert code == 2 and "[noise]" in err
    assert not (tmp_path / "a.yaml").exists() and not (tmp_path / "b.yaml").exists()


def test_the_twist_covariance_comes_without_a_controller_file_for_any_robot(tmp_path, run_cli):
    """robot_localization needs the twist covariance whatever the robot (a car, a unicycle
    has no controller snippet here): --twist-speed --controller-period without --ros-yaml
    puts it in the JSON and the text, equal to export.twist_covariance of the calibrated
    robot and the file's noise; white noise of zero there is warned about (an EKF would
    trust that velocity completely)."""
    import json

    from odomkit.io.robotfile import read_robot

    run, robot = _write_tricycle(tmp_path)
    cols = "t=t,ticks=ticks,steer=steer,gt_x=gx,gt_y=gy,gt_theta=gth"
    flags = ("--from", "trajectory", "--twist-speed", "0.2", "--controller-period", "0.02",
             "--velocity-window", "5")
    code, out, err = run_cli("calibrate", run, "--robot", robot, "--columns", cols, *flags,
                             "--out-robot", tmp_path / "cal.toml", "--json")
    assert code == 0, err
    got = json.loads(out)["twist_covariance"]
    calibrated, noise = read_robot(tmp_path / "cal.toml")
    want = twist_covariance(calibrated, noise, 0.2, 0.02, window=5)
    assert got["var_speed"] == pytest.approx(want.var_speed, rel=1e-12) and want.var_speed > 0
    assert got["var_yaw_rate"] == pytest.approx(want.var_yaw_rate, rel=1e-12) and want.var_yaw_rate > 0
    code, out, err = run_cli("calibrate", run, "--robot", robot, "--columns", cols, *flags)
    assert code == 0 and "twist covariance at 0.2 m/s" in out and not err
    silent = tmp_path / "silent.toml"
    silent.write_text(robot.read_text().replace("sigma_speed = 0.01", "sigma_speed = 0.0"))
    code, out, err = run_cli("calibrate", run, "--robot", silent, "--columns", cols, *flags)
    assert code == 0 and "gives v no variance at 0.2 m/s" in err


def test_inputs_named(tmp_path):
    with pytest.raises(ModelError, match="period"):
        twist_covariance(DiffDrive(0.4), WheelNoise(0.001, 0.001), 0.5, 0.0)
    assert InputError  # the CLI turns the ModelError into one line (see test_twist_flags_are_checked)


def test_a_tricycles_steering_ratio_leaves_its_twist_covariance_and_is_noted_in_the_yaml():
    """The steering noise is the wheel's radians whatever unit the steer channel is logged
    in (steering_ratio: the channel per radian of the wheel), so a tricycle logging 3× its
    wheel's angle has the twist covariance of one logging radians at the same (v, ω); the
    controller, which has no such parameter, is told in a comment."""
    noise = TricycleNoise(0.01, 0.005)
    plain = twist_covariance(Tricycle(0.15), noise, 0.2, 0.02, window=10, yaw_rate=0.8)
    geared = twist_covariance(Tricycle(0.15, steering_ratio=3.0), noise, 0.2, 0.02, window=10, yaw_rate=0.8)
    assert (geared.var_speed, geared.var_yaw_rate) == pytest.approx((plain.var_speed, plain.var_yaw_rate),
                                                                   rel=1e-12)
    assert geared.var_yaw_rate > 0
    assert "steering_ratio 3.0" in ros2_tricycle_yaml(Tricycle(0.15, steering_ratio=3.0), 0.03)
    assert "steering_ratio" not in ros2_tricycle_yaml(Tricycle(0.15), 0.03)
