"""odomkit.track: a log and a robot give the pose track that hand geometry predicts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.errors import InputError, ModelError
from odomkit.log import OdometryLog
from odomkit.noise import WheelNoise
from odomkit.robot import CompassOdometry, DiffDrive, GyroOdometry, Tricycle
from odomkit.track import dead_reckon_log, initial_pose

N = 400            # steps
DT = 0.05          # s


def circle(radius: float, dphi: float, n: int = N, start=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Poses (n + 1, 3) on a circle of signed radius R, heading advancing dphi per step,
    from ``start``: the centre is R to the left of the start heading."""
    x0, y0, th0 = start
    th = th0 + dphi * np.arange(n + 1)
    return np.column_stack((x0 + radius * (np.sin(th) - math.sin(th0)),
                            y0 - radius * (np.cos(th) - math.cos(th0)), th))


def _t(n: int = N) -> np.ndarray:
    return DT * np.arange(n + 1)


def diff_circle_log(radius: float, dphi: float, b: float, truth=None) -> OdometryLog:
    """Wheel increments of a constant-curvature drive: (R ∓ b/2)·δφ per step."""
    dl = np.r_[0.0, np.full(N, (radius - b / 2) * dphi)]
    dr = np.r_[0.0, np.full(N, (radius + b / 2) * dphi)]
    return OdometryLog(_t(), {"dist_left": dl, "dist_right": dr}, truth, "circle.csv")


@pytest.mark.parametrize("radius, dphi", [(2.0, 0.01), (-0.8, 0.02), (1.5, -0.012)])
def test_diff_drive_on_a_circle_gives_the_exact_circle(radius, dphi):
    b = 0.4
    track = dead_reckon_log(diff_circle_log(radius, dphi, b), DiffDrive(b))
    np.testing.assert_allclose(track.poses, circle(radius, dphi), rtol=0, atol=1e-12)
    assert track.path_length == pytest.approx(abs(radius * dphi) * N, rel=1e-12)
    assert track.duration == pytest.approx(N * DT, rel=1e-12)
    assert track.cov is None and np.array_equal(track.t, _t())


def test_ticks_are_scaled_by_metres_per_tick_and_corrections():
    """Ticks times c·m_per_tick are the wheel travel (Borenstein–Feng eq. 4.30–4.32)."""
    radius, dphi, b = 1.0, 0.01, 0.3
    robot = DiffDrive(b / 1.05, m_per_tick_left=1e-4, m_per_tick_right=2e-4,
                      c_left=0.98, c_right=1.01, c_wheel_base=1.05)
    ticks_l = np.r_[0.0, np.full(N, (radius - b / 2) * dphi / (0.98e-4))]
    ticks_r = np.r_[0.0, np.full(N, (radius + b / 2) * dphi / (1.01 * 2e-4))]
    log = OdometryLog(_t(), {"ticks_left": ticks_l, "ticks_right": ticks_r})
    np.testing.assert_allclose(dead_reckon_log(log, robot).poses, circle(radius, dphi),
                               rtol=0, atol=1e-12)


def test_gyro_odometry_on_a_circle_undoes_bias_and_scale():
    """v = 0.5 m/s and ω = 0.25 rad/s: a circle of radius v/ω = 2 m. The gyro reads
    ω/scale + bias; GyroOdometry uses scale·(reading − bias) = ω."""
    v, w, bias, scale = 0.5, 0.25, 0.003, 1.02
    log = OdometryLog(_t(), {"speed": np.full(N + 1, v), "yaw_rate": np.full(N + 1, w / scale + bias)})
    track = dead_reckon_log(log, GyroOdometry(gyro_bias=bias, gyro_scale=scale))
    np.testing.assert_allclose(track.poses, circle(v / w, w * DT), rtol=0, atol=1e-12)


def test_tricycle_on_a_circle_has_radius_wheel_to_axle_over_tan_steer():
    """Front wheel at distance L ahead of the rear axle, steered by α: the rear-axle centre
    turns on a circle of radius L/tan α at rate s·sin α/L for a front-wheel speed s."""
    length, steer, speed = 1.2, 0.3, 0.8
    log = OdometryLog(_t(), {"speed": np.full(N + 1, speed), "steer": np.full(N + 1, steer - 0.01)})
    track = dead_reckon_log(log, Tricycle(length, steering_offset=0.01))
    rate = speed * math.sin(steer) / length
    np.testing.assert_allclose(track.poses, circle(length / math.tan(steer), rate * DT),
                               rtol=0, atol=1e-12)


