"""Tricycle noise (:mod:`odomkit.noise.tricycle`): white speed, steering and sample-period
noise (Sun–Gao, Snowhite part), its Jacobian by finite differences and Q by hand."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps, diff_body_steps, tricycle_body_steps
from odomkit.noise import TricycleNoise
from odomkit.noise.tricycle import tricycle_input_cov, tricycle_input_jacobian
from odomkit.robot import DiffDrive, Tricycle

finite = dict(allow_nan=False, allow_infinity=False)


@settings(max_examples=40, deadline=None)
@given(s=st.floats(-0.5, 0.5, **finite), a=st.floats(-1.2, 1.2, **finite),
       t=st.floats(0.01, 0.2, **finite))
def test_tricycle_input_jacobian(numeric_jacobian, s, a, t):
    length = 0.8

    def body(x):  # (v, α, T) -> (Δd, Δθ), Sun–Gao Snowhite model
        return np.array(tricycle_body_steps(x[0] * x[2], x[1], length))

    got = tricycle_input_jacobian(s, a, t, length)
    assert np.allclose(got, numeric_jacobian(body, [s / t, a, t], 1e-7), atol=1e-7)


def test_tricycle_input_cov_values():
    # straight ahead: Δd = vT; var = T²σv² + v²σT² (speed and sample-period noise)
    q = tricycle_input_cov([0.2], [0.0], [0.1], 1.0, TricycleNoise(0.05, 0.01, 0.001))[0]
    assert q[0, 0] == pytest.approx(0.1**2 * 0.05**2 + 2.0**2 * 0.001**2)
    assert q[1, 1] == pytest.approx((0.2 * 0.01) ** 2)  # Δθ = s·α/L near α = 0


def test_zero_duration_step_keeps_only_the_steering_error():
    """T = 0 (a repeated time stamp): the speed is taken as 0, so only the steering error
    of the travelled s acts: J = [[0, −s sin α, 0], [0, s cos α / L, 0]] by hand."""
    s, alpha, length, sigma_a = 0.1, 0.3, 0.7, 0.02
    q = tricycle_input_cov([s], [alpha], [0.0], length, TricycleNoise(0.5, sigma_a, 0.01))[0]
    col = np.array([-s * np.sin(alpha), s * np.cos(alpha) / length])
    assert np.allclose(q, sigma_a**2 * np.outer(col, col), rtol=1e-14, atol=0)


def test_tricycle_noise_takes_l_from_the_robot(numeric_jacobian):
    """The model's Q on a log equals J diag(σ²) Jᵀ with the robot's wheel_to_axle and J by
    finite differences of the body motion in (v, α, T)."""
    rng = np.random.default_rng(41)
    m, length = 12, 0.68
    travel, steer = rng.uniform(0, 0.05, m), rng.uniform(-0.5, 0.5, m)
    dt = rng.uniform(0.05, 0.15, m)
    steps = BodySteps(*tricycle_body_steps(travel, steer, length), dt,
                      {"travel": travel, "steer": steer}, Tricycle(length))
    q = TricycleNoise(0.01, 0.02, 0.003).input_cov(steps, 2, 10)
    assert q.shape == (8, 2, 2)

    def body(x):  # (v, α, T) -> (Δd, Δθ)
        return np.array(tricycle_body_steps(x[0] * x[2], x[1], length))

    for k in (2, 9):
        jac = numeric_jacobian(body, [travel[k] / dt[k], steer[k], dt[k]], 1e-7)
        want = jac @ np.diag([0.01**2, 0.02**2, 0.003**2]) @ jac.T
        assert np.allclose(q[k - 2], want, rtol=1e-6, atol=1e-18)


def test_tricycle_noise_needs_travel_and_steering():
    d = np.full(3, 0.1)
    steps = BodySteps(*diff_body_steps(d, d, 0.4), np.full(3, 0.1), {"d_left": d, "d_right": d},
                      DiffDrive(0.4))
    with pytest.raises(ModelError, match="TricycleNoise needs the per-step input 'travel'"):
        TricycleNoise(0.01, 0.02).input_cov(steps, 0, 3)
    with pytest.raises(ModelError, match="TricycleNoise applies to a Tricycle or Car robot"):
        TricycleNoise(0.01, 0.02).check_robot(steps.robot)


@pytest.mark.parametrize("engine", ["recursion", "transition"])
def test_noise_does_not_grow_while_the_vehicle_stands_still(engine):
    """Issue 11: a tricycle that stands (encoder travel exactly 0) gathers no covariance,
    however long it stands; it grows again as soon as it moves."""
    from odomkit.integrate import dead_reckon
    from odomkit.propagate.recursion import track_covariance

    n = 300
    travel = np.full(n, 0.01)
    travel[100:250] = 0.0  # 15 s standing at 10 Hz
    steer = np.full(n, 0.2)
    robot = Tricycle(0.5)
    dd, dth = tricycle_body_steps(travel, steer, robot.wheel_to_axle)
    steps = BodySteps(dd, dth, np.full(n, 0.1), {"travel": travel, "steer": steer}, robot)
    poses = dead_reckon(dd, dth)
    cov = track_covariance(steps, poses, TricycleNoise(0.05, 0.01, 0.001), np.zeros((3, 3)),
                           engine=engine)
    np.testing.assert_allclose(cov[250], cov[100], rtol=1e-12, atol=1e-18)
    assert cov[101, 0, 0] == cov[100, 0, 0]
    assert np.trace(cov[260]) > np.trace(cov[250]) * 1.01
    # The Monte Carlo factor agrees: no draw moves a standing step.
    factor = TricycleNoise(0.05, 0.01, 0.001).input_factor(steps, 0, n)
    assert not np.any(factor[100:250]) and np.all(np.abs(factor[:100, 0, 0]) > 0)
