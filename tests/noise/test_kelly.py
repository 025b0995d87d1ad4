"""Kelly's speed, gyro and compass noise (:mod:`odomkit.noise.kelly`, Kelly 2001 Table 1):
per-step variances by hand, and the compass's per-sample heading variances checked
against Kelly eq. (13) on a straight line."""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.kinematics import BodySteps
from odomkit.noise import CompassNoise, GyroNoise, SpeedNoise
from odomkit.noise.kelly import direct_heading_variances, speed_gyro_input_cov
from odomkit.path import KellyArc
from odomkit.propagate.closed_kelly import compass_arc_cov
from odomkit.propagate.transition import propagate_direct_heading
from odomkit.robot import CompassOdometry, GyroOdometry


def test_speed_gyro_input_cov_values():
    q = speed_gyro_input_cov([-0.4, 0.2], [0.1, 0.3], SpeedNoise(0.01), GyroNoise(2e-3))
    assert np.allclose(q[:, 0, 0], [0.004, 0.002]) and np.allclose(q[:, 1, 1], [2e-4, 6e-4])
    assert not q[:, 0, 1].any()
    assert not speed_gyro_input_cov([0.4], [0.1]).any()


def test_speed_and_gyro_models_on_a_gyro_log():
    """α_ss·|Δd| (backwards travel counts) on Δd alone; σ_gg·Δt on Δθ alone."""
    dd, dt = np.array([0.05, -0.02, 0.0, 0.03]), np.array([0.1, 0.2, 0.1, 0.05])
    steps = BodySteps(dd, np.zeros(4), dt, {"yaw_rate": np.zeros(4)}, GyroOdometry())
    speed = SpeedNoise(0.01).input_cov(steps, 1, 4)
    gyro = GyroNoise(3e-4).input_cov(steps, 1, 4)
    assert np.allclose(speed[:, 0, 0], [2e-4, 0.0, 3e-4], rtol=1e-14) and not speed[:, 1].any()
    assert np.allclose(gyro[:, 1, 1], [6e-5, 3e-5, 1.5e-5], rtol=1e-14) and not gyro[:, 0].any()


def test_direct_heading_variances_use_the_spacing_around_each_sample():
    """psd/Δt with Δt the mean of the two adjacent steps (one step at the ends)."""
    dt = np.array([0.1, 0.3, 0.2])
    got = direct_heading_variances(dt, CompassNoise(6e-3))
    assert np.allclose(got, 6e-3 / np.array([0.1, 0.2, 0.25, 0.2]), rtol=1e-14)
    assert np.array_equal(direct_heading_variances([], CompassNoise(6e-3)), np.zeros(1))
    with pytest.raises(ModelError, match="dt > 0"):
        direct_heading_variances([0.1, -0.1], CompassNoise(1e-3))
    steps = BodySteps(np.full(3, 0.1), np.zeros(3), dt, {"heading": np.zeros(4)}, CompassOdometry())
    assert np.array_equal(CompassNoise(6e-3).heading_variances(steps), got)


