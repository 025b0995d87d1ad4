"""Jacobians by perturbation (manif style); the sinc factor itself: tests/test_angles.py."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odomkit.errors import InputError, ModelError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import (
    body_steps,
    car_body_jacobian,
    car_body_steps,
    car_speed_factor,
    steering_body_jacobian,
    steering_body_steps,
    step_displacement,
    step_jacobians,
    tricycle_body_jacobian,
    tricycle_body_steps,
)
from odomkit.log import OdometryLog
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Tricycle, Unicycle


def step(pose, u, method):
    dx, dy = step_displacement(pose[2], u[0], u[1], method)
    return np.array([pose[0] + dx, pose[1] + dy, pose[2] + u[1]])


@pytest.mark.parametrize("method", ["exact", "midpoint", "euler"])
@settings(max_examples=50, deadline=None)
@given(theta=st.floats(-7, 7), dd=st.floats(-0.5, 0.5), dth=st.floats(-1.5, 1.5))
def test_step_jacobians_match_central_differences(numeric_jacobian, method, theta, dd, dth):
    pose = np.array([0.3, -0.2, theta])
    u = np.array([dd, dth])
    F, G = step_jacobians(theta, dd, dth, method)
    assert np.allclose(F, numeric_jacobian(lambda p: step(p, u, method), pose), atol=1e-8)
    assert np.allclose(G, numeric_jacobian(lambda v: step(pose, v, method), u), atol=1e-8)


def test_tricycle_jacobian_matches_central_differences(numeric_jacobian):
    s, a, L = 0.07, 0.4, 0.68

    def f(v):
        dd, dth = tricycle_body_steps(v[0], v[1], v[2])
        return np.array([dd, dth])

    assert np.allclose(tricycle_body_jacobian(s, a, L), numeric_jacobian(f, [s, a, L]), atol=1e-9)


# Issue 10 item 3: only tick counts are scaled by metres per tick; a log in metres (dist_*)
# or metres per second (speed) is metres already, whatever encoder the robot file
# describes. The calibration factors (c_left, c_right, c_scale) still apply to metres.
def _log(channels, n=5, dt=0.1):
    return OdometryLog(dt * np.arange(n), {k: np.full(n, v, dtype=float) for k, v in channels.items()})


def test_diff_metres_are_not_scaled_by_metres_per_tick_but_are_calibrated():
    robot = DiffDrive(0.5, m_per_tick_left=1e-4, m_per_tick_right=2e-4, c_left=0.99, c_right=1.02)
    steps = body_steps(robot, _log({"dist_left": 0.010, "dist_right": 0.012}))
    assert np.allclose(steps.inputs["d_left"], 0.99 * 0.010, rtol=1e-15, atol=0)
    assert np.allclose(steps.inputs["d_right"], 1.02 * 0.012, rtol=1e-15, atol=0)
    ticks = body_steps(robot, _log({"ticks_left": 100, "ticks_right": 60}))
    assert np.allclose(ticks.inputs["d_left"], 0.99 * 1e-4 * 100, rtol=1e-15, atol=0)
    assert np.allclose(ticks.inputs["d_right"], 1.02 * 2e-4 * 60, rtol=1e-15, atol=0)


@pytest.mark.parametrize("channel, per_step", [("speed", 0.8 * 0.1), ("dist", 0.08)])
def test_tricycle_metres_are_not_scaled_by_metres_per_tick(channel, per_step):
    robot = Tricycle(0.7, m_per_tick=3e-5, c_scale=1.03)
    log = _log({channel: 0.8 if channel == "speed" else per_step, "steer": 0.0})
    assert np.allclose(body_steps(robot, log).inputs["travel"], 1.03 * per_step, rtol=1e-14, atol=0)
    ticks = _log({"ticks": 1000, "steer": 0.0})
    assert np.allclose(body_steps(robot, ticks).inputs["travel"], 1.03 * 3e-5 * 1000, rtol=1e-14, atol=0)


@pytest.mark.parametrize("kind", ["gyro", "compass"])
@pytest.mark.parametrize("channel, per_step", [("speed", 0.5 * 0.1), ("dist", 0.05), ("ticks", 2e-4 * 250)])
def test_kelly_robots_scale_only_ticks(kind, channel, per_step):
    robot = GyroOdometry(m_per_tick=2e-4) if kind == "gyro" else CompassOdometry(m_per_tick=2e-4)
    value = {"speed": 0.5, "dist": 0.05, "ticks": 250}[channel]
    other = {"yaw_rate": 0.0} if kind == "gyro" else {"heading": 0.0}
    assert np.allclose(body_steps(robot, _log({channel: value, **other})).dd, per_step, rtol=1e-14, atol=0)


# --- the car: rear-axle reference, speed at one wheel, front (bicycle) steering -------

@pytest.mark.parametrize("at", ["rear", "front"])
@settings(max_examples=40, deadline=None)
@given(s=st.floats(-0.5, 0.5), a=st.floats(-0.6, 0.6), h=st.floats(-0.9, 0.9))
def test_car_jacobian_matches_central_differences(numeric_jacobian, at, s, a, h):
    def f(v):
        return np.array(car_body_steps(v[0], v[1], v[2], h, at), dtype=float)

    assert np.allclose(car_body_jacobian(s, a, 2.7, h, at), numeric_jacobian(f, [s, a, 2.7]), atol=1e-8)


@pytest.mark.parametrize("at", ["rear", "front"])
@pytest.mark.parametrize("h", [0.0, 0.75, -0.75])
@pytest.mark.parametrize("alpha", [0.3, -0.45])
def test_car_drives_the_closed_circle_of_its_geometry(at, h, alpha):
    """Independent truth: with a constant steering angle α the rear-axle centre turns on a
    circle of radius R = L/tan α about the instantaneous centre (0, R) in the body frame.
    A wheel at (x_w, H) runs on a circle of radius √(x_w² + (R − H)²) about the same
    centre, so one full turn rolls it 2π times that. Fed this travel in 500 steps, the
    body steps must turn the car by exactly 2π and move the rear axle 2πR, back to the
    start."""
    length = 2.7
    radius = length / np.tan(alpha)
    x_w = length if at == "front" else 0.0
    wheel_radius = np.hypot(x_w, radius - h)  # distance of the wheel from the centre
    travel = np.full(500, 2 * np.pi * wheel_radius / 500)  # driving forwards
    steer = np.full(500, alpha)
    dd, dth = car_body_steps(travel, steer, length, h, at)
    turn = 2 * np.pi * np.sign(alpha)  # left (CCW) for α > 0
    assert np.sum(dth) == pytest.approx(turn, rel=1e-12)
    assert np.sum(dd) == pytest.approx(2 * np.pi * abs(radius), rel=1e-12)
    end = dead_reckon(dd, dth)[-1]
    assert np.allclose(end, [0.0, 0.0, turn], atol=1e-9)
    # and the design's rear-encoder formula v = v_e/(1 − tan α·H/L)
    if at == "rear":
        assert float(car_speed_factor(alpha, length, h)) == pytest.approx(
            1 / (1 - np.tan(alpha) * h / length), rel=1e-13)


def test_car_reduces_to_the_tricycle_and_to_a_plain_rear_wheel():
    s, a = np.array([0.1, -0.2, 0.05]), np.array([0.3, -0.2, 0.0])
    # front wheel on the centre line: the tricycle
    assert np.allclose(car_body_steps(s, a, 0.7, 0.0, "front"), tricycle_body_steps(s, a, 0.7),
                       rtol=1e-14, atol=0)
    assert np.allclose(car_body_jacobian(s, a, 0.7, 0.0, "front"), tricycle_body_jacobian(s, a, 0.7),
                       rtol=1e-13, atol=1e-16)
    # rear wheel on the centre line measures the reference point itself
    dd, dth = car_body_steps(s, a, 2.0)
    assert np.array_equal(dd, s) and np.allclose(dth, s * np.tan(a) / 2.0, rtol=1e-14)
    car, tri = Car(0.7, encoder_at="front"), Tricycle(0.7)
    assert np.allclose(steering_body_steps(car, s, a), steering_body_steps(tri, s, a), rtol=1e-14)
    assert np.allclose(steering_body_jacobian(car, s, a), steering_body_jacobian(tri, s, a), rtol=1e-13)
    with pytest.raises(ModelError, match="not a steered vehicle"):
        steering_body_steps(Unicycle(), s, a)  # type: ignore[arg-type]


@pytest.mark.filterwarnings("ignore:.*past any car's lock")
def test_car_rear_wheel_beyond_the_turn_centre_is_refused():
    """tan α·H/L >= 1: the wheel is at or beyond the centre of the turn, its speed is zero
    or runs backwards while the car goes forwards."""
    with pytest.raises(ModelError, match="at or beyond the centre of the turn"):
        car_body_steps([0.1], [1.2], 2.0, 0.9)
    log = _log({"speed": 1.0, "steer": 1.2})
    with pytest.raises(InputError, match="at or beyond the centre"):
        body_steps(Car(2.0, 0.9), log)
    front = body_steps(Car(2.0, 0.9, "front"), log)  # a front wheel is never at the centre
    assert np.all(np.isfinite(front.dd))


@pytest.mark.parametrize("channel, value, per_step", [("speed", 2.0, 0.2), ("dist", 0.2, 0.2),
                                                      ("ticks", 100, 0.01 * 100)])
def test_car_log_channels_scale_and_offset(channel, value, per_step):
    robot = Car(2.7, 0.8, "rear", m_per_tick=0.01, steering_offset=0.02, c_scale=1.01)
    steps = body_steps(robot, _log({channel: value, "steer": 0.1}))
    assert np.allclose(steps.inputs["travel"], 1.01 * per_step, rtol=1e-14, atol=0)
    assert np.allclose(steps.inputs["steer"], 0.12, rtol=1e-14)
    expected = car_body_steps(1.01 * per_step, 0.12, 2.7, 0.8)
    assert np.allclose(steps.dd, expected[0], rtol=1e-14)
    assert np.allclose(steps.dtheta, expected[1], rtol=1e-14)


@pytest.mark.parametrize("ratio", [1.0, 15.0])
def test_car_steering_wheel_angle_over_its_ratio_drives_the_circle_of_the_road_wheel_angle(ratio):
    """A car's CAN logs the steering wheel's angle, ``steering_ratio`` times the road
    wheel's. Independent truth: a constant road-wheel angle α = 0.3 rad and rear-axle speed
    v turn the car at v·tan α / L, and one full turn of 2π brings it back to its start. The
    offset is road-wheel radians, added after the ratio."""
    alpha, offset, length, v, dt = 0.3, 0.01, 2.7, 5.0, 0.05
    n = round(2 * np.pi * length / np.tan(alpha) / (v * dt))
    log = OdometryLog(dt * np.arange(n + 1), {"speed": np.full(n + 1, v),
                                             "steer": np.full(n + 1, ratio * (alpha - offset))})
    steps = body_steps(Car(length, steering_offset=offset, steering_ratio=ratio), log)
    np.testing.assert_allclose(steps.inputs["steer"], alpha, rtol=1e-14)
    np.testing.assert_allclose(steps.dtheta, v * dt * np.tan(alpha) / length, rtol=1e-13)
    turned = float(np.sum(steps.dtheta))
    assert abs(turned - 2 * np.pi) < v * dt * np.tan(alpha) / length  # within one step of a turn
    end = dead_reckon(steps.dd, steps.dtheta)[-1]
    assert np.hypot(*end[:2]) < 2 * v * dt  # back at the start, within a step's travel


def test_a_variable_steering_ratio_maps_and_inverts_exactly():
    """α = s + k·s³ + offset with s = measured / ratio, written out here; the inverse gives
    back the measured angle; and a constant steering-wheel angle drives the circle of its
    road-wheel angle."""
    from odomkit.kinematics import car_measured_steer, car_road_wheel_angle

    car = Car(2.7, steering_offset=0.003, steering_ratio=14.0, steering_cubic=40.0)
    measured = np.linspace(-1.9, 1.9, 41)
    s = measured / 14.0
    np.testing.assert_allclose(car_road_wheel_angle(car, measured), s + 40.0 * s**3 + 0.003, rtol=1e-15)
    for m in measured:
        alpha = float(car_road_wheel_angle(car, m))
        assert car_measured_steer(car, alpha) == pytest.approx(m, abs=1e-12)
    steps = body_steps(car, _log({"speed": 5.0, "steer": 1.2}))
    alpha = 1.2 / 14 + 40 * (1.2 / 14) ** 3 + 0.003
    np.testing.assert_allclose(steps.dtheta, 0.5 * np.tan(alpha) / 2.7, rtol=1e-13)


def test_a_steering_wheel_angle_read_as_the_road_wheel_angle_is_warned_about():
    """80° at the steering wheel read with ratio 1 would steer the bicycle past any car's
    lock (tan 1.4 rad = 5.7): a silently wrong track. Warned, naming steering_ratio; with the
    ratio set, quiet; a road-wheel angle at a real lock (35°) is quiet too."""
    import warnings

    wheel = np.radians(80.0)
    with pytest.warns(UserWarning, match=r"road-wheel angle reaches 1.4 rad \(80°\).*steering_ratio"):
        body_steps(Car(2.7), _log({"speed": 5.0, "steer": wheel}))
    # 100° read as the road wheel's angle is refused outright, naming the ratio (it was
    # refused as a rear wheel "beyond the centre of the turn", with no wheel offset at all).
    with pytest.warns(UserWarning), pytest.raises(InputError, match=r"past ±90°.*steering_ratio"):
        body_steps(Car(2.7), _log({"speed": 5.0, "steer": np.radians(100.0)}))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        body_steps(Car(2.7, steering_ratio=15.0), _log({"speed": 5.0, "steer": wheel}))
        body_steps(Car(2.7), _log({"speed": 5.0, "steer": np.radians(35.0)}))


def test_unicycle_reads_body_velocities_with_gyro_like_corrections():
    robot = Unicycle(c_scale=1.02, yaw_rate_bias=0.01, yaw_rate_scale=0.98)
    steps = body_steps(robot, _log({"speed": 0.5, "yaw_rate": 0.21}))
    assert np.allclose(steps.dd, 1.02 * 0.5 * 0.1, rtol=1e-14)
    assert np.allclose(steps.dtheta, 0.98 * (0.21 - 0.01) * 0.1, rtol=1e-14)
    assert np.allclose(steps.inputs["yaw_rate"], 0.98 * 0.2, rtol=1e-14)
    assert np.allclose(body_steps(robot, _log({"dist": 0.05, "yaw_rate": 0.0})).dd, 1.02 * 0.05, rtol=1e-14)
    with pytest.raises(InputError, match="not ticks"):
        body_steps(robot, _log({"ticks": 5, "yaw_rate": 0.0}))


# --- a travel no wheeled vehicle drives (user study: a raw counter read as increments drove a
# tricycle 561 km in 113 s, exit 0, without a word) -------------------------------------------

def _unicycle_log(speed: float) -> OdometryLog:
    t = 0.05 * np.arange(200)
    return OdometryLog(t, {"speed": np.full(t.size, speed), "yaw_rate": np.full(t.size, 0.1)}, source="u")


def test_too_fast_is_silent_on_a_fast_car_and_names_the_speeds_unit_beyond_any():
    """The median moving speed: a car at 90 m/s (324 km/h) passes; a robot's 0.5 m/s logged in
    mm/s reads 500 m/s and is named, with the speed's unit as the likely cause."""
    from odomkit.kinematics import body_steps, too_fast
    from odomkit.units import FASTEST_SPEED

    robot = Unicycle()
    fast_car = _unicycle_log(0.9 * FASTEST_SPEED)
    assert too_fast(body_steps(robot, fast_car), fast_car) is None
    log = _unicycle_log(500.0)
    what, advice = too_fast(body_steps(robot, log), log)
    assert what.startswith("the odometry moves at 500 m/s") and "mm/s" in advice


