"""``odomkit predict``/``simulate --robot ROBOT.toml`` (API study s24, H1 and H2): the
robot file's vehicle and [noise] as they are, e.g. what ``fit-noise --out`` wrote; a
tricycle's or car's segments as wheel speed, steering angle and duration; per-sample
noise with ``--sample-period``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from odomkit.cli import main
from odomkit.io.robotfile import read_robot
from odomkit.path import Spin, SteerArc, Straight
from odomkit.propagate.predict import predict

# as fit-noise writes a diff robot: white WheelNoise + SpeedNoise + LateralSlipNoise, and bias
DIFF = """[robot]
type = "diff"
wheel_base = 0.2
m_per_tick = 1.0

[noise]
k_left = 0.0
k_right = 0.00063
alpha_ss = 1e-5
alpha_lateral = 1.3e-5

[noise.parameters]
sigma_wheel_base = 0.0017
sigma_scale_right = 0.0017
"""
TRICYCLE = """[robot]
type = "tricycle"
wheel_to_axle = 0.5

[noise]
sigma_speed = 0.02
sigma_steer = 0.01
alpha_lateral = 1e-5

[noise.parameters]
sigma_steering_offset = 0.002
"""
SQUARE = ["--segment", "straight:1.7", "--segment", "spin:-1.5707963267948966"] * 4
STEER = ["--segment", "arc:0.4,0.3,4", "--segment", "straight:0.5,2"]


def _run(capsys, *args: str) -> tuple[int, dict | None, str]:
    code = main([*args])
    out = capsys.readouterr()
    return code, (json.loads(out.out) if code == 0 and "--json" in args else None), out.err


def test_predict_with_a_fitted_diff_robot_file(tmp_path, capsys):
    """The file's noise as it is, through the recursion; the same numbers as the API."""
    robot_file = tmp_path / "fitted.toml"
    robot_file.write_text(DIFF)
    code, out, err = _run(capsys, "predict", "--robot", str(robot_file), *SQUARE, "--engine",
                          "recursion", "--partitions", "50", "--json")
    assert code == 0, err
    robot, noise = read_robot(robot_file)
    path = [seg for _ in range(4) for seg in (Straight(1.7), Spin(-np.pi / 2))]
    p = predict(path, noise, robot=robot, engine="recursion", partitions=50)
    assert np.allclose(out["cov"], p.cov, rtol=1e-12, atol=0)
    # the closed form does not exist for this set: one line naming the engines
    code, _, err = _run(capsys, "predict", "--robot", str(robot_file), *SQUARE)
    assert code == 2 and "--engine recursion" in err and "Traceback" not in err


def test_tricycle_robot_file_needs_the_sample_period(tmp_path, capsys):
    robot_file = tmp_path / "tri.toml"
    robot_file.write_text(TRICYCLE)
    code, _, err = _run(capsys, "predict", "--robot", str(robot_file), *STEER, "--engine", "recursion")
    assert code == 2 and "sample period" in err and "--sample-period" in err
    assert len(err.strip().splitlines()) == 1
    code, out, err = _run(capsys, "predict", "--robot", str(robot_file), *STEER, "--engine", "recursion",
                          "--sample-period", "0.05", "--json")
    assert code == 0, err
    robot, noise = read_robot(robot_file)
    p = predict([SteerArc(0.4, 0.3, 4.0), SteerArc(0.5, 0.0, 2.0)], noise, robot=robot, engine="recursion",
                sample_period=0.05)
    assert np.allclose(out["cov"], p.cov, rtol=1e-12, atol=0)


def test_simulate_with_a_robot_file(tmp_path, capsys):
    """The Monte Carlo of the file's noise at its sample period agrees with the theory."""
    robot_file = tmp_path / "tri.toml"
    robot_file.write_text(TRICYCLE)
    code, out, err = _run(capsys, "simulate", "--robot", str(robot_file), *STEER, "--sample-period", "0.05",
                          "--runs", "4000", "--seed", "3", "--json")
    assert code == 0, err
    assert out["partitions"] == 80 and out["consistent"], out["verdict"]


@pytest.mark.parametrize("extra, message", [
    (["--k-left", "0.001"], "--robot takes the vehicle and its noise from the robot file"),
    (["--model", "gyro"], "--robot takes the vehicle and its noise from the robot file"),
    (["--wheel-base", "0.4"], "--robot takes the vehicle and its noise from the robot file"),
])
def test_robot_file_and_noise_flags_exclude_each_other(tmp_path, capsys, extra, message):
    robot_file = tmp_path / "fitted.toml"
    robot_file.write_text(DIFF)
    for command in ("predict", "simulate"):
        code, _, err = _run(capsys, command, "--robot", str(robot_file), *SQUARE, *extra)
        assert code == 2 and message in err, err


def test_a_robot_file_without_noise_is_refused(tmp_path, capsys):
    robot_file = tmp_path / "bare.toml"
    robot_file.write_text('[robot]\ntype = "diff"\nwheel_base = 0.2\nm_per_tick = 1.0\n')
    code, _, err = _run(capsys, "predict", "--robot", str(robot_file), *SQUARE)
    assert code == 2 and "no [noise]" in err
