"""Variance parameters of every noise model (what ``odomkit fit-noise`` fits).

The independent truth is each model's own covariance: a model's contribution must be
linear in each variance parameter (so a σ field must be squared and a psd field taken as
it is); a wrong power would scale it quadratically and fail here.
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps, diff_body_steps, steering_body_steps
from odomkit.noise import NOISE_MODELS, NoiseModel, ParameterUncertainty, WheelNoise
from odomkit.noise.base import variance_power
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Tricycle, Unicycle

M = 50


def _steps(robot):
    rng = np.random.default_rng(0)
    dt = np.full(M, 0.1)
    if isinstance(robot, DiffDrive):
        dl, dr = rng.uniform(0.005, 0.02, (2, M))
        dd, dth = diff_body_steps(dl, dr, robot.effective_wheel_base)
        return BodySteps(dd, dth, dt, {"d_left": dl, "d_right": dr}, robot)
    if isinstance(robot, Tricycle | Car):
        travel, steer = rng.uniform(0.005, 0.02, M), rng.uniform(-0.5, 0.5, M)
        dd, dth = steering_body_steps(robot, travel, steer)
        return BodySteps(dd, dth, dt, {"travel": travel, "steer": steer}, robot)
    dd = rng.uniform(0.005, 0.02, M)
    if isinstance(robot, GyroOdometry | Unicycle):
        rate = rng.normal(0, 0.3, M)
        return BodySteps(dd, rate * dt, dt, {"yaw_rate": rate}, robot)
    heading = np.cumsum(rng.normal(0, 0.05, M + 1))
    return BodySteps(dd, np.diff(heading), dt, {"heading": heading}, robot)


ROBOTS = [DiffDrive(0.3), Tricycle(0.15), GyroOdometry(), CompassOdometry(), Unicycle(),
          Car(2.7, 0.8)]


def _zero(cls: type[NoiseModel]) -> NoiseModel:
    from dataclasses import fields

    return cls(**{f.name: 0.0 for f in fields(cls) if not isinstance(f.default, str)})


def _contribution(model: NoiseModel, steps: BodySteps) -> np.ndarray:
    """Everything the engines take from a model, stacked."""
    parts = [model.input_cov(steps, 0, M).ravel()] if model.kind == "white" else []
    heading = model.heading_variances(steps)
    if heading is not None:
        parts.append(heading)
    lateral = model.lateral_variances(steps, 0, M)
    if lateral is not None:
        parts.append(lateral)
    parts.append(model.bias_variances(steps.robot))
    return np.concatenate(parts)


def _applies(name: str, robot) -> bool:
    try:
        _zero(NOISE_MODELS[name]).check_robot(robot)
    except ModelError:
        return False
    return True


# Only the (model, robot) pairs the model applies to: the others are refused by design
# (test_base.py checks the refusals), so they are not generated rather than skipped.
APPLICABLE = [(name, robot) for name in sorted(NOISE_MODELS) for robot in ROBOTS
              if _applies(name, robot)]


@pytest.mark.parametrize("name,robot", APPLICABLE,
                         ids=[f"{n}-{r.type_name}" for n, r in APPLICABLE])
def test_each_models_contribution_is_linear_in_each_variance_parameter(name, robot):
    model = _zero(NOISE_MODELS[name])
    steps = _steps(robot)
    params = model.variance_parameters(robot)
    assert params, name
    for key in params:
        unit = _contribution(model.from_variances({key: 1.0}), steps)
        assert np.any(unit), (name, key)
        for v in (0.25, 7.0):
            scaled = _contribution(model.from_variances({key: v}), steps)
            np.testing.assert_allclose(scaled, v * unit, rtol=1e-12, atol=0)


@pytest.mark.parametrize("name", sorted(NOISE_MODELS))
def test_from_variances_inverts_variance_parameters(name):
    model = _zero(NOISE_MODELS[name])
    values = {k: 0.1 * (i + 1) for i, k in enumerate(model.variance_parameters())}
    rebuilt = model.from_variances(values)
    assert rebuilt.variance_parameters() == pytest.approx(values, rel=1e-15)
    assert rebuilt.from_variances(rebuilt.variance_parameters()) == rebuilt


def test_sigma_and_k_fields_are_squared_psd_and_alpha_are_not():
    assert WheelNoise(0.01, 0.02).variance_parameters() == pytest.approx({"k_left": 1e-4, "k_right": 4e-4})
    assert [variance_power(n) for n in ("sigma_x", "k_x", "var_x", "psd_x", "alpha_x")] == [2, 2, 1, 1, 1]
    with pytest.raises(ModelError, match="neither"):
        variance_power("scale")


def test_only_parameters_that_apply_to_the_robot_are_listed():
    pu = ParameterUncertainty()
    assert set(pu.variance_parameters(DiffDrive(0.3))) == {"sigma_wheel_base", "sigma_scale_left",
                                                           "sigma_scale_right"}
    steered = {"sigma_wheel_base", "sigma_scale_left", "sigma_steering_offset"}
    assert set(pu.variance_parameters(Tricycle(0.15))) == steered
    assert set(pu.variance_parameters(Car(2.7))) == steered
    rate = {"sigma_scale_left", "sigma_yaw_rate_offset", "sigma_yaw_rate_scale"}
    assert set(pu.variance_parameters(GyroOdometry())) == rate
    assert set(pu.variance_parameters(Unicycle())) == rate
    assert set(pu.variance_parameters(CompassOdometry())) == {"sigma_scale_left", "sigma_heading_offset"}
    # the heading offset has no white mode (that is CompassNoise)
    white = ParameterUncertainty(mode="white")
    assert set(white.variance_parameters(CompassOdometry())) == {"sigma_scale_left"}
    assert "mode" not in pu.variance_parameters()


def test_from_variances_refuses_unknown_fields_and_negative_variances():
    with pytest.raises(ModelError, match="no field"):
        WheelNoise(0, 0).from_variances({"k_middle": 1.0})
    with pytest.raises(ModelError, match="non-negative"):
        WheelNoise(0, 0).from_variances({"k_left": -1.0})
