"""Windows that restart from the truth (odomkit.windows).

Independent truths: hand-counted window rows; window errors re-computed by dead-reckoning
each window's slice of the log on its own; Chong–Kleeman's straight-line variances; the
engines' own covariance with the full noise (the basis must add up to it to rounding);
finite differences of the odometry for the bias sensitivities.
"""

from __future__ import annotations

import numpy as np
import pytest

from odomkit.errors import InputError
from odomkit.integrate import dead_reckon
from odomkit.kinematics import body_steps
from odomkit.log import OdometryLog
from odomkit.noise import (
    CompassNoise,
    GyroNoise,
    ParameterUncertainty,
    SpeedNoise,
    TricycleNoise,
    WheelNoise,
)
from odomkit.robot import Car, CompassOdometry, DiffDrive, GyroOdometry, Tricycle, Unicycle
from odomkit.track import dead_reckon_log
from odomkit.truth import Truth
from odomkit.windows import (
    Window,
    WindowSpec,
    cumulative_travel,
    log_window_basis,
    parse_window,
    split_windows,
    window_covariance_basis,
    window_errors,
)


def test_parse_window_reads_time_and_travel():
    assert parse_window("30s") == WindowSpec(30.0, "s")
    assert parse_window(" 2.5 min ") == WindowSpec(150.0, "s")
    assert parse_window("1h") == WindowSpec(3600.0, "s")
    assert parse_window("5m") == WindowSpec(5.0, "m")
    assert parse_window("1e1s") == WindowSpec(10.0, "s")


@pytest.mark.parametrize("text", ["", "30", "s", "-5s", "0s", "5 km", "thirty s"])
def test_parse_window_refuses_bad_text_naming_the_flag(text):
    with pytest.raises(InputError, match="--window"):
        parse_window(text)


def test_split_windows_by_time_counted_by_hand():
    t = np.arange(0.0, 10.01, 0.5)  # 21 rows
    windows, skipped = split_windows(t, t, WindowSpec(3.0, "s"))
    assert [(w.start, w.end) for w in windows] == [(0, 6), (6, 12), (12, 18)]
    assert skipped == 0
    assert windows[0] == Window(0, 6, 3.0, 3.0)


def test_split_windows_by_travel_and_stationary_windows_are_counted():
    t = np.arange(0.0, 20.01, 1.0)  # 21 rows
    # Moves 1 m/s for 10 s, stands still for 10 s.
    travel = np.minimum(t, 10.0)
    windows, skipped = split_windows(t, travel, WindowSpec(4.0, "s"))
    # Rows 12..16 and 16..20 travel nothing; 8..12 travels 2 m and is kept.
    assert [(w.start, w.end) for w in windows] == [(0, 4), (4, 8), (8, 12)]
    assert skipped == 2
    windows, _ = split_windows(t, travel, WindowSpec(4.0, "s"), min_travel=0.0)
    assert len(windows) == 5
    by_travel, skipped = split_windows(t, travel, WindowSpec(3.0, "m"))
    assert [(w.start, w.end) for w in by_travel] == [(0, 3), (3, 6), (6, 9)]
    assert skipped == 0


def test_split_windows_restart_after_a_truth_gap_and_one_window_without_spec():
    t = np.arange(0.0, 20.01, 1.0)
    valid = np.ones(t.size, bool)
    valid[7:9] = False  # rows 0..6 and 9..20 have truth
    windows, _ = split_windows(t, t, WindowSpec(3.0, "s"), valid=valid)
    assert [(w.start, w.end) for w in windows] == [(0, 3), (3, 6), (9, 12), (12, 15), (15, 18)]
    whole, _ = split_windows(t, t, None, valid=valid)
    assert [(w.start, w.end) for w in whole] == [(0, 20)]


def test_a_window_longer_than_the_log_gives_none():
    t = np.arange(0.0, 5.01, 0.5)
    assert split_windows(t, t, WindowSpec(30.0, "s")) == ([], 0)


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


# --- Issue 11: the truth's own noise (Truth.sigma, Truth.heading_sigma, truth_columns) -----------


def _truth_noise_case(kind):
    """A turning log, its robot, zero-noise models (no robot noise) and the perfect odometry's
    track as the truth (so that every window error is the truth's own noise)."""
    n = 800
    t = np.arange(n) * 0.05
    if kind == "diff":
        log, robot, models = _curvy_log(n, seed=2), DiffDrive(0.3), (WheelNoise(0.0, 0.0),)
    else:
        log = OdometryLog(t, {"dist": np.full(n, 0.01), "steer": 0.3 * np.sin(t / 3)})
        robot, models = Tricycle(0.15), (TricycleNoise(0.0, 0.0, 0.0),)
    return log, robot, models, dead_reckon_log(log, robot).poses