def test_compass_heading_replaces_the_initial_heading_and_is_unwrapped():
    """A compass reading that wraps from +π to −π is a small turn, not a full one."""
    v, dphi, th0 = 0.4, 0.02, 2.5
    heading = th0 + dphi * np.arange(N + 1)
    wrapped = (heading + np.pi) % (2 * np.pi) - np.pi
    assert np.any(np.diff(wrapped) < -6)       # the premise: the reading does wrap
    log = OdometryLog(_t(), {"speed": np.full(N + 1, v), "heading": wrapped})
    track = dead_reckon_log(log, CompassOdometry(), pose0=(1.0, -2.0, 0.0))
    expected = circle(v * DT / dphi, dphi, start=(1.0, -2.0, th0))
    np.testing.assert_allclose(track.poses, expected, rtol=0, atol=1e-12)


def test_start_pose_comes_from_ground_truth_unless_given():
    radius, dphi, b, start = 1.3, 0.015, 0.4, (3.0, -1.0, 0.7)
    truth = circle(radius, dphi, start=start)
    log = diff_circle_log(radius, dphi, b, truth)
    track = dead_reckon_log(log, DiffDrive(b))
    np.testing.assert_allclose(track.poses, truth, rtol=0, atol=1e-12)
    assert initial_pose(log, None).tolist() == list(start)
    given = dead_reckon_log(log, DiffDrive(b), pose0=(0, 0, 0))
    np.testing.assert_allclose(given.poses, circle(radius, dphi), rtol=0, atol=1e-12)
    no_truth = diff_circle_log(radius, dphi, b)
    assert initial_pose(no_truth, None).tolist() == [0.0, 0.0, 0.0]


def test_covariance_from_an_initial_heading_uncertainty_on_a_straight_line():
    """No noise, heading variance σ² at the start, straight D metres: to first order
    y = D·δθ, so var(y) = D²σ², cov(y, θ) = Dσ², and x and θ keep theirs."""
    n, step, sigma2 = 100, 0.02, 1e-4
    log = OdometryLog(DT * np.arange(n + 1), {"dist_left": np.r_[0.0, np.full(n, step)],
                                              "dist_right": np.r_[0.0, np.full(n, step)]})
    cov0 = np.diag([0.0, 0.0, sigma2])
    track = dead_reckon_log(log, DiffDrive(0.4), noise=WheelNoise(0.0, 0.0), cov0=cov0)
    d = n * step
    expected = np.array([[0.0, 0.0, 0.0], [0.0, d**2 * sigma2, d * sigma2], [0.0, d * sigma2, sigma2]])
    np.testing.assert_allclose(track.cov[0], cov0, rtol=0, atol=0)
    np.testing.assert_allclose(track.cov[-1], expected, rtol=1e-12, atol=1e-20)


def test_bad_input():
    log = diff_circle_log(1.0, 0.01, 0.4)
    with pytest.raises(InputError, match="empty"):
        dead_reckon_log(OdometryLog(np.zeros(0), {}), DiffDrive(0.4))
    with pytest.raises(ModelError, match="initial pose must be three finite numbers"):
        dead_reckon_log(log, DiffDrive(0.4), pose0=(0.0, 0.0))
    with pytest.raises(ModelError, match="initial pose"):
        dead_reckon_log(log, DiffDrive(0.4), pose0=(0.0, math.nan, 0.0))
    with pytest.raises(InputError, match=r"^circle.csv: log has no ticks or dist or speed channel"):
        dead_reckon_log(log, GyroOdometry())
    with pytest.raises(ModelError, match="method"):
        dead_reckon_log(log, DiffDrive(0.4), method="rk4")  # type: ignore[arg-type]
    for bad in (np.diag([1.0, -1.0, 1.0]), np.eye(2), [[1, 1, 0], [0, 1, 0], [0, 0, 1]]):
        with pytest.raises(ModelError, match="initial covariance"):
            dead_reckon_log(log, DiffDrive(0.4), noise=WheelNoise(1e-3, 1e-3), cov0=bad)
