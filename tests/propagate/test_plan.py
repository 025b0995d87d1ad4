"""Planning the engines from a log's noise models (:mod:`odomkit.propagate.plan`): the plan
asks each model once and hands on exactly the model's answers (checked here against the
models and against hand values)."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps, diff_body_steps
from odomkit.noise import (
    ClassicalNoise,
    CompassNoise,
    NoiseSet,
    ParameterUncertainty,
    SpeedNoise,
    WheelNoise,
)
from odomkit.noise.parameters import diff_parameter_jacobian
from odomkit.noise.wheel import WheelInputs
from odomkit.propagate.plan import plan_noise
from odomkit.robot import CompassOdometry, DiffDrive

M = 30


def diff_log(seed: int = 61) -> BodySteps:
    rng = np.random.default_rng(seed)
    dl, dr = rng.uniform(-0.02, 0.05, M), rng.uniform(-0.02, 0.05, M)
    dd, dth = diff_body_steps(dl, dr, 0.4)
    return BodySteps(dd, dth, np.full(M, 0.1), {"d_left": dl, "d_right": dr}, DiffDrive(0.4))


def compass_log(dt) -> BodySteps:
    dt = np.asarray(dt, dtype=float)
    heading = np.linspace(0.0, 0.3, dt.size + 1)
    return BodySteps(np.full(dt.size, 0.05), np.diff(heading), dt, {"heading": heading},
                     CompassOdometry())


def test_compass_robot_plans_direct_heading():
    """psd/spacing per heading sample (spacing: mean of the adjacent steps, one step at
    the ends) and var Δd = α_ss·|Δd|."""
    steps = compass_log([0.1, 0.3, 0.2])
    plan = plan_noise(steps, (SpeedNoise(2e-3), CompassNoise(6e-3)))
    assert plan.direct is True and plan.method == "exact"
    assert np.allclose(plan.var_heading, 6e-3 / np.array([0.1, 0.2, 0.25, 0.2]), rtol=1e-14)
    assert np.allclose(plan.var_dd(0, 3), 2e-3 * 0.05, rtol=1e-14)
    assert plan.var_params is None and plan.wheel is None
    # speed noise alone: the compass is taken as perfect
    alone = plan_noise(steps, SpeedNoise(2e-3), "midpoint")
    assert alone.direct and alone.method == "midpoint"
    assert np.array_equal(alone.var_heading, np.zeros(4))


def test_wheel_noise_alone_is_compiled():
    steps = diff_log()
    noise = WheelNoise(0.01, 0.03)
    plan = plan_noise(steps, noise)
    assert plan.direct is False and plan.var_heading is None and plan.var_params is None
    assert isinstance(plan.wheel, WheelInputs)
    assert np.array_equal(plan.wheel.d_left, steps.inputs["d_left"])
    for a, b in ((0, 7), (7, M)):
        assert np.array_equal(plan.cov_input(a, b), noise.input_cov(steps, a, b))
        assert np.array_equal(plan.wheel.cov_input(a, b), noise.input_cov(steps, a, b))
    # by hand at one step: J diag(k²|d|) Jᵀ with J = [[½, ½], [−1/b, 1/b]]
    jac = np.array([[0.5, 0.5], [-2.5, 2.5]])
    var = np.diag([1e-4 * abs(steps.inputs["d_left"][4]), 9e-4 * abs(steps.inputs["d_right"][4])])
    assert np.allclose(plan.cov_input(4, 5)[0], jac @ var @ jac.T, rtol=1e-12)


def test_two_white_sources_add_and_are_not_compiled():
    steps = diff_log()
    wheel, speed = WheelNoise(0.01, 0.03), SpeedNoise(1e-3)
    plan = plan_noise(steps, (wheel, speed))
    assert plan.wheel is None
    assert np.allclose(plan.cov_input(0, M), wheel.input_cov(steps, 0, M) + speed.input_cov(steps, 0, M),
                       rtol=1e-14, atol=0)


def test_bias_parameters_come_from_the_model():
    steps = diff_log()
    pu = ParameterUncertainty(0.01, 0.02, 0.03)
    plan = plan_noise(steps, NoiseSet.of((WheelNoise(0.01, 0.03), pu)))
    assert isinstance(plan.wheel, WheelInputs)  # the bias adds no white source
    assert np.array_equal(plan.var_params, pu.bias_variances(steps.robot))
    assert np.allclose(plan.var_params, [1e-4, 4e-4, 9e-4], rtol=1e-14)
    assert np.array_equal(plan.param_jacobian(3, 9), pu.bias_jacobian(steps, 3, 9))
    want = diff_parameter_jacobian(steps.inputs["d_left"][3:9], steps.inputs["d_right"][3:9], 0.4)
    assert np.allclose(plan.param_jacobian(3, 9), want, rtol=1e-14)
    # white mode: no bias term; its K diag(σ²) Kᵀ is a white input instead
    white = ParameterUncertainty(0.01, 0.02, 0.03, mode="white")
    plan = plan_noise(steps, white)
    assert plan.var_params is None and plan.param_jacobian(0, 4).shape == (4, 2, 0)
    assert np.array_equal(plan.cov_input(0, M), white.input_cov(steps, 0, M))


def test_method_is_checked_and_classical_noise_brings_its_own():
    steps = diff_log()
    for bad in ("rk4", "classical", ""):
        with pytest.raises(ModelError, match="unknown method"):
            plan_noise(steps, WheelNoise(0.01, 0.01), bad)
    for method in ("exact", "midpoint", "euler"):
        assert plan_noise(steps, WheelNoise(0.01, 0.01), method).method == method
        assert plan_noise(steps, ClassicalNoise(0.01, 0.02), method).method == "classical"


def test_models_are_checked_against_the_robot():
    with pytest.raises(ModelError, match="CompassNoise applies to a CompassOdometry robot"):
        plan_noise(diff_log(), CompassNoise(1e-3))
    with pytest.raises(ModelError, match="WheelNoise applies to a DiffDrive robot"):
        plan_noise(compass_log([0.1, 0.1]), WheelNoise(0.01, 0.01))
