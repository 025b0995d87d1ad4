"""Robot files odomkit writes (``calibrate --out-robot``, ``fit-noise --out``): they read
back to the same robot and noise, and hold what a user would write (a real car's user
study, finding 11): no ``m_per_tick = 1.0`` in a speed-fed car's file (a speed channel is
metres per second already; the reader's default for a robot that may go without a wheel
size is 1.0), and ``mode`` where the reader's documentation puts it, after the σ's of
``[noise.parameters]``, not between them.
"""

from __future__ import annotations

import json
import math
import tomllib

import numpy as np
import pytest

from odomkit.io.robotfile import read_robot, write_robot
from odomkit.noise import ParameterUncertainty, TricycleNoise
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Tricycle, Unicycle


@pytest.mark.parametrize("robot", [
    Car(2.69, steering_ratio=15.0, steering_cubic=43.2, steering_offset=1.6e-4, c_scale=0.973),
    Tricycle(0.7, steering_offset=0.01),
    GyroOdometry(gyro_bias=0.001),
    CompassOdometry(heading_offset=0.02),
])
def test_a_robot_that_needs_no_wheel_size_is_written_without_the_default_one(tmp_path, robot):
    path = write_robot(tmp_path / "robot.toml", robot)
    table = tomllib.loads(path.read_text())["robot"]
    assert "m_per_tick" not in table
    assert read_robot(path) == (robot, ())


@pytest.mark.parametrize("robot", [
    Car(2.7, m_per_tick=math.pi * 0.6 / 1000),  # a car whose log counts ticks
    Tricycle(0.7, m_per_tick=2e-4),
    GyroOdometry(m_per_tick=5e-5),
    CompassOdometry(m_per_tick=5e-5),
    DiffDrive(0.3),  # the reader needs a diff's wheel sizes, even at 1 m per tick
    DiffDrive(0.3, 1e-4, 1.1e-4),
    Unicycle(c_scale=1.01),
])
def test_every_other_robot_reads_back_the_same(tmp_path, robot):
    path = write_robot(tmp_path / "robot.toml", robot)
    assert read_robot(path) == (robot, ())
    table = tomllib.loads(path.read_text())["robot"]
    if isinstance(robot, DiffDrive):
        assert table["m_per_tick_left"] == robot.m_per_tick_left
    elif not isinstance(robot, Unicycle):
        assert table["m_per_tick"] == robot.m_per_tick


def test_mode_follows_the_sigmas_of_noise_parameters(tmp_path):
    car = Car(2.7)
    noise = (TricycleNoise(0.05, 0.002),
             ParameterUncertainty(sigma_wheel_base=0.01, sigma_scale_left=0.02, sigma_steering_offset=0.003))
    path = write_robot(tmp_path / "robot.toml", car, noise)
    text = path.read_text()
    table = text.split("[noise.parameters]\n", 1)[1].split("\n\n", 1)[0].splitlines()
    keys = [line.split("=")[0].strip() for line in table if "=" in line]
    # as odomkit.io.robotfile's documentation writes it: the σ's, then mode
    assert keys == ["sigma_wheel_base", "sigma_scale_left", "sigma_steering_offset", "mode"]
    assert read_robot(path) == (car, noise)


def test_calibrate_writes_a_speed_fed_car_that_reads_back_as_the_calibrated_car(run_cli, tmp_path):
    """A car logging speed [m/s] and steering against 1 Hz fixes: ``calibrate --out-robot``
    writes no metres per tick, and the file reads back to the car of calibrate's JSON."""
    dt, L = 0.05, 2.7
    t = np.arange(int(120 / dt)) * dt
    v = 8 + 2 * np.sin(t / 13)
    steer = 0.15 * np.sin(t / 9) - 0.004  # measured 0.004 rad off
    heading = np.concatenate([[0.0], np.cumsum(v[:-1] * np.tan(steer[:-1] + 0.004) / L) * dt])
    x = np.concatenate([[0.0], np.cumsum(v[:-1] * np.cos(heading[:-1])) * dt])
    y = np.concatenate([[0.0], np.cumsum(v[:-1] * np.sin(heading[:-1])) * dt])
    np.savetxt(tmp_path / "car.csv", np.column_stack((t, v, steer)), delimiter=",", header="t,speed,steer",
               comments="")
    fix_t = np.arange(0.5, t[-1], 1.0)
    np.savetxt(tmp_path / "gps.csv", np.column_stack((fix_t, np.interp(fix_t, t, x), np.interp(fix_t, t, y))),
               delimiter=",", header="t,x,y", comments="")
    (tmp_path / "car.toml").write_text(
        '[robot]\ntype = "car"\nname = "test car"\nwheel_base = 2.7\n[noise.parameters]\n'
        'sigma_wheel_base = 0.01\nsigma_scale_left = 0.02\nsigma_steering_offset = 0.003\n')
    out = tmp_path / "calibrated.toml"
    code, stdout, err = run_cli("calibrate", tmp_path / "car.csv", "--robot", tmp_path / "car.toml",
                                "--truth", tmp_path / "gps.csv", "--truth-time-offset", "0",
                                "--out-robot", out, "--json")
    assert code == 0, err
    fitted = json.loads(stdout)["parameters"]
    written = tomllib.loads(out.read_text())
    assert "m_per_tick" not in written["robot"]
    assert list(written["noise"]["parameters"])[-1] == "mode"
    robot, noise = read_robot(out)
    assert robot == Car(fitted["wheel_base"], steering_offset=fitted["steering_offset"],
                        c_scale=fitted["c_scale"])
    assert robot.steering_offset == pytest.approx(0.004, abs=2e-4)  # the offset put in
    assert noise == (ParameterUncertainty(sigma_wheel_base=0.01, sigma_scale_left=0.02,
                                          sigma_steering_offset=0.003),)


def test_truth_given_with_the_fits_key_names_reads_back(tmp_path):
    """``NoiseFit.truth_noise`` and fit-noise's JSON name the truth's noise ``truth_sigma``,
    ``truth_heading_sigma``, ``truth_time_sigma``; the file's ``[truth]`` table ``sigma``,
    ``heading_sigma``, ``time_sigma`` (API user study, H4: the fit's names were dropped
    silently, an empty ``[truth]`` table written). Both spellings are taken."""
    from odomkit.io.robotfile import read_truth_table

    fitted = {"truth_sigma": 0.004, "truth_heading_sigma": 0.0111, "truth_time_sigma": 0.0204}
    path = write_robot(tmp_path / "fit.toml", DiffDrive(0.2), truth=fitted)
    assert read_truth_table(path) == {"sigma": 0.004, "heading_sigma": 0.0111, "time_sigma": 0.0204}
    mixed = {"sigma": 0.01, "truth_time_offset": 0.05}
    path = write_robot(tmp_path / "mixed.toml", DiffDrive(0.2), truth=mixed)
    assert read_truth_table(path) == {"sigma": 0.01, "time_offset": 0.05}


@pytest.mark.parametrize("truth, word", [
    ({"sigma": 0.01, "truth_sigmaa": 0.02}, "truth_sigmaa"),
    ({"position_sigma": 0.01}, "position_sigma"),
    ({"sigma": 0.01, "truth_sigma": 0.01}, "sigma"),  # one key given twice
])
def test_truth_with_an_unknown_or_doubled_key_is_refused(tmp_path, truth, word):
    from odomkit.errors import InputError

    with pytest.raises(InputError, match=word) as info:
        write_robot(tmp_path / "bad.toml", DiffDrive(0.2), truth=truth)
    assert "\n" not in str(info.value)
    assert not (tmp_path / "bad.toml").exists()
