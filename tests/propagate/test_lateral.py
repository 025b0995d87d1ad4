"""Lateral slip in the covariance engines (:mod:`odomkit.propagate.lateral`).

Independent truth: a brute-force numpy recursion with the slip as a third input of G,
P ← F P Fᵀ + [G | ū] diag(Q, c) [G | ū]ᵀ, where ū is the unit normal of each step's
actual displacement (from the step map, not from the module's heading rule); the exact
sum and a fine quadrature for the closed forms; every engine against the others.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from odomkit.errors import ModelError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import BodySteps, diff_body_steps
from odomkit.noise import (
    ClassicalNoise,
    CompassNoise,
    GyroNoise,
    LateralSlipNoise,
    ParameterUncertainty,
    SpeedNoise,
    WheelNoise,
)
from odomkit.path import Arc, KellyArc, Spin, Straight
from odomkit.propagate.inputs import any_step_displacement, any_step_jacobians
from odomkit.propagate.lateral import lateral_headings, lateral_segment_cov, lateral_sums
from odomkit.propagate.plan import plan_noise
from odomkit.propagate.predict import predict
from odomkit.propagate.recursion import propagate_recursion, track_covariance
from odomkit.propagate.transition import propagate_direct_heading, propagate_transition
from odomkit.robot import CompassOdometry, DiffDrive, GyroOdometry

METHODS = ["exact", "midpoint", "euler", "classical"]


def _psd(rng, n, scale):
    a = rng.normal(size=(n, n))
    return scale * a @ a.T


def _random_steps(rng, m):
    dd = rng.uniform(-0.1, 0.3, m)
    dd[np.abs(dd) < 1e-3] = 0.05  # every step moves: its normal is defined
    dtheta = rng.normal(0.0, 0.4, m)
    theta = 0.3 + np.concatenate([[0.0], np.cumsum(dtheta)[:-1]])
    return theta, dd, dtheta


def brute_force(theta, dd, dtheta, q, var_lat, cov0, method):
    """Chong–Kleeman eq. (2) with a 3-input G: (Δd, Δθ, sideways ε), 3×3 products."""
    F, G = any_step_jacobians(theta, dd, dtheta, method)
    dx, dy = any_step_displacement(theta, dd, dtheta, method)
    out = [np.array(cov0, dtype=float)]
    for k in range(dd.size):
        norm = math.hypot(dx[k], dy[k])
        normal = np.array([-dy[k] / norm, dx[k] / norm, 0.0])
        G3 = np.column_stack([G[k], normal])
        Q3 = np.zeros((3, 3))
        Q3[:2, :2] = q[k]
        Q3[2, 2] = var_lat[k]
        out.append(F[k] @ out[-1] @ F[k].T + G3 @ Q3 @ G3.T)
    return np.array(out)


def _close(a, b, rtol=1e-10):
    scale = np.abs(b).max()
    np.testing.assert_allclose(a, b, rtol=0, atol=rtol * scale)


@pytest.mark.parametrize("method", METHODS)
def test_running_sum_equals_the_three_input_recursion(method):
    rng = np.random.default_rng(11)
    m = 300
    theta, dd, dtheta = _random_steps(rng, m)
    q = np.array([_psd(rng, 2, 1e-4) for _ in range(m)])
    var_lat = rng.uniform(0.0, 2e-3, m)
    cov0 = _psd(rng, 3, 1e-3)  # correlated start: the slip must not interact with it
    truth = brute_force(theta, dd, dtheta, q, var_lat, cov0, method)
    for chunk in (m, 7):
        rec = propagate_recursion(theta, dd, dtheta, q, cov0, method, chunk_size=chunk,
                                  var_lateral=var_lat)
        _close(rec, truth)
    poses = np.empty((m + 1, 3))
    poses[:-1, 2], poses[-1, 2] = theta, theta[-1] + dtheta[-1]
    dx, dy = any_step_displacement(theta, dd, dtheta, method)
    poses[:, 0] = np.concatenate([[0.0], np.cumsum(dx)])
    poses[:, 1] = np.concatenate([[0.0], np.cumsum(dy)])
    _close(propagate_transition(poses, dd, dtheta, q, cov0, method, chunk_size=37,
                                var_lateral=var_lat), truth)
    # and the slip alone is the difference, in the x–y block only
    without = brute_force(theta, dd, dtheta, q, np.zeros(m), cov0, method)
    diff = truth - without
    assert np.abs(diff[:, 2, :]).max() < 1e-15 and np.abs(diff[:, :, 2]).max() < 1e-15
    sums = lateral_sums(theta, dtheta, var_lat, method)
    _close(diff[1:, :2, :2].reshape(m, 4)[:, [0, 1, 3]], sums, rtol=1e-9)


def _diff_log(rng, m, base=0.4):
    dl = rng.uniform(0.002, 0.02, m)
    dr = rng.uniform(0.002, 0.02, m)
    dd, dth = diff_body_steps(dl, dr, base)
    steps = BodySteps(dd, dth, np.full(m, 0.02), {"d_left": dl, "d_right": dr}, DiffDrive(base))
    return steps, dead_reckon(dd, dth, (1.0, -2.0, 0.5))


def test_track_covariance_keeps_the_wheel_fast_path_and_matches_brute_force():
    rng = np.random.default_rng(5)
    steps, poses = _diff_log(rng, 2000)
    noise = (WheelNoise(0.01, 0.015), LateralSlipNoise(5e-4))
    assert plan_noise(steps, noise).wheel is not None  # the compiled per-wheel Q_k stays
    cov0 = np.diag([1e-4, 2e-4, 1e-3])
    q = WheelNoise(0.01, 0.015).input_cov(steps, 0, len(steps))
    truth = brute_force(poses[:-1, 2], steps.dd, steps.dtheta, q, 5e-4 * np.abs(steps.dd), cov0, "exact")
    ref = track_covariance(steps, poses, noise, cov0)
    _close(ref, truth)
    for chunk in (1, 100, 999):  # chunking changes no bit
        assert np.array_equal(track_covariance(steps, poses, noise, cov0, chunk_size=chunk), ref)
    _close(track_covariance(steps, poses, noise, cov0, engine="transition", chunk_size=300), ref)


def _gyro_log(rng, m):
    dd = rng.uniform(0.01, 0.05, m)
    dt = np.full(m, 0.05)
    rate = rng.normal(0.0, 0.8, m)
    steps = BodySteps(dd, rate * dt, dt, {"yaw_rate": rate}, GyroOdometry())
    return steps, dead_reckon(dd, rate * dt)


def test_transition_engine_equals_recursion_with_bias_and_slip():
    rng = np.random.default_rng(9)
    steps, poses = _gyro_log(rng, 1500)
    noise = (SpeedNoise(1e-3), GyroNoise(1e-4), LateralSlipNoise(2e-3),
             ParameterUncertainty(sigma_scale_left=0.01, sigma_yaw_rate_offset=1e-3))
    rec = track_covariance(steps, poses, noise, np.zeros((3, 3)), chunk_size=400)
    tra = track_covariance(steps, poses, noise, np.zeros((3, 3)), engine="transition", chunk_size=256)
    _close(tra, rec)
    # the slip adds its running sum to the x–y block and nothing else, bias or not
    without = track_covariance(steps, poses, noise[:2] + noise[3:], np.zeros((3, 3)))
    sums = lateral_sums(poses[:-1, 2], steps.dtheta, 2e-3 * np.abs(steps.dd), "exact")
    _close((rec - without)[1:, :2, :2].reshape(-1, 4)[:, [0, 1, 3]], sums, rtol=1e-9)
    assert np.abs((rec - without)[:, 2, :]).max() < 1e-13


def test_direct_heading_engine_adds_the_running_sum():
    rng = np.random.default_rng(4)
    m = 800
    dt = np.full(m, 0.1)
    heading = 0.2 + np.cumsum(np.concatenate([[0.0], rng.normal(0.0, 0.1, m)]))
    dd = rng.uniform(0.01, 0.1, m)
    steps = BodySteps(dd, np.diff(heading), dt, {"heading": heading}, CompassOdometry())
    poses = dead_reckon(dd, np.diff(heading), (0.0, 0.0, heading[0]))
    base = (SpeedNoise(1e-3), CompassNoise(1e-5))
    cov0 = np.diag([1e-3, 1e-3, 0.0])
    with_slip = track_covariance(steps, poses, base + (LateralSlipNoise(1e-3),), cov0, chunk_size=333)
    without = track_covariance(steps, poses, base, cov0)
    var_lat = 1e-3 * dd
    # independent: the normals of the actual displacements
    dx, dy = any_step_displacement(heading[:-1], dd, np.diff(heading), "exact")
    n = np.stack([-dy, dx], axis=1) / np.hypot(dx, dy)[:, None]
    expected = np.cumsum(var_lat[:, None, None] * n[:, :, None] * n[:, None, :], axis=0)
    _close((with_slip - without)[1:, :2, :2], expected, rtol=1e-9)
    assert np.abs((with_slip - without)[:, 2, :]).max() == 0.0
    plan = plan_noise(steps, base, "exact")
    direct = propagate_direct_heading(heading[:-1], dd, np.diff(heading), plan.var_dd(0, m),
                                      plan.var_heading, cov0[:2, :2], chunk_size=101,
                                      var_lateral=var_lat)
    _close(direct, with_slip)


@pytest.mark.parametrize("noise,robot,log", [
    ((WheelNoise(0.01, 0.02),), None, "diff"),
    ((SpeedNoise(1e-3), GyroNoise(1e-4), ParameterUncertainty(sigma_scale_left=0.01)), None, "gyro"),
], ids=["wheel-fast-path", "gyro+bias"])
def test_zero_slip_changes_no_bit(noise, robot, log):
    rng = np.random.default_rng(2)
    steps, poses = _diff_log(rng, 700) if log == "diff" else _gyro_log(rng, 700)
    cov0 = np.diag([1e-4, 1e-4, 1e-5])
    for engine in ("recursion", "transition"):
        ref = track_covariance(steps, poses, noise, cov0, engine=engine)
        zero = track_covariance(steps, poses, noise + (LateralSlipNoise(0.0),), cov0, engine=engine)
        assert np.array_equal(ref, zero)


PATHS = {
    "wheel": ([Arc(3.0, 1.0), Straight(2.0), Spin(1.0), Arc(-1.0, -2.0)], (WheelNoise(0.01, 0.01),),
              {"wheel_base": 0.4}),
    "classical": ([Arc(3.0, 1.0), Straight(2.0)], (ClassicalNoise(0.01, 0.02),), {"wheel_base": 0.4}),
    "gyro": ([KellyArc(1.0, 0.3, 5.0), KellyArc(0.5, -0.8, 4.0)], (SpeedNoise(1e-3), GyroNoise(1e-4)), {}),
    "compass": ([KellyArc(1.0, 0.3, 5.0), KellyArc(0.5, -0.8, 4.0)], (SpeedNoise(1e-3), CompassNoise(1e-5)),
                {}),
}


@pytest.mark.parametrize("family", sorted(PATHS))
def test_zero_slip_changes_no_prediction(family):
    segs, noise, kw = PATHS[family]
    for engine in ("closed", "recursion", "transition"):
        ref = predict(segs, noise, engine=engine, partitions=50, **kw)
        zero = predict(segs, noise + (LateralSlipNoise(0.0),), engine=engine, partitions=50, **kw)
        assert np.array_equal(ref.cov, zero.cov) and np.array_equal(ref.pose, zero.pose)


@pytest.mark.parametrize("family", sorted(PATHS))
def test_closed_form_agrees_with_the_engines(family):
    segs, noise, kw = PATHS[family]
    noise = noise + (LateralSlipNoise(2e-3),)
    n = 20 if family == "classical" else 2000
    closed = predict(segs, noise, engine="closed", partitions=n, **kw)
    for engine in ("recursion", "transition"):
        p = predict(segs, noise, engine=engine, partitions=n, **kw)
        # compass and classical: the same steps, exact sums; the arcs: the integral, which
        # the midpoint-rule sum approaches as (Δθ/n)²
        rtol = 1e-11 if family in ("compass", "classical") else 1e-6
        _close(p.cov, closed.cov, rtol=rtol)
        np.testing.assert_allclose(p.pose, closed.pose, atol=1e-9)


@pytest.mark.parametrize("dtheta", [0.0, 1e-9, 0.3, -2.0, math.pi, 5.0])
def test_segment_integral_and_sum(dtheta):
    alpha, length, theta0 = 3e-3, -2.5, 0.7
    n = 20000
    chords = theta0 + (np.arange(n) + 0.5) * dtheta / n
    normals = np.stack([-np.sin(chords), np.cos(chords)], axis=1)
    fine = alpha * abs(length) / n * np.einsum("ki,kj->ij", normals, normals)
    integral = lateral_segment_cov(alpha, length, theta0, dtheta)
    np.testing.assert_allclose(integral, fine, rtol=0, atol=1e-8 * alpha * abs(length))
    np.testing.assert_allclose(lateral_segment_cov(alpha, length, theta0, dtheta, n), fine, rtol=0,
                               atol=1e-11 * alpha * abs(length))
    for steps in (1, 7):
        c = theta0 + (np.arange(steps) + 0.5) * dtheta / steps
        u = np.stack([-np.sin(c), np.cos(c)], axis=1)
        exact = alpha * abs(length) / steps * u.T @ u
        np.testing.assert_allclose(lateral_segment_cov(alpha, length, theta0, dtheta, steps), exact,
                                   rtol=0, atol=1e-15)
    assert np.trace(integral) == pytest.approx(alpha * abs(length), rel=1e-14)


def test_covariances_stay_symmetric_psd():
    rng = np.random.default_rng(13)
    steps, poses = _gyro_log(rng, 3000)
    cov = track_covariance(steps, poses, (GyroNoise(1e-6), LateralSlipNoise(1e-2)), np.zeros((3, 3)))
    assert np.array_equal(cov, np.swapaxes(cov, 1, 2))
    eig = np.linalg.eigvalsh(cov)
    assert eig.min() >= -1e-12 * eig.max()
    assert np.all(eig[1:, -1] > 0)


def test_headings_of_each_map_and_bad_input():
    th, a = np.array([0.1]), np.array([0.4])
    assert lateral_headings(th, a, "exact") == lateral_headings(th, a, "midpoint") == pytest.approx(0.3)
    assert lateral_headings(th, a, "euler") == pytest.approx(0.1)
    assert lateral_headings(th, a, "classical") == pytest.approx(0.5)
    with pytest.raises(ModelError, match="method"):
        lateral_headings(th, a, "rk4")
    with pytest.raises(ModelError, match="var_lateral"):
        propagate_recursion(th, [1.0], a, np.zeros((1, 2, 2)), np.zeros((3, 3)), var_lateral=[1.0, 2.0])



@pytest.mark.parametrize("flags,segs,noise,kw", [
    (["--wheel-base", "0.4", "--k-left", "0.01", "--k-right", "0.02", "--segment", "arc:3,1",
      "--segment", "straight:2"], [Arc(3.0, 1.0), Straight(2.0)],
     (WheelNoise(0.01, 0.02), LateralSlipNoise(1e-3)), {"wheel_base": 0.4}),
    (["--model", "gyro", "--gyro-noise", "1e-4", "--segment", "arc:1,0.3,5"], [KellyArc(1.0, 0.3, 5.0)],
     (SpeedNoise(0.0), GyroNoise(1e-4), LateralSlipNoise(1e-3)), {}),
], ids=["diff", "gyro"])
def test_predict_command_takes_the_lateral_noise_flag(capsys, flags, segs, noise, kw):
    import json

    from odomkit.cli import main

    assert main(["predict", *flags, "--lateral-noise", "1e-3", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(out["cov"], predict(segs, noise, **kw).cov, rtol=1e-14, atol=0)
    without = predict(segs, noise[:-1], **kw).cov
    assert np.abs(np.array(out["cov"]) - without).max() > 1e-4  # the flag was not ignored
    assert main(["predict", *flags, "--lateral-noise", "-1"]) == 2
    assert "--lateral-noise" in capsys.readouterr().err


@pytest.mark.parametrize("method", METHODS)
def test_compiled_pass_equals_the_numpy_reference(monkeypatch, method):
    import sys

    from odomkit import jit
    from odomkit.propagate.lateral import accumulate_lateral, add_lateral

    rng = np.random.default_rng(21)
    theta, dd, dtheta = _random_steps(rng, 500)
    var = rng.uniform(0.0, 1e-3, 500)
    start = np.array([1e-4, -2e-5, 3e-4])
    base = np.array([_psd(rng, 3, 1e-3) for _ in range(500)])
    reference = base.copy()
    add_lateral(reference, lateral_sums(theta, dtheta, var, method, start))
    for numba_missing in (False, True):
        if numba_missing:
            monkeypatch.setitem(sys.modules, "odomkit.propagate._numba", None)  # import fails
            monkeypatch.setattr(jit, "_cache", {})
        out, sums = base.copy(), start.copy()
        with pytest.warns(UserWarning, match="numba") if numba_missing else _no_warning():
            accumulate_lateral(theta[:200], dtheta[:200], var[:200], method, sums, out[:200])
            accumulate_lateral(theta[200:], dtheta[200:], var[200:], method, sums, out[200:])
        _close(out, reference, rtol=1e-14)
        _close(sums, lateral_sums(theta, dtheta, var, method, start)[-1], rtol=1e-14)


def _no_warning():
    import contextlib

    return contextlib.nullcontext()