def test_too_fast_names_the_counter_for_ticks_and_ignores_a_few_spikes():
    """Ticks: a raw counter read as increments, or m_per_tick. A counter that wraps once, read
    as increments where every other row is right, is a spike, not the median: silent here
    (check's ``counters`` finding names the wrap)."""
    from odomkit.kinematics import body_steps, too_fast

    t = 0.05 * np.arange(400)
    robot = DiffDrive(0.3, m_per_tick_left=1e-4, m_per_tick_right=1e-4)
    raw = 3e9 + np.cumsum(np.full(t.size, 40.0))
    log = OdometryLog(t, {"ticks_left": raw, "ticks_right": raw}, source="raw")
    what, advice = too_fast(body_steps(robot, log), log)
    assert "faster than any wheeled vehicle" in what and "--cumulative" in advice and "m_per_tick" in advice
    steps = np.full(t.size, 40.0)
    steps[200] = -(2.0**32) + 40.0
    log = OdometryLog(t, {"ticks_left": steps, "ticks_right": steps.copy()}, source="wrap")
    assert too_fast(body_steps(robot, log), log) is None


def test_a_tricycle_steering_encoders_ticks_over_its_ratio_drive_the_track_of_radians(tmp_path):
    """A tricycle whose steer channel is an absolute encoder's ticks (8192 a turn: 1303.8 per
    radian; user study: odomkit had no way in) reads them over steering_ratio: the track of
    the same angles in radians, to round-off; the robot file reads and writes the key."""
    from odomkit.io.robotfile import read_robot, write_robot
    from odomkit.track import dead_reckon_log

    per_radian = 8192 / (2 * np.pi)
    t = 0.05 * np.arange(600)
    angle = 0.5 * np.sin(t / 4.0)
    speed = np.full(t.size, 0.3)
    radians = OdometryLog(t, {"speed": speed, "steer": angle})
    ticks = OdometryLog(t, {"speed": speed, "steer": np.round(angle * per_radian) / 1.0})
    plain = dead_reckon_log(radians, Tricycle(1.4, steering_offset=0.01)).poses
    geared = Tricycle(1.4, steering_offset=0.01, steering_ratio=per_radian)
    got = dead_reckon_log(ticks, geared).poses
    np.testing.assert_allclose(got, plain, atol=0.5 / per_radian * 30.0)  # the ticks' rounding only
    assert abs(got[-1, 2] - plain[-1, 2]) < 1e-3 and np.ptp(plain[:, 2]) > 0.5  # it turns
    assert read_robot(write_robot(tmp_path / "tricycle.toml", geared)) == (geared, ())
    with pytest.raises(ModelError, match="steering_ratio"):
        Tricycle(1.4, steering_ratio=0.0)