def _monte_carlo_window_covariance(log, robot, poses, windows, sigma, heading_sigma, draws, seed):
    """Second moments of the window-end errors over ``draws`` noisy truths: each truth row
    moved by N(0, σ²) per axis and N(0, σθ²) in heading, each window dead-reckoned (perfect
    odometry) from its noisy start and compared with its noisy end. (W, 3, 3)"""
    rng = np.random.default_rng(seed)
    steps = body_steps(robot, log)
    rows = sorted({w.start for w in windows} | {w.end for w in windows})
    errors = np.empty((draws, len(windows), 3))
    for k in range(draws):
        noisy = {r: poses[r] + rng.normal(0.0, [sigma, sigma, heading_sigma]) for r in rows}
        for i, w in enumerate(windows):
            end = dead_reckon(steps.dd[w.start:w.end], steps.dtheta[w.start:w.end], noisy[w.start])[-1]
            errors[k, i] = noisy[w.end] - end
    errors[..., 2] = (errors[..., 2] + np.pi) % (2 * np.pi) - np.pi
    return np.einsum("kwa,kwb->wab", errors, errors) / draws


@pytest.mark.parametrize("kind", ["diff", "tricycle"])
def test_the_truths_own_noise_matches_monte_carlo(kind):
    """Issue 11: window_errors' covariance under Truth(sigma, heading_sigma) with no robot
    noise is the spread of dead reckoning from a noisy truth start to a noisy truth end;
    so are the basis's fixed part and σ²·col(−2) + σθ²·col(−1) of its truth columns.
    Tolerance: 5 standard errors of a sample second moment, sqrt((ΣiiΣjj + Σij²)/n)."""
    log, robot, models, poses = _truth_noise_case(kind)
    sigma, heading_sigma, draws = 0.004, 0.006, 4000
    windows, _ = split_windows(log.t, cumulative_travel(body_steps(robot, log)), WindowSpec(8.0, "s"))
    assert len(windows) >= 4
    ok = np.ones(len(log), bool)
    truth = Truth(log.t, poses[:, :2], poses[:, 2], sigma=sigma, heading_sigma=heading_sigma)
    predicted = window_errors(log, robot, models, poses, ok, windows, truth=truth).cov
    sample = _monte_carlo_window_covariance(log, robot, poses, windows, sigma, heading_sigma, draws, 11)
    d = np.sqrt(np.einsum("wii->wi", predicted))
    tol = 5 * np.sqrt((d[:, :, None] ** 2 * d[:, None, :] ** 2 + predicted**2) / draws)
    assert np.all(np.abs(sample - predicted) <= tol), np.max(np.abs(sample - predicted) / tol)
    # The check can fail: without the start heading's swing about the start (σθ² only on
    # θ at both ends) the covariance is far outside the same tolerance.
    swingless = np.diag([2 * sigma**2, 2 * sigma**2, 2 * heading_sigma**2])
    assert np.max(np.abs(sample - swingless) / tol) > 3
    # The basis's fixed part (no robot noise) and its truth columns say the same.
    basis = window_covariance_basis(log, robot, models, poses, ok, windows, truth=truth)
    scale = np.abs(predicted).max()
    np.testing.assert_allclose(basis.fixed / scale, predicted / scale, rtol=0, atol=1e-12)
    columns = window_covariance_basis(log, robot, models, poses, ok, windows, truth=truth, truth_columns=True)
    assert not columns.fixed.any()
    own = sigma**2 * columns.white[:, -2] + heading_sigma**2 * columns.white[:, -1]
    np.testing.assert_allclose(own / scale, predicted / scale, rtol=0, atol=1e-12)


def _truth_columns_case(case):
    """(log, robot, models, truth poses, Truth with σ and σθ, the same Truth without noise)."""
    sigma, heading_sigma = 0.003, 0.004
    if case == "compass":
        log, robot, models = _models_and_log("compass")
        poses = dead_reckon_log(log, robot).poses + 0.01
        xy, theta = poses[:, :2], poses[:, 2]
    else:
        log, robot, models = _models_and_log("diff")
        poses = dead_reckon_log(log, robot).poses + 0.01
        xy, theta = poses[:, :2], poses[:, 2]
        if case == "position_only":
            # Fixes with 2 mm of noise, σ = 1 mm below it: the start heading fitted to them
            # takes its variance from their residual (heading_from_positions), not from σ.
            sigma = 0.001
            xy = xy + np.random.default_rng(8).normal(0.0, 0.002, xy.shape)
            poses = np.column_stack((xy, np.full(len(log), np.nan)))
            theta = None
    noisy = Truth(log.t, xy, theta, sigma=sigma, heading_sigma=heading_sigma)
    return log, robot, models, poses, noisy, Truth(log.t, xy, theta)


