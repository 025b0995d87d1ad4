"""Jacobians by perturbation (manif style); the sinc factor itself: tests/test_angles.py."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odomkit.kinematics import (
    body_steps,
    step_displacement,
    step_jacobians,
    tricycle_body_jacobian,
    tricycle_body_steps,
)
from odomkit.log import OdometryLog
from odomkit.robot import CompassOdometry, DiffDrive, GyroOdometry, Tricycle


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
