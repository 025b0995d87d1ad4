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