@pytest.mark.parametrize("case", ["diff", "position_only", "compass"])
def test_truth_columns_take_the_truths_noise_out_of_fixed_and_add_back_up(case):
    """Issue 11: with truth_columns the truth's σ and σθ leave ``fixed`` (it is a noiseless
    truth's), become the last two white columns (TRUTH_NOISE), and v with σ², σθ² in them
    gives the covariance of truth_columns=False (and of the engines) to rounding. The
    position column is diag(2, 2, 0); the heading column is, with perfect odometry's
    end − start (Δx, Δy), u uᵀ for u = (−Δy, Δx, 1) (a start heading error swings the end
    about the start) plus 1 on θθ (the end heading) where the start heading is the truth's,
    only the end's 1 where it is measured (compass), zero without truth heading."""
    from odomkit.windows import TRUTH_NOISE

    log, robot, models, poses, noisy, clean = _truth_columns_case(case)
    ok = np.ones(len(log), bool)
    windows, _ = split_windows(log.t, cumulative_travel(body_steps(robot, log)), WindowSpec(8.0, "s"))
    cols = window_covariance_basis(log, robot, models, poses, ok, windows, truth=noisy, truth_columns=True)
    plain = window_covariance_basis(log, robot, models, poses, ok, windows, truth=noisy)
    noiseless = window_covariance_basis(log, robot, models, poses, ok, windows, truth=clean)
    assert TRUTH_NOISE == ((-1, "truth_sigma"), (-1, "truth_heading_sigma"))
    assert cols.white_names == plain.white_names + TRUTH_NOISE and cols.bias_names == plain.bias_names
    np.testing.assert_allclose(cols.fixed, noiseless.fixed, rtol=1e-12, atol=1e-300)
    if case != "position_only":
        assert not cols.fixed.any()
    np.testing.assert_array_equal(cols.white[:, :-2], plain.white)
    np.testing.assert_array_equal(cols.sens, plain.sens)
    position = np.broadcast_to(np.diag([2.0, 2.0, 0.0]), (len(cols.windows), 3, 3))
    np.testing.assert_array_equal(cols.white[:, -2], position)
    heading = cols.white[:, -1]
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
    robot_v = [models[i].variance_parameters(robot)[name] for i, name in plain.white_names]
    bias_v = [models[i].variance_parameters(robot)[name] for i, name in plain.bias_names]
    v = np.array(robot_v + [noisy.sigma**2, noisy.heading_sigma**2] + bias_v)
    expected = plain.covariance(np.array(robot_v + bias_v))
    direct = window_errors(log, robot, models, poses, ok, windows, truth=noisy).cov
    scale = np.abs(direct).max(axis=(1, 2))[:, None, None]
    np.testing.assert_allclose(cols.covariance(v) / scale, expected / scale, rtol=0, atol=1e-12)
    np.testing.assert_allclose(cols.covariance(v) / scale, direct / scale, rtol=0, atol=1e-12)
    # The truth's noise matters here (the check can fail): v without it falls short.
    v[len(robot_v):len(robot_v) + 2] = 0.0
    assert np.max(np.abs(cols.covariance(v) - direct) / scale) > 1e-3


def test_the_truth_heading_column_has_its_end_part_wherever_the_end_heading_is_compared():
    """The heading column's 1 on θθ at the end belongs to every window whose end heading is
    compared (its θ error is finite), also when the truth comes as poses alone (truth=None,
    as the synthetic fits pass it): the same poses with or without the Truth object give
    the same columns."""
    log, robot, models, poses, _, clean = _truth_columns_case("diff")
    ok = np.ones(len(log), bool)
    windows, _ = split_windows(log.t, log.t, WindowSpec(8.0, "s"))
    given = window_covariance_basis(log, robot, models, poses, ok, windows, truth=clean, truth_columns=True)
    bare = window_covariance_basis(log, robot, models, poses, ok, windows, truth_columns=True)
    assert np.all(np.isfinite(bare.error[:, 2]))
    np.testing.assert_array_equal(bare.white[:, -2:], given.white[:, -2:])
