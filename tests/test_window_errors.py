"""Errors and covariances at the ends of windows that restart from the truth
(odomkit.window_errors).

Independent truths: window errors re-computed by dead-reckoning each window's slice of the
log on its own; Chong–Kleeman's straight-line variances; the engines' own covariance with
the full noise (the basis must add up to it to rounding); finite differences of the
odometry for the bias sensitivities; Monte Carlo of the truth's own noise.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import body_steps
from odomkit.log import OdometryLog
from odomkit.noise import (
    CompassNoise,
    GyroNoise,
    LateralSlipNoise,
    ParameterUncertainty,
    SpeedNoise,
    TricycleNoise,
    WheelNoise,
)
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Tricycle, Unicycle
from odomkit.track import dead_reckon_log
from odomkit.truth import Truth
from odomkit.window_errors import log_window_basis, window_covariance_basis, window_errors
from odomkit.windows import Window, WindowSpec, cumulative_travel, split_windows


def _curvy_log(n=1200, dt=0.05, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    dl = 0.01 + 0.008 * np.sin(t / 2 + rng.uniform(0, 6))
    dr = 0.01 + 0.008 * np.sin(t / 3 + rng.uniform(0, 6))
    return OdometryLog(t, {"dist_left": dl, "dist_right": dr})


def test_window_errors_equal_each_window_dead_reckoned_on_its_own():
    log = _curvy_log()
    robot = DiffDrive(0.3)
    # The truth: the same wheels with a different wheel base (a systematic error).
    truth = dead_reckon_log(log, DiffDrive(0.31)).poses
    windows, _ = split_windows(log.t, log.t, WindowSpec(10.0, "s"))
    out = window_errors(log, robot, WheelNoise(0.001, 0.001), truth, np.ones(len(log), bool), windows)
    steps = body_steps(robot, log)
    for w, err in zip(windows, out.error, strict=True):
        poses = dead_reckon(steps.dd[w.start:w.end], steps.dtheta[w.start:w.end], truth[w.start])
        expected = truth[w.end] - poses[-1]
        np.testing.assert_allclose(err, expected, atol=1e-12)
    assert out.end_rows.tolist() == [w.end for w in windows]
    assert np.abs(out.error[:, 2]).max() > 1e-3  # the wheel-base error shows


def test_window_covariance_of_a_straight_line_is_chong_kleeman():
    n, d, base, k = 201, 0.01, 0.4, 0.01
    t = np.arange(n) * 0.1
    log = OdometryLog(t, {"dist_left": np.full(n, d), "dist_right": np.full(n, d)})
    truth = np.column_stack((d * np.arange(n), np.zeros(n), np.zeros(n)))
    windows, _ = split_windows(t, truth[:, 0], WindowSpec(1.0, "m"))
    out = window_errors(log, DiffDrive(base), WheelNoise(k, k), truth, np.ones(n, bool), windows)
    length = 1.0
    # Chong–Kleeman eq. (26)-(27): var x = (k_L² + k_R²) D / 4, var θ = (k_L² + k_R²) D / B²,
    # var y = (k_L² + k_R²) D³ / (3 B²) in the continuous limit (the discrete sum is
    # Σ (D − s_j)² Δs ≈ D³/3 with the exact-arc lever; 100 steps: 0.5 % off).
    assert out.cov[0, 0, 0] == pytest.approx(2 * k**2 * length / 4, rel=1e-12)
    assert out.cov[0, 2, 2] == pytest.approx(2 * k**2 * length / base**2, rel=1e-12)
    assert out.cov[0, 1, 1] == pytest.approx(2 * k**2 * length**3 / (3 * base**2), rel=1e-2)
    assert np.abs(out.error).max() < 1e-12


def test_truth_sigma_enters_at_both_window_ends():
    n = 201
    t = np.arange(n) * 0.1
    log = OdometryLog(t, {"dist_left": np.full(n, 0.01), "dist_right": np.full(n, 0.01)})
    truth = np.column_stack((0.01 * np.arange(n), np.zeros(n), np.zeros(n)))
    windows, _ = split_windows(t, truth[:, 0], WindowSpec(1.0, "m"))
    tr = Truth(t, truth[:, :2], truth[:, 2], sigma=0.02)
    plain = window_errors(log, DiffDrive(0.4), WheelNoise(0.01, 0.01), truth, np.ones(n, bool), windows)
    noisy = window_errors(log, DiffDrive(0.4), WheelNoise(0.01, 0.01), truth, np.ones(n, bool), windows,
                          truth=tr)
    np.testing.assert_allclose(noisy.cov - plain.cov,
                               np.broadcast_to(np.diag([2 * 0.02**2, 2 * 0.02**2, 0.0]), plain.cov.shape),
                               atol=1e-15)
    np.testing.assert_allclose(noisy.start_cov[0], np.diag([0.02**2, 0.02**2, 0.0]))


@pytest.mark.parametrize("reverse", [False, True])
def test_position_only_truth_fits_the_start_heading_and_carries_its_variance(reverse):
    n = 401
    t = np.arange(n) * 0.05
    sign = -1.0 if reverse else 1.0
    d = np.full(n, sign * 0.01)
    log = OdometryLog(t, {"dist_left": d, "dist_right": d})
    heading = 0.7
    poses = dead_reckon_log(log, DiffDrive(0.4), pose0=(1.0, 2.0, heading)).poses
    truth = poses.copy()
    truth[:, 2] = np.nan
    rng = np.random.default_rng(3)
    tr = Truth(t, poses[:, :2] + rng.normal(0, 1e-4, (n, 2)), None, sigma=1e-4)
    windows, _ = split_windows(t, np.abs(sign * 0.01 * np.arange(n)), WindowSpec(5.0, "s"))
    out = window_errors(log, DiffDrive(0.4), WheelNoise(0.0, 0.0), truth, np.ones(n, bool), windows, truth=tr)
    assert np.all(np.isnan(out.error[:, 2]))
    var_theta = out.start_cov[:, 2, 2]
    assert np.all(var_theta > 0) and np.all(var_theta < 1e-3)
    # The fitted heading is right (facing away from travel when reversing): a heading off
    # by π would leave the 1 m windows 2 m off.
    assert np.abs(out.error[:, :2]).max() < 0.01
    # A heading error δ over a straight window of length D moves the end by D·δ across
    # track: var(across) = D² var θ (+ σ² at both ends), with no odometry noise.
    across = np.array([-np.sin(heading), np.cos(heading)])
    length = np.array([w.travel for w in out.windows])
    var_across = np.einsum("i,wij,j->w", across, out.cov[:, :2, :2], across)
    # (rtol: the covariance turns with the fitted heading, the check with the true one)
    np.testing.assert_allclose(var_across, length**2 * var_theta + 2e-8, rtol=1e-3)


def _models_and_log(kind):
    rng = np.random.default_rng(5)
    n = 800
    t = np.arange(n) * 0.05
    if kind == "diff":
        log = _curvy_log(n)
        return log, DiffDrive(0.3), (WheelNoise(0.003, 0.002), ParameterUncertainty(0.002, 0.004, 0.003))
    steered = ParameterUncertainty(0.002, 0.01, sigma_steering_offset=0.003)
    rate = ParameterUncertainty(0, 0.01, sigma_yaw_rate_offset=0.002, sigma_yaw_rate_scale=0.01)
    if kind in ("tricycle", "car"):
        log = OdometryLog(t, {"dist": np.full(n, 0.01), "steer": 0.3 * np.sin(t / 3)})
        robot = Tricycle(0.15) if kind == "tricycle" else Car(0.3, 0.1, "front")
        return log, robot, (TricycleNoise(0.01, 0.02, 0.001), steered)
    if kind in ("gyro", "unicycle"):
        log = OdometryLog(t, {"dist": np.full(n, 0.01), "yaw_rate": 0.4 * np.sin(t / 4)})
        robot = GyroOdometry() if kind == "gyro" else Unicycle()
        return log, robot, (SpeedNoise(1e-4), GyroNoise(2e-5), rate)
    heading = np.cumsum(0.02 * np.sin(t / 4)) + rng.normal(0, 1e-3, n)
    log = OdometryLog(t, {"dist": np.full(n, 0.01), "heading": heading})
    return log, CompassOdometry(), (SpeedNoise(1e-4), CompassNoise(1e-4),
                                    ParameterUncertainty(0, 0.01, sigma_heading_offset=0.005))


@pytest.mark.parametrize("kind", ["diff", "tricycle", "car", "gyro", "unicycle", "compass"])
@pytest.mark.parametrize("position_only", [False, True])
def test_the_basis_adds_up_to_the_engines_covariance(kind, position_only):
    """P(v) = fixed + Σ v_j B_j + S diag(c(v)) Sᵀ equals the engines' run with v (1e-12)."""
    log, robot, models = _models_and_log(kind)
    n = len(log)
    truth = dead_reckon_log(log, robot).poses + 0.01
    tr = None
    if position_only:
        truth[:, 2] = np.nan
        tr = Truth(log.t, truth[:, :2], None, sigma=0.003)
    steps = body_steps(robot, log)
    windows, _ = split_windows(log.t, cumulative_travel(steps), WindowSpec(8.0, "s"))
    ok = np.ones(n, bool)
    basis = window_covariance_basis(log, robot, models, truth, ok, windows, truth=tr)
    direct = window_errors(log, robot, models, truth, ok, windows, truth=tr)
    v = np.concatenate([[models[i].variance_parameters(robot)[name] for i, name in names]
                        for names in (basis.white_names, basis.bias_names)])
    scale = np.abs(direct.cov).max(axis=(1, 2))[:, None, None]
    np.testing.assert_allclose(basis.covariance(v) / scale, direct.cov / scale, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(np.isnan(basis.error), np.isnan(direct.error))
    np.testing.assert_allclose(basis.error[:, :2], direct.error[:, :2], atol=1e-15)


def test_bias_sensitivities_match_finite_differences_with_one_sign():
    """The joint likelihood needs S itself (signs across windows), not only S Sᵀ."""
    log = _curvy_log(1600)
    base = 0.3
    truth = dead_reckon_log(log, DiffDrive(base)).poses
    windows, _ = split_windows(log.t, log.t, WindowSpec(10.0, "s"))
    basis = window_covariance_basis(log, DiffDrive(base), ParameterUncertainty(1.0, 1.0, 1.0), truth,
                                    np.ones(len(log), bool), windows)
    h = 1e-7
    moved = window_errors(log, DiffDrive(base + h), WheelNoise(0, 0), truth, np.ones(len(log), bool),
                          windows)
    # error = truth − odometry; the odometry moves by S·δ, so the error moves by −S·δ.
    fd = -moved.error / h
    np.testing.assert_allclose(basis.sens[:, :, 0], fd, rtol=1e-4, atol=1e-6 * np.abs(fd).max())


def test_windows_need_valid_truth_and_report_nan_positions():
    log = _curvy_log(200)
    truth = dead_reckon_log(log, DiffDrive(0.3)).poses
    bad = truth.copy()
    bad[100, 0] = np.nan
    windows = [Window(0, 100, 5.0, 1.0)]
    with pytest.raises(InputError, match="row 100 is NaN"):
        window_errors(log, DiffDrive(0.3), WheelNoise(0, 0), bad, np.ones(200, bool), windows)


def test_log_window_basis_is_each_length_cut_by_hand_and_merged():
    """One log, windows of 10 s and 30 s: the same windows, errors and covariances as
    cutting each length with split_windows and building its basis, in that order; None
    (and the count of windows left standing) when no length fits."""


    log = _curvy_log(n=2400)
    robot = DiffDrive(0.3)
    models = (WheelNoise(0.0, 0.0), ParameterUncertainty())
    gt = dead_reckon_log(log, robot).poses
    truth = Truth(log.t, gt[:, :2], gt[:, 2])
    specs = [WindowSpec(10.0, "s"), WindowSpec(30.0, "s")]
    basis, skipped = log_window_basis(log, robot, models, truth, specs)
    travel = cumulative_travel(body_steps(robot, log))
    valid = np.ones(len(log), bool)
    by_hand = [window_covariance_basis(log, robot, models, gt, valid,
                                       split_windows(log.t, travel, s, valid=valid)[0], truth=truth)
               for s in specs]
    assert basis is not None and skipped == 0
    assert basis.windows == by_hand[0].windows + by_hand[1].windows
    v = np.array([1e-6, 2e-6, 1e-6, 1e-6, 1e-6])
    np.testing.assert_array_equal(basis.covariance(v),
                                  np.concatenate([b.covariance(v) for b in by_hand]))
    none, _ = log_window_basis(log, robot, models, truth, [WindowSpec(1000.0, "s")])
    assert none is None


# --- Issue 11: the truth's own noise (Truth.sigma, heading_sigma, time_sigma, truth_columns) -----


def _truth_noise_case(kind):
    """A log that turns gently (0.05 … 0.16 rad/s) at a speed that varies (0.14 … 0.26 m/s)
    over seconds, its robot, zero-noise models (no robot noise) and the perfect odometry's
    track as the truth (so that every window error is the truth's own noise)."""
    n = 1000
    t = np.arange(n) * 0.05
    dist = 0.01 + 0.003 * np.sin(t / 6 + 1)  # [m] per 0.05 s step
    if kind == "diff":
        turn = 0.0008 + 0.0004 * np.sin(t / 8 + 2)
        log = OdometryLog(t, {"dist_left": dist - turn, "dist_right": dist + turn})
        robot, models = DiffDrive(0.3), (WheelNoise(0.0, 0.0),)
    else:
        log = OdometryLog(t, {"dist": dist, "steer": 0.08 + 0.04 * np.sin(t / 8)})
        robot, models = Tricycle(0.15), (TricycleNoise(0.0, 0.0, 0.0),)
    return log, robot, models, dead_reckon_log(log, robot).poses


def _monte_carlo_window_covariance(log, robot, poses, windows, sigma, heading_sigma, time_sigma, draws,
                                   seed, shift_heading=False):
    """Second moments of the window-end errors over ``draws`` noisy truths: each truth row r
    has the perfect track's position at t_r + δ_r, δ_r ~ N(0, σt²) (x and y interpolated
    linearly between the log's rows), and its heading at t_r (``shift_heading``: at
    t_r + δ_r too, interpolated alike), moved by N(0, σ²) per axis and N(0, σθ²) in
    heading; each window is dead-reckoned (perfect odometry) from its noisy start and
    compared with its noisy end. (W, 3, 3)"""
    rng = np.random.default_rng(seed)
    steps = body_steps(robot, log)
    rows = np.array(sorted({w.start for w in windows} | {w.end for w in windows}))
    errors = np.empty((draws, len(windows), 3))
    for k in range(draws):
        when = log.t[rows] + rng.normal(0.0, time_sigma, rows.size)
        fixes = np.column_stack([np.interp(when, log.t, poses[:, j]) for j in range(3)])
        if not shift_heading:
            fixes[:, 2] = poses[rows, 2]
        fixes += rng.normal(0.0, [sigma, sigma, heading_sigma], fixes.shape)
        noisy = dict(zip(rows.tolist(), fixes, strict=True))
        for i, w in enumerate(windows):
            end = dead_reckon(steps.dd[w.start:w.end], steps.dtheta[w.start:w.end], noisy[w.start])[-1]
            errors[k, i] = noisy[w.end] - end
    errors[..., 2] = (errors[..., 2] + np.pi) % (2 * np.pi) - np.pi
    return np.einsum("kwa,kwb->wab", errors, errors) / draws


@pytest.mark.parametrize("time_sigma", [0.0, 0.05])
@pytest.mark.parametrize("kind", ["diff", "tricycle"])
def test_the_truths_own_noise_matches_monte_carlo(kind, time_sigma):
    """Issue 11: window_errors' covariance under Truth(sigma, heading_sigma, time_sigma)
    with no robot noise is the spread of dead reckoning from a noisy truth start to a noisy
    truth end, the fixes' positions also taken σt off the log's clock; so are the basis's
    fixed part and σ²·col(−3) + σθ²·col(−2) + σt²·col(−1) of its truth columns.

    The heading's share of a clock offset (ω·δ) is deliberately not modelled
    (window_errors._pose_rates says why), so the Monte Carlo shifts only the positions and keeps
    each fix's heading at its row's time. That share is not negligible on this log (ω·σt
    up to 8 mrad beside σθ = 6 mrad: shifting the heading too puts the θ components up to
    16 tolerances off), so nothing here claims it is.

    Tolerance: 5 standard errors of a sample second moment, sqrt((ΣiiΣjj + Σij²)/n). The
    model takes the velocity over the 0.2 s after a window's start and before its end
    (RATE_SPAN), the Monte Carlo shifts each fix about its own time: the two differ by
    0.1 s of the velocity's change, a bias under a third of the tolerance on this log
    (checked against 40 000 draws). The first window starts at row 0, where a shift back
    would leave the log: it is left out."""
    log, robot, models, poses = _truth_noise_case(kind)
    sigma, heading_sigma, draws = 0.004, 0.006, 4000
    windows, _ = split_windows(log.t, cumulative_travel(body_steps(robot, log)), WindowSpec(8.0, "s"))
    windows = windows[1:]
    assert len(windows) >= 4
    ok = np.ones(len(log), bool)
    truth = Truth(log.t, poses[:, :2], poses[:, 2], sigma=sigma, heading_sigma=heading_sigma,
                  time_sigma=time_sigma)
    predicted = window_errors(log, robot, models, poses, ok, windows, truth=truth).cov
    sample = _monte_carlo_window_covariance(log, robot, poses, windows, sigma, heading_sigma, time_sigma,
                                            draws, 11)
    d = np.sqrt(np.einsum("wii->wi", predicted))
    tol = 5 * np.sqrt((d[:, :, None] ** 2 * d[:, None, :] ** 2 + predicted**2) / draws)
    assert np.all(np.abs(sample - predicted) <= tol), np.max(np.abs(sample - predicted) / tol)
    # The check can fail: without the time term, or without the start heading's swing
    # about the start (σθ² only on θ at both ends), the covariance is far outside the
    # same tolerance.
    if time_sigma:
        timeless = window_errors(log, robot, models, poses, ok, windows,
                                 truth=replace(truth, time_sigma=0.0)).cov
        assert np.max(np.abs(sample - timeless) / tol) > 3
    else:
        swingless = np.diag([2 * sigma**2, 2 * sigma**2, 2 * heading_sigma**2])
        assert np.max(np.abs(sample - swingless) / tol) > 3
    # The basis's fixed part (no robot noise) and its truth columns say the same.
    basis = window_covariance_basis(log, robot, models, poses, ok, windows, truth=truth)
    scale = np.abs(predicted).max()
    np.testing.assert_allclose(basis.fixed / scale, predicted / scale, rtol=0, atol=1e-12)
    columns = window_covariance_basis(log, robot, models, poses, ok, windows, truth=truth, truth_columns=True)
    assert not columns.fixed.any()
    own = (sigma**2 * columns.white[:, -3] + heading_sigma**2 * columns.white[:, -2]
           + time_sigma**2 * columns.white[:, -1])
    np.testing.assert_allclose(own / scale, predicted / scale, rtol=0, atol=1e-12)


def _truth_columns_case(case):
    """(log, robot, models, truth poses, Truth with σ, σθ and σt, the same Truth without noise).

    The log runs on a clock of 1/16 s, exact in binary, so that the velocities' span (the
    fewest steps that reach RATE_SPAN = 0.2 s: 4 steps, 0.25 s) is the same in every
    window with no rounding margin to rely on (a 0.05 s clock needs one:
    test_the_time_column_does_not_depend_on_the_clocks_origin)."""
    sigma, heading_sigma, time_sigma = 0.003, 0.004, 0.02
    log, robot, models = _models_and_log("compass" if case == "compass" else "diff")
    log = OdometryLog(np.arange(len(log)) / 16, log.channels)
    poses = dead_reckon_log(log, robot).poses + 0.01
    xy, theta = poses[:, :2], poses[:, 2]
    if case == "position_only":
        # Fixes with 2 mm of noise, σ = 1 mm below it: the start heading fitted to them
        # takes its variance from their residual (heading_from_positions), not from σ.
        sigma = 0.001
        xy = xy + np.random.default_rng(8).normal(0.0, 0.002, xy.shape)
        poses = np.column_stack((xy, np.full(len(log), np.nan)))
        theta = None
    noisy = Truth(log.t, xy, theta, sigma=sigma, heading_sigma=heading_sigma, time_sigma=time_sigma)
    return log, robot, models, poses, noisy, Truth(log.t, xy, theta)


def _time_column_by_hand(case, log, robot, poses, truth, w):
    """Φ u_a u_aᵀ Φᵀ + u_b u_bᵀ of window ``w`` from its own dead reckoning: u the position
    change over the 4 steps (0.25 s of 1/16 s, the fewest that reach 0.2 s) after the start
    and before the end divided by their time. Its θ is zero (the heading's share of a clock
    offset is left out: window_errors._pose_rates) but at a start whose heading is fitted to
    position-only truth, where the fixes' clock turns that heading by ω·δ; a start pose error
    (dx, dy, dθ) reaches the end as (dx − dθ·Δy, dy + dθ·Δx, dθ), Δ = end − start."""
    from odomkit.truth import start_heading

    steps = body_steps(robot, log)
    start = poses[w.start].copy()
    if case == "compass":
        start[2] = steps.inputs["heading"][w.start]
    elif case == "position_only":  # the odometry's path (any frame) turned onto the fixes
        whole = dead_reckon(steps.dd, steps.dtheta, np.array([5.0, -3.0, 1.0]))
        start[2] = start_heading(truth, float(log.t[w.start]), log.t, whole)[0]
    track = dead_reckon(steps.dd[w.start:w.end], steps.dtheta[w.start:w.end], start)
    u_a = (track[4] - track[0]) / (log.t[w.start + 4] - log.t[w.start])
    u_b = (track[-1] - track[-5]) / (log.t[w.end] - log.t[w.end - 4])
    u_b[2] = 0.0
    if case != "position_only":
        u_a[2] = 0.0
    dx, dy = track[-1, :2] - track[0, :2]
    carried = u_a + u_a[2] * np.array([-dy, dx, 0.0])
    return np.outer(carried, carried) + np.outer(u_b, u_b)


@pytest.mark.parametrize("case", ["diff", "position_only", "compass"])
def test_truth_columns_take_the_truths_noise_out_of_fixed_and_add_back_up(case):
    """Issue 11: with truth_columns the truth's σ, σθ and σt leave ``fixed`` (it is a
    noiseless truth's), become the last three white columns (TRUTH_NOISE), and v with σ²,
    σθ², σt² in them gives the covariance of truth_columns=False (and of the engines) to
    rounding. The position column is diag(2, 2, 0); the heading column is, with perfect
    odometry's end − start (Δx, Δy), u uᵀ for u = (−Δy, Δx, 1) (a start heading error
    swings the end about the start) plus 1 on θθ (the end heading) where the start heading
    is the truth's, only the end's 1 where it is measured (compass), zero without truth
    heading; the time column is the velocity's at both ends (_time_column_by_hand)."""
    from odomkit.window_errors import TRUTH_NOISE

    log, robot, models, poses, noisy, clean = _truth_columns_case(case)
    ok = np.ones(len(log), bool)
    windows, _ = split_windows(log.t, cumulative_travel(body_steps(robot, log)), WindowSpec(8.0, "s"))
    cols = window_covariance_basis(log, robot, models, poses, ok, windows, truth=noisy, truth_columns=True)
    plain = window_covariance_basis(log, robot, models, poses, ok, windows, truth=noisy)
    noiseless = window_covariance_basis(log, robot, models, poses, ok, windows, truth=clean)
    assert TRUTH_NOISE == ((-1, "truth_sigma"), (-1, "truth_heading_sigma"), (-1, "truth_time_sigma"))
    assert cols.white_names == plain.white_names + TRUTH_NOISE and cols.bias_names == plain.bias_names
    np.testing.assert_allclose(cols.fixed, noiseless.fixed, rtol=1e-12, atol=1e-300)
    if case != "position_only":
        assert not cols.fixed.any()
    np.testing.assert_array_equal(cols.white[:, :-3], plain.white)
    np.testing.assert_array_equal(cols.sens, plain.sens)
    position = np.broadcast_to(np.diag([2.0, 2.0, 0.0]), (len(cols.windows), 3, 3))
    np.testing.assert_array_equal(cols.white[:, -3], position)
    heading = cols.white[:, -2]
    if case == "diff":
        steps = body_steps(robot, log)
        for w, col in zip(cols.windows, heading, strict=True):
            end = dead_reckon(steps.dd[w.start:w.end], steps.dtheta[w.start:w.end], poses[w.start])[-1]
            u = np.array([-(end[1] - poses[w.start, 1]), end[0] - poses[w.start, 0], 1.0])
            np.testing.assert_allclose(col, np.outer(u, u) + np.diag([0.0, 0.0, 1.0]), rtol=1e-9, atol=1e-12)
    elif case == "compass":
        np.testing.assert_array_equal(heading, np.broadcast_to(np.diag([0.0, 0.0, 1.0]), heading.shape))
    else:
        assert not heading.any()
    for w, col in zip(cols.windows, cols.white[:, -1], strict=True):
        by_hand = _time_column_by_hand(case, log, robot, poses, noisy, w)
        np.testing.assert_allclose(col, by_hand, rtol=1e-9, atol=1e-12 * np.abs(by_hand).max())
    robot_v = [models[i].variance_parameters(robot)[name] for i, name in plain.white_names]
    bias_v = [models[i].variance_parameters(robot)[name] for i, name in plain.bias_names]
    v = np.array(robot_v + [noisy.sigma**2, noisy.heading_sigma**2, noisy.time_sigma**2] + bias_v)
    expected = plain.covariance(np.array(robot_v + bias_v))
    direct = window_errors(log, robot, models, poses, ok, windows, truth=noisy).cov
    scale = np.abs(direct).max(axis=(1, 2))[:, None, None]
    np.testing.assert_allclose(cols.covariance(v) / scale, expected / scale, rtol=0, atol=1e-12)
    np.testing.assert_allclose(cols.covariance(v) / scale, direct / scale, rtol=0, atol=1e-12)
    # The truth's noise matters here (the check can fail): v without its time part, or
    # without any of it, falls short.
    v[len(robot_v) + 2] = 0.0
    assert np.max(np.abs(cols.covariance(v) - direct) / scale) > 1e-3
    v[len(robot_v):len(robot_v) + 3] = 0.0
    assert np.max(np.abs(cols.covariance(v) - direct) / scale) > 1e-3


def test_the_truth_heading_column_has_its_end_part_wherever_the_end_heading_is_compared():
    """The heading column's 1 on θθ at the end belongs to every window whose end heading is
    compared (its θ error is finite), also when the truth comes as poses alone (truth=None,
    as the synthetic fits pass it): the same poses with or without the Truth object give
    the same truth columns (the time column's rates are the window's own dead reckoning's)."""
    log, robot, models, poses, _, clean = _truth_columns_case("diff")
    ok = np.ones(len(log), bool)
    windows, _ = split_windows(log.t, log.t, WindowSpec(8.0, "s"))
    given = window_covariance_basis(log, robot, models, poses, ok, windows, truth=clean, truth_columns=True)
    bare = window_covariance_basis(log, robot, models, poses, ok, windows, truth_columns=True)
    assert np.all(np.isfinite(bare.error[:, 2]))
    np.testing.assert_array_equal(bare.white[:, -3:], given.white[:, -3:])
    assert bare.white[:, -2].any() and bare.white[:, -1].any()


def _stop_and_go_log(n=1000, period=4.0):
    """A differential drive that stands still within 0.5 s of every multiple of ``period``
    and drives a smooth turning arc between (sin² speed, up to 0.2 m/s)."""
    t = np.arange(n) * 0.05
    phase = np.mod(t, period)
    moving = (phase > 0.5) & (phase < period - 0.5)
    speed = np.where(moving, 0.01 * np.sin(np.pi * (phase - 0.5) / (period - 1.0)) ** 2, 0.0)
    return OdometryLog(t, {"dist_left": 0.8 * speed, "dist_right": 1.2 * speed})


def test_a_robot_standing_at_both_window_ends_has_no_time_column():
    """A fix off the log's clock is off by nothing where the robot stands (u = 0): windows
    from stop to stop get an exactly zero time column, and Truth.time_sigma changes nothing
    in their covariance; the same log's windows from motion to motion do get one (the check
    can fail)."""
    log, robot, models = _stop_and_go_log(), DiffDrive(0.3), (WheelNoise(0.001, 0.001),)
    poses = dead_reckon_log(log, robot).poses
    ok = np.ones(len(log), bool)
    still, _ = split_windows(log.t, log.t, WindowSpec(4.0, "s"))
    assert len(still) >= 10
    basis = window_covariance_basis(log, robot, models, poses, ok, still, truth_columns=True)
    assert not basis.white[:, -1].any()
    assert basis.white[:, -3].any() and basis.white[:, -2].any()
    timed = Truth(log.t, poses[:, :2], poses[:, 2], sigma=0.003, heading_sigma=0.004, time_sigma=0.05)
    untimed = replace(timed, time_sigma=0.0)
    np.testing.assert_array_equal(window_errors(log, robot, models, poses, ok, still, truth=timed).cov,
                                  window_errors(log, robot, models, poses, ok, still, truth=untimed).cov)
    moving = [Window(w.start + 40, w.end + 40, w.duration, w.travel) for w in still[:-1]]
    shifted = window_covariance_basis(log, robot, models, poses, ok, moving, truth_columns=True)
    assert np.all(np.einsum("wii->w", shifted.white[:, -1]) > 0.01)  # (0.2 m/s)² at each end


def test_the_time_column_does_not_depend_on_the_clocks_origin():
    """Moving a log's clock by a constant (a time stamp's epoch) changes no window: the
    velocities' span, the fewest steps that reach RATE_SPAN, must not hinge on how the sum
    of 0.05 s steps rounds (0.2 s is 4 of them; without a rounding margin 5 where the four
    sum to 0.1999999999999993, as at row 320 of a clock from 0 but not of one from
    1000.3 s: that window's time column moved by 2 %)."""
    log = _curvy_log(800)
    robot, models = DiffDrive(0.3), (WheelNoise(0.0, 0.0),)
    poses = dead_reckon_log(log, robot).poses
    ok = np.ones(len(log), bool)
    windows, _ = split_windows(log.t, log.t, WindowSpec(8.0, "s"))
    later = OdometryLog(log.t + 1000.3, log.channels)
    here = window_covariance_basis(log, robot, models, poses, ok, windows, truth_columns=True).white[:, -1]
    there = window_covariance_basis(later, robot, models, poses, ok, windows, truth_columns=True).white[:, -1]
    np.testing.assert_allclose(there, here, rtol=1e-6, atol=1e-9 * np.abs(here).max())


@pytest.mark.parametrize("gps_sigma", [0.3, 1.0])
def test_windows_started_from_sparse_position_only_fixes_are_honest_on_a_turning_car(gps_sigma):
    """Issue 11 (a car against GPS): perfect odometry (no robot noise at all) of a car at
    5–13 m/s whose yaw rate wanders (0.13 rad/s RMS), scored in 30 s windows against 1 Hz
    fixes with σ given: every window end's error is the fixes' noise, carried through the
    start pose (its fitted heading above all: 240 m of travel) and at the end, so the NEES
    mean must lie within its χ² bounds. The start heading from a quadratic through the fixes
    alone put it at 4.4 (1 m) and 11.8 (0.3 m) on this drive, bounds 1.4–2.7; aligning the
    odometry's own path to the fixes puts it inside."""
    from odomkit.evaluate import nees_summary
    from odomkit.truth import truth_at

    rng = np.random.default_rng(11)
    dt, n = 0.02, 60_000  # 20 min
    t = np.arange(n) * dt
    speed = 8 + 3 * np.sin(t / 37) + 2 * np.sin(t / 11 + 1)
    steer = np.zeros(n)
    for j in range(1, n):
        steer[j] = 0.995 * steer[j - 1] + rng.normal(0, 0.004)
    log = OdometryLog(t, {"speed": speed, "yaw_rate": speed * np.tan(steer) / 2.7})
    robot = Unicycle()
    path = dead_reckon_log(log, robot).poses  # the truth: the odometry is perfect
    fixes = np.arange(0.3, t[-1], 1.0)
    exact = np.column_stack([np.interp(fixes, t, path[:, k]) for k in (0, 1)])
    gps = Truth(fixes, exact + rng.normal(0.0, gps_sigma, exact.shape), sigma=gps_sigma)
    at_rows = truth_at(gps, t, max_gap=None)
    windows, _ = split_windows(t, cumulative_travel(body_steps(robot, log)), WindowSpec(30.0, "s"),
                               valid=at_rows.valid)
    out = window_errors(log, robot, LateralSlipNoise(0.0), at_rows.poses, at_rows.valid, windows, truth=gps)
    assert len(out.error) >= 35 and out.dropped <= 2
    summary = nees_summary(out.error[:, :2], out.cov[:, :2, :2])
    lo, hi = summary["bounds"]
    assert lo <= summary["mean"] <= hi, (summary["mean"], lo, hi)
