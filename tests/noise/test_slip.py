"""Lateral slip (:mod:`odomkit.noise.slip`): a position-only white noise of every vehicle,
var ε_k = α_lat·|Δd_k| across the track; its place in the protocol and in robot files."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from odomkit.errors import InputError, ModelError
from odomkit.io.robotfile import read_robot, write_robot
from odomkit.kinematics import BodySteps
from odomkit.noise import (
    NOISE_MODELS,
    ClassicalNoise,
    CompassNoise,
    GyroNoise,
    LateralSlipNoise,
    NoiseSet,
    ParameterUncertainty,
    SpeedNoise,
    WheelNoise,
)
from odomkit.robot import ROBOT_TYPES, CompassOdometry, DiffDrive, GyroOdometry


def _gyro_steps(m=40, seed=3):
    rng = np.random.default_rng(seed)
    dd = rng.uniform(-0.05, 0.2, m)  # some reversing steps: the variance takes |Δd|
    dt = np.full(m, 0.1)
    rate = rng.normal(0.0, 0.5, m)
    return BodySteps(dd, rate * dt, dt, {"yaw_rate": rate}, GyroOdometry())


def test_variance_is_alpha_times_distance_travelled():
    steps = _gyro_steps()
    var = LateralSlipNoise(2e-3).lateral_variances(steps, 5, 17)
    np.testing.assert_array_equal(var, 2e-3 * np.abs(steps.dd[5:17]))
    assert var.shape == (12,) and np.all(var >= 0)


def test_it_enters_no_body_input_and_no_heading():
    steps = _gyro_steps()
    slip = LateralSlipNoise(1e-2)
    assert slip.input_variances(steps, 0, 40).shape == (40, 0)
    assert not np.any(slip.input_cov(steps, 0, 40))
    assert slip.input_factor(steps, 0, 40).shape == (40, 2, 0)
    assert slip.heading_variances(steps) is None and slip.bias_variances(steps.robot).size == 0
    assert slip.kind == "white" and slip.position_only and slip.family is None


@pytest.mark.parametrize("type_name", sorted(ROBOT_TYPES))
def test_applies_to_every_robot_type(type_name):
    assert LateralSlipNoise.robot_types == ()
    LateralSlipNoise(1e-3).check_robot(SimpleNamespace(type_name=type_name))  # type: ignore[arg-type]


def test_other_models_have_no_lateral_part_and_the_set_sums():
    steps = _gyro_steps()
    for cls in NOISE_MODELS.values():
        if cls is not LateralSlipNoise:
            assert not cls.position_only
    assert NoiseSet.of((SpeedNoise(1e-3), GyroNoise(1e-4))).lateral_variances(steps, 0, 40) is None
    both = NoiseSet.of((SpeedNoise(1e-3), GyroNoise(1e-4), LateralSlipNoise(3e-3)))
    np.testing.assert_array_equal(both.lateral_variances(steps, 0, 40), 3e-3 * np.abs(steps.dd))
    # the body inputs are those of the other models alone, bit for bit
    alone = NoiseSet.of((SpeedNoise(1e-3), GyroNoise(1e-4)))
    np.testing.assert_array_equal(both.input_cov(steps, 0, 40), alone.input_cov(steps, 0, 40))
    np.testing.assert_array_equal(both.input_factor(steps, 0, 40), alone.input_factor(steps, 0, 40))
    assert both.body_white == alone.models and both.family == "gyro"


def test_joins_a_model_with_its_own_step_map_but_nothing_else_does():
    pair = NoiseSet.of((ClassicalNoise(0.01, 0.01), LateralSlipNoise(1e-3)))
    assert pair.step_map("exact") == "classical"
    with pytest.raises(ModelError, match="cannot be combined"):
        NoiseSet.of((ClassicalNoise(0.01, 0.01), SpeedNoise(1e-3), LateralSlipNoise(1e-3)))


def test_bad_values_are_refused_by_name():
    for bad in (-1e-3, float("nan"), float("inf")):
        with pytest.raises(ModelError, match="alpha_lateral"):
            LateralSlipNoise(bad)


def test_variance_parameter_is_alpha_as_it_is():
    assert LateralSlipNoise(4e-3).variance_parameters() == {"alpha_lateral": 4e-3}
    assert LateralSlipNoise(0.0).from_variances({"alpha_lateral": 2e-3}) == LateralSlipNoise(2e-3)


@pytest.mark.parametrize("robot,noise", [
    (DiffDrive(0.4), (WheelNoise(0.01, 0.02), LateralSlipNoise(2.5e-4))),
    (DiffDrive(0.4), (ClassicalNoise(0.01, 0.02), LateralSlipNoise(2.5e-4))),
    (GyroOdometry(), (SpeedNoise(1e-3), GyroNoise(1e-5), LateralSlipNoise(7e-4),
                      ParameterUncertainty(sigma_scale_left=0.01))),
    (CompassOdometry(), (CompassNoise(1e-5), LateralSlipNoise(1e-3))),
], ids=["wheel", "classical", "gyro+bias", "compass"])
def test_robot_file_round_trip(tmp_path, robot, noise):
    path = write_robot(tmp_path / "robot.toml", robot, noise)
    assert "alpha_lateral" in path.read_text(encoding="utf-8")
    robot_back, noise_back = read_robot(path)
    assert robot_back == robot
    assert set(noise_back) == set(noise)


def test_robot_file_key_read_from_text(tmp_path):
    path = tmp_path / "robot.toml"
    path.write_text('[robot]\ntype = "diff"\nwheel_base = 0.5\nm_per_tick = 1e-4\n\n[noise]\nk_left = 0.01\n'
                    'k_right = 0.01\nalpha_lateral = 3e-4\n', encoding="utf-8")
    _, noise = read_robot(path)
    assert LateralSlipNoise(3e-4) in noise and WheelNoise(0.01, 0.01) in noise
    path.write_text('[robot]\ntype = "diff"\nwheel_base = 0.5\nm_per_tick = 1e-4\n\n'
                    '[noise]\nalpha_lateral = -1\n', encoding="utf-8")
    with pytest.raises(InputError, match="alpha_lateral"):
        read_robot(path)