def test_direct_heading_variances_give_kelly_eq_13_on_an_irregularly_sampled_line():
    """Kelly eq. (13): on a straight line at speed V the lateral variance grows as
    |V|·psd·s, however the compass is sampled.

    By hand: heading along x, y_M = Σ_k Δd_k (h_k + h_{k+1})/2, so sample j carries the
    weight V·(Δt_{j−1} + Δt_j)/2 = V·spacing_j (V·Δt/2 at the ends) and, with
    var h_j = psd/spacing_j, var y_M = V²·psd·(T − (Δt_0 + Δt_{M−1})/4). Per-step
    psd/Δt_k instead of the spacing would miss this on uneven steps."""
    rng = np.random.default_rng(31)
    m, v, psd, alpha = 500, 0.8, 3e-4, 2e-3
    dt = rng.uniform(0.02, 0.2, m)
    dd = v * dt
    var_h = direct_heading_variances(dt, CompassNoise(psd))
    cov = propagate_direct_heading(np.zeros(m), dd, np.zeros(m), alpha * dd, var_h,
                                   np.zeros((2, 2)), chunk_size=64)
    t = dt.sum()
    s = v * t
    assert cov[-1, 1, 1] == pytest.approx(v**2 * psd * (t - 0.25 * (dt[0] + dt[-1])), rel=1e-12)
    assert cov[-1, 0, 0] == pytest.approx(alpha * s, rel=1e-12)
    assert np.allclose(cov[:, 2, 2], var_h, rtol=0)  # heading errors do not accumulate
    # the continuous form (Kelly eq. 13 via the closed-form segment) up to the two ends
    kelly = compass_arc_cov(KellyArc(v, 0.0, t), SpeedNoise(alpha), CompassNoise(psd))
    assert kelly[1, 1] == pytest.approx(v * psd * s, rel=1e-12)
    assert cov[-1, 1, 1] == pytest.approx(kelly[1, 1], rel=0.5 * dt.max() / t)


def test_compass_noise_adds_nothing_to_the_integrated_motion():
    steps = BodySteps(np.full(3, 0.1), np.zeros(3), np.full(3, 0.1), {"heading": np.zeros(4)},
                      CompassOdometry())
    model = CompassNoise(1e-3)
    assert model.input_variances(steps, 0, 3).shape == (3, 0)
    assert not model.input_cov(steps, 0, 3).any()
    assert GyroNoise(1e-3).heading_variances(steps) is None


def test_sampled_compass_variance_and_sample_count():
    """A compass read every T: one reading's variance is psd/T (the white error averaged
    over T), which is what direct_heading_variances gives a log sampled every T; a path
    segment must last a whole number of periods (to 1e-9 relative, so float durations
    such as 0.3 s at 0.1 s pass)."""
    from odomkit.noise.kelly import compass_sample_count, direct_heading_variances

    noise = CompassNoise(2e-4)
    assert noise.sample_variance(0.05) == pytest.approx(4e-3, rel=1e-15)
    assert np.allclose(direct_heading_variances(np.full(5, 0.05), noise), noise.sample_variance(0.05))
    assert compass_sample_count(0.3, 0.1) == 3 and compass_sample_count(0.0, 0.1) == 0
    with pytest.raises(ModelError, match="segment 2 lasts 0.25 s"):
        compass_sample_count(0.25, 0.1, 2)
    with pytest.raises(ModelError, match="compass_period"):
        noise.sample_variance(0.0)


@pytest.mark.parametrize(("robot_type", "grows"), [("unicycle", False), ("gyro", True)])
def test_yaw_rate_noise_while_standing_grows_for_a_gyro_not_for_a_velocity_command(robot_type, grows):
    """A gyro drifts while the vehicle stands; a unicycle's commanded (or reported) body
    velocity of zero moves nothing, so its heading variance stays (issue 11)."""
    from odomkit.integrate import dead_reckon
    from odomkit.kinematics import BodySteps
    from odomkit.propagate.recursion import track_covariance
    from odomkit.robot import ROBOT_TYPES

    n = 300
    dd = np.full(n, 0.01)
    dth = np.full(n, 0.005)
    dd[100:250] = dth[100:250] = 0.0
    robot = ROBOT_TYPES[robot_type]()
    steps = BodySteps(dd, dth, np.full(n, 0.1), {"speed": dd / 0.1, "yaw_rate": dth / 0.1}, robot)
    cov = track_covariance(steps, dead_reckon(dd, dth), (SpeedNoise(1e-4), GyroNoise(1e-3)), np.zeros((3, 3)))
    assert bool(cov[250, 2, 2] > cov[100, 2, 2] * 1.5) is grows
    if not grows:
        np.testing.assert_array_equal(cov[250], cov[100])
        factor = GyroNoise(1e-3).input_factor(steps, 0, n)
        assert not np.any(factor[100:250]) and np.all(factor[:100, 1, 0] > 0)
