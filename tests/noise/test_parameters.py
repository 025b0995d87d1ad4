"""Uncertain robot parameters (:mod:`odomkit.noise.parameters`): the sensitivities
∂(Δd, Δθ)/∂β by finite differences, and the difference between a constant (bias) and a
white parameter error, checked against closed forms, whole-track finite differences and
Monte Carlo."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import BodySteps, diff_body_steps, tricycle_body_steps
from odomkit.noise import ParameterUncertainty, WheelNoise
from odomkit.noise.parameters import (
    diff_parameter_jacobian,
    scale_parameter_jacobian,
    tricycle_parameter_jacobian,
    white_parameter_cov,
)
from odomkit.propagate.recursion import track_covariance
from odomkit.propagate.transition import parameter_sensitivity
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Tricycle, Unicycle

finite = dict(allow_nan=False, allow_infinity=False)


@settings(max_examples=40, deadline=None)
@given(dl=st.floats(-0.3, 0.3, **finite), dr=st.floats(-0.3, 0.3, **finite))
def test_diff_parameter_jacobian(numeric_jacobian, dl, dr):
    base = 0.35

    def body(p):  # (b, ε_L, ε_R) -> (Δd, Δθ)
        return np.array(diff_body_steps(dl * (1 + p[1]), dr * (1 + p[2]), p[0]))

    got = diff_parameter_jacobian(dl, dr, base)
    assert np.allclose(got, numeric_jacobian(body, [base, 0.0, 0.0]), atol=1e-8)


@settings(max_examples=40, deadline=None)
@given(s=st.floats(-0.5, 0.5, **finite), a=st.floats(-1.2, 1.2, **finite))
def test_tricycle_parameter_jacobian(numeric_jacobian, s, a):
    length = 0.8

    def body(p):  # (L, ε) -> (Δd, Δθ)
        return np.array(tricycle_body_steps(s * (1 + p[1]), a, p[0]))

    got = tricycle_parameter_jacobian(s, a, length)
    assert np.allclose(got, numeric_jacobian(body, [length, 0.0]), atol=1e-8)


def test_scale_parameter_jacobian(numeric_jacobian):
    got = scale_parameter_jacobian([0.3, -0.2])
    num = numeric_jacobian(lambda p: np.array([0.3 * (1 + p[0]), 0.0]), [0.0])
    assert np.allclose(got[0], num)
    assert got[1, 0, 0] == -0.2 and got[1, 1, 0] == 0.0


def test_parameters_per_robot_type():
    """Which parameters exist depends on the vehicle (issue 11 item 1): diff (b, ε_L, ε_R),
    tricycle and car (L, ε, δα), gyro and unicycle (ε, δω, ε_ω), compass (ε, δh); the
    others are refused, not ignored."""
    pu = ParameterUncertainty(0.01, 0.02, 0.03)
    assert np.allclose(pu.bias_variances(DiffDrive(0.4)), [1e-4, 4e-4, 9e-4], rtol=1e-14)
    steered = ParameterUncertainty(0.01, 0.02, sigma_steering_offset=0.005)
    for robot in (Tricycle(0.7), Car(2.7)):
        assert np.allclose(steered.bias_variances(robot), [1e-4, 4e-4, 2.5e-5], rtol=1e-14)
    rate = ParameterUncertainty(sigma_scale_left=0.02, sigma_yaw_rate_offset=0.001,
                                sigma_yaw_rate_scale=0.03)
    for robot in (GyroOdometry(), Unicycle()):
        assert np.allclose(rate.bias_variances(robot), [4e-4, 1e-6, 9e-4], rtol=1e-14)
        assert not rate.bias_heading(robot).any()
        with pytest.raises(ModelError, match="sigma_wheel_base does not apply"):
            pu.check_robot(robot)
    compass = ParameterUncertainty(sigma_scale_left=0.02, sigma_heading_offset=0.01)
    assert np.allclose(compass.bias_variances(CompassOdometry()), [4e-4, 1e-4], rtol=1e-14)
    assert compass.bias_heading(CompassOdometry()).tolist() == [0.0, 1.0]
    with pytest.raises(ModelError, match="one traction wheel"):
        pu.bias_variances(Tricycle(0.7))
    with pytest.raises(ModelError, match="sigma_steering_offset does not apply to a DiffDrive"):
        steered.check_robot(DiffDrive(0.4))


def test_car_parameter_jacobian_matches_finite_differences(numeric_jacobian):
    """∂(Δd, Δθ)/∂(L, ε, δα) of a car, both encoder positions, against its body steps."""
    from odomkit.kinematics import car_body_steps
    from odomkit.noise.parameters import car_parameter_jacobian

    for at in ("rear", "front"):
        for s, a in ((0.3, 0.2), (-0.1, -0.5)):
            def body(p, s=s, a=a, at=at):
                return np.array(car_body_steps(s * (1 + p[1]), a + p[2], p[0], 0.7, at))

            got = car_parameter_jacobian(s, a, 2.5, 0.7, at)
            assert np.allclose(got, numeric_jacobian(body, [2.5, 0.0, 0.0]), atol=1e-9)


def test_mode_sets_the_kind_and_white_mode_repeats_the_parameters_every_step():
    """White mode: the same K and variances as the bias, drawn afresh each step, so
    Q = K diag(σ²) Kᵀ per step (the Sun–Gao exercise's treatment)."""
    rng = np.random.default_rng(51)
    d_l, d_r = rng.uniform(0, 0.05, 20), rng.uniform(0, 0.05, 20)
    steps = BodySteps(*diff_body_steps(d_l, d_r, 0.4), np.full(20, 0.1),
                      {"d_left": d_l, "d_right": d_r}, DiffDrive(0.4))
    bias, white = ParameterUncertainty(0.01, 0.02, 0.03), ParameterUncertainty(0.01, 0.02, 0.03, "white")
    assert bias.kind == "bias" and white.kind == "white"
    assert np.allclose(white.input_variances(steps, 3, 9), [1e-4, 4e-4, 9e-4], rtol=1e-14)
    k = diff_parameter_jacobian(d_l[3:9], d_r[3:9], 0.4)
    assert np.allclose(white.input_jacobian(steps, 3, 9), k, rtol=1e-14)
    assert np.allclose(white.input_cov(steps, 3, 9),
                       np.einsum("nik,k,njk->nij", k, [1e-4, 4e-4, 9e-4], k), rtol=1e-12, atol=1e-22)
    assert np.allclose(bias.bias_jacobian(steps, 3, 9), k, rtol=1e-14)


# --- parameter uncertainty: bias (constant) versus white (fresh every step) -----------

def test_scale_bias_on_a_long_straight_line_matches_the_closed_form(straight_diff):
    """D = 10 m in M = 1000 steps, wheel scales ε_L, ε_R ~ σ each, constant.

    Bias (derived by hand): δx = D(ε_L+ε_R)/2, δθ = D(ε_R−ε_L)/b, δy = ∫δθ(s)ds
    = D²(ε_R−ε_L)/(2b) -> var x = D²σ²/2, var θ = 2D²σ²/b², var y = D⁴σ²/(2b²).
    White: every step draws fresh ε, so var x = M·(D/M)²σ²/2 = D²σ²/(2M): M times less.
    """
    m, dist, base, sigma = 1000, 10.0, 0.4, 1e-3
    steps = straight_diff(m, dist, base)
    poses = dead_reckon(steps.dd, steps.dtheta)
    zero = np.zeros((3, 3))
    bias = track_covariance(steps, poses, ParameterUncertainty(0.0, sigma, sigma, "bias"), zero)
    white = track_covariance(steps, poses, ParameterUncertainty(0.0, sigma, sigma, "white"), zero)
    b = bias[-1]
    assert b[0, 0] == pytest.approx(dist**2 * sigma**2 / 2, rel=1e-12)
    assert b[2, 2] == pytest.approx(2 * dist**2 * sigma**2 / base**2, rel=1e-12)
    # exact-arc lever: step k's error acts from its midpoint -> Σ(D−(k+½)D/M)·D/M = D²/2
    assert b[1, 1] == pytest.approx(dist**4 * sigma**2 / (2 * base**2), rel=1e-12)
    assert white[-1, 0, 0] == pytest.approx(dist**2 * sigma**2 / (2 * m), rel=1e-12)
    assert white[-1, 1, 1] < b[1, 1] / 100


@pytest.mark.parametrize("engine", ["recursion", "transition"])
def test_wheel_base_bias_on_a_circle_is_the_sensitivity_outer_product(numeric_jacobian, engine):
    """Bias mode must equal s·s^T σ² with s = ∂pose_M/∂b by finite differences of the
    whole dead reckoning, plus the independent wheel noise."""
    m, base, sigma_b = 400, 0.4, 0.005
    d_l, d_r = np.full(m, 0.02), np.full(m, 0.025)  # circle, 1.5 turns
    dd, dth = diff_body_steps(d_l, d_r, base)
    steps = BodySteps(dd, dth, np.full(m, 0.1), {"d_left": d_l, "d_right": d_r}, DiffDrive(base))
    poses = dead_reckon(dd, dth)
    pu = ParameterUncertainty(sigma_wheel_base=sigma_b)
    cov = track_covariance(steps, poses, pu, np.zeros((3, 3)), engine=engine, chunk_size=64)
    sens = numeric_jacobian(lambda b: dead_reckon(*diff_body_steps(d_l, d_r, b[0]))[-1],
                            [base], 1e-7)
    assert np.allclose(cov[-1], sigma_b**2 * sens @ sens.T, rtol=1e-6, atol=1e-14)
    wheel = WheelNoise(0.01, 0.01)
    both = track_covariance(steps, poses, (wheel, pu), np.zeros((3, 3)), engine=engine)
    alone = track_covariance(steps, poses, wheel, np.zeros((3, 3)), engine=engine)
    assert np.allclose(both, alone + cov, rtol=1e-12, atol=1e-18)
    white = track_covariance(steps, poses, ParameterUncertainty(sigma_b, mode="white"),
                             np.zeros((3, 3)), engine=engine)
    assert white[-1, 1, 1] < cov[-1, 1, 1] / 10


def test_bias_mode_matches_monte_carlo_and_white_mode_does_not():
    """2000 runs, each with one constant wheel-base error b ~ N(b0, σ_b²).

    The sample variance of the final y has relative standard error √(2/(n−1)) = 3.2 %;
    4 of those (13 %) is the tolerance. The white prediction is about 1/M of it."""
    rng = np.random.default_rng(12)
    m, base, sigma_b, runs = 200, 0.4, 0.002, 2000
    d_l, d_r = np.full(m, 0.01), np.full(m, 0.012)
    dd, dth = diff_body_steps(d_l, d_r, base)
    steps = BodySteps(dd, dth, np.full(m, 0.1), {"d_left": d_l, "d_right": d_r}, DiffDrive(base))
    poses = dead_reckon(dd, dth)
    ends = np.array([dead_reckon(*diff_body_steps(d_l, d_r, b))[-1]
                     for b in base + sigma_b * rng.standard_normal(runs)])
    var_mc = ends.var(axis=0, ddof=1)
    tol = 4 * np.sqrt(2 / (runs - 1))
    for mode, ok in (("bias", True), ("white", False)):
        cov = track_covariance(steps, poses, ParameterUncertainty(sigma_b, mode=mode),
                               np.zeros((3, 3)))[-1]
        close = abs(cov[1, 1] / var_mc[1] - 1) < tol and abs(cov[2, 2] / var_mc[2] - 1) < tol
        assert close == ok, (mode, cov.diagonal(), var_mc)


def test_tricycle_and_gyro_parameter_bias_are_sensitivities(numeric_jacobian):
    rng = np.random.default_rng(13)
    m, length = 100, 0.7
    travel, steer = rng.uniform(0.0, 0.05, m), rng.normal(0.2, 0.2, m)
    dd, dth = tricycle_body_steps(travel, steer, length)
    steps = BodySteps(dd, dth, np.full(m, 0.1), {"travel": travel, "steer": steer},
                      Tricycle(length))
    poses = dead_reckon(dd, dth)
    pu = ParameterUncertainty(sigma_wheel_base=0.01, sigma_scale_left=0.02)
    cov = track_covariance(steps, poses, pu, np.zeros((3, 3)))[-1]
    sens = numeric_jacobian(
        lambda p: dead_reckon(*tricycle_body_steps(travel * (1 + p[1]), steer, p[0]))[-1],
        [length, 0.0], 1e-7)
    assert np.allclose(cov, sens @ np.diag([1e-4, 4e-4]) @ sens.T, rtol=1e-6, atol=1e-14)

    gsteps = BodySteps(dd, dth, np.full(m, 0.1), {"yaw_rate": dth / 0.1}, GyroOdometry())
    cov = track_covariance(gsteps, poses, ParameterUncertainty(sigma_scale_left=0.02),
                           np.zeros((3, 3)), engine="transition")[-1]
    sens = numeric_jacobian(lambda p: dead_reckon(dd * (1 + p[0]), dth)[-1], [0.0], 1e-7)
    assert np.allclose(cov, 4e-4 * sens @ sens.T, rtol=1e-6, atol=1e-14)


def test_parameter_sensitivity_function_and_white_cov(numeric_jacobian):
    rng = np.random.default_rng(14)
    d_l, d_r = rng.uniform(0, 0.05, 50), rng.uniform(0, 0.05, 50)
    dd, dth = diff_body_steps(d_l, d_r, 0.4)
    poses = dead_reckon(dd, dth)
    sens = parameter_sensitivity(poses[:-1, 2], dd, dth, diff_parameter_jacobian(d_l, d_r, 0.4))

    def end(p):
        return dead_reckon(*diff_body_steps(d_l * (1 + p[1]), d_r * (1 + p[2]), p[0]))[-1]

    assert np.allclose(sens[-1], numeric_jacobian(end, [0.4, 0.0, 0.0], 1e-7), atol=1e-7)
    k = diff_parameter_jacobian(d_l, d_r, 0.4)
    q = white_parameter_cov(k, [1e-4, 0.0, 0.0])
    assert np.allclose(q[:, 1, 1], 1e-4 * k[:, 1, 0] ** 2) and not q[:, 0, 0].any()


# --- every vehicle's bias through the engines (issue 11 item 1) ----------------------
# Each β maps onto the robot's own calibration fields, so the independent truth is the
# whole pipeline (log channels -> body steps -> dead reckoning) differentiated by finite
# differences in those fields.
def _vehicle_cases():
    from dataclasses import replace

    from odomkit.log import OdometryLog

    rng = np.random.default_rng(21)
    n = 120
    t = np.cumsum(np.r_[0.0, rng.uniform(0.05, 0.15, n - 1)])
    steer = 0.3 * np.sin(np.linspace(0, 4, n)) + 0.05
    ticks = rng.uniform(80, 120, n)
    rate = 0.4 * np.cos(np.linspace(0, 3, n))
    logs = {
        "diff": OdometryLog(t, {"ticks_left": ticks, "ticks_right": ticks * 1.15}),
        "steered": OdometryLog(t, {"speed": rng.uniform(0.5, 1.0, n), "steer": steer}),
        "rate": OdometryLog(t, {"ticks": ticks, "yaw_rate": rate}),
        "unicycle": OdometryLog(t, {"speed": rng.uniform(0.5, 1.0, n), "yaw_rate": rate}),
        # told to stand (speed and yaw rate zero) for rows 40-79: no bias turns it there
        "stops": OdometryLog(t, {"speed": np.where((t > t[40]) & (t < t[80]), 0.0, 0.7),
                                 "yaw_rate": np.where((t > t[40]) & (t < t[80]), 0.0, rate)}),
        "compass": OdometryLog(t, {"ticks": ticks, "heading": np.cumsum(rate * 0.1)}),
    }
    # (robot, log, noise, β -> robot with the parameters perturbed)
    return [
        ("diff", DiffDrive(0.4, 1e-4, 1e-4), logs["diff"],
         ParameterUncertainty(0.01, 0.02, 0.03),
         lambda r, p: replace(r, wheel_base=r.wheel_base + p[0], c_left=1 + p[1], c_right=1 + p[2])),
        ("tricycle", Tricycle(0.7), logs["steered"],
         ParameterUncertainty(0.01, 0.02, sigma_steering_offset=0.01),
         lambda r, p: replace(r, wheel_to_axle=r.wheel_to_axle + p[0], c_scale=1 + p[1],
                              steering_offset=p[2])),
        ("car-rear", Car(2.7, 0.8), logs["steered"],
         ParameterUncertainty(0.01, 0.02, sigma_steering_offset=0.01),
         lambda r, p: replace(r, wheel_base=r.wheel_base + p[0], c_scale=1 + p[1], steering_offset=p[2])),
        ("car-front", Car(2.7, -0.8, "front"), logs["steered"],
         ParameterUncertainty(0.01, 0.02, sigma_steering_offset=0.01),
         lambda r, p: replace(r, wheel_base=r.wheel_base + p[0], c_scale=1 + p[1], steering_offset=p[2])),
        # an additive yaw-rate error δω is a gyro_bias of −δω (gyro_scale 1)
        ("gyro", GyroOdometry(1e-4), logs["rate"],
         ParameterUncertainty(0, 0.02, sigma_yaw_rate_offset=0.003, sigma_yaw_rate_scale=0.02),
         lambda r, p: replace(r, m_per_tick=1e-4 * (1 + p[0]), gyro_bias=-p[1], gyro_scale=1 + p[2])),
        ("unicycle", Unicycle(), logs["unicycle"],
         ParameterUncertainty(0, 0.02, sigma_yaw_rate_offset=0.003, sigma_yaw_rate_scale=0.02),
         lambda r, p: replace(r, c_scale=1 + p[0], yaw_rate_bias=-p[1], yaw_rate_scale=1 + p[2])),
        ("unicycle-stops", Unicycle(), logs["stops"],
         ParameterUncertainty(0, 0.02, sigma_yaw_rate_offset=0.003, sigma_yaw_rate_scale=0.02),
         lambda r, p: replace(r, c_scale=1 + p[0], yaw_rate_bias=-p[1], yaw_rate_scale=1 + p[2])),
        ("compass", CompassOdometry(1e-4), logs["compass"],
         ParameterUncertainty(0, 0.02, sigma_heading_offset=0.01),
         lambda r, p: replace(r, m_per_tick=1e-4 * (1 + p[0]), heading_offset=p[1])),
    ]


@pytest.mark.parametrize("case", _vehicle_cases(), ids=lambda c: c[0])
@pytest.mark.parametrize("engine", ["recursion", "transition"])
def test_every_vehicles_bias_is_the_whole_track_sensitivity(numeric_jacobian, case, engine):
    """cov_k = S_k diag(σ²) S_kᵀ with S_k = ∂pose_k/∂β from finite differences of the
    whole dead reckoning, at every 10th row (row 0 too: a compass's heading offset moves
    its measured start heading), chunked so that S crosses chunk boundaries."""
    from odomkit.track import dead_reckon_log

    _, robot, log, noise, perturbed = case
    track = dead_reckon_log(log, robot)
    var = noise.bias_variances(robot)
    cov = track_covariance(track.steps, track.poses, noise, np.zeros((3, 3)), engine=engine,
                           chunk_size=37)
    p0 = np.zeros(var.size)
    rows = np.arange(0, len(log), 10)
    sens = numeric_jacobian(lambda p: dead_reckon_log(log, perturbed(robot, p)).poses[rows].ravel(), p0, 1e-6)
    sens = sens.reshape(rows.size, 3, var.size)
    want = np.einsum("nip,p,njp->nij", sens, var, sens)
    assert np.allclose(cov[rows], want, rtol=1e-5, atol=1e-12 * np.abs(want).max())
